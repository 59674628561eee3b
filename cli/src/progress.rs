//! Progress of long commands: an indicatif bar on a terminal; elsewhere (a CI log, a pipe)
//! plain lines `label: k of N done, elapsed, about T left`, at most one per
//! [`PLAIN_EVERY_S`] seconds and always the last, so a log is never silent until the end.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// Seconds between plain progress lines.
pub const PLAIN_EVERY_S: f64 = 10.0;

/// A progress report over `total` steps.
pub struct Progress {
    label: String,
    total: u64,
    done: AtomicU64,
    start: Instant,
    bar: Option<indicatif::ProgressBar>,
    /// Elapsed seconds at the last plain line.
    last: Mutex<f64>,
    /// The caller prints its own line per step (with [`Progress::status`]).
    quiet: bool,
}

impl Progress {
    /// A bar on a terminal, plain lines otherwise.
    pub fn new(label: &str, total: u64) -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = indicatif::ProgressBar::new(total);
            bar.set_style(
                indicatif::ProgressStyle::with_template(&format!(
                    "{{spinner}} {label} [{{bar:40}}] {{pos}}/{{len}} {{elapsed}} eta {{eta}}"
                ))
                .expect("valid template")
                .progress_chars("=> "),
            );
            bar
        });
        Self {
            bar,
            ..Self::plain(label, total)
        }
    }

    /// A counter for a caller that prints one line per step itself, with [`Progress::status`].
    pub fn counter(label: &str, total: u64) -> Self {
        Self {
            quiet: true,
            ..Self::plain(label, total)
        }
    }

    /// Plain lines, whatever stderr is.
    fn plain(label: &str, total: u64) -> Self {
        Self {
            label: label.to_string(),
            total,
            done: AtomicU64::new(0),
            start: Instant::now(),
            bar: None,
            last: Mutex::new(f64::NEG_INFINITY),
            quiet: false,
        }
    }

    /// `k of N done, elapsed, about T left` (the estimate from the mean time per step so far).
    pub fn status(&self) -> String {
        let done = self.done.load(Ordering::Relaxed);
        let elapsed = self.start.elapsed().as_secs_f64();
        let left = if done > 0 && done < self.total {
            format!(
                ", about {:.0} s left",
                elapsed / done as f64 * (self.total - done) as f64
            )
        } else {
            String::new()
        };
        format!("{done} of {} done, {elapsed:.0} s{left}", self.total)
    }

    /// Sets the steps done.
    pub fn set(&self, done: u64) {
        self.done.store(done.min(self.total), Ordering::Relaxed);
        self.report();
    }

    /// One more step done.
    pub fn inc(&self) {
        self.done.fetch_add(1, Ordering::Relaxed);
        self.report();
    }

    fn report(&self) {
        let done = self.done.load(Ordering::Relaxed);
        match &self.bar {
            Some(bar) => bar.set_position(done),
            None if self.quiet => {}
            None => {
                let now = self.start.elapsed().as_secs_f64();
                let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
                if done >= self.total || now - *last >= PLAIN_EVERY_S {
                    *last = now;
                    eprintln!("{}: {}", self.label, self.status());
                }
            }
        }
    }

    /// Clears the bar (plain lines stay).
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
