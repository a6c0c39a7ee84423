//! Polygons that lie on a receiver's surface, in screen space, walked along scanlines with
//! the shared edge and active-edge tables: Bouknight-Kelley's shadow polygons on the polygon
//! they fall on, Atherton-Weiler-Greenberg's lit detail polygons on their source polygon,
//! Blinn's flattened casters on their receiver.
//!
//! Each receiver has its own edge table, and its active-edge walk starts on the first line
//! where a visible run on it asks: for a run on receiver B, the walker gives the pixel
//! intervals where each of B's overlay polygons covers the run. A receiver's polygons may
//! instead be *counted* (Bouknight-Kelley's solid outlines): their edges carry the weight
//! their crossing adds to the number of polygons over a point ([`super::far_outline`]), and
//! the walker gives the intervals where that number is above zero, their union.

use super::{Cover, Decision, Detail, ShadowContext, ShadowWalker};
use crate::scan::{boundary, ActiveEdges, EdgeTable, OpenSet};
use crate::visibility::Run;
use glam::DVec2;
use rayon::prelude::*;
use std::ops::Range;

/// A set of screen polygons, each lying on a receiver polygon.
#[derive(Debug, Clone, Default)]
pub struct Overlay {
    height: u32,
    /// One edge table per receiver, in the order receivers first appeared.
    tables: Vec<EdgeTable>,
    /// The tag of each table's first polygon: its edges are tagged from 0.
    base: Vec<u32>,
    /// For each table, one past the greatest tag its edges carry: a walker keeps the open
    /// polygons of a line in a dense set of that size.
    tags: Vec<u32>,
    /// For each table, whether it is counted: its edges' tags are crossing weights.
    counted: Vec<bool>,
    /// What it holds for each receiver, by the receiver's index (as far as the greatest
    /// receiver it holds).
    slot: Vec<Option<Slot>>,
    count: usize,
    rings: Vec<Vec<DVec2>>,
    keep_rings: bool,
}

/// What an overlay holds for one receiver.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    /// Its polygons' edge table (an index into `tables`).
    Table(u32),
    /// One polygon, tagged so, that covers the whole receiver.
    Whole(u32),
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

/// One receiver's overlay polygons, gathered on their own (in parallel with other
/// receivers') before they join an [`Overlay`] with [`Overlay::from_tables`].
#[derive(Debug)]
pub struct ReceiverTable {
    receiver: u32,
    table: EdgeTable,
    count: u32,
    rings: Vec<Vec<DVec2>>,
    keep_rings: bool,
    counted: bool,
}

impl ReceiverTable {
    /// No polygons yet on scene polygon `receiver`, in an image `height` lines high;
    /// `keep_rings` keeps their outlines.
    pub fn new(receiver: u32, height: u32, keep_rings: bool) -> Self {
        ReceiverTable {
            receiver,
            table: EdgeTable::one_frame(height),
            count: 0,
            rings: Vec::new(),
            keep_rings,
            counted: false,
        }
    }

    /// `count` polygons on scene polygon `receiver`, counted: `table`'s edges are tagged
    /// with the weights their crossings add to the number of polygons over a point
    /// ([`super::far_outline::table`]).
    pub(crate) fn counted(receiver: u32, table: EdgeTable, count: u32) -> Self {
        ReceiverTable { receiver, table, count, rings: Vec::new(), keep_rings: false, counted: true }
    }

    /// Adds a polygon with several rings (holes by the even-odd rule).
    pub fn add_rings(&mut self, rings: &[Vec<DVec2>]) {
        for ring in rings {
            self.add_ring_of(ring);
        }
        self.count += 1;
    }

    /// Adds a polygon with one ring.
    pub fn add(&mut self, ring: &[DVec2]) {
        self.add_ring_of(ring);
        self.count += 1;
    }

    fn add_ring_of(&mut self, ring: &[DVec2]) {
        self.table.add_ring(self.count, ring);
        if self.keep_rings {
            self.rings.push(ring.to_vec());
        }
    }

