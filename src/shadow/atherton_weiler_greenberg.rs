//! The two-pass object-space shadow algorithm of Atherton, Weiler & Greenberg ("Polygon
//! shadow generation", SIGGRAPH 1978), as the "Árnyékolás" notes lay it out:
//!
//! 1. **Hidden-surface removal from the light.** (a) The scene is transformed into the
//!    light's view: a perspective view for point, spot and area-light samples, split into the
//!    six 90° faces of a cube around the light so nothing is lost at the seams; a parallel
//!    view for a directional light. (b) The visible parts are found by Weiler & Atherton's
//!    area sorting (`visible`): a rough depth sort, then the front polygon's outline clips
//!    everything into inside and outside lists ([`crate::geometry::weiler_atherton`]); what
//!    lies inside and behind it is hidden, and when something inside lies in front after all
//!    (the sort was wrong) that part is resolved first, recursively. (c) The visible
//!    fragments are taken back onto their source polygons' planes in world space.
//! 2. **Merge.** The lit fragments become *surface-detail polygons* of their source polygons:
//!    the [`ShadowDatabase`]. It does not depend on the camera: build it once per light and
//!    render it from any number of views (`Renderer::with_shadow_database`), or export it.
//! 3. and 4. **The view pass.** Hidden-surface removal from the eye is the visibility stage;
//!    each visible run is lit exactly where its polygon's detail polygons cover it, found by
//!    walking the detail polygons with the shared edge and active-edge tables.
//!
//! Polygons that cast no shadow still receive light: they are left out of the sort and then
//! lit where no visible caster fragment lies in front of them. The pieces of a non-planar
//! face (split into a fan by the loader) never shadow each other: each gets its lit part
//! from a sort that leaves its sibling pieces out. Area lights get one database
//! per sample; the lit fraction is the share of samples that light a point.

use super::overlay::{CoverWalker, Overlay};
use super::projection::unseen;
use super::{AthertonWeilerGreenbergOptions, ShadowContext, ShadowStage, ShadowWalker};
use crate::error::{Error, Result};
use crate::geometry::convex_split::{self, is_convex};
use crate::geometry::lone_sheets::{self, Item, NO_ITEM};
use crate::geometry::weiler_atherton::{clip, regions_apart, ring_bounds, signed_area, ClipError, Region, Ring};
use crate::geometry::{box_corners, clip_in_place, clip_polygon, even_odd, grid_cells, simple, Plane};
use crate::pieces;
use crate::scene::{LightSample, ObjText, Scene};
use crate::stats::Counters;
use crate::view::DepthPlane;
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::path::Path;
use std::time::Instant;

/// A lit fragment of a scene polygon: where one light sample reaches it.
#[derive(Debug, Clone, PartialEq)]
pub struct DetailPolygon {
    /// Index of the scene polygon it lies on.
    pub source: u32,
    /// Its outlines in world space, on the source's plane (even-odd).
    pub rings: Vec<Vec<DVec3>>,
}

/// The lit detail polygons of one light: `samples[s]` for each of its samples.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ShadowDatabase {
    /// Per sample, the lit fragments.
    pub samples: Vec<Vec<DetailPolygon>>,
}

/// One light sample's lit fragments as pass 1 makes them: a list for each of its light views
/// (a point sample's cube faces), in order, never copied into one list (ours: on s3 such a
/// copy writes 470,000 fragments to a fresh list's pages, on one thread, every frame).
type Faces = Vec<Vec<Lit>>;

/// A lit fragment as pass 1 makes it (ours): a source polygon lit whole is its index alone,
/// with no copy of its outline. On s3 nine in ten fragments are whole (the lone sheets'
/// polygons); the public [`ShadowDatabase`] spells them out as [`DetailPolygon`]s.
enum Lit {
    Whole(u32),
    Part(DetailPolygon),
}

impl Lit {
    /// The fragment as the database keeps it.
    fn into_detail(self, scene: &Scene) -> DetailPolygon {
        match self {
            Lit::Whole(source) => DetailPolygon { source, rings: vec![scene.verts(source as usize).to_vec()] },
            Lit::Part(d) => d,
        }
    }
}

/// A lit fragment as the view pass reads it: a [`Lit`] of this frame's pass 1, or a
/// [`DetailPolygon`] of a database given to the renderer.
trait Fragment: Sync {
    fn source(&self) -> u32;
    /// Whether the fragment is its whole source polygon.
    fn whole(&self, scene: &Scene) -> bool;
    /// Its outlines in world space.
    fn rings<'a>(&'a self, scene: &'a Scene) -> impl Iterator<Item = &'a [DVec3]>;
}

impl Fragment for Lit {
    fn source(&self) -> u32 {
        match self {
            Lit::Whole(source) => *source,
            Lit::Part(d) => d.source,
        }
    }

    fn whole(&self, _: &Scene) -> bool {
        matches!(self, Lit::Whole(_))
    }

    fn rings<'a>(&'a self, scene: &'a Scene) -> impl Iterator<Item = &'a [DVec3]> {
        let (whole, part) = match self {
            Lit::Whole(source) => (Some(scene.verts(*source as usize)), &[][..]),
            Lit::Part(d) => (None, &d.rings[..]),
        };
        whole.into_iter().chain(part.iter().map(Vec::as_slice))
    }
}

impl Fragment for DetailPolygon {
    fn source(&self) -> u32 {
        self.source
    }

    fn whole(&self, scene: &Scene) -> bool {
        matches!(&self.rings[..], [r] if r[..] == *scene.verts(self.source as usize))
    }

    fn rings<'a>(&'a self, _: &'a Scene) -> impl Iterator<Item = &'a [DVec3]> {
        self.rings.iter().map(Vec::as_slice)
    }
}

/// A polygon (or a piece of one) in a light view: its region in the view's 2D coordinates
/// and its nearness to the light there (an affine function: larger is nearer).
#[derive(Debug, Clone)]
struct Piece {
    source: u32,
    region: Region,
    near: DepthPlane,
    bounds: (DVec2, DVec2),
    /// Whether the region is one convex ring (then [`cut`] splits it by edges).
    convex: bool,
    /// Whether the region is the whole source polygon, one ring with its corners in order.
    whole: bool,
    /// The lone-sheet step's sheet of its polygon (ours, [`lone_sheets`]), or [`NO_ITEM`]:
    /// no two pieces of one sheet overlap.
    sheet: u32,
}

impl Piece {
    fn new(source: u32, region: Region, near: DepthPlane) -> Option<Piece> {
        let bounds = region.bounds()?;
        let convex = region.rings.len() == 1 && is_convex(&region.rings[0]);
        Some(Piece { source, region, near, bounds, convex, whole: false, sheet: NO_ITEM })
    }

    /// A piece known to be one convex ring.
    fn convex(source: u32, ring: Ring, near: DepthPlane) -> Option<Piece> {
        let region = Region::from_ring(ring);
        let bounds = region.bounds()?;
        Some(Piece { source, region, near, bounds, convex: true, whole: false, sheet: NO_ITEM })
    }

    /// A part of this piece: `region`, which lies inside it.
    fn part(&self, region: Region) -> Option<Piece> {
        Some(Piece { sheet: self.sheet, ..Piece::new(self.source, region, self.near)? })
    }

    /// A part of this piece known to be one convex ring.
    fn convex_part(&self, ring: Ring) -> Option<Piece> {
        Some(Piece { sheet: self.sheet, ..Piece::convex(self.source, ring, self.near)? })
    }

    /// Whether the two pieces lie on one sheet, where their insides cannot meet.
    fn same_sheet(&self, other: &Piece) -> bool {
        self.sheet != NO_ITEM && self.sheet == other.sheet
    }

    fn overlaps(&self, other: &Piece) -> bool {
        boxes_meet(self.bounds, other.bounds)
    }

    /// The nearest any of its vertices gets (the rough sort's key).
    fn nearest(&self) -> f64 {
        self.region.rings.iter().flatten().map(|p| self.near.inv_z(p.x, p.y)).fold(f64::NEG_INFINITY, f64::max)
    }
}

/// The least box holding two boxes (least, greatest corner).
fn box_union(a: (DVec2, DVec2), b: (DVec2, DVec2)) -> (DVec2, DVec2) {
    (a.0.min(b.0), a.1.max(b.1))
}

/// Whether two boxes (least, greatest corner) meet, edges included.
fn boxes_meet(a: (DVec2, DVec2), b: (DVec2, DVec2)) -> bool {
    a.0.x <= b.1.x && b.0.x <= a.1.x && a.0.y <= b.1.y && b.0.y <= a.1.y
}

/// Pass 1's setting and counters.
#[derive(Debug, Default)]
struct Pass1 {
    /// Split convex pieces by edges ([`AthertonWeilerGreenbergOptions::convex_split`]).
    convex_split: bool,
    /// Leave polygons behind everything out of the sort
    /// ([`AthertonWeilerGreenbergOptions::backgrounds`]).
    backgrounds: bool,
    /// Take lone sheets out of the sort ([`AthertonWeilerGreenbergOptions::lone_sheets`]).
    lone_sheets: bool,
    /// Cut the view into regions ([`AthertonWeilerGreenbergOptions::tiling`]).
    tiling: bool,
    /// Find overlapping pieces in a grid ([`AthertonWeilerGreenbergOptions::sort_grid`]).
    sort_grid: bool,
    backgrounds_found: u64,
    lone: u64,
    whole_solids_found: u64,
    fragments: u64,
    clips: u64,
    depth_max: u64,
    splits: u64,
    tiles: u64,
}

impl Pass1 {
    fn new(options: AthertonWeilerGreenbergOptions) -> Pass1 {
        Pass1 {
            convex_split: options.convex_split,
            backgrounds: options.backgrounds,
            lone_sheets: options.lone_sheets,
            tiling: options.tiling,
            sort_grid: options.sort_grid,
            ..Default::default()
        }
    }

    fn add(&mut self, o: &Pass1) {
        self.fragments += o.fragments;
        self.clips += o.clips;
        self.splits += o.splits;
        self.tiles += o.tiles;
        self.backgrounds_found += o.backgrounds_found;
        self.lone += o.lone;
        self.whole_solids_found += o.whole_solids_found;
        self.depth_max = self.depth_max.max(o.depth_max);
    }
}

/// How a piece lies relative to a clip polygon over the piece's own area.
enum Relation {
    Behind,
    Front,
    Mixed,
}

fn relation(q: &Piece, clip: &Piece) -> Relation {
    relation_at(q.region.rings.iter().flatten().copied(), &q.near, &clip.near)
}

/// How a polygon with corners `points` and nearness `near` lies relative to another's
/// plane `clip` over the polygon's own area.
fn relation_at(points: impl Iterator<Item = DVec2>, near: &DepthPlane, clip: &DepthPlane) -> Relation {
    // One pass: the nearness differences' least and greatest, and the scale of `clip`'s
    // nearness, measured against a tolerance of that scale.
    let (mut scale, mut least, mut most) = (0.0f64, f64::INFINITY, f64::NEG_INFINITY);
    for p in points {
        let c = clip.inv_z(p.x, p.y);
        let d = near.inv_z(p.x, p.y) - c;
        scale = scale.max(c.abs());
        least = least.min(d);
        most = most.max(d);
    }
    let tol = 1e-9 * scale.max(1e-300);
    let (front, behind) = (most > tol, least < -tol);
    match (front, behind) {
        (true, true) => Relation::Mixed,
        (true, false) => Relation::Front,
        _ => Relation::Behind, // behind, or coplanar (either may be seen)
    }
}

/// The part of `q` where it is nearer than `clip` (they interpenetrate): `q` clipped by the
/// half-plane where the difference of their nearness functions is positive.
fn front_part(q: &Piece, clip_piece: &Piece, stats: &mut Pass1) -> std::result::Result<Option<Piece>, ClipError> {
    let (a, b) = (&q.near, &clip_piece.near);
    let (da, db, dc) = (a.a - b.a, a.b - b.b, a.c - b.c);
    let (lo, hi) = q.bounds;
    if q.convex && stats.convex_split {
        // A convex piece is cut by the line directly.
        stats.splits += 1;
        let norm = DVec2::new(da, db).length();
        if norm == 0.0 {
            return Ok((dc > 0.0).then(|| q.clone()));
        }
        let eps = crate::geometry::tolerance(lo, hi);
        let front = convex_split::positive_part(&q.region.rings[0], |p| (da * p.x + db * p.y + dc) / norm, eps);
        return Ok(front.and_then(|r| q.convex_part(r)));
    }
    let pad = (hi - lo).max_element().max(1e-12);
    let (lo, hi) = (lo - DVec2::splat(pad), hi + DVec2::splat(pad));
    let rect = [DVec2::new(lo.x, lo.y), DVec2::new(hi.x, lo.y), DVec2::new(hi.x, hi.y), DVec2::new(lo.x, hi.y)];
    let mut half = Vec::new();
    clip_polygon(&rect, |p: DVec2| da * p.x + db * p.y + dc, &mut half);
    stats.splits += 1;
    if half.len() < 3 {
        return Ok(None);
    }
    stats.clips += 1;
    let c = clip(&q.region, &Region::from_ring(half))?;
    Ok(q.part(c.inside))
}

