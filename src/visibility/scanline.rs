//! Watkins' scanline hidden-surface algorithm (G. S. Watkins, "A real-time visible surface
//! algorithm", Utah, 1970; see also Sutherland, Sproull & Schumacker 1974, §"Watkins").
//!
//! An [`EdgeTable`] holds the edges of the screen polygons, bucketed by their first line.
//! Each line, the [`ActiveEdges`] give the crossings in x order; between two neighbouring
//! crossings the set of polygons covering the line is constant (a *span*). For each span the
//! nearest polygon is found at its two end samples. Inverse depth is linear in x along a
//! line, so if one polygon is nearest at both ends it is nearest throughout; if not, the two
//! winners' depths cross inside the span (interpenetration), and the span is split where they
//! cross and each part is solved again — Watkins' subdivision.
//!
//! The frame is walked in bands of lines, in parallel. Each band builds its own edge table
//! from the polygons that reach it, with their edges cut to its lines: a table a band's
//! size, built by the thread that walks it, in memory kept from the last frame.

use super::{push_run, Run, Visibility};
use crate::pool::{Pools, Stash};
use crate::scan::{band_height, boundary, emptied_with_room, ActiveEdges, EdgeTable, OpenSet};
use crate::scene::Scene;
use crate::stats::Counters;
use crate::view::{DepthPlane, Screen, View};
use std::ops::Range;

/// The prepared scanline stage: which polygons reach each band of lines.
pub struct ScanlineVisibility<'a> {
    scene: &'a Scene,
    screen: &'a Screen,
    /// `members[b]`: the screen polygons reaching band `b` (of `band` lines), increasing.
    members: Vec<Vec<u32>>,
    band: u32,
    width: u32,
    height: u32,
    /// Where the bands' working memory is kept from band to band (let go with the stage).
    stash: Stash,
}

/// One band's working memory, kept for the next band: its edge table, and its polygons' depth
/// planes and scene indices (the table's tags index these), and the set of open polygons.
#[derive(Default)]
struct BandScratch {
    table: EdgeTable,
    planes: Vec<DepthPlane>,
    polys: Vec<u32>,
    set: OpenSet,
}

/// The bands' working memory is let go with the stage: kept, it would sit through the shadow
/// stage's preparation, when the frame's memory peaks (27 MB of band tables on s3).
impl Drop for ScanlineVisibility<'_> {
    fn drop(&mut self) {
        self.stash.discard::<BandScratch>();
    }
}

impl<'a> ScanlineVisibility<'a> {
    /// Sorts the polygons of `screen` into the bands they reach; band tables are kept in
    /// `pools`.
    pub fn new(scene: &'a Scene, screen: &'a Screen, view: &View, pools: &Pools, counters: &mut Counters) -> Self {
        let band = band_height(view.height);
        let members = screen.band_members(view.height, band);
        counters.add(crate::stats::Counter::BandMembers, members.iter().map(Vec::len).sum::<usize>() as u64);
        ScanlineVisibility {
            scene,
            screen,
            members,
            band,
            width: view.width,
            height: view.height,
            stash: pools.stash.clone(),
        }
    }

    /// The edge table of every screen polygon over the whole frame, tagged by screen index
    /// (what `umbra trace` lists; the walk builds one per band instead).
    pub fn whole_table(&self) -> EdgeTable {
        let mut table = EdgeTable::new(self.height);
        for (i, _, ring) in self.screen.iter() {
            table.add_ring(i, ring);
        }
        table.finish();
        table
    }

    /// Walks `lines` as [`Visibility::walk`] does, also handing on each line's spans as
    /// they were resolved.
    pub fn walk_recorded(&self, lines: Range<u32>, f: &mut LineSink) {
        self.walk_lines(lines, &mut Counters::default(), true, &mut |y, runs, spans| f(y, runs, spans));
    }

