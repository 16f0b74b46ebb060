//! The failure log of a batch: one JSON object a line, `{"job": 0, "input": "...",
//! "reason": "..."}`, for each input that failed, in `NAME.failures.jsonl` beside manifest
//! `NAME.toml`. A rerun skips the inputs it lists (`batch --retry-failed` renders them
//! again), so that a long run's resumptions do not retry what cannot load. Each line is
//! written with one append, so that the shards of a job array may share the file.

use super::BatchError;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};

/// One line of the log.
#[derive(Debug, Serialize, Deserialize)]
struct Entry {
    job: usize,
    input: PathBuf,
    reason: String,
}

/// The failure log of the manifest at `manifest`.
pub fn log_path(manifest: &Path) -> PathBuf {
    let stem = manifest
        .file_stem()
        .map_or_else(|| "batch".into(), |s| s.to_string_lossy().into_owned());
    manifest.with_file_name(format!("{stem}.failures.jsonl"))
}

/// The (job, input) pairs the log at `path` lists (none where it does not exist). A line
/// that is not an entry is an error naming the file and the line.
pub fn read(path: &Path) -> Result<HashSet<(usize, PathBuf)>, BatchError> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(HashSet::new()),
        Err(e) => {
            return Err(BatchError::Io {
                path: path.display().to_string(),
                message: e.to_string(),
            });
        }
    };
    text.lines()
        .enumerate()
        .filter(|(_, line)| !line.trim().is_empty())
        .map(|(i, line)| {
            serde_json::from_str::<Entry>(line)
                .map(|e| (e.job, e.input))
                .map_err(|e| BatchError::Syntax {
                    path: path.display().to_string(),
                    line: i + 1,
                    message: format!("not a failure entry ({e}); delete the line or the file"),
                })
        })
        .collect()
}

/// Appends the failure of `input` (of job `job`) for `reason` to the log at `path`.
pub fn append(path: &Path, job: usize, input: &Path, reason: &str) -> Result<(), BatchError> {
    let io = |e: std::io::Error| BatchError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    let mut line = serde_json::to_vec(&Entry {
        job,
        input: input.to_path_buf(),
        reason: reason.to_string(),
    })
    .map_err(|e| io(std::io::Error::other(e)))?;
    line.push(b'\n');
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map_err(io)?;
    file.write_all(&line).map_err(io)
}
