//! How much of the machine other processes used while we measured, and waiting until they
//! leave it alone.
//!
//! On a shared machine another process now and then takes a core, which halves a two-thread
//! frame on two cores and leaves a one-thread frame as it was. A benchmark that does not see
//! this reports the neighbour's load as the engine's scaling. So [`Monitor`] measures the
//! *foreign cores* over a stretch of time: the CPU time the whole machine was busy, less this
//! process's own, over the wall time. [`wait`] waits for a stretch in which that stays small.
//!
//! Both counts come from Linux's `/proc` (`/proc/stat` for the machine, `/proc/self/stat` for
//! this process), in the same clock ticks, so a stretch shorter than a few ticks (10 ms each)
//! reads coarsely. Where `/proc` is missing, nothing is known and [`Monitor::foreign`] says so.

use std::time::{Duration, Instant};

/// Clock ticks per second of `/proc`'s CPU times (`USER_HZ`, 100 on every architecture Linux
/// runs umbra on).
const TICKS_PER_S: f64 = 100.0;

/// The shortest stretch whose foreign cores a report gives: 100 ticks (a shorter row read 0
/// to 3 cores on a 2-core machine for the same command).
pub(crate) const MIN_STRETCH: Duration = Duration::from_secs(1);

/// Foreign cores measured from a point in time on.
pub(crate) struct Monitor {
    start: Instant,
    ticks: Option<(u64, u64)>,
}

impl Monitor {
    /// The foreign cores where the stretch so far is [`MIN_STRETCH`] or longer; `None` for
    /// a shorter one, whose figure is noise.
    pub(crate) fn foreign_if_long(&self) -> Option<f64> {
        (self.start.elapsed() >= MIN_STRETCH).then(|| self.foreign()).flatten()
    }

    /// Starts measuring now.
    pub(crate) fn start() -> Monitor {
        Monitor { start: Instant::now(), ticks: ticks() }
    }

    /// The cores other processes used on average since [`Monitor::start`], never below 0;
    /// `None` where the system does not say.
    pub(crate) fn foreign(&self) -> Option<f64> {
        let ((busy0, own0), (busy1, own1)) = (self.ticks?, ticks()?);
        Some(foreign_cores(busy1.saturating_sub(busy0), own1.saturating_sub(own0), self.start.elapsed()))
    }
}

/// The cores others used over `wall`, in which the machine was busy `busy` ticks and this
/// process `own` of them; never below 0, and a stretch shorter than a tick counts as one.
fn foreign_cores(busy: u64, own: u64, wall: Duration) -> f64 {
    let wall = wall.as_secs_f64().max(1.0 / TICKS_PER_S);
    (busy.saturating_sub(own) as f64 / TICKS_PER_S / wall).max(0.0)
}

/// Waits until other processes used under `limit` cores over one `window`, or until
/// `give_up` has passed; whether the machine went quiet. Returns at once, `true`, where the
/// system does not say.
pub(crate) fn wait(limit: f64, window: Duration, give_up: Duration) -> bool {
    let t0 = Instant::now();
    while t0.elapsed() < give_up {
        let m = Monitor::start();
        std::thread::sleep(window);
        match m.foreign() {
            None => return true,
            Some(f) if f < limit => return true,
            Some(_) => {}
        }
    }
    false
}

/// How much slower the slowest of `threads` threads runs a fixed loop when all run it at
/// once than the fastest runs it alone (the least of three tries each): about 1 when every
/// core is free. A process outside this machine's view (another machine's work on the same
/// physical cores, behind a virtual machine) shows here and not in [`Monitor::foreign`]:
/// it slows some cores and not others, so a frame on all threads slows and one on a single
/// thread may not.
pub(crate) fn core_contention(threads: usize) -> f64 {
    let threads = threads.max(1);
    let alone = (0..3).map(|_| probe()).min().unwrap_or_default();
    let together = (0..3)
        .map(|_| {
            let start = std::sync::Barrier::new(threads);
            std::thread::scope(|s| {
                let runs: Vec<_> = (0..threads).map(|_| s.spawn(|| (start.wait(), probe()).1)).collect();
                runs.into_iter().map(|r| r.join().unwrap_or(Duration::MAX)).max().unwrap_or_default()
            })
        })
        .min()
        .unwrap_or_default();
    together.as_secs_f64() / alone.as_secs_f64().max(1e-9)
}

/// The time of a fixed loop of arithmetic and reads from a small table (a few ms).
fn probe() -> Duration {
    let table: Vec<u64> = (0..4096u64).map(|i| i.wrapping_mul(0x9E37_79B9_7F4A_7C15)).collect();
    let t = Instant::now();
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    for _ in 0..2_000_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x = x.wrapping_add(table[(x & 4095) as usize]);
    }
    std::hint::black_box(x);
    t.elapsed()
}

