//! The line-by-line reading that the OBJ and MTL parsers share: a file's text up to its
//! first line that is not UTF-8, the rejected line with its number, and words quoted for
//! messages.

/// The first line of an OBJ or MTL file that the parser rejects: its 1-based number and
/// why.
#[derive(Debug)]
pub(super) struct BadLine {
    pub line: usize,
    pub message: String,
}

/// A file's text up to the first line that is not valid UTF-8 (all of it when every line
/// is), and that line's error, to report once the lines before it have been read: the first
/// malformed line is the one reported. One check for the whole file is faster than one per
/// line.
pub(super) fn text_lines(bytes: &[u8]) -> (&str, Option<BadLine>) {
    match std::str::from_utf8(bytes) {
        Ok(text) => (text, None),
        Err(e) => {
            let valid = &bytes[..e.valid_up_to()];
            let start = valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
            // A prefix of the valid part, so this cannot fail.
            let text = std::str::from_utf8(&valid[..start]).unwrap_or_default();
            let line = valid[..start].iter().filter(|&&b| b == b'\n').count() + 1;
            let bad = BadLine {
                line,
                message: "the line is not valid UTF-8 text".into(),
            };
            (text, Some(bad))
        }
    }
}

/// A word of the file as a message shows it: quoted, escaped onto one line, and cut short.
pub(super) fn quoted(word: &str) -> String {
    const MAX: usize = 32;
    let cut: String = word.chars().take(MAX).collect();
    let more = if word.chars().nth(MAX).is_some() {
        "…"
    } else {
        ""
    };
    format!("`{}{more}`", cut.escape_debug())
}
