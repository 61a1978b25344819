//! Progress on standard error for work that takes over a second: a spinner for one long step
//! (loading, uploading) and a bar for counted steps (a benchmark's rows). Drawn only when
//! standard error is a terminal, so pipes and logs see nothing of it.

use std::io::IsTerminal;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How long work runs before its progress is shown.
const SHOW_AFTER: Duration = Duration::from_secs(1);

fn shown_on_stderr() -> bool {
    std::io::stderr().is_terminal()
}

/// Runs `work` with a spinner saying `message` that appears if it takes over a second.
pub fn spin<T>(message: &str, work: impl FnOnce() -> T) -> T {
    if !shown_on_stderr() {
        return work();
    }
    let spinner = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
    spinner.set_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    spinner.set_message(message.to_owned());
    let (done, finished) = mpsc::channel::<()>();
    let shower = {
        let spinner = spinner.clone();
        std::thread::spawn(move || {
            if finished.recv_timeout(SHOW_AFTER).is_err() {
                spinner.set_draw_target(ProgressDrawTarget::stderr());
                spinner.enable_steady_tick(Duration::from_millis(120));
            }
        })
    };
    let result = work();
    let _ = done.send(());
    let _ = shower.join();
    spinner.finish_and_clear();
    result
}

/// A bar over `total` steps that appears once the work has run for over a second.
pub struct Steps {
    bar: ProgressBar,
    started: Instant,
    visible: bool,
}

impl Steps {
    /// A bar for `total` steps of `what`.
    pub fn new(total: u64, what: &str) -> Self {
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template("{prefix} [{bar:20}] {pos}/{len} {msg} ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_prefix(what.to_owned());
        Self {
            bar,
            started: Instant::now(),
            visible: false,
        }
    }

    /// Says which step runs now.
    pub fn start(&mut self, step: &str) {
        self.reveal_if_slow();
        self.bar.set_message(step.to_owned());
    }

    /// Counts a step as done.
    pub fn done(&mut self) {
        self.bar.inc(1);
        self.reveal_if_slow();
    }

    /// Prints `line` on standard output without tearing the bar.
    pub fn println(&self, line: &str) {
        if self.visible {
            self.bar.suspend(|| println!("{line}"));
        } else {
            println!("{line}");
        }
    }

    fn reveal_if_slow(&mut self) {
        if !self.visible && self.started.elapsed() >= SHOW_AFTER && shown_on_stderr() {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.visible = true;
        }
    }
}

impl Drop for Steps {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