    /// The polygons of `parts` (tables of one receiver, none finished), one part after
    /// another: the table adding them in turn would build ([`EdgeTable::joined`]).
    pub(crate) fn joined(parts: Vec<ReceiverTable>) -> Option<Self> {
        let tags = crate::pieces::starts(parts.iter().map(|p| p.count as usize));
        let tags: Vec<u32> = tags.into_iter().map(|t| t as u32).collect();
        let (receiver, keep_rings) = (parts.first()?.receiver, parts[0].keep_rings);
        let count = parts.iter().map(|p| p.count).sum();
        let mut rings = Vec::new();
        let tables = parts
            .into_iter()
            .map(|mut p| {
                rings.append(&mut p.rings);
                p.table
            })
            .collect();
        let table = EdgeTable::joined(tables, &tags)?;
        Some(ReceiverTable { receiver, table, count, rings, keep_rings, counted: false })
    }

    /// The receiver.
    pub fn receiver(&self) -> u32 {
        self.receiver
    }

    /// Number of polygons.
    pub fn len(&self) -> usize {
        self.count as usize
    }

    /// Sorts the edge table (where it lies: it lives one frame); call once after the last
    /// polygon.
    pub fn finish(&mut self) {
        self.table.finish();
    }
}

impl Overlay {
    /// The bytes it holds: its tables, their receivers' slots, and the outlines it keeps.
    pub fn bytes(&self) -> usize {
        use crate::pool::held;
        let rings = self.rings.iter().map(held).sum::<usize>() + held(&self.rings);
        self.tables.iter().map(EdgeTable::bytes).sum::<usize>()
            + held(&self.tables)
            + held(&self.base)
            + held(&self.tags)
            + held(&self.counted)
            + held(&self.slot)
            + rings
    }

    /// An empty overlay for an image `height` lines high; `keep_rings` keeps each polygon's
    /// outline for drawing (`--debug`).
    pub fn new(height: u32, keep_rings: bool) -> Self {
        Overlay { height, keep_rings, ..Default::default() }
    }

    /// Adds a polygon lying on scene polygon `receiver`; returns its tag.
    pub fn add(&mut self, receiver: u32, ring: &[DVec2]) -> u32 {
        self.add_rings(receiver, std::slice::from_ref(&ring.to_vec()))
    }

    /// Adds a polygon with several rings (holes, by the even-odd rule) lying on `receiver`.
    pub fn add_rings(&mut self, receiver: u32, rings: &[Vec<DVec2>]) -> u32 {
        let tag = self.count as u32;
        let slot = match self.slot(receiver) {
            Some(Slot::Whole(_)) => return tag,
            Some(Slot::Table(slot)) => slot as usize,
            None => {
                self.set_slot(receiver, Slot::Table(self.tables.len() as u32));
                self.tables.len()
            }
        };
        if slot == self.tables.len() {
            self.tables.push(EdgeTable::new(self.height));
            self.base.push(tag);
            self.tags.push(0);
            self.counted.push(false);
        }
        self.tags[slot] = self.tags[slot].max(tag - self.base[slot] + 1);
        for ring in rings {
            self.tables[slot].add_ring(tag - self.base[slot], ring);
            if self.keep_rings {
                self.rings.push(ring.clone());
            }
        }
        self.count += 1;
        tag
    }

    /// An overlay of polygons given receiver by receiver (each receiver once), tagged in the
    /// order given; `rings_of` gives a polygon's rings (holes by the even-odd rule). The
    /// receivers' edge tables are built in parallel.
    pub fn from_receivers<'r, P: Sync>(
        height: u32,
        keep_rings: bool,
        receivers: &'r [(u32, Vec<P>)],
        rings_of: impl Fn(&'r P) -> &'r [Vec<DVec2>] + Sync,
    ) -> Self {
        let tables = receivers
            .par_iter()
            .map(|(receiver, polygons)| {
                let mut table = ReceiverTable::new(*receiver, height, keep_rings);
                for polygon in polygons {
                    table.add_rings(rings_of(polygon));
                }
                table.finish();
                table
            })
            .collect::<Vec<_>>();
        Overlay::from_tables(height, keep_rings, tables.into_par_iter())
    }

