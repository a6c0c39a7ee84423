//! Progress bars on standard error for long work, drawn with `indicatif` when the `cli`
//! feature is on (the default) and only on a terminal; without the feature they draw nothing,
//! so a library build needs no terminal crate.

/// A bar of `total` steps of `unit` that appears after a second of work, on a terminal.
pub(crate) struct Bar {
    #[cfg(feature = "cli")]
    bar: Option<indicatif::ProgressBar>,
    #[cfg(feature = "cli")]
    template: &'static str,
    enabled: bool,
    start: std::time::Instant,
    done: u64,
    total: u64,
    message: String,
}

impl Bar {
    /// A bar for `total` steps; `template` is indicatif's (for example
    /// `"{msg} {bar:40} {pos}/{len} lines {elapsed}"`).
    pub(crate) fn new(enabled: bool, total: u64, #[allow(unused_variables)] template: &'static str) -> Self {
        use std::io::IsTerminal;
        Bar {
            #[cfg(feature = "cli")]
            bar: None,
            #[cfg(feature = "cli")]
            template,
            enabled: enabled && std::io::stderr().is_terminal(),
            start: std::time::Instant::now(),
            done: 0,
            total,
            message: String::new(),
        }
    }

    /// What is being done now.
    pub(crate) fn set_message(&mut self, message: impl Into<String>) {
        self.message = message.into();
        #[cfg(feature = "cli")]
        if let Some(bar) = &self.bar {
            bar.set_message(self.message.clone());
        }
    }

    /// A phase of the work begins: the bar shows its name and, from now on, ticks on its own
    /// (so a long phase with no steps, such as a shadow stage's preparation, is not silent).
    pub(crate) fn phase(&mut self, name: impl Into<String>) {
        self.set_message(name);
        #[cfg(feature = "cli")]
        if self.bar.is_none() && self.enabled {
            let target = indicatif::ProgressDrawTarget::stderr();
            let bar = indicatif::ProgressBar::with_draw_target(Some(self.total), target);
            if let Ok(style) = indicatif::ProgressStyle::with_template(self.template) {
                bar.set_style(style);
            }
            bar.set_message(self.message.clone());
            bar.enable_steady_tick(std::time::Duration::from_millis(500));
            self.bar = Some(bar);
        }
    }

    /// `n` more steps done.
    pub(crate) fn advance(&mut self, n: u64) {
        self.done += n;
        #[cfg(feature = "cli")]
        {
            let due = self.start.elapsed() > std::time::Duration::from_secs(1);
            if self.bar.is_none() && self.enabled && due {
                let target = indicatif::ProgressDrawTarget::stderr();
                let bar = indicatif::ProgressBar::with_draw_target(Some(self.total), target);
                if let Ok(style) = indicatif::ProgressStyle::with_template(self.template) {
                    bar.set_style(style);
                }
                bar.set_message(self.message.clone());
                self.bar = Some(bar);
            }
            if let Some(bar) = &self.bar {
                // Once steps are being done, their rate gives an estimate of what is left.
                if bar.position() == 0 && self.done > 0 {
                    let estimate = format!("{}, about {{eta}} left", self.template);
                    if let Ok(style) = indicatif::ProgressStyle::with_template(&estimate) {
                        bar.set_style(style);
                    }
                }
                bar.set_position(self.done);
            }
        }
        #[cfg(not(feature = "cli"))]
        let _ = (self.enabled, self.start, self.total);
    }

    /// Clears the bar.
    pub(crate) fn finish(&self) {
        #[cfg(feature = "cli")]
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
