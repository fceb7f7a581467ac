//! Progress display shared by the long-running commands on stderr, hidden with `--quiet` or when
//! stderr is not a terminal (indicatif checks that itself).
//!
//! Two shapes: a spinner for short steps of unknown length, and a [`Bar`] (position, rate, time
//! left) for long work whose size is known — loading a big CSV, gradient iterations, simulating a
//! long run. The libraries report through their own small progress traits (no terminal code in
//! them); [`Bar`] implements both.
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::time::Duration;

/// A spinner with `msg`, or a hidden one.
pub fn spinner(quiet: bool, msg: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
    }
    let pb = ProgressBar::new_spinner();
    if let Ok(style) = ProgressStyle::with_template("{spinner} {msg} [{elapsed}]") {
        pb.set_style(style);
    }
    pb.set_message(msg.to_string());
    pb.enable_steady_tick(Duration::from_millis(120));
    pb
}

/// A bar over `total` items of work (channels, units) done in any order, e.g. from rayon's
/// threads (`inc` is thread-safe), or a hidden one with `quiet`.
pub fn counter(quiet: bool, what: &str, total: u64, unit: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(total);
    let template =
        format!("{{msg}} [{{bar:30}}] {{pos}}/{{len}} {unit} [{{elapsed}} elapsed, eta {{eta}}]");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(what.to_string());
    pb.enable_steady_tick(Duration::from_millis(250));
    pb
}

/// A progress bar driven by the libraries' progress callbacks: one task at a time, each with its
/// own length, unit and message.
pub struct Bar {
    pb: ProgressBar,
}

impl Bar {
    /// A bar on stderr, or a hidden one with `quiet`.
    pub fn new(quiet: bool) -> Self {
        let pb = if quiet {
            ProgressBar::hidden()
        } else {
            ProgressBar::new(0)
        };
        Self { pb }
    }

    fn begin(&self, what: &str, total: u64, bytes: bool, unit: &str) {
        // A step of unknown length is a spinner with the time elapsed.
        let template = if total == 0 {
            "{spinner} {msg} [{elapsed}]".to_string()
        } else if bytes {
            "{msg} [{bar:30}] {bytes}/{total_bytes} {binary_bytes_per_sec} [{elapsed} elapsed, eta {eta}]"
                .to_string()
        } else {
            format!(
                "{{msg}} [{{bar:30}}] {{human_pos}}/{{human_len}} {unit} {{per_sec}} [{{elapsed}} elapsed, eta {{eta}}]"
            )
        };
        if let Ok(style) = ProgressStyle::with_template(&template) {
            self.pb.set_style(style.progress_chars("=> "));
        }
        self.pb.reset();
        self.pb.set_length(total);
        self.pb.set_position(0);
        self.pb.set_message(what.to_string());
        if total == 0 {
            self.pb.enable_steady_tick(Duration::from_millis(120));
        } else {
            self.pb.disable_steady_tick();
        }
    }

    /// Removes the bar.
    pub fn clear(&self) {
        self.pb.finish_and_clear();
    }
}

/// A run that fails mid-way leaves no half-drawn bar above its error message.
impl Drop for Bar {
    fn drop(&mut self) {
        self.pb.finish_and_clear();
    }
}

impl tcomp_train::progress::Progress for Bar {
    fn start(&self, what: &str, total: u64, unit: tcomp_train::progress::Unit) {
        use tcomp_train::progress::Unit;
        match unit {
            Unit::Bytes => self.begin(what, total, true, ""),
            Unit::Rows => self.begin(what, total, false, "rows"),
            _ => self.begin(what, total, false, "iterations"),
        }
    }
    fn set(&self, done: u64) {
        self.pb.set_position(done);
    }
    fn finish(&self) {
        self.pb.finish_and_clear();
    }
}

impl tcomp_sim::progress::Progress for Bar {
    fn start(&mut self, what: &str, total: u64) {
        self.begin(what, total, false, "rows");
    }
    fn set(&mut self, done: u64) {
        self.pb.set_position(done);
    }
    fn finish(&mut self) {
        self.pb.finish_and_clear();
    }
}
