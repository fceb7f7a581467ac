//! Every child process the xtask starts runs under a deadline and is killed when it passes it or
//! when the step that owns it fails: a hung QEMU or a stuck tool fails the step with its reason
//! within minutes, instead of holding CI until its own 90-minute limit.
//!
//! [`Bounded`] owns a spawned child: [`Bounded::wait`] waits up to the deadline and kills it past
//! that, and dropping it (an early `?` in the step) kills it too. [`run`] and [`output`] are the
//! one-shot forms. The limits are the callers': each says what the process normally takes and
//! leaves a wide margin for a loaded 2-core machine.

use anyhow::{Context, Result, bail};
use std::io::Read;
use std::process::{Child, ChildStderr, ChildStdout, Command, ExitStatus, Output, Stdio};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How often a wait looks at the child.
const POLL: Duration = Duration::from_millis(20);

/// A running child with a deadline; killed when dropped unfinished.
pub struct Bounded {
    child: Child,
    what: String,
    limit: Duration,
    deadline: Instant,
}

impl Bounded {
    /// Spawns `cmd` (its stdio as the caller set it) to finish within `limit`.
    pub fn spawn(cmd: &mut Command, what: &str, limit: Duration) -> Result<Self> {
        let child = cmd.spawn().with_context(|| format!("starting {what}"))?;
        Ok(Self {
            child,
            what: what.to_string(),
            limit,
            deadline: Instant::now() + limit,
        })
    }

    /// The child's standard output, if piped and not yet taken.
    pub fn take_stdout(&mut self) -> Option<ChildStdout> {
        self.child.stdout.take()
    }

    /// The child's standard error, if piped and not yet taken.
    pub fn take_stderr(&mut self) -> Option<ChildStderr> {
        self.child.stderr.take()
    }

    /// Waits for the child to exit; past the deadline kills it and fails, naming it and the limit.
    pub fn wait(&mut self) -> Result<ExitStatus> {
        loop {
            if let Some(status) = self.child.try_wait()? {
                return Ok(status);
            }
            if Instant::now() >= self.deadline {
                self.kill();
                bail!(
                    "{} did not finish within {} s: killed",
                    self.what,
                    self.limit.as_secs()
                );
            }
            std::thread::sleep(POLL);
        }
    }

    /// Kills the child (if it still runs) and reaps it.
    pub fn kill(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            eprintln!("killing {} (pid {})", self.what, self.child.id());
            let _ = self.child.kill();
        }
        let _ = self.child.wait();
    }
}

impl Drop for Bounded {
    fn drop(&mut self) {
        self.kill();
    }
}

/// Reads a pipe to its end on a thread (so a child never blocks on a full pipe while we wait).
pub fn collect(mut pipe: impl Read + Send + 'static) -> JoinHandle<Vec<u8>> {
    std::thread::spawn(move || {
        let mut bytes = Vec::new();
        let _ = pipe.read_to_end(&mut bytes);
        bytes
    })
}

/// Runs `cmd` with inherited stdio; fails on a non-zero exit or past `limit`.
pub fn run(cmd: &mut Command, what: &str, limit: Duration) -> Result<()> {
    let status = Bounded::spawn(cmd, what, limit)?.wait()?;
    if !status.success() {
        bail!("{what} failed ({status})");
    }
    Ok(())
}

/// Runs `cmd` capturing its standard output (stderr inherited) within `limit`; the exit status is
/// the caller's to judge.
pub fn output(cmd: &mut Command, what: &str, limit: Duration) -> Result<Output> {
    cmd.stdout(Stdio::piped());
    let mut child = Bounded::spawn(cmd, what, limit)?;
    let out = collect(child.take_stdout().context("stdout")?);
    let status = child.wait()?;
    let stdout = out.join().unwrap_or_default();
    Ok(Output {
        status,
        stdout,
        stderr: Vec::new(),
    })
}

/// Minutes, for the limits.
pub const fn minutes(n: u64) -> Duration {
    Duration::from_secs(60 * n)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_child_past_its_limit_is_killed_with_its_name() {
        let t = Instant::now();
        let err = run(
            Command::new("sleep").arg("30"),
            "a sleeping child",
            Duration::from_millis(300),
        )
        .unwrap_err();
        assert!(t.elapsed() < Duration::from_secs(10));
        let msg = format!("{err}");
        assert!(
            msg.contains("a sleeping child") && msg.contains("killed"),
            "{msg}"
        );
    }

    #[test]
    fn output_is_collected_and_a_dropped_child_is_killed() {
        let out = output(
            Command::new("sh").args(["-c", "echo hello"]),
            "echo",
            Duration::from_secs(30),
        )
        .unwrap();
        assert_eq!(out.stdout, b"hello\n");
        let child = Bounded::spawn(
            Command::new("sleep").arg("30"),
            "sleep",
            Duration::from_secs(60),
        )
        .unwrap();
        let pid = child.child.id();
        drop(child);
        // Reaped: no process with that id is our child any more.
        let alive = std::path::Path::new(&format!("/proc/{pid}/stat")).exists()
            && std::fs::read_to_string(format!("/proc/{pid}/stat"))
                .is_ok_and(|s| !s.contains(") Z "));
        assert!(!alive);
    }
}
