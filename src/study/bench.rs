//! `umbra bench`: the frame time of each method on one scene, measured as a benchmark should
//! be. The scene is loaded once; each method renders `warmup` frames that are not timed (page
//! faults, caches, the shadow maps' storage), then `runs` timed frames in the same process.
//! Each row gives the median, least and greatest time of the whole frame and of every phase
//! the pipeline reports, the row's own peak memory (where the program counts its heap,
//! [`HeapProbe`]), and how many cores other processes used meanwhile. Asked to (`undisturbed`), it waits for the other processes to leave
//! the machine quiet before each row and times a row again when they did not, as the peers'
//! harness in the benchmark suite does.

use crate::error::{Error, Result};
use crate::render::{RenderOptions, Rendered, Renderer};
use crate::scene::Scene;
use crate::shadow::ShadowMethod;
use crate::study::quiet::{self, Monitor};
use crate::visibility::VisibilityMethod;
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// What to measure.
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// The visibility stages (one row per visibility × shadow pair).
    pub visibility: Vec<VisibilityMethod>,
    /// The shadow stages, with their settings.
    pub shadows: Vec<ShadowMethod>,
    /// Untimed frames first.
    pub warmup: usize,
    /// Timed frames.
    pub runs: usize,
    /// See [`RenderOptions::back_face_cull`].
    pub back_face_cull: bool,
    /// The thread counts to render with (none: as many as the caller's pool has). With
    /// several, each method renders at each count in turn, an untimed frame then a timed
    /// one, so that whatever else the machine does meanwhile falls on all of them alike; the
    /// untimed frame keeps the switch of counts out of the times. Every row after the first
    /// count's gives its speed-up over it.
    pub threads: Vec<usize>,
    /// Before each row, wait (at most five minutes) until other processes use under a tenth
    /// of a core over two seconds and all cores run a fixed loop at once within 15% of one
    /// core alone; time a row again, up to three tries in all, when others used a quarter of
    /// a core or more while it ran, or the cores ran 15% slower together right after it.
    pub undisturbed: bool,
    /// How the program counts its heap, for each row's own peak memory (none: only the
    /// process's resident high-water mark is known, which after a large row stays high for
    /// every row after it).
    pub heap: Option<HeapProbe>,
}

/// A program's count of its heap (a counting global allocator). `bench` counts one frame a
/// row, the first (a warm-up where there is one, so that the timed frames pay nothing for
/// the count): the most bytes that frame had allocated at once, the scene (loaded before)
/// not included. The `umbra` binary counts its allocator's bytes this way.
#[derive(Debug, Clone, Copy)]
pub struct HeapProbe {
    /// Starts counting from zero (`true`) or stops (`false`).
    pub count: fn(bool),
    /// The most bytes allocated at once since counting started.
    pub peak_bytes: fn() -> u64,
}

/// Foreign cores under which the machine counts as quiet, over [`QUIET_WINDOW`].
const QUIET: f64 = 0.1;
/// How long the machine must stay quiet.
const QUIET_WINDOW: Duration = Duration::from_secs(2);
/// How long to wait for a quiet machine before timing anyway.
const QUIET_GIVE_UP: Duration = Duration::from_secs(300);
/// Foreign cores during a row at which it was disturbed.
const DISTURBED: f64 = 0.25;
/// How much slower all cores at once may run a fixed loop than one alone
/// ([`quiet::core_contention`]) before the machine counts as disturbed.
const CONTENDED: f64 = 1.15;
/// Tries per row, the first included.
const TRIES: usize = 3;

/// Median, least and greatest of a set of times, in milliseconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spread {
    /// The median.
    pub median_ms: f64,
    /// The least.
    pub min_ms: f64,
    /// The greatest.
    pub max_ms: f64,
}

impl Spread {
    pub(crate) fn of(v: Vec<f64>) -> Spread {
        let (min_ms, max_ms) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
        if v.is_empty() {
            return Spread { median_ms: 0.0, min_ms: 0.0, max_ms: 0.0 };
        }
        Spread { median_ms: median(v), min_ms, max_ms }
    }
}