/// A piece's part inside another (one at most: a region, or what is left after the last
/// split), and its parts outside.
type Parts = (Option<Piece>, Vec<Piece>);

/// `q` cut by the outline of `by`: its parts inside `by` and outside it, or `None` when
/// nothing of it is inside (`q` stays as it is). Two convex pieces are split by `by`'s edges
/// ([`convex_split`], ours: the outside part comes as convex pieces); any other pair goes
/// through Weiler and Atherton's clipper.
fn cut(q: &Piece, by: &Piece, stats: &mut Pass1) -> std::result::Result<Option<Parts>, ClipError> {
    if splits(q, by, stats) {
        let Some(s) = convex_split::split(&q.region.rings[0], &by.region.rings[0]) else { return Ok(None) };
        stats.clips += 1;
        let piece = |r| q.convex_part(r);
        return Ok(Some((piece(s.inside), s.outside.into_iter().filter_map(piece).collect())));
    }
    stats.clips += 1;
    let c = clip(&q.region, &by.region)?;
    if c.inside.rings.is_empty() {
        return Ok(None);
    }
    let piece = |r| q.part(r);
    Ok(Some((piece(c.inside), piece(c.outside).into_iter().collect())))
}

/// Whether [`cut`] splits `q` by `by`'s edges (both convex, and splitting on).
fn splits(q: &Piece, by: &Piece, stats: &Pass1) -> bool {
    q.convex && by.convex && stats.convex_split
}

/// Weiler & Atherton's hidden-surface removal by area sorting: the parts of `list` that
/// nothing in the list hides.
///
/// Pieces wait in a heap in rough depth order (nearest vertex first; what is left of a piece
/// after a clip keeps its place) and sit in a uniform grid over their bounding boxes, so that
/// the front polygon meets only the pieces it may overlap.
fn visible(list: Vec<Piece>, depth: u64, stats: &mut Pass1) -> std::result::Result<Vec<Piece>, ClipError> {
    stats.depth_max = stats.depth_max.max(depth);
    let Some(mut sort) = Sorting::new(&list) else { return Ok(Vec::new()) };
    // Room for as many visible pieces as there are pieces to sort (most stay whole).
    let mut out = Vec::with_capacity(list.len());
    for p in list {
        let key = OrdF64(p.nearest());
        sort.add(p, key);
    }
    while let Some((_, std::cmp::Reverse(fi))) = sort.heap.pop() {
        let Some(front) = sort.arena[fi as usize].take() else { continue };
        // The front polygon's outline splits everything it overlaps into inside and outside.
        let mut inside = Vec::new();
        let taken: Vec<(u32, Piece)> = sort
            .overlapping(&front, fi, stats)
            .into_iter()
            .filter_map(|q| Some((q, sort.arena[q as usize].take()?)))
            .collect();
        for (q, piece, parts) in cut_all(taken, &front, stats)? {
            let Some((ins, outs)) = parts else {
                sort.arena[q as usize] = Some(piece);
                continue;
            };
            inside.extend(ins);
            // The outside part takes its parent's place: in the grid (it only shrank) and in
            // the order; further pieces of it join both at the same place in the order.
            let mut outs = outs.into_iter();
            sort.arena[q as usize] = outs.next();
            for p in outs {
                sort.add(p, sort.keys[q as usize]);
            }
        }
        // Inside and in front of the front polygon (what is behind it is hidden, and was
        // dropped as it was cut): the sort was wrong there.
        let mut fronts = Vec::new();
        for (q, relation) in inside {
            match relation {
                Relation::Behind => {} // dropped in the cut already
                Relation::Front => fronts.push(q),
                Relation::Mixed => fronts.extend(front_part(&q, &front, stats)?),
            }
        }
        if fronts.is_empty() {
            out.push(front);
            continue;
        }
        // Resolve what is in front first, then keep the front polygon where none of it is.
        let seen = visible(fronts, depth + 1, stats)?;
        let remains = outside_all(front, seen.iter(), stats)?;
        out.extend(seen);
        out.extend(remains);
    }
    stats.fragments += out.len() as u64;
    Ok(out)
}

/// Fewest pieces one front polygon cuts in parallel.
const PARALLEL_CUTS: usize = 16;

/// The most cuts one piece of the parallel loop takes: a cut's cost varies with the pieces'
/// shapes, and with rayon's own cut into a few long pieces one thread waits for the other
/// at every front polygon.
const CUTS_PER_PIECE: usize = 4;

/// A piece's part inside the front polygon unless it is wholly behind it (with how it lies),
/// and its parts outside.
type Sorted = (Option<(Piece, Relation)>, Vec<Piece>);

/// Each of `taken` cut by `front`'s outline ([`cut`]), in order, with the parts inside
/// wholly behind `front` dropped (hidden): in parallel where there are many and Weiler and
/// Atherton's clipper cuts them (a stack of polygons that all overlap one another); splits
/// by edges are too quick to share out.
fn cut_all(
    taken: Vec<(u32, Piece)>,
    front: &Piece,
    stats: &mut Pass1,
) -> std::result::Result<Vec<(u32, Piece, Option<Sorted>)>, ClipError> {
    // Without splits, the sort hands over every piece whose box meets the front polygon's:
    // those apart from it are found here (in parallel, where the cuts are).
    let cut_unless_apart = |p: &Piece, st: &mut Pass1| {
        let apart = !st.convex_split && regions_apart(&p.region, &front.region);
        let parts = if apart { None } else { cut(p, front, st)? };
        Ok(parts.map(|(ins, outs)| {
            let not_behind = |q: Piece| match relation(&q, front) {
                Relation::Behind => None,
                r => Some((q, r)),
            };
            (ins.and_then(not_behind), outs)
        }))
    };
    if taken.len() < PARALLEL_CUTS || stats.convex_split {
        return taken
            .into_iter()
            .map(|(q, p)| {
                let parts = cut_unless_apart(&p, stats)?;
                Ok((q, p, parts))
            })
            .collect();
    }
    let flags = Pass1 { convex_split: stats.convex_split, sort_grid: stats.sort_grid, ..Default::default() };
    let done: Vec<(u32, Piece, Option<Sorted>, Pass1)> = taken
        .into_par_iter()
        .with_max_len(CUTS_PER_PIECE)
        .map(|(q, p)| {
            let mut st = Pass1 { ..flags };
            let parts = cut_unless_apart(&p, &mut st)?;
            Ok((q, p, parts, st))
        })
        .collect::<std::result::Result<_, ClipError>>()?;
    Ok(done
        .into_iter()
        .map(|(q, p, parts, st)| {
            stats.add(&st);
            (q, p, parts)
        })
        .collect())
}

/// What is left of `piece` outside every piece of `by`.
fn outside_all<'a>(
    piece: Piece,
    by: impl IntoIterator<Item = &'a Piece>,
    stats: &mut Pass1,
) -> std::result::Result<Vec<Piece>, ClipError> {
    let mut remains = vec![piece];
    for s in by {
        let mut next = Vec::with_capacity(remains.len());
        for r in remains {
            match r.overlaps(s).then(|| cut(&r, s, stats)).transpose()?.flatten() {
                Some((_, outside)) => next.extend(outside),
                None => next.push(r),
            }
        }
        remains = next;
        if remains.is_empty() {
            break;
        }
    }
    Ok(remains)
}

/// The pieces of one area sort: each in an arena slot (empty once taken), in a uniform grid
/// over their bounding boxes, and in a heap by their key (rough depth order).
struct Sorting {
    arena: Vec<Option<Piece>>,
    keys: Vec<OrdF64>,
    heap: std::collections::BinaryHeap<(OrdF64, std::cmp::Reverse<u32>)>,
    grid: BoxGrid,
    /// `stamp[q]`: the last front polygon piece `q` was found for.
    stamp: Vec<u32>,
}

/// A uniform grid over boxes, about one cell per box: each cell lists, by index, the boxes
/// added that meet it, in the order they were added.
#[derive(Default)]
struct BoxGrid {
    cells: Vec<Vec<u32>>,
    lo: DVec2,
    size: DVec2,
    g: usize,
}

impl BoxGrid {
    /// An empty grid over `bounds` (least, greatest corner) for `n` boxes.
    fn new((lo, hi): (DVec2, DVec2), n: usize) -> BoxGrid {
        let g = ((n as f64).sqrt().ceil() as usize).clamp(1, 256);
        let size = (hi - lo).max(DVec2::splat(1e-300));
        BoxGrid { cells: vec![Vec::new(); g * g], lo, size, g }
    }

    /// The cells box `b` meets (the grid made by [`BoxGrid::new`]); the iterator holds no
    /// borrow of the grid.
    fn cells(&self, b: (DVec2, DVec2)) -> impl Iterator<Item = usize> {
        let g = self.g;
        grid_cells(self.lo, self.size, (g, g), b).map(move |(c, r)| c * g + r)
    }

    /// Adds box `i`, `b`, to the cells it meets.
    fn add(&mut self, i: u32, b: (DVec2, DVec2)) {
        for c in self.cells(b) {
            self.cells[c].push(i);
        }
    }
}

impl Sorting {
    /// An empty sort over the bounds of `list` (`None` when `list` is empty).
    fn new(list: &[Piece]) -> Option<Sorting> {
        let bounds = list.iter().map(|p| p.bounds).reduce(box_union)?;
        let n = list.len();
        Some(Sorting {
            arena: Vec::with_capacity(n),
            keys: Vec::with_capacity(n),
            heap: std::collections::BinaryHeap::with_capacity(n),
            grid: BoxGrid::new(bounds, n),
            stamp: Vec::with_capacity(n),
        })
    }

    /// Adds `p` with sort key `key` (nearest first, then first added).
    fn add(&mut self, p: Piece, key: OrdF64) {
        let i = self.arena.len() as u32;
        self.grid.add(i, p.bounds);
        self.heap.push((key, std::cmp::Reverse(i)));
        self.keys.push(key);
        self.stamp.push(u32::MAX);
        self.arena.push(Some(p));
    }

    /// The pieces still waiting whose insides may meet `front`'s (front polygon `fi`), each
    /// once, in the order they were added. Pieces that only share an edge with it (its
    /// neighbours on a mesh) are left out, or, where [`cut`] splits them, found apart by the
    /// split: nothing of them is inside it.
    fn overlapping(&mut self, front: &Piece, fi: u32, stats: &Pass1) -> Vec<u32> {
        // Convex pairs are tested as they are split; without splits, pairs are tested as
        // they are cut ([`cut_all`]).
        let meets = |p: &Piece| {
            p.overlaps(front)
                && !p.same_sheet(front)
                && (splits(p, front, stats) || !stats.convex_split || !regions_apart(&p.region, &front.region))
        };
        let cells = self.grid.cells(front.bounds).collect::<smallvec::SmallVec<[usize; 8]>>();
        if !stats.sort_grid || cells.len() * 4 >= self.grid.cells.len() {
            // A front polygon over much of the grid (a stack of large polygons): the pieces
            // are fewer to read than the cells' lists.
            let live = self.arena.iter().enumerate().filter_map(|(q, p)| Some((q as u32, p.as_ref()?)));
            return live.filter(|(_, p)| meets(p)).map(|(q, _)| q).collect();
        }
        let mut found = Vec::new();
        for c in cells {
            // Pieces taken since (hidden, or sorted) leave the cell as it is read.
            let (arena, stamp) = (&self.arena, &mut self.stamp);
            self.grid.cells[c].retain(|&q| {
                let Some(p) = &arena[q as usize] else { return false };
                if stamp[q as usize] != fi {
                    stamp[q as usize] = fi;
                    if meets(p) {
                        found.push(q);
                    }
                }
                true
            });
        }
        found.sort_unstable();
        found
    }
}

/// An f64 ordered by `total_cmp`, for the heap.
#[derive(Debug, Clone, Copy, PartialEq)]
struct OrdF64(f64);

impl Eq for OrdF64 {}

