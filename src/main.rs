//! The `hearth` command-line tool: `hearth demo`, `hearth kin …`, `hearth bench …`.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    restore_default_sigpipe();
    ensure_runtime_dir();
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", report(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, joined by `: `, leaving out a cause that the text already ends
/// with after a `: ` (an error that prints its source as part of its own message).
fn report(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let message = cause.to_string();
        if text.is_empty() {
            text = message;
        } else if !text.ends_with(&format!(": {message}")) {
            text.push_str(": ");
            text.push_str(&message);
        }
    }
    text
}

/// `hearth kin info … | head` should end quietly when the reader goes away, as other Unix
/// tools do, rather than panic on a closed stdout.
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal disposition to its default at start-up, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Mesa's Vulkan drivers complain on stderr when `XDG_RUNTIME_DIR` is unset (as in containers
/// and CI): give them a private directory under the temp dir.
fn ensure_runtime_dir() {
    #[cfg(unix)]
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        use std::os::unix::fs::PermissionsExt;
        // SAFETY: getuid has no preconditions.
        let uid = unsafe { libc::getuid() };
        let dir = std::env::temp_dir().join(format!("hearth-runtime-{uid}"));
        let made = std::fs::create_dir_all(&dir)
            .and_then(|()| std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700)));
        if made.is_ok() {
            // SAFETY: called at start-up, before any thread exists, so nothing reads the
            // environment concurrently.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::report;

    #[test]
    fn report_names_each_cause_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        // A cause not in the message is added; one the message ends with is not repeated.
        let e = anyhow::Error::new(io).context("loading `x.json`");
        assert_eq!(report(&e), "loading `x.json`: no such file");
        let e = anyhow::anyhow!("inner").context("x.json: cannot read: inner");
        assert_eq!(report(&e), "x.json: cannot read: inner");
        // Only a whole message after `: ` counts.
        let e = anyhow::anyhow!("1").context("steps: 11");
        assert_eq!(report(&e), "steps: 11: 1");
        let e = anyhow::Error::from(Repeats).context("loading");
        assert_eq!(report(&e), "loading: x.json: cannot read: no such file");
    }

    /// An error whose message ends with its source's, as `thiserror`'s `{source}` makes them.
    #[derive(Debug)]
    struct Repeats;

    impl std::fmt::Display for Repeats {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("x.json: cannot read: no such file")
        }
    }

    impl std::error::Error for Repeats {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            static IO: std::sync::OnceLock<std::io::Error> = std::sync::OnceLock::new();
            Some(IO.get_or_init(|| std::io::Error::new(std::io::ErrorKind::NotFound, "no such file")))
        }
    }
}
