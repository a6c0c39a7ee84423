//! Lone sheets (ours, not a paper's): which polygons of a flat arrangement no other polygon's
//! inside can meet, found without testing polygons in pairs.
//!
//! A *sheet* is a connected set of polygons, all wound the same way, that meet edge to edge,
//! each shared edge run once each way: the side of a closed mesh that faces a light, seen
//! from the light. Over a point off the edges, the number of the sheet's polygons is the
//! winding number of the sheet's boundary around it, because each shared edge is run once
//! each way and cancels. So when the boundary is one simple loop, wound as the polygons are,
//! no two polygons of the sheet overlap ([`clears_itself`] checks this).
//!
//! A polygon of such a sheet is *lone* when every cell of a uniform grid that its bounding
//! box meets is met by no other polygon's box but those of its own sheet: then nothing that
//! is not in its sheet meets it, and nothing in its sheet overlaps it. Both tests err only
//! one way: a polygon they cannot clear is simply not lone.
//!
//! The outline of a sheet's lone polygons ([`Lone::outlines`]) is their union's boundary,
//! rings whose even-odd inside is exactly that union.

use super::weiler_atherton::signed_area;
use super::{edge_loops, grid_rectangle, simple};
use glam::DVec2;
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::sync::atomic::{AtomicU32, Ordering};

/// No item (an edge with nothing across it).
pub(crate) const NO_ITEM: u32 = u32::MAX;

/// One polygon of the arrangement.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Item<'a> {
    /// Its bounding box (least, greatest corner).
    pub bounds: (DVec2, DVec2),
    /// For a polygon that may belong to a sheet: its outline, and for each edge (from
    /// corner `k` to `k + 1`) the item across it, or [`NO_ITEM`]. The item across must run
    /// the same two points the other way and name this item across that edge, or have no
    /// `sheet` (debug builds check it): the joins trust it.
    pub sheet: Option<(&'a [DVec2], &'a [u32])>,
}

/// What [`find`] finds.
#[derive(Debug, Clone, Default)]
pub(crate) struct Lone {
    /// `lone[i]`: whether item `i` is lone.
    pub lone: Vec<bool>,
    /// Per sheet with lone polygons: one of them, and the rings of their union's boundary.
    pub outlines: Vec<(u32, Vec<Vec<DVec2>>)>,
    /// `sheet[i]`: the sheet of item `i` (its least item) where that sheet clears itself, so
    /// that no two of its items overlap; [`NO_ITEM`] for any other item.
    pub sheet: Vec<u32>,
}

/// Grid cells marked per item, on average, beyond which [`find`] gives up (a crowd of large
/// polygons): it then finds no polygon lone.
const MARKS_PER_ITEM: usize = 16;

/// The lone items of `items`, and the outlines of each sheet's lone items.
pub(crate) fn find(items: &[Item]) -> Lone {
    let n = items.len();
    let mut lone = Lone { lone: vec![false; n], outlines: Vec::new(), sheet: Vec::new() };
    let root = sheets(items);
    // Each sheet's members, by root, and whether its boundary is one simple loop (the
    // sheets in parallel).
    let pairs = root.par_iter().enumerate().filter(|(_, &r)| r != NO_ITEM).map(|(i, &r)| (r, i as u32));
    let members = crate::pieces::grouped(pairs.collect());
    // `valid[r]`: whether the sheet rooted at item `r` clears itself.
    let mut valid = vec![false; n];
    for (r, ok) in members.par_iter().map(|(r, m)| (*r, clears_itself(items, &root, m))).collect::<Vec<_>>() {
        valid[r as usize] = ok;
    }
    let in_valid = |i: usize| root[i] != NO_ITEM && valid[root[i] as usize];
    lone.sheet = (0..n).into_par_iter().map(|i| if in_valid(i) { root[i] } else { NO_ITEM }).collect();
    // The grid: each cell holds the one owner whose boxes meet it, or CONFLICT.
    let owner = |i: usize| if in_valid(i) { root[i] } else { (n + i) as u32 };
    let Some(grid) = Grid::new(items, owner) else { return lone };
    lone.lone = (0..n).into_par_iter().map(|i| in_valid(i) && grid.only(i, root[i])).collect();
    lone.outlines = members
        .par_iter()
        .filter_map(|(_, m)| {
            let first = *m.iter().find(|&&i| lone.lone[i as usize])?;
            Some((first, outline(items, &lone.lone, m)))
        })
        .collect();
    lone
}