    /// The screen polygons that reach `lines`, increasing: one band's list when `lines` lie
    /// in one band, else the union of the bands' lists.
    fn members_of(&self, lines: &Range<u32>) -> std::borrow::Cow<'_, [u32]> {
        let (first, last) = (lines.start / self.band, lines.end.saturating_sub(1) / self.band);
        let bands =
            &self.members[(first as usize).min(self.members.len())..(last as usize + 1).min(self.members.len())];
        match bands {
            [one] => one.as_slice().into(),
            _ => {
                let mut all: Vec<u32> = bands.concat();
                all.sort_unstable();
                all.dedup();
                all.into()
            }
        }
    }

    /// Builds the edge table of `lines` in `scratch`: the edges of the polygons reaching
    /// them, cut to them, tagged by their place in the band's list.
    fn build_band(&self, lines: &Range<u32>, scratch: &mut BandScratch) {
        let members = self.members_of(lines);
        let BandScratch { table, planes, polys, set } = scratch;
        table.clear_to(self.height, lines.clone());
        // Room for every member's edges at once (a ring gives at most one edge a corner):
        // grown edge by edge, the table's reallocations were 2% of s3's frame.
        table.reserve(members.iter().map(|&i| self.screen.get(i).1.len()).sum());
        emptied_with_room(planes, members.len());
        emptied_with_room(polys, members.len());
        for (k, &i) in members.iter().enumerate() {
            let (p, ring) = self.screen.get(i);
            table.add_ring(k as u32, ring);
            planes.push(p.depth);
            polys.push(p.poly);
        }
        table.finish();
        set.reset(members.len());
    }

    fn walk_lines(&self, lines: Range<u32>, counters: &mut Counters, record: bool, f: &mut LineSink) {
        let mut scratch: BandScratch = self.stash.take();
        self.build_band(&lines, &mut scratch);
        let BandScratch { table, planes, polys, set } = &mut scratch;
        counters.add(crate::stats::Counter::Edges, table.len() as u64);
        let mut aet = ActiveEdges::new(table, lines.clone());
        let mut runs = Vec::new();
        let mut walk = Walk {
            scene: self.scene,
            planes: planes.as_slice(),
            polys: polys.as_slice(),
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
        counters.add(crate::stats::Counter::EdgesEntered, aet.entered);
        counters.add(crate::stats::Counter::Spans, walk.spans);
        counters.add(crate::stats::Counter::SpanSplits, walk.splits);
        counters.add(crate::stats::Counter::DepthTests, walk.depth_tests);
        counters.add(crate::stats::Counter::ActiveEdgesMax, max_active as u64);
        // Working memory of this band: its table, active edges, the span set, the runs.
        let band_bytes = table.bytes() + aet.bytes() + set.bytes() + runs.capacity() * std::mem::size_of::<Run>();
        counters.add(crate::stats::Counter::BandBytesMax, band_bytes as u64);
        drop(aet);
        self.stash.put(scratch);
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

/// Whether polygon `i` at inverse depth `z` is nearer than `best` at `best_z`: larger `1/z`,
/// and on a tie the lower index.
#[inline]
fn nearer((z, i): (f64, u32), (best_z, best): (f64, u32)) -> bool {
    z > best_z || (z == best_z && i < best)
}

/// Per-band scratch and counters.
struct Walk<'s> {
    scene: &'s Scene,
    /// The band's polygons' depth planes and scene indices, by tag.
    planes: &'s [DepthPlane],
    polys: &'s [u32],
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
        let mut best_z = self.planes[best as usize].inv_z(xc, self.yc);
        for &i in &set[1..] {
            let z = self.planes[i as usize].inv_z(xc, self.yc);
            if nearer((z, i), (best_z, best)) {
                (best, best_z) = (i, z);
            }
        }
        best
    }

    /// [`Walk::nearest`] at pixels `a` and `b` in one pass over the set.
    #[inline]
    fn nearest_at_both_ends(&mut self, set: &[u32], a: u32, b: u32) -> (u32, u32) {
        let (xa, xb) = (a as f64 + 0.5, b as f64 + 0.5);
        self.depth_tests += 2 * set.len() as u64;
        let first = &self.planes[set[0] as usize];
        let (mut left, mut right) = (set[0], set[0]);
        let (mut left_z, mut right_z) = (first.inv_z(xa, self.yc), first.inv_z(xb, self.yc));
        for &i in &set[1..] {
            let plane = &self.planes[i as usize];
            let (za, zb) = (plane.inv_z(xa, self.yc), plane.inv_z(xb, self.yc));
            if nearer((za, i), (left_z, left)) {
                (left, left_z) = (i, za);
            }
            if nearer((zb, i), (right_z, right)) {
                (right, right_z) = (i, zb);
            }
        }
        (left, right)
    }

    /// Resolves span `a..b` covered by `set`, splitting it where the nearest polygon changes.
    fn resolve(&mut self, set: &[u32], a: u32, b: u32, depth: u32, runs: &mut Vec<Run>) {
        self.spans += 1;
        let (left, right) = if b - a == 1 {
            let one = self.nearest(set, a);
            (one, one)
        } else {
            self.nearest_at_both_ends(set, a, b - 1)
        };
        let split = (left != right).then(|| {
            // The two winners' inverse depths are equal at x* (they interpenetrate there).
            let (l, r) = (&self.planes[left as usize], &self.planes[right as usize]);
            let x_star = ((r.b - l.b) * self.yc + (r.c - l.c)) / (l.a - r.a);
            let m = if x_star.is_finite() { boundary(x_star, u32::MAX) } else { a + (b - a) / 2 };
            m.clamp(a + 1, b - 1)
        });
        if let Some(record) = &mut self.record {
            let (xa, xb, yc) = (a as f64 + 0.5, (b - 1) as f64 + 0.5, self.yc);
            let covering = set
                .iter()
                .map(|&i| {
                    let (poly, depth) = (self.polys[i as usize], &self.planes[i as usize]);
                    (poly, self.scene.polygons[poly as usize].face, depth.inv_z(xa, yc), depth.inv_z(xb, yc))
                })
                .collect();
            let nearest = (self.polys[left as usize], self.polys[right as usize]);
            record.push(SpanRecord { x0: a, x1: b, depth, covering, nearest, split_at: split });
        }
        match split {
            None => push_run(runs, a, b, self.polys[left as usize]),
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
