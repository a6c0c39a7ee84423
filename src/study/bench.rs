//! `umbra bench`: the frame time of each method on one scene, measured as a benchmark should
//! be. The scene is loaded once; each method renders `warmup` frames that are not timed (page
//! faults, caches, the shadow maps' storage), then `runs` timed frames in the same process.
//! Each row gives the median, least and greatest time of the whole frame and of every phase
//! the pipeline reports, and the process's peak resident memory so far.

use crate::error::{Error, Result};
use crate::render::{RenderOptions, Rendered, Renderer};
use crate::scene::Scene;
use crate::shadow::ShadowMethod;
use crate::visibility::VisibilityMethod;
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

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
}

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
    pub(crate) fn of(mut v: Vec<f64>) -> Spread {
        v.sort_by(f64::total_cmp);
        let median_ms = if v.is_empty() { 0.0 } else { v[v.len() / 2] };
        Spread { median_ms, min_ms: v.first().copied().unwrap_or(0.0), max_ms: v.last().copied().unwrap_or(0.0) }
    }
}

/// One method's measurement.
#[derive(Debug, Clone, Serialize)]
pub struct BenchRow {
    /// The visibility stage.
    pub visibility: String,
    /// The shadow stage.
    pub shadows: String,
    /// Timed frames.
    pub runs: usize,
    /// The whole frame, as the caller sees it (`render` called and returned).
    #[serde(flatten)]
    pub frame: Spread,
    /// Each phase the pipeline reports (`view`, `visibility`, `shadow_prepare`, `shading`,
    /// `reflections` where mirrors are seen).
    pub phases: BTreeMap<String, Spread>,
    /// The process's peak resident memory after the row, in MB (0 where the system does
    /// not say).
    pub peak_rss_mb: f64,
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
}

/// The measuring core of `bench`, `compare` and `scale`: `warmup` untimed renders, then
/// `runs` (at least one) timed renders of `scene` in this process, all through one
/// [`Renderer`], so that every frame after the first reuses the memory of the one before
/// (the times are the algorithms', not the system's page faults).
pub fn measure(scene: &Scene, opts: &RenderOptions, warmup: usize, runs: usize) -> Result<Measured> {
    let mut renderer = Renderer::new();
    for _ in 0..warmup {
        renderer.render(scene, opts)?;
    }
    let (mut times_ms, mut phases) = (Vec::new(), BTreeMap::<String, Vec<f64>>::new());
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let out = renderer.render(scene, opts)?;
        times_ms.push(t.elapsed().as_secs_f64() * 1e3);
        for (k, ms) in out.stats.time_ms.iter().filter(|(k, _)| **k != "total") {
            phases.entry(k.to_string()).or_default().push(*ms);
        }
    }
    let last = renderer.into_rendered().ok_or_else(|| Error::Internal("no timed run".into()))?;
    let phases = phases.into_iter().map(|(k, v)| (k, Spread::of(v))).collect();
    Ok(Measured { frame: Spread::of(times_ms.clone()), times_ms, phases, last })
}

/// Measures every visibility × shadow pair on `scene`; `progress` is told each row as it
/// starts.
pub fn bench(scene: &Scene, o: &BenchOptions, mut progress: impl FnMut(&str)) -> Result<Vec<BenchRow>> {
    if o.runs == 0 {
        return Err(Error::InvalidOption("bench needs at least one timed run".into()));
    }
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
            let m = measure(scene, &opts, o.warmup, o.runs)?;
            rows.push(BenchRow {
                visibility: v.name().into(),
                shadows: s.name().into(),
                runs: o.runs,
                frame: m.frame,
                phases: m.phases,
                peak_rss_mb: peak_rss_mb(),
            });
        }
    }
    Ok(rows)
}

/// The peak resident set of this process in MB (`VmHWM` in `/proc/self/status`; 0 where
/// there is no such file).
fn peak_rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0)
}

/// The rows as a readable table: one line per method, the frame and each phase as
/// `median (min–max)`.
pub fn table(rows: &[BenchRow]) -> String {
    // The phases in the pipeline's order, then any others by name.
    const ORDER: [&str; 6] = ["view", "visibility", "shadow_prepare", "shadow_walk", "shading", "reflections"];
    let mut phases: Vec<&str> = rows.iter().flat_map(|r| r.phases.keys().map(String::as_str)).collect();
    phases.sort_by_key(|p| (ORDER.iter().position(|o| o == p).unwrap_or(ORDER.len()), *p));
    phases.dedup();
    let cell = |s: &Spread| format!("{:.1} ({:.1}–{:.1})", s.median_ms, s.min_ms, s.max_ms);
    let mut out = format!("{:<10} {:<26} {:>24}", "visibility", "shadows", "frame ms: median (min–max)");
    for p in &phases {
        out += &format!(" {:>22}", p);
    }
    out += &format!(" {:>9}\n", "peak MB");
    for r in rows {
        out += &format!("{:<10} {:<26} {:>24}", r.visibility, r.shadows, cell(&r.frame));
        for p in &phases {
            out += &format!(" {:>22}", r.phases.get(*p).map_or_else(|| "-".to_string(), cell));
        }
        out += &format!(" {:>9.0}\n", r.peak_rss_mb);
    }
    out
}