    /// An overlay of receivers' tables (each receiver once), tagged in the order given:
    /// table `k`'s polygon `i` gets tag `i` plus the number of polygons before it. Tables
    /// are best finished where they were built, in parallel; any that is not is finished
    /// here.
    pub fn from_tables(height: u32, keep_rings: bool, tables: impl ParallelIterator<Item = ReceiverTable>) -> Self {
        let mut overlay = Overlay::new(height, keep_rings);
        // The tables (half a million on a large scene) are finished and moved by all
        // threads; one thread only numbers them.
        let mut tables: Vec<ReceiverTable> = tables
            .filter(|t| t.count > 0)
            .map(|mut t| {
                t.finish();
                t
            })
            .collect();
        if let Some(last) = tables.iter().map(|t| t.receiver).max() {
            overlay.slot.resize(last as usize + 1, None);
        }
        for (k, t) in tables.iter_mut().enumerate() {
            overlay.slot[t.receiver as usize] = Some(Slot::Table(k as u32));
            overlay.base.push(overlay.count as u32);
            overlay.tags.push(if t.counted { 0 } else { t.count });
            overlay.counted.push(t.counted);
            overlay.count += t.count as usize;
            overlay.rings.append(&mut t.rings);
        }
        overlay.tables = tables.into_par_iter().map(|t| t.table).collect();
        overlay
    }

    /// Adds, for each of `receivers`, one polygon that covers it whole (its outline is the
    /// receiver's own), tagged in the order given: a run on it is covered from end to end,
    /// with no edges to walk. It takes the place of any polygons added on it before.
    pub fn add_wholes(&mut self, receivers: &[u32]) {
        for &r in receivers {
            self.set_slot(r, Slot::Whole(self.count as u32));
            self.count += 1;
        }
    }

    /// What the overlay holds for `receiver`.
    fn slot(&self, receiver: u32) -> Option<Slot> {
        self.slot.get(receiver as usize).copied().flatten()
    }

    /// Sets what the overlay holds for `receiver`.
    fn set_slot(&mut self, receiver: u32, slot: Slot) {
        let r = receiver as usize;
        if r >= self.slot.len() {
            self.slot.resize((r + 1).max(2 * self.slot.len()), None);
        }
        self.slot[r] = Some(slot);
    }

    /// Sorts the edge tables; call once after the last `add`.
    pub fn finish(&mut self) {
        for t in &mut self.tables {
            t.finish();
        }
    }

    /// Number of polygons.
    pub fn len(&self) -> usize {
        self.count
    }

    /// The kept outlines (empty unless made with `keep_rings`).
    pub fn rings(&self) -> &[Vec<DVec2>] {
        &self.rings
    }

    /// A walker over `lines`.
    pub fn walker(&self, lines: Range<u32>) -> OverlayWalker<'_> {
        OverlayWalker {
            overlay: self,
            end: lines.end,
            line: lines.start,
            active: (0..self.tables.len()).map(|_| None).collect(),
            lines: vec![LineIntervals::default(); self.tables.len()],
            open: OpenSet::new(0),
        }
    }
}

/// Steps an [`Overlay`] down the lines; each receiver's active edges start where a run on it
/// first asks and follow the lines from there.
pub struct OverlayWalker<'a> {
    overlay: &'a Overlay,
    end: u32,
    line: u32,
    active: Vec<Option<ActiveEdges<'a>>>,
    /// Each receiver's intervals on the line it was last asked about.
    lines: Vec<LineIntervals>,
    open: OpenSet,
}