/// Each item's sheet (the least item of it), or [`NO_ITEM`] for items that are in none: the
/// items joined across their shared edges where both are wound the same way. Every pair is
/// joined by all threads ([`Sets`]): each set's root is its least member, whatever the order
/// of the joins.
fn sheets<'a>(items: &[Item<'a>]) -> Vec<u32> {
    let sign = |i: usize| {
        let a = items[i].sheet.map_or(0.0, |(ring, _)| signed_area(ring));
        f64::from(a > 0.0) - f64::from(a < 0.0)
    };
    let signs: Vec<f64> = (0..items.len()).into_par_iter().map(sign).collect();
    let sets = Sets::new(items.len());
    let across_of = |item: &Item<'a>| item.sheet.map_or(&[][..], |(_, across)| across);
    // A pair names each other ([`Item::sheet`]), and is joined from its lesser item alone
    // (ours: half the joins), its shared edges taken as they are named: they run back.
    items.par_iter().enumerate().for_each(|(i, item)| {
        let i = i as u32;
        for &j in across_of(item) {
            if j == NO_ITEM || j < i || j as usize >= items.len() || items[j as usize].sheet.is_none() {
                continue;
            }
            debug_assert!(runs_back(items, i, j) && runs_back(items, j, i), "items {i} and {j} do not run back");
            if signs[i as usize] != 0.0 && signs[i as usize] == signs[j as usize] {
                sets.join(i, j);
            }
        }
    });
    (0..items.len() as u32)
        .into_par_iter()
        .map(|i| if signs[i as usize] == 0.0 { NO_ITEM } else { sets.root(i) })
        .collect()
}

/// Disjoint sets of items that all threads join at once: each item's parent, a root its
/// own. A root is only ever hung under a smaller root, so each set's root is its least
/// member, whatever order the joins come in; a thread shortening a path (a parent replaced
/// by the grandparent) keeps every item in its set.
struct Sets {
    parent: Vec<AtomicU32>,
}

impl Sets {
    fn new(n: usize) -> Sets {
        let mut parent = Vec::new();
        parent.par_extend((0..n as u32).into_par_iter().map(AtomicU32::new));
        Sets { parent }
    }

    /// The root of `i`'s set.
    fn root(&self, mut i: u32) -> u32 {
        loop {
            let p = self.parent[i as usize].load(Ordering::Acquire);
            if p == i {
                return i;
            }
            let g = self.parent[p as usize].load(Ordering::Acquire);
            if g != p {
                let _ = self.parent[i as usize].compare_exchange(p, g, Ordering::AcqRel, Ordering::Acquire);
            }
            i = g;
        }
    }

    /// Joins the sets of `a` and `b`: the greater root hung under the lesser, if no other
    /// thread has hung it first (then again, from the new roots).
    fn join(&self, a: u32, b: u32) {
        loop {
            let (ra, rb) = (self.root(a), self.root(b));
            if ra == rb {
                return;
            }
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            if self.parent[hi as usize].compare_exchange(hi, lo, Ordering::AcqRel, Ordering::Acquire).is_ok() {
                return;
            }
        }
    }
}

/// Whether item `j` names `i` across every edge of `i` that names `j`, and runs it the
/// other way ([`Item::sheet`]'s promise, checked in debug builds).
fn runs_back(items: &[Item], i: u32, j: u32) -> bool {
    let (Some((ri, ai)), Some((rj, aj))) = (items[i as usize].sheet, items[j as usize].sheet) else { return false };
    // The corner after `k` of a ring of `n`, stepped round without a division.
    let next = |k: usize, n: usize| if k + 1 == n { 0 } else { k + 1 };
    (0..ri.len()).filter(|&k| ai[k] == j).all(|k| {
        let (a, b) = (ri[k], ri[next(k, ri.len())]);
        (0..rj.len()).any(|m| aj[m] == i && rj[m] == b && rj[next(m, rj.len())] == a)
    })
}

