//! The edge table and active edge table (Watkins 1970; Foley et al. §3.6), written once and
//! used by every stage that walks polygons along scanlines: visible polygons, projected shadow
//! polygons, lit detail polygons, shadow-volume polygons, and the z-buffer's rasteriser.
//!
//! Sampling follows the pixel-centre rule: line `y` is sampled at `y + 0.5`; an edge is active
//! on the lines whose centre lies in `[y_top, y_bottom)` (horizontal edges never are); a
//! crossing at `x` separates the pixels whose centre lies left of `x` from the rest, so a span
//! between crossings `xl <= xr` covers the pixels `ceil(xl - 0.5) .. ceil(xr - 0.5)`. Two
//! polygons that share an edge therefore never both cover a pixel centre on it, and never
//! leave one uncovered.
//!
//! [`for_each_span`] walks a single ring that is monotone in y (every convex polygon, so every
//! triangle of a mesh) down its two chains instead: the same edges, the same crossings, the
//! same spans, without building a table for a polygon a few lines tall.
//!
//! The crossing of an edge is evaluated on each line from the edge's top vertex
//! (`x_top + (y + 0.5 - y_top) dx/dy`), not accumulated by repeated addition: the same cost,
//! and no drift on long, nearly horizontal edges. Two polygons that share an edge compute
//! bit-identical crossings because the edge is always taken from its upper vertex.

use crate::geometry::RingList;
use crate::pieces::{starts, stretches};
use glam::DVec2;
use rayon::prelude::*;
use std::ops::Range;

/// Lines per band, when the lines of a frame are shared among threads in bands: enough bands
/// to keep every core busy (four a thread or more), few enough that each band's setup (the
/// active edges at its first line) stays small (64 lines or more a band, or 8 for small
/// images), and as many bands for every thread: 17 bands of 64 lines on two threads would
/// keep one thread a band longer than the other.
pub fn band_height(height: u32) -> u32 {
    let threads = (rayon::current_num_threads() as u32).max(1);
    let bands = height.div_ceil(64).max(4 * threads).next_multiple_of(threads);
    height.div_ceil(bands).max(8)
}

/// One non-horizontal edge, stored from its upper vertex.
#[derive(Debug, Clone, Copy)]
struct Edge {
    x_top: f64,
    y_top: f64,
    dxdy: f64,
    first: u32,
    end: u32,
    tag: u32,
    /// Its place in the order edges were added, in a table sorted where it lies (see
    /// [`EdgeTable::one_frame`]; it fills the struct's padding).
    seq: u32,
}

const _: () = assert!(std::mem::size_of::<Edge>() == 40);

impl Edge {
    /// A placeholder, overwritten before it is read.
    const NONE: Edge = Edge { x_top: 0.0, y_top: 0.0, dxdy: 0.0, first: 0, end: 0, tag: 0, seq: 0 };

    /// The edge from `a` to `b` in an image `height` lines high; `None` when it is
    /// horizontal, not finite, or active on no line.
    fn new(tag: u32, a: DVec2, b: DVec2, height: u32) -> Option<Edge> {
        if a.y == b.y || !(a.is_finite() && b.is_finite()) {
            return None;
        }
        let (top, bot) = if a.y < b.y { (a, b) } else { (b, a) };
        // The pixel-centre rule down the screen is the rule across it.
        let (first, end) = (boundary(top.y, height), boundary(bot.y, height));
        let dxdy = (bot.x - top.x) / (bot.y - top.y);
        (first < end).then_some(Edge { x_top: top.x, y_top: top.y, dxdy, first, end, tag, seq: 0 })
    }

    /// The edge, cut to `lines` when given; none when nothing of it is left.
    fn within(tag: u32, a: DVec2, b: DVec2, height: u32, lines: &Option<Range<u32>>) -> Option<Edge> {
        let mut e = Edge::new(tag, a, b, height)?;
        if let Some(lines) = lines {
            (e.first, e.end) = (e.first.max(lines.start), e.end.min(lines.end));
        }
        (e.first < e.end).then_some(e)
    }

    #[inline]
    fn x_at(&self, line: u32) -> f64 {
        x_on(self.x_top, self.y_top, self.dxdy, line)
    }
}

/// Where the edge through `(x_top, y_top)` with slope `dxdy` crosses the centre of `line`,
/// evaluated from its top vertex (so every holder of the edge gets the same bits).
#[inline]
fn x_on(x_top: f64, y_top: f64, dxdy: f64, line: u32) -> f64 {
    x_top + (line as f64 + 0.5 - y_top) * dxdy
}

/// Where an edge of polygon `tag` crosses the current scanline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Screen x of the crossing.
    pub x: f64,
    /// The tag of the polygon the edge belongs to.
    pub tag: u32,
    /// The line after the edge's last.
    end: u32,
    /// The edge's line equation, carried along so that stepping to the next line reads the
    /// active list alone, in order, not the table at scattered places.
    x_top: f64,
    y_top: f64,
    dxdy: f64,
}

impl Crossing {
    /// Edge `e`'s crossing with `line`.
    #[inline]
    fn of(e: &Edge, line: u32) -> Crossing {
        Crossing { x: e.x_at(line), tag: e.tag, end: e.end, x_top: e.x_top, y_top: e.y_top, dxdy: e.dxdy }
    }

    /// The same edge's crossing with `line`, as [`Edge::x_at`] finds it.
    #[inline]
    fn at(&self, line: u32) -> f64 {
        x_on(self.x_top, self.y_top, self.dxdy, line)
    }
}

/// The bits of `x` as an unsigned number in the order of [`f64::total_cmp`].
#[inline]
fn ordered_bits(x: f64) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | 1 << 63
    }
}

/// The `x` whose [`ordered_bits`] are `b`.
#[inline]
fn from_ordered_bits(b: u64) -> f64 {
    f64::from_bits(if b >> 63 == 1 { b & !(1 << 63) } else { !b })
}

/// Fewer keys than this are sorted by the standard library's sort alone.
const DISTRIBUTE_FROM: usize = 48;

/// Sorts `keys` (an x as [`ordered_bits`], then a distinct index) as `sort_unstable` does,
/// in about linear time when the x are spread over an interval (ours): the keys are dealt
/// into as many buckets as there are keys, by where their x falls between the least and the
/// greatest, in order (a counting sort into `spare`), and then each bucket is sorted by
/// itself. The bucket grows with x, so only keys in one bucket can be out of order. Keys
/// whose x are not all finite, or all equal, are sorted by `sort_unstable`. `counts` is
/// scratch.
fn sort_by_x(keys: &mut Vec<(u64, u32)>, spare: &mut Vec<(u64, u32)>, counts: &mut Vec<u32>) {
    let n = keys.len();
    let x = |k: &(u64, u32)| from_ordered_bits(k.0);
    if n < DISTRIBUTE_FROM {
        keys.sort_unstable();
        return;
    }
    let widen = |(lo, hi, finite): (f64, f64, bool), x: f64| (lo.min(x), hi.max(x), finite && x.is_finite());
    let (lo, hi, finite) = keys.iter().map(x).fold((f64::INFINITY, f64::NEG_INFINITY, true), widen);
    let per_unit = n as f64 / (hi - lo);
    if !finite || !per_unit.is_finite() {
        keys.sort_unstable();
        return;
    }
    let bucket = |k: &(u64, u32)| (((x(k) - lo) * per_unit) as usize).min(n - 1);
    counts.clear();
    counts.resize(n + 1, 0);
    for k in keys.iter() {
        counts[bucket(k) + 1] += 1;
    }
    for b in 0..n {
        counts[b + 1] += counts[b];
    }
    spare.clear();
    spare.resize(n, (0, 0));
    for k in keys.iter() {
        let slot = &mut counts[bucket(k)];
        spare[*slot as usize] = *k;
        *slot += 1;
    }
    // Each bucket now ends where the next began: `counts[b]` is bucket `b + 1`'s start.
    let mut start = 0;
    for &end in &counts[..n] {
        let end = end as usize;
        if end - start > 1 {
            spare[start..end].sort_unstable();
        }
        start = end;
    }
    std::mem::swap(keys, spare);
}