impl PartialOrd for OrdF64 {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for OrdF64 {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// The parts of `o` (a polygon that casts no shadow) that no visible caster piece in `seen`
/// lies in front of.
fn unshadowed(o: Piece, seen: &[Piece], stats: &mut Pass1) -> std::result::Result<Vec<Piece>, ClipError> {
    let casters: Vec<&Piece> = seen.iter().filter(|s| s.overlaps(&o) && !regions_apart(&s.region, &o.region)).collect();
    let mut lit = vec![o];
    for s in casters {
        let mut next = Vec::with_capacity(lit.len());
        for piece in lit {
            if !piece.overlaps(s) {
                next.push(piece);
                continue;
            }
            let Some((inside, outside)) = cut(&piece, s, stats)? else {
                next.push(piece);
                continue;
            };
            next.extend(outside);
            // Over the overlap, the caster hides `o` where it is nearer.
            if let Some(overlap) = inside {
                let caster = Piece { near: s.near, sheet: s.sheet, ..overlap.clone() };
                match relation(&caster, &overlap) {
                    Relation::Behind => next.push(overlap),
                    Relation::Front => {}
                    Relation::Mixed => match front_part(&caster, &overlap, stats)? {
                        Some(hiding) => match cut(&overlap, &hiding, stats)? {
                            Some((_, outside)) => next.extend(outside),
                            None => next.push(overlap),
                        },
                        None => next.push(overlap),
                    },
                }
            }
        }
        lit = next;
    }
    Ok(lit)
}

fn clip_error(e: ClipError) -> Error {
    Error::Internal(format!("atherton-weiler-greenberg: {e}"))
}

/// One view from the light: how world points map into its 2D coordinates.
#[derive(Debug, Clone, Copy)]
enum LightView {
    /// A 90° face of the cube around a point light: `(u, v) = (p·e1, p·e2) / p·axis` with
    /// `p` relative to the light.
    Face { light: DVec3, axis: DVec3, e1: DVec3, e2: DVec3 },
    /// Parallel to a directional light: `(u, v) = (p·e1, p·e2)`, depth `p·d`.
    Parallel { d: DVec3, e1: DVec3, e2: DVec3 },
}

impl LightView {
    fn views(sample: LightSample) -> Vec<LightView> {
        match sample {
            LightSample::Point(light) => [DVec3::X, DVec3::NEG_X, DVec3::Y, DVec3::NEG_Y, DVec3::Z, DVec3::NEG_Z]
                .into_iter()
                .map(|axis| {
                    let e1 = axis.any_orthonormal_vector();
                    LightView::Face { light, axis, e1, e2: axis.cross(e1) }
                })
                .collect(),
            LightSample::Directional(d) => {
                let e1 = d.any_orthonormal_vector();
                vec![LightView::Parallel { d, e1, e2: d.cross(e1) }]
            }
        }
    }

    /// Polygon `verts` cut to this view (for a cube face, its frustum) and mapped into it,
    /// its corners added to `out`; its nearness function and whether nothing was cut off, or
    /// `None` (and nothing added) when nothing is left or it is edge-on. `scratch` is room
    /// for the cut.
    fn map_into(
        &self,
        verts: &[DVec3],
        plane: &Plane,
        near: f64,
        out: &mut Vec<DVec2>,
        scratch: &mut [Vec<DVec3>; 2],
    ) -> Option<(DepthPlane, bool)> {
        match *self {
            LightView::Face { light, axis, e1, e2 } => {
                // The frustum |x|, |y| <= z, and a tiny near plane at the light, with
                // (x, y, z) = (p·e1, p·e2, p·axis) the face's frame of `p`, a point relative
                // to the light: each side's value (positive inside).
                let frame = |p: DVec3| face_frame(p, e1, e2, axis);
                let sides = |f: DVec3| face_sides(f, near);
                let planes: [&dyn Fn(DVec3) -> f64; 5] = [
                    &|p| sides(frame(p))[0],
                    &|p| sides(frame(p))[1],
                    &|p| sides(frame(p))[2],
                    &|p| sides(frame(p))[3],
                    &|p| sides(frame(p))[4],
                ];
                // Most polygons lie wholly outside some side of a face's frustum: they are
                // dropped before they are copied. Each corner is put in the face's frame
                // once, and every side read from it; a polygon wholly inside is mapped from
                // those frames (ours).
                let [a, b] = scratch;
                b.clear();
                b.extend(verts.iter().map(|&v| frame(v - light)));
                let (mut outside, mut whole) = ([true; 5], true);
                for &f in b.iter() {
                    for (out, side) in outside.iter_mut().zip(sides(f)) {
                        *out &= side < 0.0;
                        whole &= side >= 0.0;
                    }
                }
                if outside.contains(&true) {
                    return None;
                }
                if !whole {
                    a.clear();
                    a.extend(verts.iter().map(|&v| v - light));
                    for f in planes {
                        clip_in_place(a, b, f);
                    }
                    b.clear();
                    b.extend(a.iter().map(|&p| frame(p)));
                }
                if b.len() < 3 {
                    return None;
                }
                let near_fn = self.nearness(plane)?;
                out.extend(b.iter().map(|f| DVec2::new(f.x, f.y) / f.z));
                Some((near_fn, whole))
            }
            LightView::Parallel { e1, e2, .. } => {
                let near_fn = self.nearness(plane)?;
                out.extend(verts.iter().map(|p| DVec2::new(p.dot(e1), p.dot(e2))));
                Some((near_fn, true))
            }
        }
    }

    /// How near the light `plane` lies over each point of this view (larger is nearer), or
    /// `None` where the view sees it edge-on.
    fn nearness(&self, plane: &Plane) -> Option<DepthPlane> {
        match *self {
            LightView::Face { light, axis, e1, e2 } => {
                // Nearness = 1 / (depth along the axis) of the plane's point seen at (u, v):
                // the ray (axis + u e1 + v e2) t meets n·(light + ray t) + d = 0.
                let k = plane.distance(light);
                let n = plane.n;
                (k != 0.0).then(|| DepthPlane { a: -n.dot(e1) / k, b: -n.dot(e2) / k, c: -n.dot(axis) / k })
            }
            LightView::Parallel { d, e1, e2 } => {
                // The plane's point at (u, v) is u e1 + v e2 + s d with s = −(n·(u e1 + v e2) + d0)/(n·d);
                // nearness is −s.
                let nd = plane.n.dot(d);
                (nd != 0.0).then(|| DepthPlane { a: plane.n.dot(e1) / nd, b: plane.n.dot(e2) / nd, c: plane.d / nd })
            }
        }
    }

    /// World point `p` in this view, mapped as [`LightView::map_into`] maps the corners of a
    /// polygon it cuts nothing off; `None` where a cube face's frustum or its near plane
    /// (`near` from the light) leaves `p` out.
    fn point(&self, p: DVec3, near: f64) -> Option<DVec2> {
        match *self {
            LightView::Face { light, axis, e1, e2 } => {
                let f = face_frame(p - light, e1, e2, axis);
                face_sides(f, near).iter().all(|&side| side >= 0.0).then(|| DVec2::new(f.x, f.y) / f.z)
            }
            LightView::Parallel { e1, e2, .. } => Some(DVec2::new(p.dot(e1), p.dot(e2))),
        }
    }

    /// Whether the box `(lo, hi)` lies wholly outside one side of a cube face's frustum or
    /// its near plane (never, for a parallel view).
    fn misses_box(&self, (lo, hi): (DVec3, DVec3), near: f64) -> bool {
        let LightView::Face { light, axis, e1, e2 } = *self else { return false };
        let sides = box_corners(lo, hi).map(|c| face_sides(face_frame(c - light, e1, e2, axis), near));
        (0..5).any(|side| sides.iter().all(|s| s[side] < 0.0))
    }