/// The directed edges of `members` with no member of `keep` across them (`keep(j)`), as
/// (from, to) points.
fn boundary(items: &[Item], members: &[u32], keep: impl Fn(u32) -> bool) -> Vec<(DVec2, DVec2)> {
    let mut edges = Vec::new();
    for &i in members {
        let Some((ring, across)) = items[i as usize].sheet else { continue };
        for k in 0..ring.len() {
            if across[k] == NO_ITEM || !keep(across[k]) {
                edges.push((ring[k], ring[(k + 1) % ring.len()]));
            }
        }
    }
    edges
}

/// Whether the boundary of sheet `members` is one simple loop wound as its polygons are
/// (not several loops, a corner passed twice, or edges that meet or cross): then no two of
/// its polygons overlap.
fn clears_itself(items: &[Item], root: &[u32], members: &[u32]) -> bool {
    let r = root[members[0] as usize];
    let edges = boundary(items, members, |j| root[j as usize] == r);
    let Some(rings) = chain(&edges) else { return false };
    let ([ring], Some((first, _))) = (&rings[..], items[members[0] as usize].sheet) else { return false };
    signed_area(ring) * signed_area(first) > 0.0 && simple(ring)
}

/// The rings of the union of `members` that are lone.
fn outline(items: &[Item], lone: &[bool], members: &[u32]) -> Vec<Vec<DVec2>> {
    let kept: Vec<u32> = members.iter().copied().filter(|&i| lone[i as usize]).collect();
    if kept.is_empty() {
        return Vec::new();
    }
    let edges = boundary(items, &kept, |j| lone[j as usize]);
    chain_all(&edges)
}

/// The key of a point, by its exact value.
fn key(p: DVec2) -> [u64; 2] {
    [p.x.to_bits(), p.y.to_bits()]
}

/// Directed edges chained into closed rings, each corner left by one edge only; `None` when
/// a corner is left by two, or an edge leads nowhere.
pub(crate) fn chain(edges: &[(DVec2, DVec2)]) -> Option<Vec<Vec<DVec2>>> {
    let ends: Vec<([u64; 2], [u64; 2])> = edges.iter().map(|&(a, b)| (key(a), key(b))).collect();
    let loops = edge_loops(&ends)?;
    Some(loops.into_iter().map(|l| l.into_iter().map(|e| edges[e].0).collect()).collect())
}

/// Directed edges (each corner left as often as it is reached) chained into closed rings.
pub(crate) fn chain_all(edges: &[(DVec2, DVec2)]) -> Vec<Vec<DVec2>> {
    let mut from: FxHashMap<[u64; 2], Vec<usize>> = FxHashMap::default();
    for (e, &(a, _)) in edges.iter().enumerate() {
        from.entry(key(a)).or_default().push(e);
    }
    let mut used = vec![false; edges.len()];
    let mut rings = Vec::new();
    for start in 0..edges.len() {
        let mut ring = Vec::new();
        let mut e = Some(start);
        while let Some(k) = e.filter(|&k| !used[k]) {
            used[k] = true;
            ring.push(edges[k].0);
            e = from.get(&key(edges[k].1)).and_then(|next| next.iter().copied().find(|&m| !used[m]));
        }
        if ring.len() >= 3 {
            rings.push(ring);
        }
    }
    rings
}

/// A uniform grid over the items' boxes whose cells hold one owner each.
struct Grid {
    /// Each cell's mark, as all threads left it.
    cells: Vec<AtomicU32>,
    /// Each item's cells: its first and last column, first and last row.
    rects: Vec<[u16; 4]>,
    /// Columns and rows.
    g: (usize, usize),
}

/// A cell no box meets.
const EMPTY: u32 = u32::MAX;
/// A cell the boxes of two owners meet.
const CONFLICT: u32 = u32::MAX - 1;

/// Most cells a grid has per item.
const CELLS_PER_ITEM: usize = 4;