/// One receiver's intervals on one line, whole (not clipped to a run), ordered by where they
/// start, with the furthest end reached so far at each: a receiver seen in many runs on a
/// line pairs its crossings once, and each run reads only the intervals that can reach it.
#[derive(Debug, Clone, Default)]
struct LineIntervals {
    line: Option<u32>,
    all: Vec<Interval>,
    reach: Vec<u32>,
}

impl OverlayWalker<'_> {
    /// Moves to `line` (lines must come in increasing order).
    pub fn advance_to(&mut self, line: u32) {
        self.line = line;
    }

    /// Writes into `out` the intervals of the current line where the overlay polygons on
    /// `receiver` cover pixels of `x0..x1` (clipped to it), ordered by where they start.
    pub fn intervals(&mut self, receiver: u32, x0: u32, x1: u32, out: &mut Vec<Interval>) {
        out.clear();
        let slot = match self.overlay.slot(receiver) {
            None => return,
            Some(Slot::Whole(tag)) => return out.push(Interval { start: x0, end: x1, tag }),
            Some(Slot::Table(slot)) => slot,
        };
        let table = &self.overlay.tables[slot as usize];
        let (line, end) = (self.line, self.end);
        let cached = &mut self.lines[slot as usize];
        if cached.line != Some(line) {
            let aet = self.active[slot as usize].get_or_insert_with(|| ActiveEdges::new(table, line..end));
            let (base, tags) = (self.overlay.base[slot as usize], self.overlay.tags[slot as usize]);
            if self.overlay.counted[slot as usize] {
                cached.count(aet.advance_to(line), base);
            } else {
                cached.pair(aet.advance_to(line), &mut self.open, base, tags as usize);
            }
            cached.line = Some(line);
        }
        // The intervals starting before the run's end, from the first whose reach passes
        // its start.
        let from = cached.reach.partition_point(|&r| r <= x0);
        for iv in cached.all[from..].iter().take_while(|iv| iv.start < x1).filter(|iv| iv.end > x0) {
            out.push(Interval { start: iv.start.max(x0), end: iv.end.min(x1), tag: iv.tag });
        }
        out.sort_unstable_by_key(|i| (i.start, i.end, i.tag));
    }
}

impl LineIntervals {
    /// Pairs a line's crossings (sorted by x) into each polygon's covered intervals, tagging
    /// each with `base` plus its edges' tag (below `tags`).
    fn pair(&mut self, crossings: &[crate::scan::Crossing], open: &mut OpenSet, base: u32, tags: usize) {
        self.all.clear();
        // Dense: a receiver under a stack of casters has hundreds of polygons open at once
        // (s4), and a sparse set searches them all at every crossing.
        open.reset(tags);
        for c in crossings {
            let at = boundary(c.x, u32::MAX);
            if let Some(start) = open.toggle(c.tag, at) {
                if start < at {
                    self.all.push(Interval { start, end: at, tag: base + c.tag });
                }
            }
        }
        self.all.sort_unstable_by_key(|i| (i.start, i.end, i.tag));
        self.find_reach();
    }

    /// A counted receiver's line: the crossings (sorted by x, tagged with their weights)
    /// summed from the left, a pixel's number being the sum of the crossings at or left of
    /// its centre; the intervals where it is above zero, each tagged `tag`.
    fn count(&mut self, crossings: &[crate::scan::Crossing], tag: u32) {
        self.all.clear();
        let (mut sum, mut open) = (0i32, None);
        for (k, c) in crossings.iter().enumerate() {
            sum += c.tag as i32;
            let at = boundary(c.x, u32::MAX);
            // The number changes between pixels once all crossings before the same pixel
            // are summed.
            if crossings.get(k + 1).is_some_and(|next| boundary(next.x, u32::MAX) == at) {
                continue;
            }
            match open {
                None if sum > 0 => open = Some(at),
                Some(start) if sum <= 0 => {
                    if start < at {
                        self.all.push(Interval { start, end: at, tag });
                    }
                    open = None;
                }
                _ => {}
            }
        }
        self.find_reach();
    }

