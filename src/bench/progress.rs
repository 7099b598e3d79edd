//! Progress bar on stderr (indicatif): current data set and structure, ETA.
//! Hidden with `--quiet` or when stderr is not a terminal.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::{IsTerminal, Write};

pub struct Progress {
    bar: ProgressBar,
}

impl Progress {
    pub fn new(total: u64, quiet: bool) -> Self {
        let bar = ProgressBar::new(total);
        if quiet || !std::io::stderr().is_terminal() {
            bar.set_draw_target(ProgressDrawTarget::hidden());
        }
        let style = ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} ETA {eta} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        bar.set_style(style);
        Progress { bar }
    }

    pub fn at(&self, what: &str) {
        self.bar.set_message(what.to_string());
    }

    /// More work than planned (a warm-up that needed more runs).
    pub fn grow(&self, n: u64) {
        self.bar.inc_length(n);
    }

    pub fn step(&self, n: u64) {
        self.bar.inc(n);
    }

    /// Prints a `note:` line above the bar (or plainly when hidden).
    pub fn note(&self, line: &str) {
        if self.bar.is_hidden() {
            // Dropped where stderr cannot take it, never a panic.
            let _ = writeln!(std::io::stderr(), "note: {line}");
        } else {
            self.bar.println(format!("note: {line}"));
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