/// The first pixel whose centre lies at or right of `x`, clamped to `0..=width`:
/// `ceil(x - 0.5)` (one rounding instruction on the x86-64-v3 target; `NaN` gives 0).
#[inline]
pub fn boundary(x: f64, width: u32) -> u32 {
    (x - 0.5).ceil().clamp(0.0, width as f64) as u32
}

/// Edges bucketed by the first scanline they are active on.
#[derive(Debug, Clone, Default)]
pub struct EdgeTable {
    edges: Vec<Edge>,
    /// `edges[bucket[i]..bucket[i+1]]` start on line `lines.start + i`.
    bucket: Vec<u32>,
    lines: Range<u32>,
    height: u32,
    built: bool,
    /// The edges (indices into `edges`, increasing) that span more than [`LONG_EDGE`] lines:
    /// with them, a band's first active edges are found without reading every edge above it.
    long: Vec<u32>,
    /// The sorted edges' last buffer, kept for the next frame's sort.
    spare: Vec<Edge>,
    /// The lines edges are cut to, if any ([`EdgeTable::clear_to`]).
    within: Option<Range<u32>>,
    /// Sorted where it lies, with no second buffer ([`EdgeTable::one_frame`]).
    in_place: bool,
}

/// Empties `list` and gives it room for `n` items. A list short of room takes a new buffer:
/// growing the old one would copy its stale items (the bands' edge tables, each as long as
/// the longest band before it, did so at every band).
pub(crate) fn emptied_with_room<T>(list: &mut Vec<T>, n: usize) {
    list.clear();
    if list.capacity() < n {
        *list = Vec::with_capacity(n);
    }
}

/// The edges of the closed `ring` of polygon `tag`, in order, in an image `height` lines
/// high, cut to the lines `within` if given.
fn ring_edges<'a>(
    tag: u32,
    ring: &'a [DVec2],
    height: u32,
    within: &'a Option<Range<u32>>,
) -> impl Iterator<Item = Edge> + 'a {
    let from = ring.last().into_iter().chain(ring);
    from.zip(ring).filter_map(move |(&a, &b)| Edge::within(tag, a, b, height, within))
}

/// A table with at least this many edges is sorted by all threads.
const PARALLEL_SORT: usize = 1 << 16;

/// A table with at most this many edges is sorted where it lies, by the standard library's
/// stable sort (whose scratch for so few 40-byte edges is on the stack), not scattered into a
/// second buffer, and keeps no buckets.
const SORT_IN_PLACE: usize = 96;

/// Places the `edges` that start on the table's lines `lines` (counted from `lo`, the
/// table's first line) into `out`, which holds exactly those lines' buckets, in order.
fn scatter(edges: &[Edge], lo: u32, bucket: &[u32], lines: Range<usize>, out: &mut [Edge]) {
    let base = bucket[lines.start];
    let mut next: Vec<u32> = bucket[lines.clone()].iter().map(|&b| b - base).collect();
    for e in edges {
        let line = (e.first - lo) as usize;
        if lines.contains(&line) {
            let slot = &mut next[line - lines.start];
            out[*slot as usize] = *e;
            *slot += 1;
        }
    }
}

/// An edge spanning at most this many lines that starts this far above a band has ended
/// before it.
const LONG_EDGE: u32 = 32;

impl EdgeTable {
    /// An empty table for an image `height` lines high.
    pub fn new(height: u32) -> Self {
        EdgeTable { height, ..Default::default() }
    }

    /// An empty table for an image `height` lines high that is sorted once and dropped (a
    /// receiver's shadow polygons): its edges are numbered as they are added and sorted where
    /// they lie by line and number, by all threads when there are many, instead of scattered
    /// into a second buffer kept for the next frame (s3's floor holds a million shadow
    /// polygons' edges, 40 MB).
    pub fn one_frame(height: u32) -> Self {
        EdgeTable { height, in_place: true, ..Default::default() }
    }

    /// Empties the table, keeping its memory, for an image `height` lines high.
    pub fn clear(&mut self, height: u32) {
        self.edges.clear();
        self.bucket.clear();
        self.long.clear();
        self.height = height;
        self.lines = 0..0;
        self.built = false;
        self.within = None;
    }

    /// Empties the table, keeping its memory, for the lines `lines` of an image `height`
    /// lines high: edges added from now on are cut to those lines (the part of each edge on
    /// them, with the same line equation, so the same crossings).
    pub fn clear_to(&mut self, height: u32, lines: Range<u32>) {
        self.clear(height);
        self.within = Some(lines);
    }

    /// Makes room for `edges` more edges (without copying stale ones, when it is empty).
    pub(crate) fn reserve(&mut self, edges: usize) {
        if self.edges.is_empty() {
            emptied_with_room(&mut self.edges, edges);
        } else {
            self.edges.reserve(edges);
        }
    }

    /// Adds the edges of a closed ring of polygon `tag`. Rings of one tag combine by the
    /// even-odd rule.
    pub fn add_ring(&mut self, tag: u32, ring: &[DVec2]) {
        let start = self.edges.len();
        self.edges.extend(ring_edges(tag, ring, self.height, &self.within));
        if self.in_place {
            for (seq, e) in (start as u32..).zip(&mut self.edges[start..]) {
                e.seq = seq;
            }
        }
        self.built = false;
    }

    /// Adds one edge `a → b` tagged `tag`, on its own: an outline whose edges are not the
    /// rings of one polygon each (z-fail's far outline, whose tags are weights).
    pub(crate) fn add_edge(&mut self, tag: u32, a: DVec2, b: DVec2) {
        let seq = self.edges.len() as u32;
        self.edges.extend(Edge::within(tag, a, b, self.height, &self.within).map(|e| Edge { seq, ..e }));
        self.built = false;
    }