/// The median of `v` (the upper of the two middle values for an even count; 0 for none).
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// One method's measurement.
#[derive(Debug, Clone, Serialize)]
pub struct BenchRow {
    /// The visibility stage.
    pub visibility: String,
    /// The shadow stage.
    pub shadows: String,
    /// The threads it rendered with.
    pub threads: usize,
    /// Timed frames.
    pub runs: usize,
    /// The whole frame, as the caller sees it (`render` called and returned).
    #[serde(flatten)]
    pub frame: Spread,
    /// With several thread counts: the first count's frame over this one's, the median over
    /// the runs of each run against the one rendered beside it.
    pub speedup: Option<f64>,
    /// With several thread counts: the first count's fastest frame over this one's fastest.
    /// Another process can only slow a frame, so the fastest frames are the nearest to an
    /// idle machine's ("best"): beside [`BenchRow::speedup`], it tells the engine's scaling
    /// from a neighbour's load when the two differ.
    pub speedup_best: Option<f64>,
    /// With several thread counts: the frame's serial fraction, the share of the first
    /// count's time that did not get faster with more threads, from Amdahl's law over the
    /// two counts' medians (`T_n / T_1 = s + (1 − s)·n₁/n` for the first count n₁, solved
    /// for `s`; clamped to [0, 1]). It predicts the speed-up at any count:
    /// `1 / (s + (1 − s)/n)` from one thread. An inference from two counts on a quiet
    /// machine, not a measurement of which code ran alone.
    pub serial_fraction: Option<f64>,
    /// The same, phase by phase (`phases`' names), with several thread counts.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub phase_serial: BTreeMap<String, f64>,
    /// Each phase the pipeline reports (`view`, `visibility`, `shadow_prepare`, `shading`,
    /// `reflections` where mirrors are seen).
    pub phases: BTreeMap<String, Spread>,
    /// The row's own peak: the most heap its first frame had allocated at once, the scene
    /// not included, in MB (`None` without a [`HeapProbe`]).
    pub peak_mb: Option<f64>,
    /// The process's peak resident memory after the row, in MB (0 where the system does
    /// not say): a high-water mark, so a row after a larger one shows the larger one's.
    pub peak_rss_mb: f64,
    /// What else the machine did while the row ran.
    #[serde(flatten)]
    pub disturbance: Disturbance,
}

/// What else the machine did while a row ran.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Disturbance {
    /// The cores other processes used on average while the kept try ran, warm-up included
    /// (`None` where the system does not say).
    pub foreign_cores: Option<f64>,
    /// With `undisturbed`, right after the kept try: how much slower the slowest core ran a
    /// fixed loop with all cores at once than one core alone (about 1 when all are free).
    pub contention: Option<f64>,
    /// How often the row was timed (more than once only when `undisturbed`).
    pub tries: usize,
}

/// One method measured: its frame and phases over the timed runs, and the last run.
pub struct Measured {
    /// The whole frame, as the caller sees it (`render` called and returned).
    pub frame: Spread,
    /// Every timed run's frame, in order.
    pub times_ms: Vec<f64>,
    /// Each phase the pipeline reports.
    pub phases: BTreeMap<String, Spread>,
    /// The last timed run's frame and statistics.
    pub last: Rendered,
    /// The most heap the first frame had allocated at once, where the heap was counted.
    pub peak_bytes: Option<u64>,
}

/// The measuring core of `bench`, `compare` and `scale`: `warmup` untimed renders, then
/// `runs` (at least one) timed renders of `scene` in this process, all through one
/// [`Renderer`], so that every frame after the first reuses the memory of the one before
/// (the times are the algorithms', not the system's page faults).
pub fn measure(scene: &Scene, opts: &RenderOptions, warmup: usize, runs: usize) -> Result<Measured> {
    let mut timing = Timing::default();
    for i in 0..warmup + runs.max(1) {
        timing.frame(scene, opts, i >= warmup)?;
    }
    timing.finish()
}

/// One method's frames, rendered through one [`Renderer`] and timed.
#[derive(Default)]
struct Timing {
    renderer: Renderer,
    times_ms: Vec<f64>,
    phases: BTreeMap<String, Vec<f64>>,
    peak_bytes: Option<u64>,
}

impl Timing {
    /// Renders one frame, and records it when `timed`.
    fn frame(&mut self, scene: &Scene, opts: &RenderOptions, timed: bool) -> Result<()> {
        let t = Instant::now();
        let out = self.renderer.render(scene, opts)?;
        if timed {
            self.times_ms.push(t.elapsed().as_secs_f64() * 1e3);
            for (k, ms) in out.stats.time_ms.steps() {
                self.phases.entry(k.to_string()).or_default().push(ms);
            }
        }
        Ok(())
    }