    /// The world point on `plane` that this view sees at `q`.
    fn unmap(&self, q: DVec2, plane: &Plane) -> DVec3 {
        match *self {
            LightView::Face { light, axis, e1, e2 } => {
                let ray = axis + e1 * q.x + e2 * q.y;
                light + ray * (-plane.distance(light) / plane.n.dot(ray))
            }
            LightView::Parallel { d, e1, e2 } => {
                let p = e1 * q.x + e2 * q.y;
                p - d * (plane.distance(p) / plane.n.dot(d))
            }
        }
    }
}

/// Point `p`, relative to the light, in a cube face's frame: `(p·e1, p·e2, p·axis)`.
fn face_frame(p: DVec3, e1: DVec3, e2: DVec3, axis: DVec3) -> DVec3 {
    DVec3::new(p.dot(e1), p.dot(e2), p.dot(axis))
}

/// The sides of a cube face's frustum `|x|, |y| <= z` and of its near plane `z >= near` at
/// point `f` of the face's frame: each side's value, positive inside.
fn face_sides(f: DVec3, near: f64) -> [f64; 5] {
    [f.z - f.x, f.z + f.x, f.z - f.y, f.z + f.y, f.z - near]
}

/// Per polygon of `scene` (for a point light sample; empty for others): the one face of the
/// light's cube, numbered as [`LightView::views`] gives them, that holds all its corners
/// inside its open frustum, or `None` where there is no such face. Such a polygon is in no
/// other face's frustum (ours, to spare each face the frustum tests of the polygons that lie
/// in another). `unseen` polygons are left as `None`.
fn cube_faces(scene: &Scene, sample: LightSample, unseen: &[bool]) -> Vec<Option<u8>> {
    let LightSample::Point(light) = sample else { return Vec::new() };
    (0..scene.polygons.len())
        .into_par_iter()
        .map(|i| {
            if unseen[i] {
                return None;
            }
            let mut corners = scene.verts(i).iter().map(|&v| cube_face(v - light));
            let first = corners.next().flatten();
            corners.all(|f| f == first).then_some(first).flatten()
        })
        .collect()
}

/// The cube face (numbered as in [`LightView::views`]) whose open frustum holds `p`, a point
/// relative to the light: the axis along which `p` reaches farthest, if it is the only one.
fn cube_face(p: DVec3) -> Option<u8> {
    let a = p.abs();
    let axis = if a.x > a.y && a.x > a.z {
        0
    } else if a.y > a.x && a.y > a.z {
        1
    } else if a.z > a.x && a.z > a.y {
        2
    } else {
        return None;
    };
    Some(2 * axis as u8 + u8::from(p[axis] < 0.0))
}

/// Per light view (`views` of them), the polygons it may see, in increasing order: all but
/// the `unseen`, less those that `face` (from [`cube_faces`]; empty for none) puts wholly in
/// another view. One pass sorts the polygons into each view's own list and one list that
/// every view shares (ours: each view scanning the whole scene would make 6 million tests a
/// frame on s3).
fn view_lists(face: &[Option<u8>], unseen: &[bool], views: usize) -> Vec<Vec<u32>> {
    let n = unseen.len();
    let parts: Vec<Vec<Vec<u32>>> = (0..n.div_ceil(MAP_PIECE))
        .into_par_iter()
        .map(|k| {
            // `lists[views]`: the shared list.
            let mut lists = vec![Vec::new(); views + 1];
            for i in (k * MAP_PIECE..n.min((k + 1) * MAP_PIECE)).filter(|&i| !unseen[i]) {
                let own = face.get(i).copied().flatten().map_or(views, usize::from).min(views);
                lists[own].push(i as u32);
            }
            lists
        })
        .collect();
    let joined = |v: usize| pieces::joined(&parts.iter().map(|l| &l[v][..]).collect::<Vec<_>>(), |_, &i| i);
    let shared = joined(views);
    (0..views).into_par_iter().map(|v| merged(&joined(v), &shared)).collect()
}

/// Two increasing lists with nothing in common merged into one.
fn merged(a: &[u32], b: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        if a[i] < b[j] {
            out.push(a[i]);
            i += 1;
        } else {
            out.push(b[j]);
            j += 1;
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

/// A polygon's region for the clipper, whose rings must not cross themselves: a
/// self-intersecting outline (`crossing`; inside by the even-odd rule) becomes the
/// trapezoids of its even-odd region ([`crate::geometry::even_odd`]), which touch but never
/// cross.
fn even_odd_region(ring: Vec<DVec2>, crossing: bool) -> Region {
    if !crossing {
        return Region::from_ring(ring);
    }
    let rings = even_odd::trapezoids(&ring)
        .into_iter()
        .filter_map(|t| {
            let mut r = t.to_vec();
            r.dedup();
            (r.len() >= 3).then_some(r)
        })
        .collect();
    Region { rings }
}

/// The polygons of one light view, mapped into it (step 1(a)): their outlines side by side
/// in one list, so that the many polygons of a view cost no allocation each; most of them
/// leave as lone ([`take_lone`]) without ever becoming [`Piece`]s.
#[derive(Debug, Default)]
struct Mapped {
    points: Vec<DVec2>,
    polys: Vec<MappedPolygon>,
}

/// Polygons a task of [`Mapped::new`] maps.
const MAP_PIECE: usize = 4096;

/// One polygon of a [`Mapped`] view.
#[derive(Debug, Clone, Copy)]
struct MappedPolygon {
    source: u32,
    /// Its outline: `points[first..first + len]`.
    first: u32,
    len: u32,
    near: DepthPlane,
    bounds: (DVec2, DVec2),
    /// The outline crosses itself.
    crossing: bool,
    /// The outline is the whole source polygon, its corners in order, and does not cross
    /// itself.
    whole: bool,
    casts: bool,
}

impl Mapped {
    /// The polygons `seen` of `scene` (in increasing order) mapped into `view`, in
    /// parallel, in order.
    fn new(scene: &Scene, seen: &[u32], view: LightView, extent: f64) -> Mapped {
        let mut parts: Vec<Mapped> = seen
            .par_chunks(MAP_PIECE)
            .map(|chunk| {
                // Room for every polygon the view may see, whole (ours: lists grown as they
                // fill are copied again at each doubling).
                let corners = chunk.iter().map(|&i| scene.verts(i as usize).len()).sum();
                let mut m = Mapped { points: Vec::with_capacity(corners), polys: Vec::with_capacity(chunk.len()) };
                let mut scratch = [Vec::new(), Vec::new()];
                for &i in chunk {
                    m.push(scene, view, i as usize, 1e-9 * extent, &mut scratch);
                }
                // The parts and the joined view exist at once: no part keeps room to spare.
                m.points.shrink_to_fit();
                m.polys.shrink_to_fit();
                m
            })
            .collect();
        // Each part's outlines start where the parts before it end.
        let base = pieces::starts(parts.iter().map(|m| m.points.len()));
        let polys: Vec<&[MappedPolygon]> = parts.iter().map(|m| &m.polys[..]).collect();
        let polys = pieces::joined(&polys, |k, &p| MappedPolygon { first: p.first + base[k] as u32, ..p });
        // The parts' polygons are let go before their outlines are joined.
        for part in &mut parts {
            part.polys = Vec::new();
        }
        let points: Vec<&[DVec2]> = parts.iter().map(|m| &m.points[..]).collect();
        Mapped { points: pieces::joined(&points, |_, &p| p), polys }
    }

    /// Maps polygon `i` of `scene`, if the view sees any of it.
    fn push(&mut self, scene: &Scene, view: LightView, i: usize, near: f64, scratch: &mut [Vec<DVec3>; 2]) {
        let first = self.points.len();
        let Some((near, cut_whole)) =
            view.map_into(scene.verts(i), &scene.polygons[i].plane, near, &mut self.points, scratch)
        else {
            return;
        };
        let ring = &self.points[first..];
        let Some(bounds) = ring_bounds(ring) else { return };
        let crossing = ring.len() >= 4 && even_odd::self_intersects(ring);
        self.polys.push(MappedPolygon {
            source: i as u32,
            first: first as u32,
            len: ring.len() as u32,
            near,
            bounds,
            crossing,
            whole: cut_whole && !crossing,
            casts: scene.casts_shadows(i),
        });
    }

    /// Appends the polygons of `other`.
    fn extend(&mut self, other: Mapped) {
        let base = self.points.len() as u32;
        self.points.extend(other.points);
        self.polys.extend(other.polys.into_iter().map(|p| MappedPolygon { first: p.first + base, ..p }));
    }

    fn ring(&self, p: &MappedPolygon) -> &[DVec2] {
        &self.points[p.first as usize..(p.first + p.len) as usize]
    }

    /// Polygon `p` as a piece for the sort.
    fn piece(&self, p: &MappedPolygon) -> Option<Piece> {
        let mut piece = Piece::new(p.source, even_odd_region(self.ring(p).to_vec(), p.crossing), p.near)?;
        piece.whole = p.whole;
        Some(piece)
    }

    /// The pieces of the polygons that `keep` keeps, casters and others apart, in order,
    /// each in its `sheet` (if any).
    fn pieces(
        &self,
        keep: impl Fn(usize) -> bool + Sync,
        sheet: impl Fn(usize) -> Option<u32> + Sync,
    ) -> (Vec<Piece>, Vec<Piece>) {
        let of = |casts: bool| {
            let all = self.polys.par_iter().enumerate().filter(|(i, p)| p.casts == casts && keep(*i));
            let piece = |(i, p)| Some(Piece { sheet: sheet(i).unwrap_or(NO_ITEM), ..self.piece(p)? });
            all.filter_map(piece).collect()
        };
        (of(true), of(false))
    }
}

/// Steps 1(a)-(c) and 2 for one view of one light sample: the scene mapped into the view,
/// the casters sorted, the lit fragments of every polygon taken back into world space.
fn lit_in_view(
    scene: &Scene,
    seen: &[u32],
    view: LightView,
    solids: Vec<WholeSolid>,
    extent: f64,
    stats: &mut Pass1,
) -> std::result::Result<Vec<Lit>, ClipError> {
    // The polygons of the solids that may be settled whole are not mapped one by one (ours).
    let mut mapped = if solids.is_empty() {
        Mapped::new(scene, seen, view, extent)
    } else {
        let offered = solids.par_iter().flat_map_iter(|w| w.polygons.iter().map(|&i| i as usize));
        let settling = pieces::marked(scene.polygons.len(), offered);
        let rest: Vec<u32> = seen.par_iter().copied().filter(|&i| !settling[i as usize]).collect();
        Mapped::new(scene, &rest, view, extent)
    };
    // Lone polygons and wide backgrounds leave the view before it is cut (ours).
    let lone = match stats.lone_sheets {
        true => take_lone(scene, &mut mapped, stats.backgrounds, solids, (view, extent)),
        false => LoneSplit::default(),
    };
    stats.lone += lone.lone.len() as u64;
    stats.whole_solids_found += lone.whole_solids;
    stats.backgrounds_found += lone.behind.len() as u64;
    let sheet = |i: usize| lone.sheet.binary_search_by_key(&(i as u32), |&(j, _)| j).ok().map(|k| lone.sheet[k].1);
    let (casters, others) = mapped.pieces(|i| lone.sorted.get(i) != Some(&false), sheet);
    drop(mapped);
    // Independent regions of the view (one, for up to TILE_PIECES casters), sorted in
    // parallel.
    let all = casters.iter().chain(&others).map(|p| p.bounds);
    let rect = all.fold((DVec2::INFINITY, DVec2::NEG_INFINITY), box_union);
    // Cutting may copy pieces that straddle a border: at most three more copies in all than
    // there are pieces, however the cuts fall.
    let copies = 3 * (casters.len() + others.len());
    let lists = if stats.tiling { regions(casters, others, rect, copies) } else { vec![(casters, others)] };
    stats.tiles += lists.len() as u64;
    // Step 1(c) too, region by region: the lit pieces back onto their planes (a whole
    // polygon as it is).
    let unmap = |p: Piece| {
        if p.whole {
            return Lit::Whole(p.source);
        }
        let plane = scene.polygons[p.source as usize].plane;
        let rings = p.region.rings.iter().map(|r| r.iter().map(|&q| view.unmap(q, &plane)).collect()).collect();
        Lit::Part(DetailPolygon { source: p.source, rings })
    };
    let keep_cover = !lone.behind.is_empty();
    let done: Vec<(Vec<Lit>, Vec<Piece>, Pass1)> = lists
        .into_par_iter()
        .with_max_len(1)
        .map(|(casters, others)| {
            let convex_split = stats.convex_split && !stacked(&casters, &others);
            let mut st = Pass1 {
                convex_split,
                backgrounds: stats.backgrounds,
                sort_grid: stats.sort_grid,
                ..Default::default()
            };
            let mut cover = Vec::new();
            let lit = lit_pieces(scene, casters, others, keep_cover.then_some(&mut cover), &mut st)?;
            Ok((lit.into_iter().map(unmap).collect(), cover, st))
        })
        .collect::<std::result::Result<_, ClipError>>()?;
    // Room for every fragment at once: the lone polygons, half a million on s3, come last.
    let fragments = done.iter().map(|(lit, _, _)| lit.len()).sum::<usize>() + lone.behind.len() + lone.lone.len();
    let mut detail = Vec::with_capacity(fragments);
    let mut cover = Vec::new();
    for (lit, c, st) in done {
        detail.extend(lit);
        cover.extend(c);
        stats.add(&st);
    }
    // The wide backgrounds, lit where no visible piece or lone sheet covers them.
    let over: Vec<&Piece> = cover.iter().chain(&lone.outlines).collect();
    let behind: Vec<Piece> = lone.behind.into_par_iter().filter_map(|b| holed(b, &over)).collect();
    detail.par_extend(behind.into_par_iter().map(unmap));
    detail.par_extend(lone.lone.into_par_iter().map(Lit::Whole));
    Ok(detail)
}

/// What the whole-solid step (ours) reads of one light sample.
struct SampleSolids<'a> {
    sample: LightSample,
    /// Per polygon, whether the sample need not consider it ([`unseen`]).
    unseen: &'a [bool],
    /// Per polygon, its cube face ([`cube_faces`]; empty without face binning).
    face: &'a [Option<u8>],
    /// Per closed solid, whether it is closed as seen from the sample.
    closed: Vec<bool>,
    /// Each closed solid's polygons, in increasing order.
    members: &'a [Vec<u32>],
}

/// A closed solid offered to the lone-sheet step whole (ours,
/// [`AthertonWeilerGreenbergOptions::whole_solids`]): its polygons facing the light, shown
/// by [`whole_solid`] never to overlap one another in the view, and the outline of their
/// union there.
struct WholeSolid {
    /// Its polygons facing the light, in increasing order.
    polygons: Vec<u32>,
    /// Their corners in the view.
    corners: Vec<[DVec2; 3]>,
    /// The outline of their union in the view: one simple ring.
    ring: Vec<DVec2>,
    /// The ring's box.
    bounds: (DVec2, DVec2),
    /// Its first polygon's nearness in the view (for the outline's piece).
    near: DepthPlane,
    /// The box of those polygons' corners in world space, and the light sample.
    world: (DVec3, DVec3),
    sample: LightSample,
}

impl WholeSolid {
    /// Whether the box of the polygons lies on the light's side of `plane`, each corner by
    /// more than `margin`: then along every ray from the light that meets both, the
    /// polygons come first.
    fn before(&self, plane: &Plane, margin: f64) -> bool {
        let (lo, hi) = self.world;
        let side = self.sample.side_of(plane);
        let side = if side == 0.0 { return false } else { side.signum() };
        box_corners(lo, hi).iter().all(|&c| plane.distance(c) * side > margin)
    }
}

/// The closed solids whose side facing the light can be offered whole in view `v` (ours):
/// [`whole_solid`] for each solid whose box the view does not miss, in parallel.
fn whole_solids(scene: &Scene, view: &LightView, v: u8, of: &SampleSolids, extent: f64) -> Vec<WholeSolid> {
    let near = 1e-9 * extent;
    (0..of.members.len())
        .into_par_iter()
        .with_max_len(1)
        .filter(|&s| of.closed[s] && !view.misses_box((scene.solids[s].lo, scene.solids[s].hi), near))
        .filter_map(|s| whole_solid(scene, view, v, of, s, near))
        .collect()
}

/// Closed solid `s`'s polygons facing the light as one [`WholeSolid`] of view `v`, when:
/// - every polygon of the solid casts shadows, and every one facing the light (not
///   [`unseen`]) is a triangle in view `v` alone (its cube face), none of it cut off;
/// - each such triangle, as the view maps its corners, turns the same way, decided beyond
///   rounding (Shewchuk's first error bound for the orientation's determinant);
/// - the edges of those triangles that have no triangle facing the light across them chain
///   into one simple ring ([`simple`]), turning as the triangles do.
///
/// Then no two of the triangles overlap in the view. Over any point off the edges, the
/// triangles that hold it, each counted with its turn, number the ring's winding number
/// round it: each edge between two of them is run once each way (the scene's edge
/// neighbours promise it), with the same mapped corners, and cancels. Every turn is the
/// same and the ring's winding number is 0 or that turn, so at most one triangle holds the
/// point, and their union is the ring's inside. Mapping only the corners, it costs a
/// fraction of passing each polygon through the lone-sheet step.
fn whole_solid(scene: &Scene, view: &LightView, v: u8, of: &SampleSolids, s: usize, near: f64) -> Option<WholeSolid> {
    let facing = |i: u32| of.unseen.get(i as usize) == Some(&false);
    let (mut polygons, mut mapped, mut edges, mut turn) = (Vec::new(), Vec::new(), Vec::new(), 0.0);
    let mut world = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &i in &of.members[s] {
        if !scene.casts_shadows(i as usize) {
            return None;
        }
        if !facing(i) {
            continue;
        }
        if !of.face.is_empty() && of.face[i as usize] != Some(v) {
            return None;
        }
        let &[a, b, c] = scene.verts(i as usize) else { return None };
        let corners = [view.point(a, near)?, view.point(b, near)?, view.point(c, near)?];
        let t = turn_of(corners);
        if t == 0.0 || (turn != 0.0 && t != turn) {
            return None;
        }
        turn = t;
        polygons.push(i);
        mapped.push(corners);
        world = [a, b, c].iter().fold(world, |(lo, hi), &p| (lo.min(p), hi.max(p)));
        for (k, &q) in scene.across(i as usize).iter().enumerate() {
            if q == crate::scene::NO_POLYGON || !facing(q) {
                edges.push((corners[k], corners[(k + 1) % 3]));
            }
        }
    }
    let rings = lone_sheets::chain(&edges)?;
    let [ring] = &rings[..] else { return None };
    if signed_area(ring) * turn <= 0.0 || !simple(ring) {
        return None;
    }
    let near = view.nearness(&scene.polygons[*polygons.first()? as usize].plane)?;
    Some(WholeSolid {
        bounds: ring_bounds(ring)?,
        ring: ring.clone(),
        polygons,
        corners: mapped,
        near,
        world,
        sample: of.sample,
    })
}

/// The box of a triangle's corners.
fn corner_box(c: &[DVec2; 3]) -> (DVec2, DVec2) {
    (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]))
}

/// The turn of triangle `[a, b, c]`: 1 counter-clockwise, −1 clockwise, 0 where rounding
/// could have decided the sign of its determinant (Shewchuk's bound for the determinant
/// computed in floating point from the corners; "Adaptive precision floating-point
/// arithmetic and fast robust geometric predicates", 1997).
fn turn_of([a, b, c]: [DVec2; 3]) -> f64 {
    let left = (a.x - c.x) * (b.y - c.y);
    let right = (a.y - c.y) * (b.x - c.x);
    let det = left - right;
    let bound = 3.330_669_073_875_472e-16 * (left.abs() + right.abs());
    if det > bound {
        1.0
    } else if det < -bound {
        -1.0
    } else {
        0.0
    }
}

/// What the lone-sheet step (ours) takes out of a light view before it is cut into regions.
#[derive(Debug, Default)]
struct LoneSplit {
    /// The polygons (by source) that nothing else in the view meets ([`lone_sheets`]):
    /// wholly lit, and they hide nothing but wide backgrounds.
    lone: Vec<u32>,
    /// The outlines of the lone polygons, sheet by sheet: the holes they make in `behind`.
    outlines: Vec<Piece>,
    /// Wide backgrounds ([`wide_backgrounds`]), lit last.
    behind: Vec<Piece>,
    /// `sorted[i]`: whether mapped polygon `i` is neither, and goes on to the sort.
    sorted: Vec<bool>,
    /// The polygons that go on to the sort on a sheet that clears itself, as (mapped
    /// polygon, its sheet), in increasing order (ours: the sort passes over pairs of one
    /// sheet, which never overlap).
    sheet: Vec<(u32, u32)>,
    /// The solids offered whole ([`whole_solids`]) that were lone, their polygons in `lone`.
    whole_solids: u64,
}

/// Step 1(b), ours, before the sort: the casters no other polygon in the view meets leave
/// it, found sheet by sheet ([`lone_sheets`]: the side of a closed mesh that faces the light
/// is one sheet, whose polygons never overlap one another), and so do wide backgrounds,
/// which would otherwise meet everything over them.
///
/// The closed solids offered whole (`solids`, [`whole_solids`]; their polygons are not in
/// `m`) are lone where their boxes meet no other box but the wide backgrounds', and
/// otherwise lone in the polygons whose boxes meet none ([`settle`]); their other polygons
/// are mapped into `m` (`view`) and go through the step polygon by polygon.
fn take_lone(
    scene: &Scene,
    m: &mut Mapped,
    backgrounds: bool,
    solids: Vec<WholeSolid>,
    (view, extent): (LightView, f64),
) -> LoneSplit {
    let mut behind = if backgrounds && m.polys.par_iter().all(|p| p.casts) {
        wide_backgrounds(scene, m, &solids, extent)
    } else {
        vec![false; m.polys.len()]
    };
    let met = met_by(&solids, m, &behind);
    let settled: Vec<Settled> =
        solids.par_iter().zip(met).with_max_len(1).map(|(w, met)| settle(scene, w, &met)).collect();
    drop(solids);
    let rest: Vec<u32> = settled.iter().flat_map(|s| s.rest.iter().copied()).collect();
    if !rest.is_empty() {
        m.extend(Mapped::new(scene, &rest, view, extent));
        behind.resize(m.polys.len(), false);
    }
    let m = &*m;
    let n = m.polys.len();
    let kept: Vec<usize> = (0..n).into_par_iter().filter(|&i| !behind[i]).collect();
    // The items across each whole caster's edges, by their places among the kept (a whole
    // polygon is mapped once a view: a source's place is read from `place`): worked out in
    // parallel, in order.
    let sheet = |p: &MappedPolygon| p.casts && p.whole;
    let place = SheetPlaces::new(m, &kept, sheet, scene.polygons.len());
    let across: Vec<u32> = kept
        .par_iter()
        .map(|&i| &m.polys[i])
        .filter(|p| sheet(p))
        .flat_map_iter(|p| scene.across(p.source as usize).iter())
        .map(|&q| place.get(q))
        .collect();
    let edges_of = |&i: &usize| if sheet(&m.polys[i]) { m.polys[i].len as usize } else { 0 };
    let first = pieces::starts(kept.iter().map(edges_of));
    let items: Vec<Item> = kept
        .par_iter()
        .zip(&first)
        .map(|(&i, &f)| {
            let p = &m.polys[i];
            Item { bounds: p.bounds, sheet: sheet(p).then(|| (m.ring(p), &across[f..f + p.len as usize])) }
        })
        .collect();
    let found = lone_sheets::find(&items);
    // Without lone polygons, wide backgrounds gain nothing from leaving before the cut: they
    // stay, to be found region by region.
    if settled.iter().all(|s| s.lone.is_empty()) && !found.lone.contains(&true) {
        return LoneSplit::default();
    }
    let outlines = found
        .outlines
        .into_iter()
        .filter_map(|(one, rings)| {
            let p = &m.polys[kept[one as usize]];
            Piece::new(p.source, Region { rings: rings.into() }, p.near)
        })
        .chain(
            settled
                .iter()
                .filter_map(|s| Piece::new(*s.lone.first()?, Region { rings: s.outline.clone().into() }, s.near)),
        )
        .collect();
    // What goes on to the sort: the kept polygons (all but the wide backgrounds) not lone.
    let sorted = pieces::marked(n, kept.par_iter().zip(&found.lone).filter(|(_, &l)| !l).map(|(&i, _)| i));
    let mut lone: Vec<u32> =
        kept.par_iter().zip(&found.lone).filter(|(_, &l)| l).map(|(&i, _)| m.polys[i].source).collect();
    lone.extend(settled.iter().flat_map(|s| s.lone.iter().copied()));
    let behind = (0..n).into_par_iter().filter(|&i| behind[i]).filter_map(|i| m.piece(&m.polys[i])).collect();
    let on_sheet = kept.par_iter().zip(&found.sheet).zip(&found.lone).filter(|((_, &s), &l)| s != NO_ITEM && !l);
    let sheet = on_sheet.map(|((&i, &s), _)| (i as u32, s)).collect();
    let whole_solids = settled.iter().filter(|s| s.rest.is_empty()).count() as u64;
    LoneSplit { lone, outlines, behind, sorted, sheet, whole_solids }
}

/// What of an offered solid is lone ([`settle`]).
struct Settled {
    /// Its lone polygons, and the rings of their union's boundary (even-odd).
    lone: Vec<u32>,
    outline: Vec<Vec<DVec2>>,
    /// The solid's nearness (for the outline's piece).
    near: DepthPlane,
    /// Its other polygons, to be mapped.
    rest: Vec<u32>,
}

/// What of solid `w` is lone, given `met`, the boxes of everything else in the view that
/// meets its box but the wide backgrounds ([`met_by`]): with none, all of it, its ring the
/// outline; otherwise the polygons whose own boxes meet none of them (nothing else meets
/// them, and no polygon of the solid overlaps them: [`whole_solid`]), outlined by their
/// edges with no lone polygon across.
fn settle(scene: &Scene, w: &WholeSolid, met: &[(DVec2, DVec2)]) -> Settled {
    let near = w.near;
    if met.is_empty() {
        return Settled { lone: w.polygons.clone(), outline: vec![w.ring.clone()], near, rest: Vec::new() };
    }
    let mut grid = BoxGrid::new(w.bounds, met.len());
    for (k, &b) in met.iter().enumerate() {
        grid.add(k as u32, b);
    }
    let clear =
        |b: (DVec2, DVec2)| grid.cells(b).all(|c| grid.cells[c].iter().all(|&k| !boxes_meet(b, met[k as usize])));
    let lone: Vec<bool> = w.corners.iter().map(|c| clear(corner_box(c))).collect();
    let (mut kept, mut rest, mut edges) = (Vec::new(), Vec::new(), Vec::new());
    let lone_at = |q: u32| w.polygons.binary_search(&q).is_ok_and(|j| lone[j]);
    for (j, &i) in w.polygons.iter().enumerate() {
        if !lone[j] {
            rest.push(i);
            continue;
        }
        kept.push(i);
        let c = &w.corners[j];
        for (k, &q) in scene.across(i as usize).iter().enumerate() {
            if !lone_at(q) {
                edges.push((c[k], c[(k + 1) % 3]));
            }
        }
    }
    Settled { lone: kept, outline: lone_sheets::chain_all(&edges), near, rest }
}

/// For each offered solid, the boxes of what else in the view meets its box: the other
/// solids' polygons and the polygons of `m` that are not wide backgrounds (`behind`).
fn met_by(solids: &[WholeSolid], m: &Mapped, behind: &[bool]) -> Vec<Vec<(DVec2, DVec2)>> {
    let Some(all) = solids.iter().map(|w| w.bounds).reduce(box_union) else { return Vec::new() };
    let mut grid = BoxGrid::new(all, 4 * solids.len());
    for (k, w) in solids.iter().enumerate() {
        grid.add(k as u32, w.bounds);
    }
    // The solids (but `own`) whose boxes meet `b`.
    let meeting = |b: (DVec2, DVec2), own: Option<u32>| {
        let mut found: Vec<u32> = grid
            .cells(b)
            .flat_map(|c| grid.cells[c].iter().copied())
            .filter(|&k| Some(k) != own && boxes_meet(b, solids[k as usize].bounds))
            .collect();
        found.sort_unstable();
        found.dedup();
        found
    };
    let polygons = m.polys.par_iter().zip(behind).filter(|&(p, &b)| !b && boxes_meet(p.bounds, all));
    let mut pairs: Vec<(u32, (DVec2, DVec2))> =
        polygons.flat_map_iter(|(p, _)| meeting(p.bounds, None).into_iter().map(move |k| (k, p.bounds))).collect();
    pairs.par_sort_unstable_by(|a, b| a.0.cmp(&b.0));
    (0..solids.len())
        .into_par_iter()
        .map(|k| {
            let w = &solids[k];
            let of_k = pairs.partition_point(|p| p.0 < k as u32)..pairs.partition_point(|p| p.0 <= k as u32);
            let mut met: Vec<(DVec2, DVec2)> = pairs[of_k].iter().map(|p| p.1).collect();
            for j in meeting(w.bounds, Some(k as u32)) {
                let other = solids[j as usize].corners.iter().map(corner_box);
                met.extend(other.filter(|&b| boxes_meet(b, w.bounds)));
            }
            met
        })
        .collect()
}

/// The places among `kept` (indices into `m.polys`) of the sheet polygons (`sheet`), by the
/// scene polygon each is mapped from (a view maps a polygon at most once); [`NO_ITEM`] for any
/// other polygon. One list as long as the scene's polygons, written by all threads, where the
/// view holds many of them (three million bisections over the kept polygons' sources, one
/// for each edge of every whole caster, were a third of s3's lone-sheet step on one thread);
/// a hash map where it holds few (the list cost each of s3's five nearly empty cube faces
/// 3 ms).
enum SheetPlaces {
    Listed(Vec<u32>),
    Hashed(FxHashMap<u32, u32>),
}

impl SheetPlaces {
    fn new(m: &Mapped, kept: &[usize], sheet: impl Fn(&MappedPolygon) -> bool + Sync, polygons: usize) -> Self {
        use std::sync::atomic::{AtomicU32, Ordering::Relaxed};
        let sheets = kept.par_iter().enumerate().filter(|&(_, &i)| sheet(&m.polys[i]));
        if kept.len() * 16 < polygons {
            return SheetPlaces::Hashed(sheets.map(|(k, &i)| (m.polys[i].source, k as u32)).collect());
        }
        let mut place = Vec::new();
        place.par_extend((0..polygons).into_par_iter().map(|_| AtomicU32::new(NO_ITEM)));
        sheets.for_each(|(k, &i)| place[m.polys[i].source as usize].store(k as u32, Relaxed));
        SheetPlaces::Listed(place.into_par_iter().map(AtomicU32::into_inner).collect())
    }