    /// The furthest end reached at each interval.
    fn find_reach(&mut self) {
        self.reach.clear();
        let mut far = 0;
        self.reach.extend(self.all.iter().map(|iv| {
            far = far.max(iv.end);
            far
        }));
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
            detail: Detail::Covers {
                covers: self.intervals.iter().map(|i| Cover { polygon: i.tag, start: i.start, end: i.end }).collect(),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shadow::far_outline;

    /// The intervals a receiver's polygons cover on each line, from the overlay's walker.
    fn covered(overlay: &Overlay, receiver: u32, lines: u32, width: u32) -> Vec<Vec<(u32, u32)>> {
        let mut walker = overlay.walker(0..lines);
        let mut out = Vec::new();
        (0..lines)
            .map(|line| {
                walker.advance_to(line);
                walker.intervals(receiver, 0, width, &mut out);
                out.iter().map(|iv| (iv.start, iv.end)).collect()
            })
            .collect()
    }

    /// The pixels of `0..width` that any of a line's `intervals` covers.
    fn union(intervals: &[(u32, u32)], width: u32) -> Vec<u32> {
        (0..width).filter(|&x| intervals.iter().any(|&(s, e)| (s..e).contains(&x))).collect()
    }

    /// A counted receiver covers the union of its polygons, wound alike: shared edges
    /// cancelled, overlaps counted twice, and polygons wound the other way subtracted.
    #[test]
    fn a_counted_receiver_covers_the_union_of_its_polygons() {
        let p = |x: f64, y: f64| DVec2::new(x, y);
        // Two triangles making a square (their diagonal shared), a square overlapping it,
        // and a square apart, all counter-clockwise.
        let rings = [
            vec![p(1.0, 1.0), p(9.0, 1.0), p(9.0, 9.0)],
            vec![p(1.0, 1.0), p(9.0, 9.0), p(1.0, 9.0)],
            vec![p(5.2, 4.3), p(14.1, 4.3), p(14.1, 12.7), p(5.2, 12.7)],
            vec![p(17.5, 2.2), p(19.4, 2.2), p(19.4, 6.6), p(17.5, 6.6)],
        ];
        let (lines, width) = (14, 24);
        let mut each = Overlay::new(lines, false);
        for r in &rings {
            each.add(0, r);
        }
        each.finish();
        let mut edges = Vec::new();
        for r in &rings {
            far_outline::push_ring(r, 1, &mut edges);
        }
        let cancelled = far_outline::cancel(edges.clone());
        assert!(cancelled.len() < edges.len(), "the shared diagonal cancels");
        let table = far_outline::table(lines, &cancelled);
        let counted = Overlay::from_tables(lines, false, vec![ReceiverTable::counted(0, table, 4)].into_par_iter());
        let (by_polygon, by_count) = (covered(&each, 0, lines, width), covered(&counted, 0, lines, width));
        let mut lit_somewhere = 0;
        for line in 0..lines as usize {
            let want = union(&by_polygon[line], width);
            let got = union(&by_count[line], width);
            assert_eq!(got, want, "line {line}");
            // The counted intervals are disjoint, in order.
            assert!(by_count[line].windows(2).all(|w| w[0].1 < w[1].0), "line {line}: {:?}", by_count[line]);
            lit_somewhere += want.len();
        }
        assert!(lit_somewhere > 100, "{lit_somewhere}");
        // A ring wound the other way (clockwise: negative shoelace area) takes its part away.
        let mut holed = cancelled;
        far_outline::push_ring(&[p(3.1, 3.2), p(3.1, 6.8), p(6.6, 6.8), p(6.6, 3.2)], 1, &mut holed);
        let table = far_outline::table(lines, &far_outline::cancel(holed));
        let counted = Overlay::from_tables(lines, false, vec![ReceiverTable::counted(0, table, 5)].into_par_iter());
        let line5 = union(&covered(&counted, 0, lines, width)[5], width);
        assert!(!line5.contains(&4) && line5.contains(&2) && line5.contains(&8), "{line5:?}");
    }
}
