//! Watkins' scanline hidden-surface algorithm (G. S. Watkins, "A real-time visible surface
//! algorithm", Utah, 1970; see also Sutherland, Sproull & Schumacker 1974, §"Watkins").
//!
//! One [`EdgeTable`] holds the edges of every screen polygon, bucketed by their first line.
//! Each line, the [`ActiveEdges`] give the crossings in x order; between two neighbouring
//! crossings the set of polygons covering the line is constant (a *span*). For each span the
//! nearest polygon is found at its two end samples. Inverse depth is linear in x along a
//! line, so if one polygon is nearest at both ends it is nearest throughout; if not, the two
//! winners' depths cross inside the span (interpenetration), and the span is split where they
//! cross and each part is solved again — Watkins' subdivision.

use super::{push_run, Run, Visibility};
use crate::scan::{boundary, ActiveEdges, EdgeTable, OpenSet};
use crate::scene::Scene;
use crate::stats::Counters;
use crate::view::{ScreenPolygon, View};
use std::ops::Range;

/// The prepared scanline stage: the edge table of every screen polygon.
pub struct ScanlineVisibility<'a> {
    screen: &'a [ScreenPolygon],
    faces: Vec<u32>,
    table: EdgeTable,
    width: u32,
}

impl<'a> ScanlineVisibility<'a> {
    /// Builds the edge table of `screen`.
    pub fn new(scene: &Scene, screen: &'a [ScreenPolygon], view: &View, counters: &mut Counters) -> Self {
        let mut table = EdgeTable::new(view.height);
        for (i, p) in screen.iter().enumerate() {
            table.add_ring(i as u32, &p.ring);
        }
        table.finish();
        counters.add("edges", table.len() as u64);
        counters.add("table_bytes", table.bytes() as u64);
        let faces = scene.polygons.iter().map(|p| p.face).collect();
        ScanlineVisibility { screen, faces, table, width: view.width }
    }

    /// The edge table the walk uses.
    pub fn table(&self) -> &EdgeTable {
        &self.table
    }

    /// Walks `lines` as [`Visibility::walk`] does, also handing on each line's spans as
    /// they were resolved.
    pub fn walk_recorded(&self, lines: Range<u32>, f: &mut LineSink) {
        self.walk_lines(lines, &mut Counters::default(), true, &mut |y, runs, spans| f(y, runs, spans));
    }

    fn walk_lines(&self, lines: Range<u32>, counters: &mut Counters, record: bool, f: &mut LineSink) {
        let mut aet = ActiveEdges::new(&self.table, lines.clone());
        let mut set = OpenSet::new(self.screen.len());
        let mut runs = Vec::new();
        let mut walk = Walk {
            screen: self.screen,
            faces: &self.faces,
            yc: 0.0,
            spans: 0,
            splits: 0,
            depth_tests: 0,
            record: record.then(Vec::new),
        };
        let mut max_active = 0;
        let mut next = lines.start;
        let emit_empty_until = |upto: u32, next: &mut u32, f: &mut LineSink| {
            while *next < upto {
                f(*next, &[], &[]);
                *next += 1;
            }
        };
        while let Some((line, xs)) = aet.next_line() {
            emit_empty_until(line, &mut next, f);
            walk.yc = line as f64 + 0.5;
            max_active = max_active.max(xs.len());
            runs.clear();
            if let Some(r) = &mut walk.record {
                r.clear();
            }
            let mut prev = 0;
            for c in xs {
                let b = boundary(c.x, self.width);
                if b > prev && !set.is_empty() {
                    walk.resolve(set.tags(), prev, b, 0, &mut runs);
                }
                prev = prev.max(b);
                set.toggle(c.tag, b);
            }
            // Every polygon's crossings pair up, so the set is empty again here.
            debug_assert!(set.is_empty());
            f(line, &runs, walk.record.as_deref().unwrap_or(&[]));
            next = line + 1;
        }
        emit_empty_until(lines.end, &mut next, f);
        counters.add("edges_entered", aet.entered);
        counters.add("spans", walk.spans);
        counters.add("span_splits", walk.splits);
        counters.add("depth_tests", walk.depth_tests);
        counters.add("active_edges_max", max_active as u64);
        // Working memory of this band: active edges, the inside flags, the span set, the runs.
        let band_bytes = aet.bytes() + set.bytes() + runs.capacity() * std::mem::size_of::<Run>();
        counters.add("band_bytes_max", band_bytes as u64);
    }
}