    /// The finished table of the rings of polygons `0..rings.len()` (ring `i` tagged `i`),
    /// for an image `height` lines high: the table [`EdgeTable::add_ring`] (ring by ring)
    /// and [`EdgeTable::finish`] build, sorted as it is made, with no unsorted list beside it
    /// (ours: z-fail's three million edges on s3 would be held twice, 88 MB each). A
    /// counting sort straight from the rings: the lines are cut into bands, and each band
    /// reads the rings that reach it (binned by [`bins`]), counts the edges that start on its
    /// lines, then works them out again and places them in its own stretch of the table, in
    /// the order added.
    pub(crate) fn of_rings<R: RingList + ?Sized>(height: u32, rings: &R) -> EdgeTable {
        let band = band_height(height);
        let bands: Vec<Range<u32>> =
            (0..height.div_ceil(band)).map(|b| b * band..((b + 1) * band).min(height)).collect();
        let bins = ring_bins(rings, band, height);
        // The edges of the rings reaching `lines` (band `b`) that start on them, in order.
        let starting = |(b, lines): (usize, &Range<u32>)| {
            let lines = lines.clone();
            let reaching = bins[b].iter().map(|&i| i as usize);
            reaching
                .flat_map(|i| ring_edges(i as u32, rings.ring(i), height, &None))
                .filter(move |e| lines.contains(&e.first))
        };
        let counts: Vec<(Vec<u32>, u32)> = bands
            .par_iter()
            .enumerate()
            .map(|(b, lines)| {
                let mut per_line = vec![0u32; lines.len()];
                let mut end = 0;
                for e in starting((b, lines)) {
                    per_line[(e.first - lines.start) as usize] += 1;
                    end = end.max(e.end);
                }
                (per_line, end)
            })
            .collect();
        let per_line: Vec<u32> = counts.iter().flat_map(|(c, _)| c.iter().copied()).collect();
        let mut table = EdgeTable { height, built: true, ..Default::default() };
        let (Some(lo), Some(hi)) = (per_line.iter().position(|&c| c > 0), counts.iter().map(|c| c.1).max()) else {
            return table;
        };
        table.lines = lo as u32..hi;
        table.bucket.push(0);
        for &c in &per_line[lo..hi as usize] {
            table.bucket.push(table.bucket.last().copied().unwrap_or(0) + c);
        }
        let total = table.bucket.last().copied().unwrap_or(0) as usize;
        table.edges.par_extend(rayon::iter::repeat_n(Edge::NONE, total));
        let lengths = counts.iter().map(|(c, _)| c.iter().sum::<u32>() as usize);
        let stretches = stretches(&mut table.edges, lengths);
        let placed = bands.par_iter().enumerate().zip(counts).zip(stretches);
        placed.for_each(|(((b, lines), (per_line, _)), stretch)| {
            let mut next = starts(per_line.iter().map(|&c| c as usize));
            for e in starting((b, lines)) {
                let slot = &mut next[(e.first - lines.start) as usize];
                stretch[*slot] = e;
                *slot += 1;
            }
        });
        table.mark_long(true);
        table
    }

    /// The edges of `parts` (tables made alike, none sorted yet), one part after another,
    /// the tags of part `k` raised by `tags[k]`: the table adding their rings in turn would
    /// build. Copied by all threads, each part into its own stretch (s3's floor under
    /// Bouknight-Kelley joins 1.47 million edges, 59 MB, from its pieces: on one thread 4 ms
    /// in a frame that reuses the last frame's memory, 75-95 ms in a process's first frame,
    /// where every page is fresh).
    pub(crate) fn joined(parts: Vec<EdgeTable>, tags: &[u32]) -> Option<EdgeTable> {
        let starts = starts(parts.iter().map(|t| t.edges.len()));
        let in_place = parts.first()?.in_place;
        let edges = {
            let lists: Vec<&[Edge]> = parts.iter().map(|t| &t.edges[..]).collect();
            // A part sorted where it lies numbers its edges from 0; the join numbers them on.
            crate::pieces::joined(&lists, |k, e| Edge {
                tag: e.tag + tags[k],
                seq: if in_place { e.seq + starts[k] as u32 } else { e.seq },
                ..*e
            })
        };
        let mut parts = parts.into_iter();
        let first = parts.next()?;
        crate::pieces::let_go(parts.collect());
        Some(EdgeTable { edges, built: false, ..first })
    }

    /// Sorts the edges into buckets by first line (a counting sort, stable: a line's edges
    /// keep the order they were added in). Call it after the last `add_ring` and before
    /// walking the table.
    pub fn finish(&mut self) {
        if self.built {
            return;
        }
        self.built = true;
        if self.edges.is_empty() {
            self.lines = 0..0;
            self.bucket.clear();
            return;
        }
        let threads = rayon::current_num_threads();
        let parallel = threads > 1 && self.edges.len() >= PARALLEL_SORT;
        let (lo, hi) = if parallel {
            self.edges
                .par_iter()
                .map(|e| (e.first, e.end))
                .reduce(|| (u32::MAX, 0), |a, b| (a.0.min(b.0), a.1.max(b.1)))
        } else {
            self.edges.iter().fold((u32::MAX, 0), |(lo, hi), e| (lo.min(e.first), hi.max(e.end)))
        };
        self.lines = lo..hi.max(lo);
        self.bucket.clear();
        if self.edges.len() <= SORT_IN_PLACE {
            // A stable sort by first line orders them as the buckets do, with no second
            // buffer and no bucket per line: a line's first edge is found by bisection
            // (half a million receivers' small tables each kept both, 80 MB on s3).
            self.edges.sort_by_key(|e| e.first);
            self.mark_long(false);
            return;
        }
        if self.in_place {
            self.sort_in_place(parallel);
            return;
        }
        let n = (self.lines.end - lo) as usize;
        self.bucket.resize(n + 1, 0);
        let count = |edges: &[Edge], per_line: &mut [u32]| {
            for e in edges {
                per_line[(e.first - lo) as usize] += 1;
            }
        };
        if parallel {
            let per_line = self
                .edges
                .par_chunks(PARALLEL_SORT)
                .map(|chunk| {
                    let mut per_line = vec![0u32; n];
                    count(chunk, &mut per_line);
                    per_line
                })
                .reduce_with(|mut a, b| {
                    a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
                    a
                })
                .unwrap_or_default();
            self.bucket[1..].copy_from_slice(&per_line);
        } else {
            count(&self.edges, &mut self.bucket[1..]);
        }
        for i in 0..n {
            self.bucket[i + 1] += self.bucket[i];
        }
        let mut sorted = std::mem::take(&mut self.spare);
        emptied_with_room(&mut sorted, self.edges.len());
        // A fresh list of millions of edges is first touched here: in parallel, its pages
        // are found and zeroed by every thread.
        if parallel {
            sorted.par_extend(rayon::iter::repeat_n(Edge::NONE, self.edges.len()));
            self.scatter_in_bands(&mut sorted, threads);
        } else {
            sorted.resize(self.edges.len(), Edge::NONE);
            scatter(&self.edges, lo, &self.bucket, 0..n, &mut sorted);
        }
        self.spare = std::mem::replace(&mut self.edges, sorted);
        self.mark_long(parallel);
    }

    /// Sorts a [`EdgeTable::one_frame`] table where it lies, by first line and then the
    /// order added (the order the buckets give), and finds its buckets.
    fn sort_in_place(&mut self, parallel: bool) {
        let key = |e: &Edge| (e.first, e.seq);
        if parallel {
            self.edges.par_sort_unstable_by_key(key);
        } else {
            self.edges.sort_unstable_by_key(key);
        }
        let lo = self.lines.start;
        self.bucket.extend((lo..=self.lines.end).map(|line| self.edges.partition_point(|e| e.first < line) as u32));
        self.mark_long(parallel);
    }

    /// Lists the sorted edges longer than [`LONG_EDGE`] lines.
    fn mark_long(&mut self, parallel: bool) {
        self.long.clear();
        let is_long = |(i, e): (usize, &Edge)| (e.end - e.first > LONG_EDGE).then_some(i as u32);
        if parallel {
            self.long.par_extend(self.edges.par_iter().enumerate().filter_map(is_long));
        } else {
            self.long.extend(self.edges.iter().enumerate().filter_map(is_long));
        }
    }

    /// The scatter of the counting sort, shared among `bands` threads: the lines are cut into
    /// bands holding about as many edges each, and each band reads every edge and places
    /// those that start in it, in order, in its own stretch of `sorted`.
    fn scatter_in_bands(&self, sorted: &mut [Edge], bands: usize) {
        let (lo, n, total) = (self.lines.start, self.bucket.len() - 1, self.edges.len());
        let mut cuts: Vec<usize> =
            (0..=bands).map(|k| self.bucket.partition_point(|&b| (b as usize) < total * k / bands)).collect();
        cuts[0] = 0;
        cuts[bands] = n;
        let bands: Vec<Range<usize>> = cuts.windows(2).map(|w| w[0]..w[1].max(w[0])).collect();
        let lengths = bands.iter().map(|lines| (self.bucket[lines.end] - self.bucket[lines.start]) as usize);
        let stretches = stretches(sorted, lengths);
        bands
            .into_par_iter()
            .zip(stretches)
            .for_each(|(lines, stretch)| scatter(&self.edges, lo, &self.bucket, lines, stretch));
    }

