//! The command line's progress bar: the library's progress reports, drawn with `indicatif`
//! on standard error when it is a terminal, after a second of work.

use std::sync::Mutex;
use std::time::{Duration, Instant};
use umbra::Progress;

/// A bar that appears after a second of work, on a terminal. Feed it the library's reports
/// with [`TerminalBar::report`]; it clears itself when dropped.
pub struct TerminalBar {
    state: Mutex<State>,
    template: &'static str,
    enabled: bool,
    start: Instant,
}

#[derive(Default)]
struct State {
    bar: Option<indicatif::ProgressBar>,
    phase: String,
    done: u64,
}

impl TerminalBar {
    /// A bar drawn with indicatif's `template` (for example
    /// `"{msg} {bar:40} {pos}/{len} lines {elapsed}"`).
    pub fn new(template: &'static str) -> TerminalBar {
        use std::io::IsTerminal;
        TerminalBar {
            state: Mutex::default(),
            template,
            enabled: std::io::stderr().is_terminal(),
            start: Instant::now(),
        }
    }

    /// Shows one report. A new phase shows its name and starts the bar ticking on its own
    /// (so a long phase with no steps, such as a shadow stage's preparation, is not silent);
    /// once steps are being done, their rate gives an estimate of what is left.
    pub fn report(&self, p: Progress<'_>) {
        if !self.enabled {
            return;
        }
        let Ok(mut s) = self.state.lock() else { return };
        let new_phase = s.phase != p.phase;
        let due = self.start.elapsed() > Duration::from_secs(1);
        if s.bar.is_none() && (new_phase || due) {
            let bar = indicatif::ProgressBar::with_draw_target(Some(p.total), indicatif::ProgressDrawTarget::stderr());
            if let Ok(style) = indicatif::ProgressStyle::with_template(self.template) {
                bar.set_style(style);
            }
            bar.enable_steady_tick(Duration::from_millis(500));
            s.bar = Some(bar);
        }
        let first_steps = s.done == 0 && p.done > 0;
        if let Some(bar) = &s.bar {
            if new_phase {
                bar.set_message(p.phase.to_owned());
            }
            if first_steps {
                let estimate = format!("{}, about {{eta}} left", self.template);
                if let Ok(style) = indicatif::ProgressStyle::with_template(&estimate) {
                    bar.set_style(style);
                }
            }
            bar.set_length(p.total);
            bar.set_position(p.done);
        }
        if new_phase {
            s.phase = p.phase.to_owned();
        }
        s.done = p.done;
    }
}

impl TerminalBar {
    /// Clears the bar (the work is done).
    pub fn finish(&self) {
        if let Ok(mut s) = self.state.lock() {
            if let Some(bar) = s.bar.take() {
                bar.finish_and_clear();
            }
        }
    }
}

impl Drop for TerminalBar {
    fn drop(&mut self) {
        self.finish();
    }
}
