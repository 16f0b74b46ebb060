//! The `meshtrace` binary: parses the command line, runs the command, and prints any error
//! once, on one line, with a non-zero exit.

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    if std::env::var_os("NODEVICE_SELECT").is_none() {
        // Mesa's implicit device-select Vulkan layer only reorders adapters (meshtrace picks
        // its own) and, on a headless machine, prints "XDG_RUNTIME_DIR is invalid" errors
        // while probing for a Wayland display; this variable turns it off.
        // SAFETY: nothing else runs yet, so no thread can read the environment concurrently.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
    let args = cli::Cli::parse();
    let result = match &args.command {
        cli::Command::Render(r) => cli::render(r),
        cli::Command::Info(i) => cli::info(i),
        cli::Command::Merge(m) => cli::merge(m),
        cli::Command::Batch(b) => cli::batch(b),
        cli::Command::Adapters => cli::adapters(),
        cli::Command::Bench(b) => cli::bench(b),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // Whoever read the output stopped reading (`meshtrace info x.toml | head`).
        Err(e)
            if e.downcast_ref::<std::io::Error>()
                .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe) =>
        {
            ExitCode::SUCCESS
        }
        // Stopped by Ctrl-C or SIGTERM: what the user asked for, so not an `error:`; the
        // status still says the render is not complete.
        Err(e) if e.is::<cli::Interrupted>() => {
            eprintln!("{}", one_line(&e));
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {}", one_line(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by ": ", skipping a cause that the message before it
/// already ends with (library errors quote their source in their own message).
fn one_line(e: &anyhow::Error) -> String {
    let mut line = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !line.ends_with(&cause) {
            line.push_str(": ");
            line.push_str(&cause);
        }
    }
    line
}