    /// The spreads of the timed frames, and the last frame.
    fn finish(self) -> Result<Measured> {
        let last = self.renderer.into_rendered().ok_or_else(|| Error::Internal("no timed run".into()))?;
        let phases = self.phases.into_iter().map(|(k, v)| (k, Spread::of(v))).collect();
        let (times_ms, peak_bytes) = (self.times_ms, self.peak_bytes);
        Ok(Measured { frame: Spread::of(times_ms.clone()), times_ms, phases, last, peak_bytes })
    }
}

/// Measures every visibility × shadow pair on `scene`, at each thread count; `progress` is
/// told each row as it starts.
pub fn bench(scene: &Scene, o: &BenchOptions, mut progress: impl FnMut(&str)) -> Result<Vec<BenchRow>> {
    if o.runs == 0 {
        return Err(Error::out_of_range("bench: timed runs", 0, "at least 1"));
    }
    let pools = pools(&o.threads)?;
    let mut rows = Vec::new();
    for &v in &o.visibility {
        for s in &o.shadows {
            progress(&format!("{v} + {s}"));
            let opts = RenderOptions {
                visibility: v,
                shadows: s.clone(),
                back_face_cull: o.back_face_cull,
                ..RenderOptions::default()
            };
            let (each, disturbance) = measure_undisturbed(scene, &opts, o, &pools, &mut progress)?;
            let (first, first_min) = (each[0].times_ms.clone(), each[0].frame.min_ms);
            let (first_phases, first_frame) = (each[0].phases.clone(), each[0].frame.median_ms);
            let n1 = pools[0].current_num_threads();
            for (m, pool) in each.into_iter().zip(&pools) {
                let peak_mb = m.peak_bytes.map(|b| b as f64 / (1024.0 * 1024.0));
                let several = pools.len() > 1;
                let speedup = several.then(|| paired_ratio(&first, &m.times_ms));
                let speedup_best = several.then(|| times_faster(first_min, m.frame.min_ms));
                let n = pool.current_num_threads();
                let serial = serial_fraction(first_frame, m.frame.median_ms, n1, n);
                let phase_serial = m
                    .phases
                    .iter()
                    .filter_map(|(k, sp)| {
                        let t1 = first_phases.get(k)?.median_ms;
                        Some((k.clone(), serial_fraction(t1, sp.median_ms, n1, n)?))
                    })
                    .collect();
                rows.push(BenchRow {
                    visibility: v.name().into(),
                    shadows: s.label(),
                    threads: pool.current_num_threads(),
                    runs: o.runs,
                    frame: m.frame,
                    speedup,
                    speedup_best,
                    serial_fraction: serial,
                    phase_serial,
                    phases: m.phases,
                    peak_mb,
                    peak_rss_mb: peak_rss_mb(),
                    disturbance,
                });
            }
        }
    }
    Ok(rows)
}

/// A pool per thread count, or one of the caller's size where none is given.
fn pools(threads: &[usize]) -> Result<Vec<rayon::ThreadPool>> {
    if threads.contains(&0) {
        return Err(Error::out_of_range("bench: threads", 0, "at least 1"));
    }
    let counts = if threads.is_empty() { vec![rayon::current_num_threads()] } else { threads.to_vec() };
    counts
        .into_iter()
        .map(|n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| Error::InvalidOption(format!("cannot start {n} threads: {e}")))
        })
        .collect()
}

/// The median over runs of `first[i] / other[i]`: how many times faster `other` ran than
/// `first`, each run against the one beside it in time.
fn paired_ratio(first: &[f64], other: &[f64]) -> f64 {
    median(first.iter().zip(other).map(|(&a, &b)| times_faster(a, b)).collect())
}

/// Amdahl's serial fraction from a time `t1` at `n1` threads and `tn` at `n` threads:
/// `tn / t1 = (s + (1 − s)/n) / (s + (1 − s)/n1)` solved for `s`, clamped to [0, 1]; `None`
/// for equal counts or times too small to tell.
pub fn serial_fraction(t1: f64, tn: f64, n1: usize, n: usize) -> Option<f64> {
    if n == n1 || t1 <= 1e-6 || tn <= 0.0 {
        return None;
    }
    let (r, a, b) = (tn / t1, 1.0 / n1 as f64, 1.0 / n as f64);
    let s = (b - r * a) / (r - r * a - 1.0 + b);
    s.is_finite().then(|| s.clamp(0.0, 1.0))
}