impl Grid {
    /// Every item's box marked with `owner(i)`, on square cells as wide as the median box
    /// (fewer where that would make more than [`CELLS_PER_ITEM`] per item); `None` when that
    /// would mark more than [`MARKS_PER_ITEM`] cells per item.
    fn new(items: &[Item], owner: impl Fn(usize) -> u32 + Sync) -> Option<Grid> {
        let (lo, hi) = items.par_iter().map(|i| i.bounds).reduce_with(|a, b| (a.0.min(b.0), a.1.max(b.1)))?;
        let size = (hi - lo).max(DVec2::splat(1e-300));
        let mut widths: Vec<f64> = items.par_iter().map(|i| (i.bounds.1 - i.bounds.0).max_element()).collect();
        let k = widths.len() / 2;
        let median = *widths.select_nth_unstable_by(k, f64::total_cmp).1;
        let most = (CELLS_PER_ITEM * items.len()).max(1) as f64;
        let cell = median.max((size.x * size.y / most).sqrt()).max(1e-300);
        let count = |w: f64| ((w / cell).ceil() as usize).clamp(1, 4096);
        let g = (count(size.x), count(size.y));
        // Each item's cells, found once for the marks and the reads (at most 4,096 a side).
        let rects: Vec<[u16; 4]> = items
            .par_iter()
            .map(|item| {
                let (c0, c1, r0, r1) = grid_rectangle(lo, size, g, item.bounds);
                [c0, c1, r0, r1].map(|v| v as u16)
            })
            .collect();
        let marks: usize =
            rects.par_iter().map(|&[c0, c1, r0, r1]| usize::from(c1 + 1 - c0) * usize::from(r1 + 1 - r0)).sum();
        if marks > MARKS_PER_ITEM * items.len() + 1024 {
            return None;
        }
        // Marked by all threads: a cell's mark is the same whatever order its owners come in
        // (one owner, or CONFLICT), so each is merged into its cell atomically.
        let cells: Vec<AtomicU32> = (0..g.0 * g.1).into_par_iter().map(|_| AtomicU32::new(EMPTY)).collect();
        rects.par_iter().enumerate().for_each(|(i, &rect)| {
            let o = owner(i);
            let merge = |cell: u32| (cell != o && cell != CONFLICT).then_some(if cell == EMPTY { o } else { CONFLICT });
            // Nested loops over the rectangle: an iterator of iterators asks at every step
            // which one it is in.
            let [c0, c1, r0, r1] = rect.map(usize::from);
            for column in cells[c0 * g.1..(c1 + 1) * g.1].chunks(g.1) {
                for cell in &column[r0..=r1] {
                    let _ = cell.fetch_update(Ordering::Relaxed, Ordering::Relaxed, merge);
                }
            }
        });
        Some(Grid { cells, rects, g })
    }