    /// The place of scene polygon `s`, if it is a sheet polygon of the view.
    fn get(&self, s: u32) -> u32 {
        match self {
            SheetPlaces::Listed(place) => place.get(s as usize).copied().unwrap_or(NO_ITEM),
            SheetPlaces::Hashed(place) => place.get(&s).copied().unwrap_or(NO_ITEM),
        }
    }
}

/// Most wide polygons a light view tries as backgrounds.
const WIDE_TRIED: usize = 16;

/// `behind[i]`: whether mapped caster `i` is a wide background (ours): convex, not a piece
/// of a fan, with a box at least 1/64 of the view's, and every other caster whose box meets
/// its box lies inside it and wholly in front of it. It hides nothing and is met by
/// everything over it; left out of the regions, it is lit at the end, the visible pieces
/// over it cut out as holes.
fn wide_backgrounds(scene: &Scene, m: &Mapped, solids: &[WholeSolid], extent: f64) -> Vec<bool> {
    let mut behind = vec![false; m.polys.len()];
    // The view's box and its wide polygons, found by all threads.
    let Some((lo, hi)) = m.polys.par_iter().map(|p| p.bounds).reduce_with(box_union) else {
        return behind;
    };
    let area = |b: (DVec2, DVec2)| (b.1 - b.0).x * (b.1 - b.0).y;
    let mut wide: Vec<usize> = (0..m.polys.len())
        .into_par_iter()
        .filter(|&i| area(m.polys[i].bounds) * 64.0 >= area((lo, hi)))
        .filter(|&i| !m.polys[i].crossing && is_convex(m.ring(&m.polys[i])))
        .filter(|&i| !scene.fan_piece(m.polys[i].source as usize))
        .collect();
    wide.sort_unstable_by(|&a, &b| area(m.polys[b].bounds).total_cmp(&area(m.polys[a].bounds)));
    for &w in wide.iter().take(WIDE_TRIED) {
        let b = &m.polys[w];
        let ring = m.ring(b);
        behind[w] = m.polys.par_chunks(WIDE_PIECE).enumerate().all(|(k, chunk)| {
            // The polygons the candidate must hold: all but itself whose boxes meet its box.
            let tested =
                || chunk.iter().enumerate().filter(|&(j, q)| k * WIDE_PIECE + j != w && boxes_meet(q.bounds, b.bounds));
            // Where the candidate holds their whole box, their corners need no test of their
            // own (ours: on s3 the floor holds every sphere).
            let held =
                tested().map(|(_, q)| q.bounds).reduce(box_union).is_some_and(|u| convex_split::holds_box(ring, u));
            tested().all(|(_, q)| {
                let points = || m.ring(q).iter().copied();
                (held || convex_split::holds(ring, points()))
                    && matches!(relation_at(points(), &q.near, &b.near), Relation::Front)
            })
        }) && solids.iter().filter(|w| boxes_meet(w.bounds, b.bounds)).all(|w| {
            // A solid offered whole: its outline inside, and its box on the light's side of
            // the candidate's plane.
            let plane = &scene.polygons[b.source as usize].plane;
            let held = convex_split::holds_box(ring, w.bounds) || convex_split::holds(ring, w.ring.iter().copied());
            held && w.before(plane, 1e-9 * extent)
        });
    }
    behind
}

/// Polygons [`wide_backgrounds`] tests as one piece.
const WIDE_PIECE: usize = 1024;

/// `b` with the pieces of `over` that meet its box cut out as holes (by the even-odd rule):
/// they must lie inside it and not overlap one another.
fn holed<'a>(b: Piece, over: &[&'a Piece]) -> Option<Piece> {
    let mut rings = b.region.rings.to_vec();
    let holes = |s: &&'a Piece| s.overlaps(&b).then(|| s.region.rings.iter().cloned()).into_iter().flatten();
    // In order, and by all threads where there are many (ours: a floor under a crowd takes
    // tens of thousands of holes).
    match over.len() < PARALLEL_HOLES {
        true => rings.extend(over.iter().flat_map(holes)),
        false => rings.par_extend(over.par_iter().flat_map_iter(holes)),
    }
    Piece::new(b.source, Region { rings: rings.into() }, b.near)
}