/// One span as Watkins' algorithm resolved it (recorded for `umbra trace`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SpanRecord {
    /// First pixel.
    pub x0: u32,
    /// One past the last pixel.
    pub x1: u32,
    /// Subdivision depth (0: a span between two crossings).
    pub depth: u32,
    /// The polygons covering it: (scene polygon, face id, 1/z at the first and last pixel).
    pub covering: Vec<(u32, u32, f64, f64)>,
    /// The nearest polygon at each end (scene polygon index).
    pub nearest: (u32, u32),
    /// Where it was split, when the two ends disagree (interpenetration).
    pub split_at: Option<u32>,
}

/// Receives each line's runs and, when recording, its spans.
type LineSink<'f> = dyn FnMut(u32, &[Run], &[SpanRecord]) + 'f;

/// Per-band scratch and counters.
struct Walk<'s> {
    screen: &'s [ScreenPolygon],
    faces: &'s [u32],
    yc: f64,
    spans: u64,
    splits: u64,
    depth_tests: u64,
    /// When tracing: every span resolved.
    record: Option<Vec<SpanRecord>>,
}

impl Walk<'_> {
    /// The polygon of `set` nearest the eye at the centre of pixel `x` (ties: lowest index).
    #[inline]
    fn nearest(&mut self, set: &[u32], x: u32) -> u32 {
        let xc = x as f64 + 0.5;
        self.depth_tests += set.len() as u64;
        let mut best = set[0];
        let mut best_z = self.screen[best as usize].depth.inv_z(xc, self.yc);
        for &i in &set[1..] {
            let z = self.screen[i as usize].depth.inv_z(xc, self.yc);
            if z > best_z || (z == best_z && i < best) {
                best = i;
                best_z = z;
            }
        }
        best
    }

    /// Resolves span `a..b` covered by `set`, splitting it where the nearest polygon changes.
    fn resolve(&mut self, set: &[u32], a: u32, b: u32, depth: u32, runs: &mut Vec<Run>) {
        self.spans += 1;
        let left = self.nearest(set, a);
        let right = if b - a == 1 { left } else { self.nearest(set, b - 1) };
        let split = (left != right).then(|| {
            // The two winners' inverse depths are equal at x* (they interpenetrate there).
            let (l, r) = (&self.screen[left as usize].depth, &self.screen[right as usize].depth);
            let x_star = ((r.b - l.b) * self.yc + (r.c - l.c)) / (l.a - r.a);
            let m = if x_star.is_finite() { boundary(x_star, u32::MAX) } else { a + (b - a) / 2 };
            m.clamp(a + 1, b - 1)
        });
        if let Some(record) = &mut self.record {
            let (xa, xb, yc) = (a as f64 + 0.5, (b - 1) as f64 + 0.5, self.yc);
            let covering = set
                .iter()
                .map(|&i| {
                    let p = &self.screen[i as usize];
                    (p.poly, self.faces[p.poly as usize], p.depth.inv_z(xa, yc), p.depth.inv_z(xb, yc))
                })
                .collect();
            let nearest = (self.screen[left as usize].poly, self.screen[right as usize].poly);
            record.push(SpanRecord { x0: a, x1: b, depth, covering, nearest, split_at: split });
        }
        match split {
            None => push_run(runs, a, b, self.screen[left as usize].poly),
            Some(m) => {
                self.splits += 1;
                self.resolve(set, a, m, depth + 1, runs);
                self.resolve(set, m, b, depth + 1, runs);
            }
        }
    }
}

impl Visibility for ScanlineVisibility<'_> {
    fn walk(&self, lines: Range<u32>, counters: &mut Counters, f: &mut dyn FnMut(u32, &[Run])) {
        self.walk_lines(lines, counters, false, &mut |y, runs, _| f(y, runs));
    }

    fn span_splits(&self, lines: Range<u32>, out: &mut [u16]) {
        let w = self.width as usize;
        let y0 = lines.start;
        self.walk_lines(lines, &mut Counters::default(), true, &mut |y, _, spans| {
            let row = &mut out[(y - y0) as usize * w..(y - y0 + 1) as usize * w];
            for s in spans.iter().filter(|s| s.split_at.is_some()) {
                for v in &mut row[s.x0 as usize..s.x1 as usize] {
                    *v += 1;
                }
            }
        });
    }
}
