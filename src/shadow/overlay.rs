//! Polygons that lie on a receiver's surface, in screen space, walked along scanlines with
//! the shared edge and active-edge tables: Bouknight-Kelley's shadow polygons on the polygon
//! they fall on, Atherton-Weiler-Greenberg's lit detail polygons on their source polygon.
//!
//! Each line, the crossings are grouped by receiver; for a visible run on receiver B the
//! walker gives the pixel intervals where each of B's overlay polygons covers the run.

use super::{Decision, ShadowContext, ShadowWalker};
use crate::scan::{boundary, ActiveEdges, EdgeTable};
use crate::visibility::Run;
use glam::DVec2;
use std::ops::Range;

/// A set of screen polygons, each lying on a receiver polygon.
#[derive(Debug, Clone, Default)]
pub struct Overlay {
    table: EdgeTable,
    receiver: Vec<u32>,
    rings: Vec<Vec<DVec2>>,
    keep_rings: bool,
}

/// Where overlay polygon `tag` covers pixels `start..end` of the current line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Interval {
    /// First pixel covered.
    pub start: u32,
    /// One past the last pixel covered.
    pub end: u32,
    /// The overlay polygon.
    pub tag: u32,
}

impl Overlay {
    /// An empty overlay for an image `height` lines high; `keep_rings` keeps each polygon's
    /// outline for drawing (`--debug`).
    pub fn new(height: u32, keep_rings: bool) -> Self {
        Overlay { table: EdgeTable::new(height), keep_rings, ..Default::default() }
    }

    /// Adds a polygon lying on scene polygon `receiver`; returns its tag.
    pub fn add(&mut self, receiver: u32, ring: &[DVec2]) -> u32 {
        self.add_rings(receiver, std::slice::from_ref(&ring.to_vec()))
    }

    /// Adds a polygon with several rings (holes, by the even-odd rule) lying on `receiver`.
    pub fn add_rings(&mut self, receiver: u32, rings: &[Vec<DVec2>]) -> u32 {
        let tag = self.receiver.len() as u32;
        for ring in rings {
            self.table.add_ring(tag, ring);
            if self.keep_rings {
                self.rings.push(ring.clone());
            }
        }
        self.receiver.push(receiver);
        tag
    }

    /// Sorts the edge table; call once after the last `add`.
    pub fn finish(&mut self) {
        self.table.finish();
    }

    /// Number of polygons.
    pub fn len(&self) -> usize {
        self.receiver.len()
    }

    /// The kept outlines (empty unless made with `keep_rings`).
    pub fn rings(&self) -> &[Vec<DVec2>] {
        &self.rings
    }

    /// A walker over `lines`.
    pub fn walker(&self, lines: Range<u32>) -> OverlayWalker<'_> {
        OverlayWalker {
            overlay: self,
            aet: ActiveEdges::new(&self.table, lines),
            grouped: Vec::new(),
            open: Vec::new(),
        }
    }
}

/// Steps an [`Overlay`] down the lines, grouping each line's crossings by receiver.
pub struct OverlayWalker<'a> {
    overlay: &'a Overlay,
    aet: ActiveEdges<'a>,
    /// This line's crossings as (receiver, x, tag), by receiver, then x.
    grouped: Vec<(u32, f64, u32)>,
    open: Vec<(u32, f64)>,
}

impl OverlayWalker<'_> {
    /// Moves to `line` (lines must come in increasing order).
    pub fn advance_to(&mut self, line: u32) {
        let xs = self.aet.advance_to(line);
        self.grouped.clear();
        self.grouped.extend(xs.iter().map(|c| (self.overlay.receiver[c.tag as usize], c.x, c.tag)));
        // By receiver, then x (the crossings' own order).
        self.grouped.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    }

    /// Writes into `out` the intervals of the current line where the overlay polygons on
    /// `receiver` cover pixels of `x0..x1` (clipped to it), ordered by where they start.
    pub fn intervals(&mut self, receiver: u32, x0: u32, x1: u32, out: &mut Vec<Interval>) {
        out.clear();
        let lo = self.grouped.partition_point(|g| g.0 < receiver);
        let hi = lo + self.grouped[lo..].partition_point(|g| g.0 == receiver);
        self.open.clear();
        for &(_, x, tag) in &self.grouped[lo..hi] {
            match self.open.iter().position(|o| o.0 == tag) {
                None => self.open.push((tag, x)),
                Some(k) => {
                    let (_, xin) = self.open.swap_remove(k);
                    let start = boundary(xin, u32::MAX).max(x0);
                    let end = boundary(x, u32::MAX).min(x1);
                    if start < end {
                        out.push(Interval { start, end, tag });
                    }
                }
            }
        }
        out.sort_unstable_by_key(|i| (i.start, i.end));
    }
}

/// A shadow walker that answers by coverage alone: the pixels of a run that its polygon's
/// overlay polygons cover get `inside`, the others `outside`. Atherton-Weiler-Greenberg's
/// view pass (lit where detail polygons cover) and Blinn's planar shadows (dark where a
/// flattened caster covers) are both this.
pub struct CoverWalker<'a> {
    ctx: &'a ShadowContext<'a>,
    walkers: Vec<OverlayWalker<'a>>,
    intervals: Vec<Interval>,
    inside: f32,
    outside: f32,
    what: &'static str,
}

impl<'a> CoverWalker<'a> {
    /// A walker over one overlay per light sample (`overlays[sample_index(l, s)]`).
    pub fn new(
        ctx: &'a ShadowContext<'a>,
        overlays: &'a [Overlay],
        inside: f32,
        outside: f32,
        what: &'static str,
    ) -> Self {
        let walkers = overlays.iter().map(|o| o.walker(0..ctx.view.height)).collect();
        CoverWalker { ctx, walkers, intervals: Vec::new(), inside, outside, what }
    }
}

impl ShadowWalker for CoverWalker<'_> {
    fn start_line(&mut self, line: u32) {
        for w in &mut self.walkers {
            w.advance_to(line);
        }
    }

    fn lit(&mut self, light: usize, sample: usize, _line: u32, run: &Run, lit: &mut [f32]) {
        lit.fill(self.outside);
        let k = self.ctx.sample_index(light, sample);
        self.walkers[k].intervals(run.poly, run.x0, run.x1, &mut self.intervals);
        for iv in &self.intervals {
            lit[(iv.start - run.x0) as usize..(iv.end - run.x0) as usize].fill(self.inside);
        }
    }

    fn decision(&self) -> Decision {
        let on: Vec<String> =
            self.intervals.iter().map(|i| format!("#{} covers {}..{}", i.tag, i.start, i.end)).collect();
        Decision {
            tested: self.intervals.iter().map(|i| (i.start, i.end, 1)).collect(),
            note: format!("{} {}(s) on this polygon cover [{}]", self.intervals.len(), self.what, on.join(", ")),
        }
    }
}