    /// Every edge as (tag, first line, end line, x at its top, y at its top, dx/dy).
    pub fn edges(&self) -> impl Iterator<Item = (u32, u32, u32, f64, f64, f64)> + '_ {
        self.edges.iter().map(|e| (e.tag, e.first, e.end, e.x_top, e.y_top, e.dxdy))
    }

    /// Bytes held by the table.
    pub fn bytes(&self) -> usize {
        (self.edges.capacity() + self.spare.capacity()) * std::mem::size_of::<Edge>()
            + (self.bucket.capacity() + self.long.capacity()) * 4
    }

    /// Number of edges.
    pub fn len(&self) -> usize {
        self.edges.len()
    }

    /// The number of edges that start above `line`, one of the table's lines or its end:
    /// from the buckets, or by bisection in a small table, which has none.
    fn before(&self, line: u32) -> usize {
        match self.bucket.is_empty() {
            true => self.edges.partition_point(|e| e.first < line),
            false => self.bucket[(line - self.lines.start) as usize] as usize,
        }
    }
}

/// The active edge table: walks an [`EdgeTable`] down a range of lines, giving each line's
/// crossings sorted by x. Edges enter from their bucket and leave after their last line; the
/// list stays sorted by an insertion sort, which costs little because order changes only
/// where edges cross, and entering edges are sorted apart and merged in.
#[derive(Debug)]
pub struct ActiveEdges<'a> {
    table: &'a EdgeTable,
    next: u32,
    end: u32,
    active: Vec<Crossing>,
    incoming: Vec<Crossing>,
    /// Scratch: the entering edges' keys (their crossings' x as ordered bits, then their
    /// place in the table), sorted in place of the crossings themselves.
    order: Vec<(u64, u32)>,
    /// Scratch for sorting `order` ([`sort_by_x`]).
    spare_order: Vec<(u64, u32)>,
    counts: Vec<u32>,
    /// The first edge of the table not entered yet (edges are sorted by first line, and the
    /// walk takes one line after another).
    cursor: usize,
    current: Option<u32>,
    /// Edges that entered so far (a counter for the stats).
    pub entered: u64,
}

impl<'a> ActiveEdges<'a> {
    /// Walks a finished `table` over `lines` (clamped to the lines the table covers). A range
    /// that starts below the table's first line picks up the edges already active there.
    pub fn new(table: &'a EdgeTable, lines: Range<u32>) -> ActiveEdges<'a> {
        debug_assert!(table.built, "EdgeTable::finish must be called before walking");
        let start = lines.start.max(table.lines.start);
        let end = lines.end.min(table.lines.end);
        let (mut active, mut cursor) = (Vec::new(), 0);
        if start > table.lines.start && start < end {
            let upto = table.before(start);
            cursor = upto;
            // Above `near`, only the long edges can reach `start`; taken in index order, the
            // candidates are the same as reading every edge above `start`.
            let near = table.before(start.saturating_sub(LONG_EDGE).max(table.lines.start));
            let long = &table.long[..table.long.partition_point(|&i| (i as usize) < near)];
            for i in long.iter().map(|&i| i as usize).chain(near..upto) {
                let e = &table.edges[i];
                if e.end > start {
                    active.push(Crossing::of(e, start));
                }
            }
            active.sort_unstable_by(|a, b| a.x.total_cmp(&b.x));
        }
        ActiveEdges {
            table,
            next: start,
            end,
            active,
            incoming: Vec::new(),
            order: Vec::new(),
            spare_order: Vec::new(),
            counts: Vec::new(),
            cursor,
            current: None,
            entered: 0,
        }
    }

    /// Advances to the next line: its index and its crossings in increasing x.
    pub fn next_line(&mut self) -> Option<(u32, &[Crossing])> {
        if self.next >= self.end {
            return None;
        }
        let line = self.next;
        self.next += 1;
        // Edges whose last line has passed leave; the others step to this line (one pass).
        // An edge moves only when one before it has left.
        let active = &mut self.active[..];
        let mut kept = 0;
        for i in 0..active.len() {
            if active[i].end > line {
                if kept != i {
                    active[kept] = active[i];
                }
                let c = &mut active[kept];
                c.x = c.at(line);
                kept += 1;
            }
        }
        self.active.truncate(kept);
        // Insertion sort: the list was sorted on the previous line, and only edges that
        // cross each other between two lines are out of order now (the others are passed
        // over without being moved).
        let active = &mut self.active[..];
        for i in 1..active.len() {
            if active[i - 1].x <= active[i].x {
                continue;
            }
            let item = active[i];
            let mut j = i;
            while j > 0 && active[j - 1].x > item.x {
                active[j] = active[j - 1];
                j -= 1;
            }
            active[j] = item;
        }
        // Edges that start on this line are sorted among themselves (by x, then by their
        // order in the table), then merged in. The sort moves sixteen-byte keys, not the
        // crossings, and deals them into buckets by x first ([`sort_by_x`]; ours: s3's
        // lines each have about a thousand entering edges).
        let rest = &self.table.edges[self.cursor..];
        let entering = &rest[..rest.iter().take_while(|e| e.first == line).count()];
        self.cursor += entering.len();
        if !entering.is_empty() {
            self.entered += entering.len() as u64;
            self.order.clear();
            self.order.extend(entering.iter().enumerate().map(|(i, e)| (ordered_bits(e.x_at(line)), i as u32)));
            sort_by_x(&mut self.order, &mut self.spare_order, &mut self.counts);
            self.incoming.clear();
            self.incoming.extend(self.order.iter().map(|&(_, i)| Crossing::of(&entering[i as usize], line)));
            self.merge_incoming();
        }
        self.current = Some(line);
        Some((line, &self.active))
    }

    /// Merges the sorted `incoming` into the sorted `active` list, in place from the back:
    /// the active edges left of every entering one are not moved (an entering edge goes after
    /// the active edges at its own x).
    fn merge_incoming(&mut self) {
        let (mut i, mut j) = (self.active.len(), self.incoming.len());
        self.active.extend_from_slice(&self.incoming);
        let (active, incoming) = (&mut self.active[..], &self.incoming[..]);
        let mut k = active.len();
        while j > 0 {
            k -= 1;
            if i > 0 && active[i - 1].x > incoming[j - 1].x {
                i -= 1;
                active[k] = active[i];
            } else {
                j -= 1;
                active[k] = incoming[j];
            }
        }
    }

    /// Steps forward to `line` (which must not be behind the last line walked) and gives its
    /// crossings; none on lines the table does not reach. More than [`LONG_EDGE`] lines
    /// ahead, the walk starts afresh at `line`, reading the table there (as [`Self::new`]
    /// does), instead of stepping through every line between: a band of lines far down the
    /// frame does not walk the lines above it.
    pub fn advance_to(&mut self, line: u32) -> &[Crossing] {
        if line > self.next.saturating_add(LONG_EDGE) && line < self.end {
            let entered = self.entered;
            *self = ActiveEdges::new(self.table, line..self.end);
            self.entered = entered;
        }
        while self.next <= line && self.next_line().is_some() {}
        if self.current == Some(line) {
            &self.active
        } else {
            &[]
        }
    }

    /// Bytes held by the walker.
    pub fn bytes(&self) -> usize {
        (self.active.capacity() + self.incoming.capacity()) * std::mem::size_of::<Crossing>()
            + (self.order.capacity() + self.spare_order.capacity()) * std::mem::size_of::<(u64, u32)>()
            + self.counts.capacity() * 4
    }
}

/// Calls `f(line, x0, x1)` for every pixel span `x0..x1` (non-empty, within `0..width`)
/// inside the even-odd region of a single polygon's rings, line by line. `table` is scratch
/// space, reused between calls.
pub fn for_each_span(
    table: &mut EdgeTable,
    rings: &[&[DVec2]],
    width: u32,
    height: u32,
    lines: Range<u32>,
    mut f: impl FnMut(u32, u32, u32),
) {
    if let [ring] = rings {
        if monotone_spans(ring, width, height, lines.clone(), &mut f) {
            return;
        }
    }
    table_spans(table, rings, width, height, lines, f);
}

/// The lines on which [`for_each_span`] can find spans of `rings`: every edge is active
/// between the pixel-centre boundaries of its ends' y ([`Edge::new`]), so all of them lie
/// between the boundaries of the least and the greatest finite y (an edge with an end that
/// is not finite is never active). Empty when no point is finite. A rasteriser that shares
/// the lines among threads in bands draws a ring only in the bands it reaches (ours).
pub fn lines_reached(rings: &[&[DVec2]], height: u32) -> Range<u32> {
    let ys = rings.iter().flat_map(|r| r.iter()).filter(|p| p.is_finite()).map(|p| p.y);
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| (lo.min(y), hi.max(y)));
    if lo > hi {
        return 0..0;
    }
    boundary(lo, height)..boundary(hi, height)
}

