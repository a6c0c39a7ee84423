//! Visibility stages: which polygon is seen at each pixel centre. Every stage hands on the
//! same thing, runs of equal polygon per scanline, so every shadow stage works behind any of
//! them and they can be compared run for run.

mod ray_cast;
mod scanline;
mod zbuffer;

use ray_cast::RayCastVisibility;
pub(crate) use scanline::ScanlineVisibility;
pub use scanline::SpanRecord;
use zbuffer::ZBufferVisibility;

use crate::pool::Pools;
use crate::scene::Scene;
use crate::stats::Counters;
use crate::view::{Screen, View};
use std::ops::Range;

/// A run of pixels `x0..x1` on one scanline that all see scene polygon `poly`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Run {
    /// First pixel.
    pub x0: u32,
    /// One past the last pixel.
    pub x1: u32,
    /// Index into [`Scene::polygons`].
    pub poly: u32,
}

/// A prepared visibility stage.
pub(crate) trait Visibility: Sync {
    /// Walks `lines` in increasing order, calling `f(line, runs)` with each line's runs in
    /// increasing x (lines with no runs included). Several bands may be walked at once.
    fn walk(&self, lines: Range<u32>, counters: &mut Counters, f: &mut dyn FnMut(u32, &[Run]));

    /// Adds to `out` (one entry per pixel of `lines`, row-major) how many times each pixel's
    /// span was split; only the scanline stage splits spans.
    fn span_splits(&self, _lines: Range<u32>, _out: &mut [u16]) {}
}

/// The visibility methods, chosen by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum VisibilityMethod {
    /// Watkins' scanline algorithm with edge and active-edge tables.
    Scanline,
    /// Catmull's depth buffer.
    ZBuffer,
    /// One ray per pixel centre (the reference).
    RayCast,
}

impl VisibilityMethod {
    /// Every method.
    pub const ALL: [VisibilityMethod; 3] =
        [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer, VisibilityMethod::RayCast];

    /// The method's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            VisibilityMethod::Scanline => "scanline",
            VisibilityMethod::ZBuffer => "zbuffer",
            VisibilityMethod::RayCast => "ray-cast",
        }
    }

    /// Prepares the stage for a view of `scene`; `screen` are the scene's screen polygons;
    /// frame-sized buffers come from `pools`.
    pub(crate) fn prepare<'a>(
        self,
        scene: &'a Scene,
        view: &'a View,
        screen: &'a Screen,
        pools: &Pools,
        counters: &mut Counters,
    ) -> Box<dyn Visibility + 'a> {
        match self {
            VisibilityMethod::Scanline => Box::new(ScanlineVisibility::new(scene, screen, view, pools, counters)),
            VisibilityMethod::ZBuffer => Box::new(ZBufferVisibility::new(screen, view, pools, counters)),
            VisibilityMethod::RayCast => Box::new(RayCastVisibility::new(scene, view)),
        }
    }
}

crate::error::named!(VisibilityMethod, "visibility method");

/// The visible runs of every line of a frame: what every visibility stage hands on.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FrameRuns {
    /// `lines[y]`: the runs of line `y` in increasing x.
    pub lines: Vec<Vec<Run>>,
}

impl FrameRuns {
    /// `visible[i]`: whether scene polygon `i` is seen at some pixel (of `n` polygons),
    /// marked by all threads, line by line.
    pub fn visible(&self, n: usize) -> Vec<bool> {
        use rayon::prelude::*;
        crate::pieces::marked(n, self.lines.par_iter().flat_map_iter(|line| line.iter().map(|r| r.poly as usize)))
    }

    /// Number of runs.
    pub fn count(&self) -> usize {
        self.lines.iter().map(Vec::len).sum()
    }
}

/// Walks every line of a prepared stage in parallel bands and keeps the runs.
pub(crate) fn resolve(vis: &dyn Visibility, height: u32, counters: &mut Counters) -> FrameRuns {
    use rayon::prelude::*;
    let band = crate::scan::band_height(height);
    let bands: Vec<(Vec<Vec<Run>>, Counters)> = (0..height.div_ceil(band))
        .into_par_iter()
        .map(|b| {
            let mut c = Counters::default();
            let mut lines = Vec::new();
            vis.walk(b * band..((b + 1) * band).min(height), &mut c, &mut |_, r| lines.push(r.to_vec()));
            (lines, c)
        })
        .collect();
    let mut runs = FrameRuns { lines: Vec::with_capacity(height as usize) };
    for (lines, c) in bands {
        runs.lines.extend(lines);
        counters.merge(&c);
    }
    counters.add(crate::stats::Counter::Runs, runs.count() as u64);
    runs
}

/// Runs one visibility stage alone over a whole frame of `scene`: projects, prepares and
/// resolves every line, as the renderer does (for benchmarks and studies).
pub fn resolve_frame(scene: &Scene, method: VisibilityMethod) -> (FrameRuns, Counters) {
    let view = View::new(&scene.camera);
    let screen = view.screen_polygons(scene);
    let mut counters = Counters::default();
    let vis = method.prepare(scene, &view, &screen, &Pools::default(), &mut counters);
    let runs = resolve(&*vis, view.height, &mut counters);
    (runs, counters)
}

/// Appends `x0..x1` seeing `poly` to `runs`, merging it with the last run when they join.
#[inline]
pub(crate) fn push_run(runs: &mut Vec<Run>, x0: u32, x1: u32, poly: u32) {
    if let Some(last) = runs.last_mut() {
        if last.poly == poly && last.x1 == x0 {
            last.x1 = x1;
            return;
        }
    }
    runs.push(Run { x0, x1, poly });
}

/// Turns one line of per-pixel polygon indices (`u32::MAX` for none) into runs.
pub(crate) fn runs_of_row(row: &[u32], runs: &mut Vec<Run>) {
    runs.clear();
    let mut x = 0;
    while x < row.len() {
        let p = row[x];
        let start = x;
        while x < row.len() && row[x] == p {
            x += 1;
        }
        if p != u32::MAX {
            runs.push(Run { x0: start as u32, x1: x as u32, poly: p });
        }
    }
}