/// How many times faster a frame of `b` ms ran than one of `a` ms (a zero time read as a
/// nanosecond).
fn times_faster(a: f64, b: f64) -> f64 {
    a / b.max(1e-9)
}

/// One method measured at every pool's thread count, in turn frame by frame (warm-up frames
/// first), and the foreign cores and tries of the kept try: once, or as
/// [`BenchOptions::undisturbed`] says.
fn measure_undisturbed(
    scene: &Scene,
    opts: &RenderOptions,
    o: &BenchOptions,
    pools: &[rayon::ThreadPool],
    progress: &mut impl FnMut(&str),
) -> Result<(Vec<Measured>, Disturbance)> {
    let cores = pools.iter().map(|p| p.current_num_threads()).max().unwrap_or(1);
    let mut tries = 0;
    loop {
        tries += 1;
        if o.undisturbed && !wait_for_quiet(cores) {
            progress("the machine did not go quiet in five minutes; timing anyway");
        }
        let monitor = Monitor::start();
        let mut timings: Vec<Timing> = pools.iter().map(|_| Timing::default()).collect();
        for i in 0..o.warmup + o.runs {
            let timed = i >= o.warmup;
            // Where the count changes before each frame, an untimed frame first settles the
            // new count's threads, cores and caches, as a run of frames at one count would.
            let settle = usize::from(timed && pools.len() > 1);
            for (timing, pool) in timings.iter_mut().zip(pools) {
                pool.install(|| (0..settle).try_for_each(|_| timing.frame(scene, opts, false)))?;
                // Each count's first frame is counted on its own (see `HeapProbe`), the rest
                // are not: what the renderers of the other counts keep is not its own.
                let counted = o.heap.filter(|_| i == 0);
                if let Some(h) = counted {
                    (h.count)(true);
                }
                let frame = pool.install(|| timing.frame(scene, opts, timed));
                if let Some(h) = counted {
                    timing.peak_bytes = Some((h.peak_bytes)());
                    (h.count)(false);
                }
                frame?;
            }
        }
        let foreign = monitor.foreign_if_long();
        let contention = o.undisturbed.then(|| quiet::core_contention(cores));
        let each = timings.into_iter().map(Timing::finish).collect::<Result<Vec<_>>>()?;
        let disturbed = foreign.is_some_and(|f| f >= DISTURBED) || contention.is_some_and(|c| c >= CONTENDED);
        if !o.undisturbed || !disturbed || tries == TRIES {
            return Ok((each, Disturbance { foreign_cores: foreign, contention, tries }));
        }
        progress(&format!(
            "others used {:.2} cores meanwhile, and all cores ran {:.2}x slower than one; timing again",
            foreign.unwrap_or(0.0),
            contention.unwrap_or(1.0)
        ));
    }
}

/// Waits until other processes use under [`QUIET`] cores over [`QUIET_WINDOW`] and all
/// `cores` run as fast as one (under [`CONTENDED`]), for at most [`QUIET_GIVE_UP`];
/// whether they did.
fn wait_for_quiet(cores: usize) -> bool {
    let t0 = Instant::now();
    while t0.elapsed() < QUIET_GIVE_UP {
        if quiet::wait(QUIET, QUIET_WINDOW, QUIET_GIVE_UP.saturating_sub(t0.elapsed()))
            && quiet::core_contention(cores) < CONTENDED
        {
            return true;
        }
    }
    false
}

/// The peak resident set of this process in MB of 2²⁰ bytes (`VmHWM` in
/// `/proc/self/status`; 0 where there is no such file).
pub fn peak_rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0)
}