/// Fewer pieces than this are read for holes by one thread.
const PARALLEL_HOLES: usize = 1024;

/// Deepest a list's pieces may lie over one another (by area, on average) for convex
/// pieces to be split by edges.
const SPLIT_DEPTH: f64 = 8.0;

/// Whether the pieces lie over one another too deeply to be split by edges: more than
/// [`SPLIT_DEPTH`] deep on average over their bounding box. Splitting cuts a piece along the
/// whole lines through the edges over it, so under `d` others a polygon comes apart into
/// some `d²` convex pieces, where Weiler and Atherton's clipper keeps it one region (a stack
/// of 200 large quads: 20,625 pieces and a pass ten times as long).
fn stacked(casters: &[Piece], others: &[Piece]) -> bool {
    let all = || casters.iter().chain(others);
    let Some((lo, hi)) = all().map(|p| p.bounds).reduce(box_union) else { return false };
    let area = |p: &Piece| p.region.rings.iter().map(|r| signed_area(r).abs()).sum::<f64>();
    all().map(area).sum::<f64>() > SPLIT_DEPTH * (hi - lo).x * (hi - lo).y
}

/// Most casters a region of a light view keeps before it is cut in four.
const TILE_PIECES: usize = 1024;

/// Regions of a light view (ours, not the paper's), found by cutting the view in four, at the
/// median of the casters' centres, until each region holds at most [`TILE_PIECES`]
/// casters: each region's pieces, cut to it, are
/// sorted on their own, since what hides what inside one region depends only on what lies in
/// it. A large polygon behind many small ones (a floor under a crowd) is then clipped only by
/// those over each region, not by all of them in turn, and the regions are sorted in
/// parallel. A region is not cut where cutting does not pay: where some quarter would hold
/// every caster of the region, or the quarters together twice as many (casters larger than
/// the quarters, as a stack of polygons covering one another is: cutting would only copy
/// them, four times a level), nor where the cut would make more than `copies` copies of
/// straddling pieces (what is left of that budget is shared among the quarters by their
/// pieces).
fn regions(casters: Vec<Piece>, others: Vec<Piece>, rect: (DVec2, DVec2), copies: usize) -> Vec<List> {
    let (lo, hi) = rect;
    let mid = median_centre(&casters).unwrap_or((lo + hi) * 0.5).clamp(lo, hi);
    let quarters = [
        (lo, mid),
        (DVec2::new(mid.x, lo.y), DVec2::new(hi.x, mid.y)),
        (DVec2::new(lo.x, mid.y), DVec2::new(mid.x, hi.y)),
        (mid, hi),
    ];
    let count = |pieces: &[Piece], q| pieces.iter().filter(|p| touches(p.bounds, q)).count();
    let counts = quarters.map(|q| count(&casters, q));
    let (held, others_held) =
        (counts.iter().sum::<usize>(), quarters.iter().map(|&q| count(&others, q)).sum::<usize>());
    let made = (held + others_held).saturating_sub(casters.len() + others.len());
    let pays = counts.iter().all(|&c| c < casters.len()) && held <= 2 * casters.len() && made <= copies;
    if casters.len() <= TILE_PIECES || !pays {
        return vec![(casters, others)];
    }
    // The copies left are shared among the quarters by their pieces; the quarters are cut
    // in parallel, and their regions listed in order.
    let (left, all) = (copies - made, held + others_held);
    let (cs, os) = (into_quarters(casters, &quarters), into_quarters(others, &quarters));
    let quarters: Vec<(List, (DVec2, DVec2))> = cs.into_iter().zip(os).zip(quarters).collect();
    quarters
        .into_par_iter()
        .map(|((c, o), q)| {
            let share = left * (c.len() + o.len()) / all.max(1);
            regions(c, o, q, share)
        })
        .flatten()
        .collect()
}

/// One region's casters and other polygons.
type List = (Vec<Piece>, Vec<Piece>);

/// The median of the pieces' box centres, in x and in y: a cut there shares them out evenly
/// wherever they crowd (a mesh over a floor: cutting the floor's box in the middle would
/// leave the mesh in one quarter).
fn median_centre(pieces: &[Piece]) -> Option<DVec2> {
    let mut xs: Vec<f64> = pieces.iter().map(|p| p.bounds.0.x + p.bounds.1.x).collect();
    let mut ys: Vec<f64> = pieces.iter().map(|p| p.bounds.0.y + p.bounds.1.y).collect();
    let k = xs.len().checked_sub(1)? / 2;
    let (x, y) = (*xs.select_nth_unstable_by(k, f64::total_cmp).1, *ys.select_nth_unstable_by(k, f64::total_cmp).1);
    Some(DVec2::new(x, y) * 0.5)
}

/// Each piece into the quarters its box overlaps, cut to each when it crosses a border.
fn into_quarters(pieces: Vec<Piece>, quarters: &[(DVec2, DVec2); 4]) -> [Vec<Piece>; 4] {
    let hits = |b: (DVec2, DVec2)| (0..4).filter(move |&k| touches(b, quarters[k]));
    // Each quarter is given its room at once: a list grown as it fills is copied at each
    // doubling.
    let mut counts = [0; 4];
    pieces.iter().flat_map(|p| hits(p.bounds)).for_each(|k| counts[k] += 1);
    let mut out = counts.map(Vec::with_capacity);
    for p in pieces {
        let hit: smallvec::SmallVec<[usize; 4]> = hits(p.bounds).collect();
        if let [k] = hit[..] {
            out[k].push(p);
            continue;
        }
        for k in hit {
            out[k].extend(p.part(cut_to(&p.region, quarters[k])));
        }
    }
    out
}

/// Whether the box `b` overlaps the rectangle `q` (both as (least, greatest) corners).
fn touches(b: (DVec2, DVec2), q: (DVec2, DVec2)) -> bool {
    b.0.x < q.1.x && b.1.x > q.0.x && b.0.y < q.1.y && b.1.y > q.0.y
}

/// `region` cut to the rectangle `(lo, hi)`, ring by ring (Sutherland-Hodgman; the even-odd
/// rule keeps holes holes).
fn cut_to(region: &Region, (lo, hi): (DVec2, DVec2)) -> Region {
    let mut rings = Vec::new();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for ring in &region.rings {
        clip_polygon(ring, |p: DVec2| p.x - lo.x, &mut a);
        clip_polygon(&a, |p: DVec2| hi.x - p.x, &mut b);
        clip_polygon(&b, |p: DVec2| p.y - lo.y, &mut a);
        clip_polygon(&a, |p: DVec2| hi.y - p.y, &mut b);
        if b.len() >= 3 {
            rings.push(b.clone());
        }
    }
    Region { rings: rings.into() }
}