/// [`bins`] of `rings`: each band's rings, found from the lines each ring reaches
/// ([`lines_reached`], worked out in parallel).
pub(crate) fn ring_bins<R: RingList + ?Sized>(rings: &R, band: u32, height: u32) -> Vec<Vec<u32>> {
    let reach: Vec<Range<u32>> =
        (0..rings.count()).into_par_iter().map(|i| lines_reached(&[rings.ring(i)], height)).collect();
    bins(&reach, band, height)
}

/// For each band of `band` lines from the top of an image `height` lines high, the indices of
/// the rings whose lines (`reach`, as [`lines_reached`] gives them) meet it, in order: a
/// band then reads only its own rings, not every ring's lines (ours; z-fail's million caps
/// on s3, read by eighteen bands, twice each). Worked out by pieces of the rings in
/// parallel, each piece's lists joined in order.
pub(crate) fn bins(reach: &[Range<u32>], band: u32, height: u32) -> Vec<Vec<u32>> {
    let band = band.max(1);
    let count = height.div_ceil(band) as usize;
    let pieces: Vec<Vec<Vec<u32>>> = reach
        .par_chunks(1 << 16)
        .enumerate()
        .map(|(k, piece)| {
            let mut lists = vec![Vec::new(); count];
            for (i, r) in (k << 16..).zip(piece).filter(|(_, r)| !r.is_empty()) {
                for list in &mut lists[(r.start / band) as usize..=((r.end - 1) / band) as usize] {
                    list.push(i as u32);
                }
            }
            lists
        })
        .collect();
    (0..count).into_par_iter().map(|b| pieces.iter().flat_map(|p| p[b].iter().copied()).collect()).collect()
}

/// [`for_each_span`] through the edge table and the active edge table: any rings.
fn table_spans(
    table: &mut EdgeTable,
    rings: &[&[DVec2]],
    width: u32,
    height: u32,
    lines: Range<u32>,
    mut f: impl FnMut(u32, u32, u32),
) {
    table.clear(height);
    for r in rings {
        table.add_ring(0, r);
    }
    table.finish();
    let mut aet = ActiveEdges::new(table, lines);
    while let Some((line, xs)) = aet.next_line() {
        for pair in xs.chunks_exact(2) {
            let (x0, x1) = (boundary(pair[0].x, width), boundary(pair[1].x, width));
            if x0 < x1 {
                f(line, x0, x1);
            }
        }
    }
}

/// The spans of one ring that is monotone in y (its y goes down once and up once, as every
/// convex polygon's does), walked down its two chains without an edge table: the same edges
/// and crossings as the table's, so the same spans, for a fraction of the cost on small
/// polygons. Returns `false`, having done nothing, for any other ring.
fn monotone_spans(
    ring: &[DVec2],
    width: u32,
    height: u32,
    lines: Range<u32>,
    f: &mut impl FnMut(u32, u32, u32),
) -> bool {
    let n = ring.len();
    if n < 3 || !ring.iter().all(|p| p.is_finite()) {
        return false;
    }
    // Count the turns of y's direction around the ring (flat edges turn nothing).
    let dy = |i: usize| ring[(i + 1) % n].y - ring[i].y;
    let Some(mut down) = (0..n).rev().map(dy).find(|&d| d != 0.0).map(|d| d > 0.0) else {
        return true; // flat: no edge crosses a line
    };
    let mut turns = 0;
    for d in (0..n).map(dy).filter(|&d| d != 0.0) {
        turns += usize::from((d > 0.0) != down);
        down = d > 0.0;
    }
    if turns != 2 {
        return false;
    }
    let top = (0..n).min_by(|&a, &b| ring[a].y.total_cmp(&ring[b].y)).unwrap_or(0);
    // The two chains, walked from the top vertex one way round and the other, a pair of
    // edges at a time: on the lines where both stay active, the span lies between them.
    let mut chains = [Chain { ring, at: top, step: 1 }, Chain { ring, at: top, step: n - 1 }];
    let (mut a, mut b) = (chains[0].next(height), chains[1].next(height));
    while let (Some(ea), Some(eb)) = (a, b) {
        for line in lines.start.max(ea.first.max(eb.first))..lines.end.min(ea.end.min(eb.end)) {
            let (xa, xb) = (ea.x_at(line), eb.x_at(line));
            let (xl, xr) = if xb < xa { (xb, xa) } else { (xa, xb) };
            let (x0, x1) = (boundary(xl, width), boundary(xr, width));
            if x0 < x1 {
                f(line, x0, x1);
            }
        }
        if ea.end <= eb.end {
            a = chains[0].next(height);
        }
        if eb.end <= ea.end {
            b = chains[1].next(height);
        }
    }
    true
}

/// One side of a y-monotone ring, walked down from its top vertex.
struct Chain<'r> {
    ring: &'r [DVec2],
    /// The vertex the chain has reached.
    at: usize,
    /// `1` or `len − 1`: which way round the ring.
    step: usize,
}

impl Chain<'_> {
    /// The chain's next edge that is active on some line; `None` at the bottom.
    fn next(&mut self, height: u32) -> Option<Edge> {
        loop {
            let next = (self.at + self.step) % self.ring.len();
            let (a, b) = (self.ring[self.at], self.ring[next]);
            if b.y < a.y || next == self.at {
                return None;
            }
            self.at = next;
            if let Some(e) = Edge::new(0, a, b, height) {
                return Some(e);
            }
        }
    }
}

/// The coverage step, written once: walking a line's crossings in order, which tagged
/// polygons cover the pixels reached, under the even-odd rule (each crossing of a tag's
/// boundary toggles it). A tag opens at the first pixel right of a crossing and closes at the
/// next. The open tags stay in the order they opened except where a closed one's slot was
/// filled by the last. Toggling is O(1) in a dense set (each tag knows its slot), or a
/// search of the open tags for a tag beyond its numbering.
///
/// Watkins' visibility keeps the open tags as the span's covering set (dense over a band's
/// members), the overlay walker turns open/close pairs into per-tag intervals (dense over a
/// receiver's polygons), and Crow's walker into covered pieces of a run (dense over the
/// shadow polygons).
#[derive(Debug, Clone, Default)]
pub(crate) struct OpenSet {
    /// `slot[tag]`: the tag's index in `tags` while open, else `CLOSED` (empty: sparse).
    slot: Vec<u32>,
    tags: Vec<u32>,
    starts: Vec<u32>,
}