    /// Whether every cell item `i` meets is held by `owner` alone.
    fn only(&self, i: usize, owner: u32) -> bool {
        let [c0, c1, r0, r1] = self.rects[i].map(usize::from);
        let column = |c: usize| &self.cells[c * self.g.1 + r0..=c * self.g.1 + r1];
        (c0..=c1).all(|c| column(c).iter().all(|cell| cell.load(Ordering::Relaxed) == owner))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::inside_even_odd as inside;

    /// Polygons' outlines, and for each the items across its edges.
    type Sheet = (Vec<Vec<DVec2>>, Vec<Vec<u32>>);

    /// Sets joined by all threads at once, in whatever order, have the roots one thread
    /// joining them in turn gives: each set's least member (40,000 random joins among
    /// 20,000 items, a few long chains among them).
    #[test]
    fn sets_joined_by_all_threads_are_rooted_at_their_least_member() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let n = 20_000u32;
        let mut pairs: Vec<(u32, u32)> = (0..40_000).map(|_| (rng.gen_range(0..n), rng.gen_range(0..n))).collect();
        pairs.extend((1..2_000).map(|i| (i * 7 % n, (i - 1) * 7 % n)));
        let sets = Sets::new(n as usize);
        pairs.par_iter().with_max_len(64).for_each(|&(a, b)| sets.join(a, b));
        // One thread: label every item with the least member of its connected component.
        let mut least: Vec<u32> = (0..n).collect();
        loop {
            let mut changed = false;
            for &(a, b) in &pairs {
                let m = least[a as usize].min(least[b as usize]);
                for i in [a, b] {
                    if least[i as usize] != m {
                        least[i as usize] = m;
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        let roots: Vec<u32> = (0..n).map(|i| sets.root(i)).collect();
        assert_eq!(roots, least);
        assert!(roots.iter().enumerate().filter(|&(i, &r)| i as u32 != r).count() > 10_000);
    }

    /// A fan of `n` triangles around `c`, corners at `radius(k)` and angle `turns * k / n`
    /// of a full turn: triangle `k` is (c, p_k, p_k+1), and its neighbours share the spokes.
    fn fan(c: DVec2, n: usize, turns: f64, radius: impl Fn(usize) -> f64) -> Sheet {
        let closed = turns == 1.0;
        let p = |k: usize| {
            let k = if closed { k % n } else { k };
            let a = std::f64::consts::TAU * turns * k as f64 / n as f64;
            c + DVec2::new(a.cos(), a.sin()) * radius(k)
        };
        let rings = (0..n).map(|k| vec![c, p(k), p(k + 1)]).collect();
        let across = (0..n)
            .map(|k| {
                let before = if k > 0 {
                    k - 1
                } else if closed {
                    n - 1
                } else {
                    NO_ITEM as usize
                };
                let after = if k + 1 < n {
                    k + 1
                } else if closed {
                    0
                } else {
                    NO_ITEM as usize
                };
                vec![before as u32, NO_ITEM, after as u32]
            })
            .collect();
        (rings, across)
    }

    fn bounds(ring: &[DVec2]) -> (DVec2, DVec2) {
        ring.iter().fold((ring[0], ring[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)))
    }

    /// Items for fans given as (rings, across), their indices offset fan by fan.
    fn items<'a>(fans: &'a [Sheet], shifted: &'a mut Vec<Vec<u32>>) -> Vec<Item<'a>> {
        let mut base = 0;
        for (rings, across) in fans {
            shifted.extend(across.iter().map(|a| a.iter().map(|&j| if j == NO_ITEM { j } else { j + base }).collect()));
            base += rings.len() as u32;
        }
        let rings = fans.iter().flat_map(|f| &f.0);
        rings.zip(shifted.iter()).map(|(r, a)| Item { bounds: bounds(r), sheet: Some((r, a)) }).collect()
    }

    #[test]
    fn a_disc_alone_is_lone_and_its_outline_is_its_rim() {
        let disc = fan(DVec2::ZERO, 24, 1.0, |_| 1.0);
        let mut across = Vec::new();
        let found = find(&items(std::slice::from_ref(&disc), &mut across));
        assert!(found.lone.iter().all(|&l| l));
        let [(_, rings)] = &found.outlines[..] else { panic!("{} outlines", found.outlines.len()) };
        assert_eq!(rings.len(), 1);
        assert_eq!(rings[0].len(), 24, "the rim's corners");
        let tri_area: f64 = disc.0.iter().map(|r| signed_area(r)).sum();
        assert!((signed_area(&rings[0]) - tri_area).abs() < 1e-12);
    }

    /// A fan that turns one and a quarter times round covers its first quarter twice: its
    /// boundary is one loop, but it crosses itself, and nothing in it is lone.
    #[test]
    fn a_sheet_that_folds_over_itself_is_not_lone() {
        let spiral = fan(DVec2::ZERO, 30, 1.25, |k| 1.0 + 0.02 * k as f64);
        let mut across = Vec::new();
        let found = find(&items(std::slice::from_ref(&spiral), &mut across));
        assert!(found.lone.iter().all(|&l| !l));
        assert!(found.outlines.is_empty());
    }

    /// A strip of `n` unit squares along x, each cut into two triangles, moved by `place`
    /// (a rotation and a shift): triangle 2k is the lower one of square k.
    fn strip(n: usize, place: impl Fn(DVec2) -> DVec2) -> Sheet {
        let (mut rings, mut across) = (Vec::new(), Vec::new());
        let p = |x: usize, y: usize| place(DVec2::new(x as f64, y as f64));
        let t = |i: usize| if i < 2 * n { i as u32 } else { NO_ITEM };
        for k in 0..n {
            let (lower, upper) = (2 * k, 2 * k + 1);
            rings.push(vec![p(k, 0), p(k + 1, 0), p(k + 1, 1)]);
            across.push(vec![NO_ITEM, t(upper + 2), upper as u32]);
            rings.push(vec![p(k, 0), p(k + 1, 1), p(k, 1)]);
            across.push(vec![lower as u32, NO_ITEM, lower.checked_sub(2).map_or(NO_ITEM, |l| l as u32)]);
        }
        (rings, across)
    }

    /// Two strips that cross: the triangles near the crossing are not lone, those far from
    /// it are; a third strip far away is lone whole. No lone triangle overlaps any other
    /// triangle, and the outlines hold exactly the lone triangles.
    #[test]
    fn crossing_sheets_keep_their_far_ends_lone() {
        let fans = [
            strip(20, |p| p),
            strip(20, |p| DVec2::new(10.5 - p.y, p.x - 10.0)),
            strip(20, |p| p + DVec2::new(0.0, 40.0)),
        ];
        let mut across = Vec::new();
        let its = items(&fans, &mut across);
        let found = find(&its);
        let lone = |f: usize, k: usize| found.lone[40 * f + k];
        assert!(lone(0, 0) && lone(0, 39) && !lone(0, 20) && !lone(0, 21));
        assert!(lone(1, 0) && lone(1, 39) && !lone(1, 20));
        assert!((0..40).all(|k| lone(2, k)));
        // Sampled: where two triangles overlap, neither is lone; the outlines' even-odd
        // inside is the lone triangles'.
        for i in 0..420 {
            for j in 0..500 {
                let q = DVec2::new(-0.5 + i as f64 * 0.05 + 0.0013, -10.5 + j as f64 * 0.1 + 0.0017);
                let over: Vec<usize> = (0..its.len()).filter(|&t| inside(its[t].sheet.unwrap().0, q)).collect();
                if over.len() > 1 {
                    assert!(over.iter().all(|&t| !found.lone[t]), "{q} under {over:?}");
                }
                let held = found.outlines.iter().flat_map(|o| &o.1).filter(|r| inside(r, q)).count() % 2 == 1;
                assert_eq!(held, over.len() == 1 && found.lone[over[0]], "{q}");
            }
        }
    }

    /// A polygon of no sheet (a cut piece) over a disc keeps the triangles under it from
    /// being lone, and is never lone itself.
    #[test]
    fn a_polygon_of_no_sheet_is_never_lone_and_shades_what_it_meets() {
        let disc = fan(DVec2::ZERO, 16, 1.0, |_| 1.0);
        let mut across = Vec::new();
        let mut its = items(std::slice::from_ref(&disc), &mut across);
        let square = [DVec2::new(0.5, -0.1), DVec2::new(0.7, -0.1), DVec2::new(0.7, 0.1), DVec2::new(0.5, 0.1)];
        its.push(Item { bounds: bounds(&square), sheet: None });
        let found = find(&its);
        assert!(!found.lone[16] && !found.lone[0] && !found.lone[15]);
        assert!(found.lone[8]);
    }

    /// A sheet whose boundary is two loops (a ring round a hole) is not cleared: its
    /// polygons are not lone, though none overlap.
    #[test]
    fn a_sheet_with_a_hole_is_not_cleared() {
        let n = 12;
        let p = |k: usize, r: f64| {
            let a = std::f64::consts::TAU * (k % n) as f64 / n as f64;
            DVec2::new(a.cos(), a.sin()) * r
        };
        // Quads between radius 1 and 2, each sharing its radial sides with its neighbours.
        let rings: Vec<Vec<DVec2>> = (0..n).map(|k| vec![p(k, 1.0), p(k, 2.0), p(k + 1, 2.0), p(k + 1, 1.0)]).collect();
        let across: Vec<Vec<u32>> =
            (0..n).map(|k| vec![((k + n - 1) % n) as u32, NO_ITEM, ((k + 1) % n) as u32, NO_ITEM]).collect();
        let its: Vec<Item> =
            rings.iter().zip(&across).map(|(r, a)| Item { bounds: bounds(r), sheet: Some((r, a)) }).collect();
        assert!(find(&its).lone.iter().all(|&l| !l));
    }
}