/// The rows as a readable table, at most 120 columns for the usual labels: one line per
/// method, the frame as `median (min–max)` and each phase's median in ms, the row's own peak
/// memory, and where they say something: the threads with the speed-up over the first count
/// (median of pairs, then fastest against fastest), and the cores others used. Every
/// phase's spread and the resident high-water mark are in `--json`.
pub fn table(rows: &[BenchRow]) -> String {
    // The phases in the pipeline's order, then any others by name.
    const ORDER: [&str; 6] = ["view", "visibility", "shadow_prepare", "shadow_walk", "shading", "reflections"];
    let mut phases: Vec<&str> = rows.iter().flat_map(|r| r.phases.keys().map(String::as_str)).collect();
    phases.sort_by_key(|p| (ORDER.iter().position(|o| o == p).unwrap_or(ORDER.len()), *p));
    phases.dedup();
    let short = |p: &str| match p {
        "visibility" => "visib.".to_string(),
        "shadow_prepare" => "prepare".to_string(),
        "shadow_walk" => "walk".to_string(),
        "reflections" => "mirrors".to_string(),
        other => other.to_string(),
    };
    let several = rows.iter().any(|r| r.speedup.is_some());
    // One visibility stage for every row: named once above the table, not on every row.
    let one_visibility = rows.first().map(|r| &r.visibility).filter(|v| rows.iter().all(|r| &r.visibility == *v));
    let others = rows.iter().any(|r| r.disturbance.foreign_cores.is_some());
    let method = if one_visibility.is_some() { "shadows" } else { "visibility + shadows" };
    let mut header: Vec<String> = vec![method.into(), "frame (min–max)".into()];
    header.extend(phases.iter().map(|p| short(p)));
    header.push("peak MB".into());
    if several {
        header.extend(["thr", "speed-up", "best", "serial"].map(String::from));
    }
    if others {
        header.push("others".into());
    }
    let ratio = |x: Option<f64>| x.map_or_else(|| "-".to_string(), |x| format!("{x:.2}"));
    let lines: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let f = &r.frame;
            let name =
                if one_visibility.is_some() { r.shadows.clone() } else { format!("{} + {}", r.visibility, r.shadows) };
            let mut cells = vec![name, format!("{:.1} ({:.1}–{:.1})", f.median_ms, f.min_ms, f.max_ms)];
            cells.extend(phases.iter().map(|p| r.phases.get(*p).map_or("-".into(), |s| format!("{:.1}", s.median_ms))));
            cells.push(r.peak_mb.map_or_else(|| format!("{:.0}*", r.peak_rss_mb), |m| format!("{m:.0}")));
            if several {
                let serial = r.serial_fraction.map_or("-".into(), |s| format!("{:.0}%", 100.0 * s));
                cells.extend([r.threads.to_string(), ratio(r.speedup), ratio(r.speedup_best), serial]);
            }
            if others {
                cells.push(r.disturbance.foreign_cores.map_or("-".into(), |c| format!("{c:.2}")));
            }
            cells
        })
        .collect();
    let widths: Vec<usize> = (0..header.len())
        .map(|c| std::iter::once(&header).chain(&lines).map(|l| l[c].chars().count()).max().unwrap_or(0))
        .collect();
    let line = |cells: &[String]| {
        let mut out = format!("{:<w$}", cells[0], w = widths[0]);
        for (c, w) in cells.iter().zip(&widths).skip(1) {
            out += &format!(" {c:>w$}", w = *w);
        }
        out + "\n"
    };
    let mut out = one_visibility.map_or_else(String::new, |v| format!("visibility: {v}\n"));
    out += &line(&header);
    for l in &lines {
        out += &line(l);
    }
    out += "times in ms: the frame's median (least–greatest), each phase's median (visib.: the visibility stage);\n";
    if several {
        out += "thr: threads; speed-up and best over the first count (paired, fastest); serial: Amdahl's serial fraction\n";
    }
    out += "--json has every spread, each phase's serial fraction and the resident high-water mark\n";
    if rows.iter().any(|r| r.peak_mb.is_none()) {
        out += "* the process's resident high-water mark: no heap count for this row\n";
    }
    out
}

#[cfg(test)]
mod tests {
    use super::serial_fraction;

    /// Amdahl's law read backwards: a frame that is 10% serial runs in 0.55 of its one-thread
    /// time at two threads and 0.15625 at sixteen; the fraction comes back from either pair.
    #[test]
    fn the_serial_fraction_is_amdahls_law_read_backwards() {
        let t = |s: f64, n: f64| s + (1.0 - s) / n;
        for s in [0.0, 0.02, 0.1, 0.5, 1.0] {
            let got = serial_fraction(100.0, 100.0 * t(s, 2.0), 1, 2).unwrap();
            assert!((got - s).abs() < 1e-12, "{s}: {got}");
            let got = serial_fraction(100.0 * t(s, 2.0), 100.0 * t(s, 16.0), 2, 16).unwrap();
            assert!((got - s).abs() < 1e-12, "{s} from 2 and 16: {got}");
        }
        assert_eq!(serial_fraction(100.0, 100.0, 2, 2), None);
    }
}