const CLOSED: u32 = u32::MAX;

impl OpenSet {
    /// An empty dense set for tags `0..tags`.
    pub(crate) fn new(tags: usize) -> OpenSet {
        OpenSet { slot: vec![CLOSED; tags], tags: Vec::new(), starts: Vec::new() }
    }

    /// Empties the set and makes it dense for tags `0..tags` at least, keeping its memory
    /// (it never shrinks: a set reset for many sizes in turn sets each slot once).
    pub(crate) fn reset(&mut self, tags: usize) {
        self.clear();
        // Every slot is closed after `clear`: only new ones need setting.
        if self.slot.len() < tags {
            self.slot.resize(tags, CLOSED);
        }
    }

    /// An empty sparse set, for any tags (a dense set takes the tags beyond its numbering
    /// the same way).
    #[cfg(test)]
    pub(crate) fn sparse() -> OpenSet {
        OpenSet::default()
    }

    fn slot_of(&self, tag: u32) -> u32 {
        // A tag beyond a dense set's numbering is looked for as in a sparse one.
        match self.slot.get(tag as usize) {
            Some(&slot) => slot,
            None => self.tags.iter().position(|&t| t == tag).map_or(CLOSED, |k| k as u32),
        }
    }

    fn set_slot(&mut self, tag: u32, slot: u32) {
        if let Some(s) = self.slot.get_mut(tag as usize) {
            *s = slot;
        }
    }

    /// Toggles `tag` at pixel `at`: opens it there, or closes it and returns where it opened.
    #[inline]
    pub(crate) fn toggle(&mut self, tag: u32, at: u32) -> Option<u32> {
        let slot = self.slot_of(tag);
        if slot == CLOSED {
            self.set_slot(tag, self.tags.len() as u32);
            self.tags.push(tag);
            self.starts.push(at);
            return None;
        }
        self.tags.swap_remove(slot as usize);
        let start = self.starts.swap_remove(slot as usize);
        if let Some(&moved) = self.tags.get(slot as usize) {
            self.set_slot(moved, slot);
        }
        self.set_slot(tag, CLOSED);
        Some(start)
    }

    /// The open tags.
    pub(crate) fn tags(&self) -> &[u32] {
        &self.tags
    }

    /// The open tags with the pixel each opened at.
    pub(crate) fn open(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.tags.iter().copied().zip(self.starts.iter().copied())
    }

    /// Moves every open tag's start to `at` (no later than it), as if it had opened there.
    pub(crate) fn restart_at(&mut self, at: u32) {
        for s in &mut self.starts {
            *s = at;
        }
    }

    /// Whether no tag is open.
    pub(crate) fn is_empty(&self) -> bool {
        self.tags.is_empty()
    }

    /// Closes every tag.
    pub(crate) fn clear(&mut self) {
        for i in 0..self.tags.len() {
            self.set_slot(self.tags[i], CLOSED);
        }
        self.tags.clear();
        self.starts.clear();
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        4 * (self.slot.capacity() + self.tags.capacity() + self.starts.capacity())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bucketed sort of entering edges' keys gives `sort_unstable`'s order: spread,
    /// clustered and nearly equal x, with infinities, NaN and signed zeros among them.
    #[test]
    fn sort_by_x_sorts_as_sort_unstable() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let (mut spare, mut counts) = (Vec::new(), Vec::new());
        let specials = [0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -f64::NAN, 1e300, -1e300, 5e-324];
        for case in 0..400 {
            let n = rng.gen_range(0..600);
            // Spread, clustered on a few values, or with a special value among them.
            let pick = |rng: &mut rand_chacha::ChaCha8Rng| match case % 4 {
                0 => rng.gen_range(-50.0..2000.0),
                1 => rng.gen_range(0..5) as f64 * 0.25,
                2 if rng.gen_bool(0.02) => specials[rng.gen_range(0..specials.len())],
                _ => rng.gen_range(100.0..100.000_001),
            };
            let mut keys: Vec<(u64, u32)> = (0..n).map(|i| (ordered_bits(pick(&mut rng)), i)).collect();
            let mut want = keys.clone();
            want.sort_unstable();
            sort_by_x(&mut keys, &mut spare, &mut counts);
            assert_eq!(keys, want, "case {case}");
        }
        for x in [0.0, -0.0, 1.5, -7.25, f64::INFINITY, f64::NEG_INFINITY, f64::MAX, 5e-324] {
            assert_eq!(from_ordered_bits(ordered_bits(x)).to_bits(), x.to_bits());
        }
    }