/// Step 1(b) on one list of pieces: the lit part of every caster and of every other polygon.
/// With `cover`, also the pieces that cover the casters' area once over: the visible pieces
/// and the lit parts of backgrounds.
fn lit_pieces(
    scene: &Scene,
    casters: Vec<Piece>,
    others: Vec<Piece>,
    mut cover: Option<&mut Vec<Piece>>,
    stats: &mut Pass1,
) -> std::result::Result<Vec<Piece>, ClipError> {
    // The pieces of a face split into a fan never shadow each other: their lit parts come
    // from a sort without their sibling pieces.
    let face = |p: &Piece| scene.polygons[p.source as usize].face;
    let mut pieces_of: FxHashMap<u32, usize> = FxHashMap::default();
    for c in &casters {
        *pieces_of.entry(face(c)).or_default() += 1;
    }
    let split = |p: &Piece| pieces_of.get(&face(p)).is_some_and(|&n| n > 1);
    // Backgrounds leave the sort where every polygon here casts shadows: a polygon that
    // casts none is lit against the visible parts of every caster (`unshadowed`), and a
    // background's would be missing.
    let back = if stats.backgrounds && others.is_empty() { backgrounds(&casters, &split) } else { Vec::new() };
    // Each list is given its room at once (ours: a list grown as it fills is copied at
    // each doubling).
    let behind = back.iter().filter(|&&b| b).count();
    let (mut kept, mut backs) = (Vec::with_capacity(casters.len() - behind), Vec::with_capacity(behind));
    for (i, c) in casters.into_iter().enumerate() {
        if back.get(i) == Some(&true) {
            backs.push(c);
        } else {
            kept.push(c);
        }
    }
    // The casters are kept for the fans' own sorts, where there are fans.
    let casters = if kept.iter().any(split) { kept.clone() } else { Vec::new() };
    let seen = visible(kept, 0, stats)?;
    let mut pieces: Vec<Piece> = seen.iter().filter(|p| !split(p)).cloned().collect();
    for p in casters.iter().filter(|p| split(p)) {
        let list =
            casters.iter().filter(|q| q.source == p.source || (face(q) != face(p) && q.overlaps(p))).cloned().collect();
        let own = visible(list, 0, stats)?;
        pieces.extend(own.into_iter().filter(|v| v.source == p.source));
    }
    // Polygons that cast no shadow: lit where no visible caster lies in front.
    for o in others {
        pieces.extend(unshadowed(o, &seen, stats)?);
    }
    stats.backgrounds_found += backs.len() as u64;
    let boxes = if backs.is_empty() { SeenBoxes::default() } else { SeenBoxes::new(&seen) };
    let mut near = Vec::new();
    for b in backs {
        let lit = behind_all(b, &seen, &boxes, &mut near, stats)?;
        if let Some(c) = cover.as_deref_mut() {
            c.extend(lit.iter().cloned());
        }
        pieces.extend(lit);
    }
    if let Some(c) = cover {
        c.extend(seen);
    }
    Ok(pieces)
}

/// `back[i]`: whether caster `i` lies behind everything in the list it overlaps (ours, not
/// the paper's): every other caster whose inside meets its inside lies wholly in front of
/// it. Such a polygon (a floor under a crowd) hides nothing, so the area sort can leave it
/// out ([`behind_all`] lights it). Pieces of a face split into a fan (`split`) stay in the
/// sort. Pairs are found by a sweep over the pieces' boxes.
fn backgrounds(casters: &[Piece], split: &impl Fn(&Piece) -> bool) -> Vec<bool> {
    let mut back: Vec<bool> = casters.iter().map(|p| !split(p)).collect();
    let mut order: Vec<usize> = (0..casters.len()).collect();
    order.sort_unstable_by(|&a, &b| casters[a].bounds.0.x.total_cmp(&casters[b].bounds.0.x));
    // The casters whose boxes the sweep line is inside, each with its box beside it (ours:
    // read in one pass, not through the pieces).
    let mut active: Vec<(usize, (DVec2, DVec2))> = Vec::new();
    for &i in &order {
        let a = &casters[i];
        active.retain(|(_, bounds)| bounds.1.x >= a.bounds.0.x);
        for &(k, _) in active.iter().filter(|(_, bounds)| boxes_meet(a.bounds, *bounds)) {
            let b = &casters[k];
            if a.same_sheet(b) {
                continue;
            }
            // Whether the pair would clear either flag, asked (once their boxes meet) before
            // the dearer question whether their insides meet at all.
            let clears_i = back[i] && !matches!(relation(b, a), Relation::Front);
            let clears_k = back[k] && !matches!(relation(a, b), Relation::Front);
            if (clears_i || clears_k) && !regions_apart(&a.region, &b.region) {
                back[i] &= !clears_i;
                back[k] &= !clears_k;
            }
        }
        active.push((i, a.bounds));
    }
    back
}

/// The lit part of `b`, a polygon behind everything it overlaps: where no visible piece of
/// `seen` covers it. The visible pieces do not overlap one another, so when all those over
/// `b` lie inside it they become holes in it, as they are, by the even-odd rule (ours: no
/// clip); otherwise `b` is cut by each. `boxes` holds `seen`'s boxes (ours: the pieces are
/// read only where their boxes meet `b`'s); `near` is room for their indices.
fn behind_all(
    b: Piece,
    seen: &[Piece],
    boxes: &SeenBoxes,
    near: &mut Vec<u32>,
    stats: &mut Pass1,
) -> std::result::Result<Vec<Piece>, ClipError> {
    // A piece inside `b` meets it; one that is not is asked whether it is apart.
    let within =
        |s: &Piece| b.convex && convex_split::holds(&b.region.rings[0], s.region.rings.iter().flatten().copied());
    // The visible pieces whose boxes meet `b`'s, in order.
    boxes.meeting(b.bounds, near);
    let meeting = || near.iter().map(|&i| &seen[i as usize]).filter(|s| !s.same_sheet(&b));
    let mut holes = Vec::new();
    for s in meeting() {
        if within(s) {
            holes.push(s);
        } else if !regions_apart(&s.region, &b.region) {
            let over: Vec<&Piece> = meeting().filter(|s| !regions_apart(&s.region, &b.region)).collect();
            return outside_all(b, over, stats);
        }
    }
    Ok(holed(b, &holes).into_iter().collect())
}

/// The boxes of a region's visible pieces in a uniform grid (ours): each background behind
/// them reads only the pieces whose boxes share a cell with its box, not every piece.
#[derive(Default)]
struct SeenBoxes {
    boxes: Vec<(DVec2, DVec2)>,
    grid: BoxGrid,
}

impl SeenBoxes {
    fn new(seen: &[Piece]) -> SeenBoxes {
        let boxes: Vec<(DVec2, DVec2)> = seen.iter().map(|p| p.bounds).collect();
        let Some(bounds) = boxes.iter().copied().reduce(box_union) else { return SeenBoxes::default() };
        let mut grid = BoxGrid::new(bounds, boxes.len());
        for (i, &b) in boxes.iter().enumerate() {
            grid.add(i as u32, b);
        }
        SeenBoxes { boxes, grid }
    }

    /// The pieces whose boxes meet `b`, into `out`, in increasing order.
    fn meeting(&self, b: (DVec2, DVec2), out: &mut Vec<u32>) {
        out.clear();
        if self.boxes.is_empty() {
            return;
        }
        for c in self.grid.cells(b) {
            out.extend(self.grid.cells[c].iter().filter(|&&i| boxes_meet(self.boxes[i as usize], b)));
        }
        out.sort_unstable();
        out.dedup();
    }
}

/// Pass 1 and the merge for light `light` of `scene` ([`ShadowDatabase::build`]): every
/// sample's lit fragments. A point sample's six cube faces are independent, and are sorted in
/// parallel.
fn lit_fragments(
    scene: &Scene,
    light: usize,
    options: AthertonWeilerGreenbergOptions,
    counters: &mut Counters,
) -> Result<Vec<Faces>> {
    let l = scene.lights.get(light).ok_or_else(|| {
        Error::out_of_range(
            "light",
            light,
            format!("a light of the scene (it has {}, numbered from 0)", scene.lights.len()),
        )
    })?;
    let extent = scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length().max(1e-300));
    let t = Instant::now();
    let mut done: Vec<(usize, Vec<Lit>, Pass1)> = Vec::new();
    let offer_solids = options.lone_sheets && options.whole_solids && !scene.solids.is_empty();
    let members = if offer_solids { scene.solid_members() } else { Vec::new() };
    for (s, sample) in l.samples().into_iter().enumerate() {
        let unseen = unseen(scene, sample, extent, options.solid_cull);
        // A polygon wholly inside one cube face is mapped into that face alone.
        let face = if options.face_binning { cube_faces(scene, sample, &unseen) } else { Vec::new() };
        let views = LightView::views(sample);
        let seen = view_lists(&face, &unseen, views.len());
        let closed = if offer_solids { scene.closed_from(sample) } else { Vec::new() };
        let solids = SampleSolids { sample, unseen: &unseen, face: &face, closed, members: &members };
        let views: Vec<(Vec<Lit>, Pass1)> = views
            .into_par_iter()
            .zip(&seen)
            .enumerate()
            .map(|(v, (view, seen))| {
                let mut stats = Pass1::new(options);
                let whole =
                    if offer_solids { whole_solids(scene, &view, v as u8, &solids, extent) } else { Vec::new() };
                let lit = lit_in_view(scene, seen, view, whole, extent, &mut stats).map_err(clip_error)?;
                Ok((lit, stats))
            })
            .collect::<Result<_>>()?;
        done.extend(views.into_iter().map(|(lit, stats)| (s, lit, stats)));
    }
    let mut samples: Vec<Faces> = (0..l.sample_count()).map(|_| Vec::new()).collect();
    let mut stats = Pass1::new(options);
    for (s, lit, st) in done {
        samples[s].push(lit);
        stats.add(&st);
    }
    counters.add(crate::stats::Counter::LightSpaceFragments, stats.fragments);
    counters.add(crate::stats::Counter::ClipOperations, stats.clips);
    counters.add(crate::stats::Counter::InterpenetrationSplits, stats.splits);
    counters.add(crate::stats::Counter::AreaSortDepthMax, stats.depth_max);
    counters.add(crate::stats::Counter::LightViewTiles, stats.tiles);
    counters.add(crate::stats::Counter::LightViewBackgrounds, stats.backgrounds_found);
    counters.add(crate::stats::Counter::LightViewLone, stats.lone);
    counters.add(crate::stats::Counter::LightViewWholeSolids, stats.whole_solids_found);
    let detail: usize = samples.iter().flatten().map(Vec::len).sum();
    let verts: usize = samples
        .par_iter()
        .flat_map(|faces| faces.par_iter().flat_map(|f| f.par_iter()))
        .map(|d| d.rings(scene).map(<[DVec3]>::len).sum::<usize>())
        .sum();
    counters.add(crate::stats::Counter::DetailPolygons, detail as u64);
    counters.add(crate::stats::Counter::DetailVertices, verts as u64);
    counters.add(crate::stats::Counter::Pass1Us, t.elapsed().as_micros() as u64);
    Ok(samples)
}

impl ShadowDatabase {
    /// Pass 1 and the merge for light `light` of `scene`: every sample's lit detail polygons.
    /// A point sample's six cube faces are independent, and are sorted in parallel.
    pub fn build(
        scene: &Scene,
        light: usize,
        options: AthertonWeilerGreenbergOptions,
        counters: &mut Counters,
    ) -> Result<ShadowDatabase> {
        let lit = lit_fragments(scene, light, options, counters)?;
        let detail = |s: Faces| s.into_par_iter().flatten().map(|f| f.into_detail(scene)).collect();
        Ok(ShadowDatabase { samples: lit.into_iter().map(detail).collect() })
    }

    /// Writes the database as an OBJ file: one group per detail polygon, named after its
    /// light sample and the face id of its source polygon (`g sample<s>_face<id>`); holes are
    /// separate faces of the same group.
    pub fn write_obj(&self, scene: &Scene, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let mut obj = ObjText::with_header("# umbra: Atherton-Weiler-Greenberg lit detail polygons\n");
        for (s, polys) in self.samples.iter().enumerate() {
            for d in polys {
                obj.group(&format!("sample{s}_face{}", scene.polygons[d.source as usize].face));
                for ring in &d.rings {
                    let ids: Vec<usize> = ring.iter().map(|&v| obj.vertex(v)).collect();
                    obj.face(ids.into_iter().map(|v| (v, None)));
                }
            }
        }
        obj.save(path)
    }
}

/// The prepared stage: each sample's detail polygons in screen space.
pub struct AthertonWeilerGreenberg<'a> {
    ctx: &'a ShadowContext<'a>,
    detail: Vec<Overlay>,
}

