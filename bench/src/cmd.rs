//! Running external commands (cargo, gcc, QEMU, apt-get) with clear errors and time limits.

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::thread;
use std::time::{Duration, Instant};

/// A failed step, with what was being done.
#[derive(Debug)]
pub struct Error(String);

impl Error {
    /// An error with this message.
    pub fn new(msg: impl Into<String>) -> Self {
        Error(msg.into())
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Error(e.to_string())
    }
}

/// Result of the bench steps.
pub type Result<T> = std::result::Result<T, Error>;

/// Adds context to errors.
pub trait Context<T> {
    /// Prefixes the error with `what`.
    fn context(self, what: impl fmt::Display) -> Result<T>;
}

impl<T, E: fmt::Display> Context<T> for std::result::Result<T, E> {
    fn context(self, what: impl fmt::Display) -> Result<T> {
        self.map_err(|e| Error(format!("{what}: {e}")))
    }
}

/// What a finished command gave.
#[derive(Debug)]
pub struct Output {
    /// Exit code (`None`: killed by a signal).
    pub code: Option<i32>,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

/// The command line as a string, for messages.
pub fn display(cmd: &Command) -> String {
    let mut s = cmd.get_program().to_string_lossy().into_owned();
    for a in cmd.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    s
}

/// Runs `cmd` to completion within `limit`, capturing its output; killed and an error
/// after `limit`.
pub fn run(cmd: &mut Command, limit: Duration) -> Result<Output> {
    let line = display(cmd);
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| Error::new(format!("cannot start `{line}`: {e}")))?;
    // Drain both pipes on threads so that a chatty child never blocks on a full pipe.
    let mut out = child
        .stdout
        .take()
        .ok_or_else(|| Error::new("no stdout pipe"))?;
    let mut err = child
        .stderr
        .take()
        .ok_or_else(|| Error::new("no stderr pipe"))?;
    let out_thread = thread::spawn(move || {
        let mut s = Vec::new();
        let _ = out.read_to_end(&mut s);
        s
    });
    let err_thread = thread::spawn(move || {
        let mut s = Vec::new();
        let _ = err.read_to_end(&mut s);
        s
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        if start.elapsed() > limit {
            // Our own child, by its handle.
            let _ = child.kill();
            let _ = child.wait();
            return Err(Error::new(format!(
                "`{line}` did not finish within {} s and was stopped",
                limit.as_secs()
            )));
        }
        thread::sleep(Duration::from_millis(20));
    };
    let stdout = String::from_utf8_lossy(&out_thread.join().unwrap_or_default()).into_owned();
    let stderr = String::from_utf8_lossy(&err_thread.join().unwrap_or_default()).into_owned();
    Ok(Output {
        code: status.code(),
        stdout,
        stderr,
    })
}

/// Runs `cmd` and requires exit code 0; the error quotes the end of its standard error.
pub fn run_ok(cmd: &mut Command, limit: Duration) -> Result<Output> {
    let line = display(cmd);
    let out = run(cmd, limit)?;
    if out.code != Some(0) {
        return Err(Error::new(format!(
            "`{line}` failed ({}):\n{}",
            match out.code {
                Some(c) => format!("exit code {c}"),
                None => "killed by a signal".into(),
            },
            tail(&out.stderr, 40)
        )));
    }
    Ok(out)
}

/// The last `n` lines of `s`.
pub fn tail(s: &str, n: usize) -> String {
    let lines: Vec<&str> = s.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

/// The first line a command prints on stdout, trimmed (for version strings); `None` if
/// it cannot run.
pub fn first_line(program: &str, args: &[&str]) -> Option<String> {
    let out = run(Command::new(program).args(args), Duration::from_secs(30)).ok()?;
    if out.code != Some(0) {
        return None;
    }
    out.stdout.lines().next().map(|l| l.trim().to_string())
}

/// The full path of `program` found in `PATH`, if any.
pub fn which(program: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join(program))
        .find(|p| is_executable(p))
}

fn is_executable(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    p.metadata()
        .map(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
        .unwrap_or(false)
}