/// The machine's busy ticks and this process's own, now.
fn ticks() -> Option<(u64, u64)> {
    let machine = std::fs::read_to_string("/proc/stat").ok()?;
    let own = std::fs::read_to_string("/proc/self/stat").ok()?;
    Some((busy_ticks(&machine)?, own_ticks(&own)?))
}

/// The busy ticks of all cores in `/proc/stat`'s text: its `cpu` line's user, nice, system,
/// irq, softirq and steal (idle and iowait left out; guest time is already in user).
fn busy_ticks(stat: &str) -> Option<u64> {
    let line = stat.lines().find(|l| l.starts_with("cpu "))?;
    let f: Vec<u64> = line.split_whitespace().skip(1).take(8).map(|x| x.parse().ok()).collect::<Option<_>>()?;
    let [user, nice, system, _idle, _iowait, irq, softirq, steal] = f[..] else { return None };
    Some(user + nice + system + irq + softirq + steal)
}

/// The ticks this process ran, user and system, from `/proc/self/stat`'s text: its 14th and
/// 15th fields, counted after the command name, which is in brackets and may hold spaces.
fn own_ticks(stat: &str) -> Option<u64> {
    let rest = &stat[stat.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // After the name come the state (field 3), ..., utime (14) and stime (15).
    let (utime, stime) = (f.get(11)?.parse::<u64>().ok()?, f.get(12)?.parse::<u64>().ok()?);
    Some(utime + stime)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_machine_is_busy_in_user_nice_system_irq_softirq_and_steal() {
        let stat = "cpu  10 20 30 4000 500 6 7 8 9 0\ncpu0 5 10 15 2000 250 3 3 4 0 0\nintr 1 2\n";
        assert_eq!(busy_ticks(stat), Some(10 + 20 + 30 + 6 + 7 + 8));
        assert_eq!(busy_ticks("cpu0 1 2 3 4 5 6 7 8\n"), None, "only the all-cores line counts");
        assert_eq!(busy_ticks("cpu  1 2 x 4 5 6 7 8\n"), None);
        assert_eq!(busy_ticks("cpu  1 2 3\n"), None);
    }

    #[test]
    fn own_time_is_read_after_the_bracketed_name_even_with_spaces_and_brackets_in_it() {
        let fields = "S 1 2 3 4 5 6 7 8 9 10 250 31 0 0 20 0 3 0 100";
        assert_eq!(own_ticks(&format!("4242 (umbra) {fields}")), Some(281));
        assert_eq!(own_ticks(&format!("4242 (a (b) c) {fields}")), Some(281));
        assert_eq!(own_ticks("4242 (umbra) S 1 2"), None);
    }

    #[test]
    fn foreign_cores_are_the_busy_ticks_not_ours_over_the_wall_time() {
        // Two seconds; the machine busy 300 ticks, 100 of them ours: one core of others.
        assert_eq!(foreign_cores(300, 100, Duration::from_secs(2)), 1.0);
        assert_eq!(foreign_cores(100, 100, Duration::from_secs(2)), 0.0);
        // Ticks are counted on their own clock, so ours can read above the machine's.
        assert_eq!(foreign_cores(99, 101, Duration::from_secs(2)), 0.0);
        // A stretch shorter than a tick is read as one tick.
        assert_eq!(foreign_cores(2, 1, Duration::ZERO), 1.0);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn on_linux_the_monitor_reads_proc() {
        let m = Monitor::start();
        std::thread::sleep(Duration::from_millis(30));
        assert!(m.foreign().is_some_and(|f| f.is_finite() && f >= 0.0));
    }

    #[test]
    fn the_contention_probe_gives_a_positive_finite_ratio() {
        // Only the shape of the answer is tested: its value is the machine's noise (a bound
        // on it failed under a loaded machine, as any timed test would).
        for threads in [1, 2] {
            let ratio = core_contention(threads);
            assert!(ratio.is_finite() && ratio > 0.0, "{threads} thread(s): {ratio}");
        }
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn waiting_ends_when_the_machine_is_quiet_or_the_time_is_up() {
        let (window, give_up) = (Duration::from_millis(20), Duration::from_millis(100));
        assert!(wait(f64::INFINITY, window, give_up), "any load is under no limit");
        let t = Instant::now();
        assert!(!wait(-1.0, window, give_up), "no load is under a negative limit");
        assert!(t.elapsed() >= give_up);
    }
}