    /// The keys the walk sorts entering edges by order x as `f64::total_cmp` does: signed
    /// zeros, infinities, subnormals and random values of both signs, every pair.
    #[test]
    fn ordered_bits_order_as_total_cmp() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut xs = vec![0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::MIN_POSITIVE / 4.0, -f64::MIN_POSITIVE];
        xs.extend((0..200).map(|_| rng.gen_range(-1e3..1e3) * 10f64.powi(rng.gen_range(-300..300))));
        for &a in &xs {
            for &b in &xs {
                assert_eq!(ordered_bits(a).cmp(&ordered_bits(b)), a.total_cmp(&b), "{a} against {b}");
            }
        }
    }

    #[test]
    fn every_thread_gets_as_many_bands_of_at_most_64_lines() {
        for threads in 1..=4 {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            for height in [256, 480, 720, 1000, 1080, 1090, 2160, 4321] {
                let band = pool.install(|| band_height(height));
                let bands = height.div_ceil(band);
                assert!((8..=64).contains(&band), "{threads} threads, {height} lines: {band}");
                assert!(bands % threads as u32 == 0 && bands >= 4 * threads as u32, "{threads}, {height}: {bands}");
            }
            // A small image: bands of 8 lines at least.
            assert_eq!(pool.install(|| band_height(20)), 8);
        }
        let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        assert_eq!(two.install(|| band_height(1080)), 60);
    }

    #[test]
    fn a_large_table_built_and_sorted_by_several_threads_is_the_table_one_thread_builds() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
        // Triangles bunched toward the top, so that the bands hold unequal numbers of lines.
        let rings: Vec<Vec<DVec2>> = (0..3 * PARALLEL_SORT / 2)
            .map(|_| {
                let y = rng.gen_range(0.0f64..1.0).powi(3) * 1000.0;
                let at = DVec2::new(rng.gen_range(0.0..1900.0), y);
                (0..3).map(|_| at + DVec2::new(rng.gen_range(0.0..20.0), rng.gen_range(0.0..60.0))).collect()
            })
            .collect();
        let sorted_by = |threads: usize, one_frame: bool| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut t = if one_frame { EdgeTable::one_frame(1080) } else { EdgeTable::new(1080) };
                for (tag, ring) in rings.iter().enumerate() {
                    t.add_ring(tag as u32, ring);
                }
                t.finish();
                assert!(t.len() >= PARALLEL_SORT);
                (
                    t.edges().map(|e| (e.0, e.1, e.2, e.3.to_bits())).collect::<Vec<_>>(),
                    t.bucket.clone(),
                    t.long.clone(),
                )
            })
        };
        let one = sorted_by(1, false);
        for threads in [2, 3] {
            assert_eq!(sorted_by(threads, false), one, "{threads} threads");
        }
        // A table sorted where it lies, by one thread or several, is the same table.
        for threads in [1, 2] {
            assert_eq!(sorted_by(threads, true), one, "{threads} threads, sorted where it lies");
        }
        // And the table that adding the rings one by one builds, either way.
        for mut by_one in [EdgeTable::new(1080), EdgeTable::one_frame(1080)] {
            for (tag, ring) in rings.iter().enumerate() {
                by_one.add_ring(tag as u32, ring);
            }
            by_one.finish();
            let listed: Vec<_> = by_one.edges().map(|e| (e.0, e.1, e.2, e.3.to_bits())).collect();
            assert_eq!((listed, by_one.bucket.clone(), by_one.long.clone()), one);
        }
        // Stable: each line's edges in the order they were added (by tag, as added).
        let edges = &one.0;
        assert!(edges.windows(2).all(|w| (w[0].1, w[0].0) <= (w[1].1, w[1].0)));
    }

    fn spans(ring: &[DVec2], w: u32, h: u32) -> Vec<(u32, u32, u32)> {
        let mut t = EdgeTable::new(h);
        let mut v = Vec::new();
        for_each_span(&mut t, &[ring], w, h, 0..h, |y, a, b| v.push((y, a, b)));
        v
    }

    proptest::proptest! {
        /// The chain walk gives the edge table's spans, line for line, on every ring it
        /// takes (triangles, convex and concave polygons, bow-ties, rings reaching outside
        /// the image, vertices on pixel centres), and it takes every triangle.
        #[test]
        fn monotone_walk_matches_the_edge_table(
            points in proptest::collection::vec((-4i32..44, -4i32..36), 3..8),
            halves in proptest::bool::ANY,
            band in (0u32..32, 0u32..32),
        ) {
            let scale = if halves { 0.5 } else { 0.37 };
            let ring: Vec<DVec2> = points.iter().map(|&(x, y)| DVec2::new(x as f64 * scale * 2.0, y as f64 * scale * 2.0)).collect();
            let lines = band.0.min(band.1)..band.0.max(band.1) + 1;
            let (mut walked, mut table) = (Vec::new(), Vec::new());
            let took = monotone_spans(&ring, 40, 32, lines.clone(), &mut |y, a, b| walked.push((y, a, b)));
            table_spans(&mut EdgeTable::new(32), &[&ring], 40, 32, lines, |y, a, b| table.push((y, a, b)));
            proptest::prop_assert!(took || ring.len() > 3, "a triangle was refused: {ring:?}");
            if took {
                proptest::prop_assert_eq!(walked, table);
            }
        }

        /// Every span of a ring lies on the lines [`lines_reached`] names (a ring reaching
        /// past the image, with a point at infinity, or flat, included), and those are the
        /// lines its edges are active on, first to last, where its edges are all finite.
        #[test]
        fn a_rings_spans_lie_on_the_lines_it_reaches(
            points in proptest::collection::vec((-4i32..44, -4i32..36), 3..8),
            infinite in proptest::option::of(0usize..8),
        ) {
            let mut ring: Vec<DVec2> = points.iter().map(|&(x, y)| DVec2::new(x as f64 * 0.74, y as f64 * 0.74)).collect();
            if let Some(k) = infinite.filter(|&k| k < ring.len()) {
                ring[k].y = f64::INFINITY;
            }
            let reached = lines_reached(&[&ring], 32);
            let found = spans(&ring, 40, 32);
            for &(y, _, _) in &found {
                proptest::prop_assert!(reached.contains(&y), "line {y} outside {reached:?}: {ring:?}");
            }
            proptest::prop_assert!(reached.end <= 32);
            if ring.iter().all(|p| p.is_finite()) {
                let edges = (0..ring.len()).filter_map(|i| Edge::new(0, ring[i], ring[(i + 1) % ring.len()], 32));
                let active = edges.fold(None, |r: Option<Range<u32>>, e| {
                    Some(r.map_or(e.first..e.end, |r| r.start.min(e.first)..r.end.max(e.end)))
                });
                proptest::prop_assert_eq!(Some(reached.clone()).filter(|r| !r.is_empty()), active);
            }
        }
    }

    /// Each band's bin holds, in order, exactly the rings whose lines meet the band: the
    /// lists a filter of every ring's lines makes, band by band (empty reaches in none).
    #[test]
    fn a_band_bins_the_rings_that_reach_it() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let reach: Vec<Range<u32>> = (0..200_000)
            .map(|_| {
                let a = rng.gen_range(0..100u32);
                a..(a + rng.gen_range(0..30u32)).min(100)
            })
            .collect();
        let bins = bins(&reach, 8, 100);
        assert_eq!(bins.len(), 13);
        for (b, bin) in bins.iter().enumerate() {
            let lines = b as u32 * 8..(b as u32 * 8 + 8).min(100);
            let want: Vec<u32> = (0..reach.len() as u32)
                .filter(|&i| {
                    let r = &reach[i as usize];
                    !r.is_empty() && r.start < lines.end && lines.start < r.end
                })
                .collect();
            assert!(bin == &want, "band {b}: {} rings binned, {} reach it", bin.len(), want.len());
        }
    }

    /// A table sorted as it is made from the rings is the table adding them and sorting
    /// builds: the same edges in the same order, and the same crossings on every line walked
    /// from any line, at one thread and at several, for rings inside the image, reaching
    /// past it, with points at infinity, and for no rings at all.
    #[test]
    fn a_table_sorted_as_made_is_the_table_sorted_after() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        let mut rings: Vec<Vec<DVec2>> = (0..3000)
            .map(|_| {
                let at = DVec2::new(rng.gen_range(-10.0..90.0), rng.gen_range(-10.0..70.0));
                let n = rng.gen_range(3..7);
                (0..n).map(|_| at + DVec2::new(rng.gen_range(-6.0..6.0), rng.gen_range(-6.0..25.0))).collect()
            })
            .collect();
        rings[7][1].y = f64::INFINITY;
        rings[8][0] = DVec2::NAN;
        let listed = |t: &EdgeTable| t.edges().map(|e| (e.0, e.1, e.2, e.3.to_bits())).collect::<Vec<_>>();
        let walked = |t: &EdgeTable, from: u32| {
            let mut aet = ActiveEdges::new(t, from..60);
            let mut out = Vec::new();
            while let Some((line, xs)) = aet.next_line() {
                out.extend(xs.iter().map(|c| (line, c.tag, c.x.to_bits())));
            }
            out
        };
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                for count in [0, 5, 3000] {
                    let mut after = EdgeTable::new(60);
                    for (tag, ring) in rings[..count].iter().enumerate() {
                        after.add_ring(tag as u32, ring);
                    }
                    after.finish();
                    let made = EdgeTable::of_rings(60, &rings[..count]);
                    assert_eq!(listed(&made), listed(&after), "{threads} thread(s), {count} rings");
                    for from in [0, 17, 59] {
                        assert_eq!(walked(&made, from), walked(&after, from), "{threads}, {count}, from {from}");
                    }
                }
            });
        }
        assert!(EdgeTable::of_rings(60, &rings[..]).len() > 8000);
    }

    /// Tables of consecutive pieces of the rings, each numbering its own from 0, appended
    /// with their tags raised make the table that adding every ring in turn makes: the
    /// same edges, tags and order once sorted (where a tag were not raised, or a piece's
    /// order lost, the lists would differ).
    #[test]
    fn tables_of_pieces_joined_make_the_table_of_the_whole() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let rings: Vec<Vec<DVec2>> = (0..700)
            .map(|_| {
                let at = DVec2::new(rng.gen_range(0.0..80.0), rng.gen_range(0.0..50.0));
                (0..3).map(|_| at + DVec2::new(rng.gen_range(0.0..9.0), rng.gen_range(0.0..9.0))).collect()
            })
            .collect();
        let listed = |t: &EdgeTable| t.edges().map(|e| (e.0, e.1, e.2, e.3.to_bits())).collect::<Vec<_>>();
        let mut whole = EdgeTable::one_frame(60);
        for (tag, ring) in rings.iter().enumerate() {
            whole.add_ring(tag as u32, ring);
        }
        whole.finish();
        let pieces: Vec<EdgeTable> = rings
            .chunks(256)
            .map(|piece| {
                let mut t = EdgeTable::one_frame(60);
                piece.iter().enumerate().for_each(|(tag, ring)| t.add_ring(tag as u32, ring));
                t
            })
            .collect();
        let join = |tags: [u32; 3]| {
            let mut joined = EdgeTable::joined(pieces.clone(), &tags).unwrap_or_default();
            joined.finish();
            joined
        };
        assert!(whole.len() > 1500, "{}", whole.len());
        assert_eq!(listed(&join([0, 256, 512])), listed(&whole));
        let unraised = join([0, 0, 0]);
        assert_ne!(listed(&unraised), listed(&whole));
    }

    #[test]
    fn boundary_is_the_first_pixel_centre_at_or_right_of_x() {
        let cases = [
            (-3.0, 0),
            (0.0, 0),
            (0.5, 0),
            (0.50000001, 1),
            (1.0, 1),
            (1.5, 1),
            (2.49, 2),
            (7.5, 7),
            (9.9, 10),
            (10.5, 10),
            (1e9, 10),
            (f64::INFINITY, 10),
            (f64::NEG_INFINITY, 0),
            (f64::NAN, 0),
        ];
        for (x, want) in cases {
            assert_eq!(boundary(x, 10), want, "x = {x}");
        }
        // Between the clamps, pixel b's centre is at or right of x and pixel b - 1's left of it.
        let mut x = 0.25;
        while x < 9.75 {
            let b = boundary(x, 10);
            assert!(b as f64 + 0.5 >= x && (b as f64 - 0.5) < x, "x = {x}, b = {b}");
            x += 0.0625 + 1e-7;
        }
        assert_eq!(boundary(4.5, u32::MAX), 4);
        assert_eq!(boundary(1e300, u32::MAX), u32::MAX);
    }

    #[test]
    fn square_covers_the_pixel_centres_inside() {
        let sq = [DVec2::new(1.0, 1.0), DVec2::new(4.0, 1.0), DVec2::new(4.0, 3.0), DVec2::new(1.0, 3.0)];
        assert_eq!(spans(&sq, 8, 8), vec![(1, 1, 4), (2, 1, 4)]);
    }

    #[test]
    fn shared_edges_cover_each_centre_once() {
        // Two triangles sharing a diagonal tile a square: every centre covered exactly once.
        let a = [DVec2::new(0.0, 0.0), DVec2::new(7.3, 0.0), DVec2::new(0.0, 5.9)];
        let b = [DVec2::new(7.3, 0.0), DVec2::new(7.3, 5.9), DVec2::new(0.0, 5.9)];
        let mut count = [[0; 8]; 6];
        for (y, x0, x1) in spans(&a, 8, 6).into_iter().chain(spans(&b, 8, 6)) {
            for x in x0..x1 {
                count[y as usize][x as usize] += 1;
            }
        }
        for row in &count {
            assert_eq!(&row[..7], &[1; 7]);
        }
    }

    #[test]
    fn band_start_picks_up_active_edges() {
        let tri = [DVec2::new(0.0, 0.0), DVec2::new(10.0, 10.0), DVec2::new(0.0, 10.0)];
        let mut t = EdgeTable::new(10);
        t.add_ring(0, &tri);
        t.finish();
        let all: Vec<_> = {
            let mut a = ActiveEdges::new(&t, 0..10);
            let mut v = Vec::new();
            while let Some((y, xs)) = a.next_line() {
                v.push((y, xs.to_vec()));
            }
            v
        };
        let mut b = ActiveEdges::new(&t, 5..10);
        let (y, xs) = b.next_line().unwrap();
        assert_eq!((y, xs.to_vec()), all[5]);
    }

    /// Advancing far ahead starts the walk afresh there, with the crossings a walk through
    /// every line would have (compared sorted by x and tag: equal x may come in either
    /// order), over random rings and jumps of any length.
    #[test]
    fn advancing_far_ahead_gives_the_crossings_of_a_full_walk() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut t = EdgeTable::new(400);
        for tag in 0..300 {
            let (cx, cy) = (rng.gen_range(0.0..100.0), rng.gen_range(-20.0..420.0));
            let ring: Vec<DVec2> = (0..rng.gen_range(3..6))
                .map(|_| DVec2::new(cx + rng.gen_range(-30.0..30.0), cy + rng.gen_range(-90.0..90.0)))
                .collect();
            t.add_ring(tag, &ring);
        }
        t.finish();
        let key = |xs: &[Crossing]| {
            let mut k: Vec<(u64, u32)> = xs.iter().map(|c| (c.x.to_bits(), c.tag)).collect();
            k.sort_unstable();
            k
        };
        let mut full = ActiveEdges::new(&t, 0..400);
        let every: Vec<Vec<(u64, u32)>> = (0..400).map(|y| key(full.advance_to(y))).collect();
        for _ in 0..50 {
            let mut walk = ActiveEdges::new(&t, 0..400);
            let mut y = 0;
            while y < 400 {
                assert_eq!(key(walk.advance_to(y)), every[y as usize], "line {y}");
                y += if rng.gen_bool(0.3) { rng.gen_range(33..200) } else { 1 };
            }
        }
    }

    #[test]
    fn long_thin_edges_do_not_drift() {
        // A sliver 1e5 pixels long: each line's crossing equals the exact interpolation.
        let ring = [DVec2::new(0.0, 0.0), DVec2::new(1e5, 1000.0), DVec2::new(0.0, 0.3)];
        let mut t = EdgeTable::new(1000);
        t.add_ring(0, &ring);
        t.finish();
        let mut a = ActiveEdges::new(&t, 0..1000);
        while let Some((y, xs)) = a.next_line() {
            let exact = (y as f64 + 0.5) * 100.0;
            assert!(xs.iter().any(|c| (c.x - exact).abs() < 1e-9), "line {y}");
        }
    }

    /// The coverage step against a per-pixel even-odd count: for random tagged crossings on
    /// a line, the intervals the open set gives cover each pixel exactly when an odd number
    /// of that tag's crossings lie left of the pixel's centre.
    #[test]
    fn open_set_intervals_equal_the_even_odd_count_at_every_pixel() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1970);
        for _ in 0..500 {
            let (tags, width) = (rng.gen_range(1..6u32), 40u32);
            // Each tag crosses an even number of times, as a closed ring does.
            let mut xs: Vec<(f64, u32)> = Vec::new();
            for t in 0..tags {
                for _ in 0..2 * rng.gen_range(0..4) {
                    xs.push((rng.gen_range(-5.0..45.0), t));
                }
            }
            xs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut set = if rng.gen_bool(0.5) { OpenSet::new(tags as usize) } else { OpenSet::sparse() };
            let mut covered = vec![vec![false; width as usize]; tags as usize];
            for &(x, t) in &xs {
                if let Some(start) = set.toggle(t, boundary(x, width)) {
                    for px in start..boundary(x, width) {
                        covered[t as usize][px as usize] = true;
                    }
                }
            }
            assert!(set.is_empty(), "every tag closes");
            for t in 0..tags {
                for px in 0..width {
                    let centre = px as f64 + 0.5;
                    let left = xs.iter().filter(|&&(x, u)| u == t && x <= centre).count();
                    assert_eq!(covered[t as usize][px as usize], left % 2 == 1, "tag {t} pixel {px} of {xs:?}");
                }
            }
        }
    }
}
