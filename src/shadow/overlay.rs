//! Polygons that lie on a receiver's surface, in screen space, walked along scanlines with
//! the shared edge and active-edge tables: Bouknight-Kelley's shadow polygons on the polygon
//! they fall on, Atherton-Weiler-Greenberg's lit detail polygons on their source polygon.
//!
//! Each line, the crossings are grouped by receiver; for a visible run on receiver B the
//! walker gives the pixel intervals where each of B's overlay polygons covers the run.

use crate::scan::{boundary, ActiveEdges, EdgeTable};
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
