//! Progress of long work, reported to the program that asked for it through a callback. The
//! library draws nothing; the command line draws a bar on a terminal.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Where a piece of work is.
#[derive(Debug, Clone, Copy)]
pub struct Progress<'a> {
    /// What is being done now ("visibility (scanline)", "zbuffer + crow").
    pub phase: &'a str,
    /// Steps done.
    pub done: u64,
    /// Steps in all.
    pub total: u64,
    /// What a step is ("lines" of a frame, "renders" of a comparison).
    pub unit: &'a str,
}

/// A program's progress callback: called when a phase begins and as steps are done, from
/// any thread.
pub type ProgressFn = dyn Fn(Progress<'_>) + Send + Sync;

/// Reports one piece of work to a callback, when there is one.
pub(crate) struct Reporter<'f> {
    to: Option<&'f (dyn Fn(Progress<'_>) + Send + Sync + 'f)>,
    phase: Mutex<String>,
    done: AtomicU64,
    total: u64,
    unit: &'static str,
}

impl<'f> Reporter<'f> {
    /// Work of `total` steps of `unit`, reported to `to`.
    pub(crate) fn new(
        to: Option<&'f (dyn Fn(Progress<'_>) + Send + Sync + 'f)>,
        total: u64,
        unit: &'static str,
    ) -> Self {
        Reporter { to, phase: Mutex::new(String::new()), done: AtomicU64::new(0), total, unit }
    }

    /// A phase of the work begins.
    pub(crate) fn phase(&self, name: impl Into<String>) {
        let Some(to) = self.to else { return };
        let name = name.into();
        to(Progress { phase: &name, done: self.done.load(Ordering::Relaxed), total: self.total, unit: self.unit });
        if let Ok(mut phase) = self.phase.lock() {
            *phase = name;
        }
    }

    /// A phase that does the work's steps over again begins, from none done.
    pub(crate) fn again(&self, name: impl Into<String>) {
        self.done.store(0, Ordering::Relaxed);
        self.phase(name);
    }

    /// `n` more steps done.
    pub(crate) fn advance(&self, n: u64) {
        let Some(to) = self.to else { return };
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        if let Ok(phase) = self.phase.lock() {
            to(Progress { phase: &phase, done, total: self.total, unit: self.unit });
        }
    }
}