impl<'a> AthertonWeilerGreenberg<'a> {
    /// Builds the databases (or takes the ones in the options) and puts their detail polygons
    /// through the camera.
    pub fn new(
        ctx: &'a ShadowContext<'a>,
        options: AthertonWeilerGreenbergOptions,
        counters: &mut Counters,
    ) -> Result<Self> {
        let mut detail = Vec::new();
        match &ctx.awg_database {
            Some(db) if db.len() == ctx.scene.lights.len() => {
                for polys in db.iter().flat_map(|d| &d.samples) {
                    let (wholes, screen) = through_camera(ctx, std::slice::from_ref(polys));
                    detail.push(overlay(ctx, &wholes, screen, counters));
                }
            }
            Some(_) => {
                return Err(Error::InvalidOption("the shadow database does not match the scene's lights".into()))
            }
            None => {
                // The lights are independent: built side by side, one light's last cube face
                // overlaps the next light's work. Counters are merged in light order.
                let built: Vec<(Vec<Faces>, Counters)> = (0..ctx.scene.lights.len())
                    .into_par_iter()
                    .with_max_len(1)
                    .map(|l| {
                        let mut c = Counters::default();
                        Ok((lit_fragments(ctx.scene, l, options, &mut c)?, c))
                    })
                    .collect::<Result<_>>()?;
                for (samples, c) in built {
                    counters.merge(&c);
                    for faces in samples {
                        let (wholes, screen) = through_camera(ctx, &faces);
                        // Fragments built for this frame alone go once they are through the
                        // camera, before the overlay is made.
                        faces.into_iter().for_each(crate::pieces::let_go);
                        detail.push(overlay(ctx, &wholes, screen, counters));
                    }
                }
            }
        }
        Ok(AthertonWeilerGreenberg { ctx, detail })
    }
}

/// Fragments on screen: each one's source and its outlines.
type OnScreen = Vec<(u32, Vec<Vec<DVec2>>)>;

/// One sample's lit fragments (the lists of `parts`, one after another) through the camera,
/// in parallel: the sources of those seen that are whole polygons, and the others' outlines
/// on screen with their sources. A fragment that is its whole source polygon (ours) covers
/// every run on it: it needs no edges (but is drawn with them for `--debug`).
fn through_camera<F: Fragment>(ctx: &ShadowContext, parts: &[Vec<F>]) -> (Vec<u32>, OnScreen) {
    use rayon::iter::Either;
    let scene = ctx.scene;
    parts
        .par_iter()
        .flat_map(|p| p.par_iter())
        .filter(|d| ctx.visible[d.source() as usize])
        .map_init(
            || ([Vec::new(), Vec::new()], Vec::new()),
            |(scratch, ring), d| {
                if !ctx.keep_outlines && d.whole(scene) {
                    return Either::Left(d.source());
                }
                let mut rings = Vec::new();
                for r in d.rings(scene) {
                    if ctx.view.clip_project(r, scratch, ring) {
                        rings.push(ring.clone());
                    }
                }
                Either::Right((d.source(), rings))
            },
        )
        .partition_map(|e| e)
}

/// One sample's overlay of the fragments [`through_camera`] gave.
fn overlay(ctx: &ShadowContext, wholes: &[u32], screen: OnScreen, counters: &mut Counters) -> Overlay {
    // Grouped by source polygon, in the order sources first come, by all threads (a hash
    // map filled on one thread was a serial tenth of s3's preparation); each source's edge
    // table is built on its own, in parallel.
    let receivers = grouped_by_source(&screen);
    let rings_of = |&i: &u32| screen[i as usize].1.as_slice();
    let mut overlay = Overlay::from_receivers(ctx.view.height, ctx.keep_outlines, &receivers, rings_of);
    overlay.add_wholes(wholes);
    counters.add(crate::stats::Counter::DetailPolygonsInView, overlay.len() as u64);
    crate::pieces::let_go(screen);
    overlay
}

/// The detail polygons on screen with outlines (their places in `screen`), grouped by
/// source polygon, each group in screen order and the groups in the order their sources
/// first come: found by sorting, by all threads.
fn grouped_by_source(screen: &[(u32, Vec<Vec<DVec2>>)]) -> Vec<(u32, Vec<u32>)> {
    let pairs = screen.par_iter().enumerate().filter(|(_, s)| !s.1.is_empty()).map(|(i, s)| (s.0, i as u32));
    let mut groups = pieces::grouped(pairs.collect());
    groups.par_sort_unstable_by_key(|(_, members)| members[0]);
    groups
}

impl ShadowStage for AthertonWeilerGreenberg<'_> {
    /// The detail polygons' overlays (a database kept by the renderer is not counted).
    fn bytes(&self) -> usize {
        self.detail.iter().map(Overlay::bytes).sum()
    }

    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        Box::new(CoverWalker::new(self.ctx, &self.detail, 1.0, 0.0, "lit detail polygon"))
    }

    fn outlines(&self) -> Vec<Vec<DVec2>> {
        self.detail.first().map_or_else(Vec::new, |o| o.rings().to_vec())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::newell_normal;
    use rand::{Rng, SeedableRng};

    /// A polygon that [`cube_faces`] puts in one cube face maps into no other: for random
    /// triangles around a light, many with corners on or a hair off the faces' borders (where
    /// two or three coordinates are equal in size), every face but the chosen one finds
    /// nothing of it, so leaving it out of those faces changes nothing.
    /// Each view's list is the one a scan of the whole scene gives: the polygons not unseen
    /// whose corners lie in no other face alone, in increasing order (over several pieces of
    /// [`MAP_PIECE`] polygons).
    #[test]
    fn each_view_lists_the_polygons_a_scan_of_the_scene_gives_it() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(40);
        let n = 3 * MAP_PIECE + 17;
        let unseen: Vec<bool> = (0..n).map(|_| rng.gen_bool(0.3)).collect();
        let face: Vec<Option<u8>> =
            (0..n).map(|i| (!unseen[i] && rng.gen_bool(0.8)).then(|| rng.gen_range(0..6))).collect();
        let lists = view_lists(&face, &unseen, 6);
        for (f, list) in lists.iter().enumerate() {
            let scan: Vec<u32> = (0..n as u32)
                .filter(|&i| !unseen[i as usize] && face[i as usize].is_none_or(|g| g as usize == f))
                .collect();
            assert_eq!(list, &scan);
        }
        assert!(lists.iter().all(|l| l.len() > n / 10 && l.len() < n / 2));
        // Without binning every view lists every polygon not unseen.
        let all: Vec<u32> = (0..n as u32).filter(|&i| !unseen[i as usize]).collect();
        assert!(view_lists(&[], &unseen, 6).iter().all(|l| l == &all));
    }

    #[test]
    fn a_polygon_in_one_cube_face_maps_into_no_other() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1978);
        let light = DVec3::new(0.25, -0.5, 2.0);
        let views = LightView::views(LightSample::Point(light));
        let (mut alone, mut several) = (0, 0);
        for _ in 0..20_000 {
            // Corners near one another, and near a border: a random point with one
            // coordinate's size copied onto another, then nudged by 0, 1 or a few units in
            // the last place.
            let c = DVec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
            let (a, b) = (rng.gen_range(0..3), rng.gen_range(0..3));
            let mut corner = || {
                let mut p =
                    c + DVec3::new(rng.gen_range(-0.1..0.1), rng.gen_range(-0.1..0.1), rng.gen_range(-0.1..0.1));
                if rng.gen_bool(0.5) {
                    let sign = if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
                    p[b] = sign * p[a].abs();
                    let nudge = [0u64, 1, 3][rng.gen_range(0..3)];
                    p[b] = f64::from_bits(p[b].to_bits().wrapping_add(nudge));
                }
                light + p
            };
            let verts = [corner(), corner(), corner()];
            let n = newell_normal(&verts);
            if n.length() < 1e-12 {
                continue;
            }
            let plane = Plane::new(n.normalize(), verts[0]);
            let first = verts.iter().map(|&v| cube_face(v - light)).next().flatten();
            let face = (verts.iter().all(|&v| cube_face(v - light) == first)).then_some(first).flatten();
            let Some(face) = face else {
                several += 1;
                continue;
            };
            alone += 1;
            for (g, view) in views.iter().enumerate().filter(|&(g, _)| g != face as usize) {
                let mut out = Vec::new();
                let got = view.map_into(&verts, &plane, 1e-9, &mut out, &mut [Vec::new(), Vec::new()]);
                assert!(got.is_none() && out.is_empty(), "{verts:?} in face {face} maps into face {g}");
            }
        }
        assert!(alone > 1000 && several > 1000, "{alone} in one face, {several} not");
    }

    /// The turn of a triangle is the exact sign of its determinant wherever it is not 0: on
    /// 200,000 triangles with dyadic corners (whose determinants i128 gives exactly) on or
    /// within a unit or two of a line, where the f64 products round, and it is 0 for every
    /// triangle on the line; and it is never 0 on the triangles well away from one.
    #[test]
    fn a_triangle_turns_the_way_its_exact_determinant_says() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1997);
        let (mut decided, mut undecided) = (0, 0);
        for k in 0..200_000 {
            // Corners below 2^41 over 2^20: every difference exact, the products rounded.
            let big = 1i64 << 40;
            let a = [rng.gen_range(-big..big), rng.gen_range(-big..big)];
            let dir = [rng.gen_range(-4096..4096), rng.gen_range(-4096..4096)];
            let along = |m: i64| [a[0] + m * dir[0], a[1] + m * dir[1]];
            let b = along(rng.gen_range(-(1 << 18)..1 << 18));
            let mut c = along(rng.gen_range(-(1 << 18)..1 << 18));
            c[rng.gen_range(0..2)] += rng.gen_range(-2..=2);
            if k % 10 == 0 {
                c = [rng.gen_range(-big..big), rng.gen_range(-big..big)];
            }
            let exact = {
                let w = |p: [i64; 2], q: [i64; 2], d: usize| i128::from(p[d] - q[d]);
                (w(a, c, 0) * w(b, c, 1) - w(a, c, 1) * w(b, c, 0)).signum() as f64
            };
            let f = |p: [i64; 2]| DVec2::new(p[0] as f64, p[1] as f64) / (1u64 << 20) as f64;
            let got = turn_of([f(a), f(b), f(c)]);
            assert!(got == 0.0 || got == exact, "{a:?} {b:?} {c:?}: {got} against {exact}");
            if k % 10 == 0 {
                assert_ne!(got, 0.0, "{a:?} {b:?} {c:?}");
            }
            if got == 0.0 {
                undecided += 1;
            } else {
                decided += 1;
            }
        }
        assert!(undecided > 10_000 && decided > 50_000, "{decided} decided, {undecided} not");
    }

    /// A sphere lit from one side is offered whole in the view that holds it, every
    /// polygon facing the light in it; the same sphere with its cap pushed in, lit from the
    /// side, turns the dent's far wall to the light behind its near rim, so that its front
    /// folds over itself in the view, and is not offered.
    #[test]
    fn a_front_that_folds_over_itself_is_not_offered_whole() {
        use crate::scene::{Camera, Light, Material, Object};
        let offered = |dent: bool| {
            let centre = DVec3::new(0.0, 1.0, 0.0);
            let mut mesh = crate::generate::geodesic_sphere(centre, 1.0, 3);
            if dent {
                let top = centre.y + 0.3;
                mesh.positions.iter_mut().filter(|p| p.y > top).for_each(|p| p.y = top - 0.6 * (p.y - top));
            }
            let camera = Camera { width: 32, height: 24, ..Camera::new(DVec3::new(0.0, 3.0, 6.0), centre) };
            let light = DVec3::new(-4.0, 3.5, 0.5);
            let scene = Scene::builder(camera)
                .material(Material::new("m"))
                .object(Object::new(mesh), "m")
                .light(Light::point(light))
                .build()
                .unwrap();
            let sample = LightSample::Point(light);
            let extent = scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length());
            let unseen = unseen(&scene, sample, extent, true);
            let face = cube_faces(&scene, sample, &unseen);
            let members = scene.solid_members();
            let of = SampleSolids {
                sample,
                unseen: &unseen,
                face: &face,
                closed: scene.closed_from(sample),
                members: &members,
            };
            let facing = unseen.iter().filter(|&&u| !u).count();
            let views = LightView::views(sample);
            let found: Vec<WholeSolid> = views
                .iter()
                .enumerate()
                .flat_map(|(v, view)| whole_solids(&scene, view, v as u8, &of, extent))
                .collect();
            (found.iter().map(|w| w.polygons.len()).collect::<Vec<_>>(), facing)
        };
        let (whole, facing) = offered(false);
        assert_eq!(whole, vec![facing], "the sphere's {facing} polygons facing the light");
        let (dented, facing) = offered(true);
        assert!(dented.is_empty() && facing > 100, "{dented:?} offered of {facing} facing the light");
    }
}
