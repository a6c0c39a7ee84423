//! The scan-line shadow algorithm of Appel (1968) and Bouknight & Kelley (1970), as the "Árnyékolás" notes
//! describes it.
//!
//! For every light sample:
//!
//! 1. **Pairs.** Polygon A can shadow polygon B only by its projection from the light onto
//!    B's plane, A'. There are n(n−1) ordered pairs (A, B) for n polygons.
//! 2. **The sphere prefilter.** Every polygon is projected onto a sphere around the light and
//!    its extent kept (a bounding cone of the directions to its vertices, binned by
//!    spherical coordinates with the azimuth's wrap-around handled). Pairs whose extents do
//!    not overlap cannot shadow each other and are never projected. For a directional light
//!    the "sphere" is the plane across the light's direction, and the extents are boxes there.
//!    Pairs where A lies wholly behind B as seen from the light are dropped too. A corner
//!    that A shares with B lies on B's plane, whatever rounding makes of its distance: on a
//!    closed mesh most candidate pairs are neighbours of this kind, and none of them is
//!    projected.
//! 3. **Projection.** Only the part of A between the light and B's plane can shadow B: A is
//!    clipped by the plane through the light parallel to B and by B's plane, and also by the
//!    pyramid from the light over B's bounding rectangle (what falls outside it cannot fall
//!    on B, and this keeps the projection finite), then projected from the light onto B's
//!    plane (`Q = L − (P − L)(N·L + d)/(N·(P − L))`, the "Special Effect" notes; a parallel projection along
//!    the light's direction for a directional light, the "Árnyékolás" notes' `M_par`). The shadow polygon
//!    A' is then put through the camera into screen space, still attached to B.
//! 4. **Scan segments.** For each visible run on B, the shadow polygons on B are walked with
//!    the shared edge and active-edge tables ([`super::overlay`]). Then, recursively: if no
//!    shadow polygon touches the segment it is lit; if one covers it fully it is in shadow;
//!    if one covers it partly, the segment is split at that polygon's edges and each part is
//!    examined again.
//!
//! Self-shadowing (B's seen side facing away from the light) needs no projection: the
//! pipeline's same-side rule answers it before this stage is asked (see [`super`]).
//!
//! Degenerate input: a light on A's plane makes A's shadow zero-area (A is skipped as a
//! caster for that sample); a light on B's plane leaves B unlit by the same-side rule;
//! polygons on the far side of the light from B are clipped away by the plane through the
//! light; zero-area projections are dropped. None of these divide by zero.

use super::far_outline::{self, FarEdge};
use super::overlay::{Interval, Overlay, OverlayWalker, ReceiverTable};
use super::own_solid::{Own, OwnSolid};
use super::projection::{self, bounding_rectangle, light_side, Projector, Target};
use super::solid_outlines::{self, SolidOutlines};
use super::{
    BouknightKelleyOptions, Cover, Decision, Detail, Outcome, Segment, ShadowContext, ShadowStage, ShadowWalker,
};
use crate::geometry::{grid_rectangle, newell_normal};
use crate::pool::Pool;
use crate::scene::{LightSample, Scene};
use crate::stats::Counters;
use crate::visibility::Run;
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::time::Instant;

/// The prepared stage: for each light sample, the shadow polygons on their receivers.
pub struct BouknightKelley<'a> {
    ctx: &'a ShadowContext<'a>,
    /// `shadows[sample_index(l, s)]`.
    shadows: Vec<Overlay>,
    /// What became of each receiver's pairs, per sample, when the options keep outlines
    /// (for traces).
    pairs: Vec<FxHashMap<u32, Pairs>>,
}

/// What became of one receiver's pairs (kept for traces).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Pairs {
    /// The casters the prefilter kept (all casters without it).
    pub kept: Vec<u32>,
    /// Of those, the ones wholly behind the receiver as the light sees it.
    pub behind: Vec<u32>,
    /// The caster of each shadow polygon on the receiver: `(shadow polygon, caster)`.
    pub shadow_polygons: Vec<(u32, u32)>,
}

impl Pairs {
    /// Adds what became of the pairs of `other`, a later piece of the same receiver's.
    fn append(&mut self, mut other: Pairs) {
        self.kept.append(&mut other.kept);
        self.behind.append(&mut other.behind);
        self.shadow_polygons.append(&mut other.shadow_polygons);
    }
}

impl<'a> BouknightKelley<'a> {
    /// Makes the shadow polygons of every light sample.
    pub fn new(ctx: &'a ShadowContext<'a>, options: BouknightKelleyOptions, counters: &mut Counters) -> Self {
        let (shadows, pairs) =
            ctx.all_samples().map(|(_, _, sample)| shadow_polygons(ctx, options, sample, counters)).unzip();
        BouknightKelley { ctx, shadows, pairs }
    }
}

/// Steps 1-3 for one light sample. Receivers are the polygons seen at some pixel, with the
/// light on their seen side; each gathers its candidate casters (through the prefilter, or
/// all of them), drops those wholly behind it, and projects the rest. Receivers are
/// independent, so they are worked on in parallel.
fn shadow_polygons(
    ctx: &ShadowContext,
    options: BouknightKelleyOptions,
    sample: LightSample,
    counters: &mut Counters,
) -> (Overlay, FxHashMap<u32, Pairs>) {
    let scene = ctx.scene;
    let n = scene.polygons.len();
    counters.add(crate::stats::Counter::Pairs, (n as u64) * (n as u64).saturating_sub(1));
    let seen = |i: usize| !options.seen_receivers || ctx.visible[i];
    let receivers: Vec<u32> = (0..n as u32)
        .into_par_iter()
        .filter(|&i| seen(i as usize) && sample.on_seen_side(&scene.polygons[i as usize].plane, ctx.view.eye))
        .collect();
    let (casters, dropped) = projection::casters(scene, sample, ctx.extent, options.solid_cull);
    if options.solid_cull {
        counters.add(crate::stats::Counter::CastersDroppedFacingAway, dropped.len() as u64);
    }
    counters.add(crate::stats::Counter::Receivers, receivers.len() as u64);
    counters.add(crate::stats::Counter::Casters, casters.len() as u64);
    counters.add(crate::stats::Counter::PairsWithRoles, receivers.len() as u64 * casters.len() as u64);

    // Outlines follow the prefilter's candidates: without it every caster is one, and a
    // receiver would outline every solid whose shadow misses it.
    let outlines = (options.solid_outlines && options.prefilter && !ctx.keep_outlines)
        .then(|| SolidOutlines::new(scene, &casters, sample, &ctx.pools.stash));
    let own = (options.own_solid && options.drop_behind).then(|| OwnSolid::kept(scene, &ctx.pools.stash));
    let t = Instant::now();
    let extents = options.prefilter.then(|| Extents::new(scene, sample, &casters, &receivers));
    let (grid, extents) = match extents {
        Some(e) if options.sphere_grid => (Some(SphereGrid::new(e, &casters)), None),
        e => (None, e),
    };
    counters.add(crate::stats::Counter::PrefilterGridUs, t.elapsed().as_micros() as u64);

    // Receivers differ widely in cost, so the loop is cut into pieces of at most
    // `RECEIVERS_PER_PIECE` (rayon's own cut leaves a few long pieces, and a thread that
    // runs out of work waits for the last); the pieces share their threads' stamps. Each
    // piece gathers every receiver's candidates (step 2), then projects them (step 3), and
    // folds its receivers' results into one `Piece`, in order: the clock is read twice a
    // phase of a piece, not of a receiver (s3's 277,000 receivers' reads were 3% of its
    // frame).
    let stamps = Pool::default();
    let gather = |b: u32, stamp: &mut [u32], out: &mut Vec<u32>, tally: &mut Tally| {
        let own = own.as_deref().and_then(|o| o.of(scene, b, sample));
        match (&grid, &extents) {
            (Some(g), _) => g.candidates(b, own, &scene.solid_of, stamp, out),
            (None, Some(e)) => tally.tested += e.every_pair(b, &casters, out),
            (None, None) => out.clone_from(&casters),
        }
        if let (Some(o), None) = (own, &grid) {
            out.retain(|&a| !o.skips(a, scene.solid_of[a as usize]));
        }
        tally.on_own_solid += own.is_some() as u64;
        tally.own_solid_front += own.map_or(0, |o| o.front.len() as u64);
    };
    let pieces: Vec<Piece> = receivers
        .par_chunks(RECEIVERS_PER_PIECE)
        .map_init(
            || {
                let mut stamp = stamps.lease();
                if stamp.len() != n {
                    stamp.clear();
                    stamp.resize(n, u32::MAX);
                }
                (Workspace::default(), stamp, Vec::new(), Vec::new())
            },
            |(work, stamp, one, gathered), receivers| {
                let (t, mut tally) = (Instant::now(), Tally::default());
                gathered.clear();
                let mut ends = Vec::with_capacity(receivers.len());
                for &b in receivers {
                    gather(b, stamp, one, &mut tally);
                    gathered.extend_from_slice(one);
                    ends.push(gathered.len());
                }
                tally.prefilter_ns = t.elapsed().as_nanos() as u64;
                let (t, mut piece) = (Instant::now(), Piece::default());
                for (k, &b) in receivers.iter().enumerate() {
                    let candidates = &gathered[k.checked_sub(1).map_or(0, |j| ends[j])..ends[k]];
                    let onto = Onto { ctx, options, sample, b };
                    let outlined = outlines.as_ref().map_or(Vec::new(), |o| outlined_solids(onto, o, candidates));
                    let (tally, table, pairs) = match &outlines {
                        Some(o) if !outlined.is_empty() => project_counted(onto, o, &outlined, candidates),
                        _ => project_onto(onto, candidates, work),
                    };
                    piece.add(tally, table, pairs, ctx.keep_outlines);
                }
                tally.projection_ns = t.elapsed().as_nanos() as u64;
                piece.tally.add(&tally);
                piece
            },
        )
        .collect();
    // The grid is let go before the overlay is made (a million polygons' cones).
    drop((grid, extents));

    let (overlay, total, kept_pairs) = merge(ctx, pieces);
    if options.prefilter {
        counters.add(crate::stats::Counter::PairsKeptByPrefilter, total.kept);
        if !options.sphere_grid {
            counters.add(crate::stats::Counter::PairsTestedByPrefilter, total.tested);
        }
    }
    if let Some(own) = &own {
        counters.add(crate::stats::Counter::ReceiversOnOwnSolid, total.on_own_solid);
        counters.add(crate::stats::Counter::OwnSolidFront, total.own_solid_front);
        counters.add(crate::stats::Counter::OwnSolidBytes, own.bytes() as u64);
    }
    if options.drop_behind {
        counters.add(crate::stats::Counter::PairsDroppedBehind, total.behind);
    }
    if options.wedge {
        counters.add(crate::stats::Counter::PairsOutsideReceiver, total.outside);
    }
    if options.slab {
        counters.add(crate::stats::Counter::PairsApart, total.apart);
    }
    counters.add(crate::stats::Counter::ProjectionsEmpty, total.empty);
    if outlines.is_some() {
        counters.add(crate::stats::Counter::SolidOutlines, total.outlines);
        counters.add(crate::stats::Counter::PairsOutlined, total.outlined);
    }
    counters.add(crate::stats::Counter::ShadowPolygons, overlay.len() as u64);
    counters.add(crate::stats::Counter::PrefilterCpuUs, total.prefilter_ns / 1000);
    counters.add(crate::stats::Counter::ProjectionCpuUs, total.projection_ns / 1000);
    (overlay, kept_pairs)
}

/// Steps 2 and 3 for the receiver `onto` names, `b`: each candidate caster (not a piece of `b`'s own face) is
/// projected from the light onto `b`'s plane and into the image, unless (ours, with their
/// switches) it lies wholly behind `b` as the light sees it, outside `b`'s wedge, or apart
/// from all between the light and `b` ([`apart`]). Returns
/// the tally, the shadow polygons' edge table, and (for traces) what became of each pair.
///
/// A receiver under more than [`CASTERS_PER_PIECE`] candidates (s3's floor has a million)
/// is worked on by all threads (ours), its candidates cut into pieces in order whose tables
/// and pairs are appended in order: the table one thread would build, and no thread left to
/// project a million casters alone.
fn project_onto(onto: Onto, candidates: &[u32], work: &mut Workspace) -> (Tally, ReceiverTable, Pairs) {
    if candidates.len() <= CASTERS_PER_PIECE {
        let (tally, mut table, pairs) = project_piece(onto, candidates, work);
        table.finish();
        return (tally, table, pairs);
    }
    let parts: Vec<(Tally, ReceiverTable, Pairs)> = candidates
        .par_chunks(CASTERS_PER_PIECE)
        .map_init(Workspace::default, |work, piece| project_piece(onto, piece, work))
        .collect();
    let (mut tally, mut pairs, mut tables) = (Tally::default(), Pairs::default(), Vec::with_capacity(parts.len()));
    for (t, table, p) in parts {
        tally.add(&t);
        pairs.append(p);
        tables.push(table);
    }
    let table = ReceiverTable::joined(tables);
    let (b, ctx) = (onto.b, onto.ctx);
    let mut table = table.unwrap_or_else(|| ReceiverTable::new(b, ctx.view.height, ctx.keep_outlines));
    table.finish();
    (tally, table, pairs)
}

/// The solids outlined on the receiver `onto` names (ours, [`solid_outlines`]): of a
/// receiver with many `candidates`, the solids that give it many and fit between it and the
/// light, in increasing order.
fn outlined_solids(onto: Onto, outlines: &SolidOutlines, candidates: &[u32]) -> Vec<u32> {
    if candidates.len() < solid_outlines::RECEIVER_MIN {
        return Vec::new();
    }
    let (ctx, scene) = (onto.ctx, onto.ctx.scene);
    let mut count: FxHashMap<u32, u32> = FxHashMap::default();
    for &a in candidates {
        let s = scene.solid_of[a as usize];
        if (s as usize) < scene.solids.len() {
            *count.entry(s).or_default() += 1;
        }
    }
    let target = onto.target();
    let mut solids: Vec<u32> = count
        .into_iter()
        .filter(|&(s, k)| {
            k >= solid_outlines::PER_SOLID && outlines.fits(scene, s, &target, ctx.view, 1e-9 * ctx.extent)
        })
        .map(|(s, _)| s)
        .collect();
    solids.sort_unstable();
    solids
}

/// Steps 2 and 3 for the receiver `onto` names with the solids `outlined` outlined (ours,
/// [`solid_outlines`]): their boundaries' edges, and every other candidate's shadow
/// polygon, counted into one table, their shared edges cancelled. A receiver with more
/// candidates left than one thread's piece is worked on by all threads, as in
/// [`project_onto`].
fn project_counted(
    onto: Onto,
    outlines: &SolidOutlines,
    outlined: &[u32],
    candidates: &[u32],
) -> (Tally, ReceiverTable, Pairs) {
    let Onto { ctx, sample, b, .. } = onto;
    let (scene, view, target) = (ctx.scene, ctx.view, onto.target());
    // A caster in an outline: on an outlined solid, facing the light.
    let in_outline = |a: u32| outlined.binary_search(&scene.solid_of[a as usize]).is_ok() && outlines.outlined(a);
    let rest: Vec<u32> = candidates.iter().copied().filter(|&a| !in_outline(a)).collect();
    let mut tally = Tally { outlines: outlined.len() as u64, ..Tally::default() };
    tally.outlined = (candidates.len() - rest.len()) as u64;
    tally.kept = tally.outlined;
    // Each solid's outline on its own, by all threads (the first receiver to ask finds a
    // solid's boundary: a pass over its polygons).
    let mut edges: Vec<FarEdge> = outlined
        .par_iter()
        .flat_map_iter(|&s| {
            let winding = solid_outlines::winding(view, &target, scene.solids[s as usize].sign);
            let mut edges = Vec::new();
            solid_outlines::push_outline(view, &target, outlines.edges(scene, s), winding, &mut edges);
            edges
        })
        .collect();
    let piece = |work: &mut Workspace, piece: &[u32]| {
        let mut edges = Vec::new();
        let mut made = 0u32;
        let (tally, _) = project_each(onto, piece, work, |ring, a| {
            // The caster's side of the light, taken round the way its corners run (as the
            // front outline takes it: a reflected scene's corners run against their plane).
            let plane = &scene.polygons[a as usize].plane;
            let side = sample.side_of(plane) * newell_normal(scene.verts(a as usize)).dot(plane.n).signum();
            far_outline::push_ring(ring, solid_outlines::winding(view, &target, side), &mut edges);
            made += 1;
        });
        (tally, edges, made)
    };
    let parts: Vec<(Tally, Vec<FarEdge>, u32)> = if rest.len() <= CASTERS_PER_PIECE {
        vec![piece(&mut Workspace::default(), &rest)]
    } else {
        rest.par_chunks(CASTERS_PER_PIECE).map_init(Workspace::default, piece).collect()
    };
    let mut count = outlined.len() as u32;
    for (t, mut e, made) in parts {
        tally.add(&t);
        edges.append(&mut e);
        count += made;
    }
    let table = far_outline::table(view.height, &far_outline::cancel(edges));
    (tally, ReceiverTable::counted(b, table, count), Pairs::default())
}

/// Whose shadows fall on which receiver: the frame, the stage's switches, the light sample
/// and receiver `b`.
#[derive(Clone, Copy)]
struct Onto<'c> {
    ctx: &'c ShadowContext<'c>,
    options: BouknightKelleyOptions,
    sample: LightSample,
    b: u32,
}

impl Onto<'_> {
    /// Receiver `b`'s plane, within its bounding rectangle, lit by the sample.
    fn target(&self) -> Target {
        let plane = self.ctx.scene.polygons[self.b as usize].plane;
        Target::new(plane, bounding_rectangle(self.ctx.scene.verts(self.b as usize), &plane), self.sample)
    }
}

/// One thread's scratch for projecting casters: the projector, the clipper's buffers and
/// the screen ring.
#[derive(Default)]
struct Workspace {
    proj: Projector,
    scratch: [Vec<DVec3>; 2],
    ring: Vec<DVec2>,
}

/// The most candidate casters of one receiver that one thread projects (see
/// [`project_onto`]).
const CASTERS_PER_PIECE: usize = 8192;

/// Steps 2 and 3 for the receiver `onto` names and the candidates `candidates` (all of them, or a piece),
/// into an unfinished table.
fn project_piece(onto: Onto, candidates: &[u32], work: &mut Workspace) -> (Tally, ReceiverTable, Pairs) {
    let (b, ctx) = (onto.b, onto.ctx);
    let record = ctx.keep_outlines;
    let mut table = ReceiverTable::new(b, ctx.view.height, record);
    let mut made = Vec::new();
    let (tally, mut pairs) = project_each(onto, candidates, work, |ring, a| {
        table.add(ring);
        if record {
            made.push((0, a));
        }
    });
    pairs.shadow_polygons = made;
    (tally, table, pairs)
}

/// Steps 2 and 3 for the receiver `onto` names and the candidates `candidates`: each shadow
/// polygon made, on screen, goes to `made` with its caster. Returns the tally and (for
/// traces) the pairs kept and dropped as behind.
fn project_each(
    onto: Onto,
    candidates: &[u32],
    work: &mut Workspace,
    mut made: impl FnMut(&[DVec2], u32),
) -> (Tally, Pairs) {
    let Onto { ctx, options, sample, b } = onto;
    let (scene, record) = (ctx.scene, ctx.keep_outlines);
    let Workspace { proj, scratch, ring } = work;
    let mut tally = Tally::default();
    let mut pairs = Pairs::default();
    let plane = scene.polygons[b as usize].plane;
    let side = light_side(&plane, sample);
    let b_verts = scene.verts(b as usize);
    // B's target is made for the first caster to be clipped: on s3, at most 26,600 of
    // 277,000 receivers have one, the others' casters all dropped first.
    let mut target = None;
    let wedge = if options.wedge { Wedge::of(b_verts, sample, ctx.extent) } else { None };
    let margin = 1e-9 * ctx.extent;
    for &a in candidates {
        if scene.polygons[a as usize].face == scene.polygons[b as usize].face {
            continue;
        }
        tally.kept += 1;
        if record {
            pairs.kept.push(a);
        }
        let a_verts = scene.verts(a as usize);
        if options.drop_behind && a_verts.iter().all(|&v| plane.distance(v) * side <= 0.0 || b_verts.contains(&v)) {
            tally.behind += 1;
            if record {
                pairs.behind.push(a);
            }
        } else if wedge.as_ref().is_some_and(|w| w.misses(a_verts)) {
            tally.outside += 1;
        } else if options.slab && apart(sample, b_verts, a_verts, scene.polygons[a as usize].plane.n, margin) {
            tally.apart += 1;
        } else if !proj.project(a_verts, target.get_or_insert_with(|| onto.target())) {
            tally.empty += 1;
        } else if ctx.view.clip_project(&proj.shadow, scratch, ring) {
            made(ring, a);
        }
    }
    (tally, pairs)
}

/// Casters whose grid keys one piece of the grid's parallel loop writes.
const KEY_CHUNK: usize = 4096;

/// Grid cells whose first keys one piece of the grid's parallel loop finds.
const CELL_CHUNK: usize = 4096;

/// The most receivers one piece of the parallel loop over them takes.
const RECEIVERS_PER_PIECE: usize = 512;

/// What one piece of the loop over receivers made: their tallies summed, and their tables.
/// In the usual frame only the tables that hold shadow polygons are kept (most receivers'
/// are empty: a result kept per receiver costs a few hundred bytes each) and the pairs are
/// let go; for traces, every receiver's table and pairs, in order.
#[derive(Default)]
struct Piece {
    tally: Tally,
    tables: Vec<ReceiverTable>,
    pairs: Vec<Pairs>,
}

impl Piece {
    fn add(&mut self, tally: Tally, table: ReceiverTable, pairs: Pairs, keep_pairs: bool) {
        self.tally.add(&tally);
        if keep_pairs {
            self.pairs.push(pairs);
        } else if table.len() == 0 {
            return;
        }
        self.tables.push(table);
    }
}

/// Every receiver's shadow polygons into one overlay, tagged with their receiver, and the
/// tallies summed.
fn merge(ctx: &ShadowContext, pieces: Vec<Piece>) -> (Overlay, Tally, FxHashMap<u32, Pairs>) {
    let mut total = Tally::default();
    for piece in &pieces {
        total.add(&piece.tally);
    }
    let mut kept_pairs = FxHashMap::default();
    if !ctx.keep_outlines {
        // The usual frame: the tables (a hundred thousand on a large scene) moved by all
        // threads.
        let tables = pieces.into_par_iter().flat_map_iter(|piece| piece.tables);
        return (Overlay::from_tables(ctx.view.height, false, tables), total, kept_pairs);
    }
    let mut tables = Vec::new();
    let mut tag = 0;
    for (table, mut pairs) in pieces.into_iter().flat_map(|piece| piece.tables.into_iter().zip(piece.pairs)) {
        for (i, p) in pairs.shadow_polygons.iter_mut().enumerate() {
            p.0 = tag + i as u32;
        }
        tag += table.len() as u32;
        kept_pairs.insert(table.receiver(), pairs);
        tables.push(table);
    }
    let overlay = Overlay::from_tables(ctx.view.height, ctx.keep_outlines, tables.into_par_iter());
    (overlay, total, kept_pairs)
}

/// What happened to one receiver's pairs.
#[derive(Default, Clone)]
struct Tally {
    tested: u64,
    on_own_solid: u64,
    own_solid_front: u64,
    outlines: u64,
    outlined: u64,
    kept: u64,
    behind: u64,
    outside: u64,
    apart: u64,
    empty: u64,
    prefilter_ns: u64,
    projection_ns: u64,
}

impl Tally {
    fn add(&mut self, o: &Tally) {
        self.tested += o.tested;
        self.on_own_solid += o.on_own_solid;
        self.own_solid_front += o.own_solid_front;
        self.outlines += o.outlines;
        self.outlined += o.outlined;
        self.kept += o.kept;
        self.behind += o.behind;
        self.outside += o.outside;
        self.apart += o.apart;
        self.empty += o.empty;
        self.prefilter_ns += o.prefilter_ns;
        self.projection_ns += o.projection_ns;
    }
}

/// The wedge a triangle receiver cuts from the light (ours, not the paper's): the three
/// planes through the light and each of its edges, facing out. A caster wholly and strictly
/// outside one of them is seen from the light beside the receiver, never over it: its
/// shadow on the receiver's plane lies outside the receiver, so it is not projected. (The
/// paper projects it onto the receiver's plane and finds the projection beside it.) A corner
/// of the receiver's edge lies on that edge's plane exactly, so a neighbour across the edge
/// needs only its other corners outside.
struct Wedge {
    /// Each plane's unit normal (pointing out) and the receiver's edge on it.
    planes: [(DVec3, DVec3, DVec3); 3],
    /// How far outside a caster's corners must lie: rounding never decides a pair.
    margin: f64,
}

impl Wedge {
    /// The wedge of receiver `verts`, when it is a triangle the light does not see edge-on.
    /// Inlined, as [`Wedge::misses`] is, into the loop over a receiver's casters (ours: as
    /// calls, the 224-byte wedge was returned through memory and each test was a call;
    /// inlined, s3's preparation takes 1.4% fewer instructions).
    #[inline(always)]
    fn of(verts: &[DVec3], sample: LightSample, extent: f64) -> Option<Wedge> {
        let [a, b, c] = verts else { return None };
        let plane = |p: DVec3, q: DVec3, opposite: DVec3| {
            let along = match sample {
                LightSample::Point(s) => s - p,
                LightSample::Directional(d) => d,
            };
            let n = (q - p).cross(along).normalize_or_zero();
            let inside = n.dot(opposite - p);
            (inside != 0.0 && n != DVec3::ZERO).then(|| (if inside > 0.0 { -n } else { n }, p, q))
        };
        let planes = [plane(*a, *b, *c)?, plane(*b, *c, *a)?, plane(*c, *a, *b)?];
        Some(Wedge { planes, margin: 1e-9 * extent })
    }

    /// Whether every corner of `verts` lies outside one and the same plane of the wedge, or
    /// is a corner of the receiver's edge on that plane (which lies on the plane exactly: a
    /// neighbour across that edge is seen from the light beside the receiver too).
    #[inline(always)]
    fn misses(&self, verts: &[DVec3]) -> bool {
        self.planes.iter().any(|&(n, p, q)| verts.iter().all(|&v| n.dot(v - p) > self.margin || v == p || v == q))
    }
}

/// The slab test (ours, `slab`): whether polygon `verts` lies apart from the hull of the
/// light and the receiver `receiver` (the prism from the receiver toward a directional
/// light) by more than `margin` along `n`, the polygon's normal. Its corners span a thin
/// slab across `n`; when the hull lies wholly on one side of it, no segment from a point of
/// the receiver to the light meets the polygon, and its shadow misses the receiver. On s3
/// the floor is such a caster for 268,564 receivers on the spheres: it reaches round each
/// of them, so neither the behind test nor the wedge drops it, and without this test it is
/// projected, as the paper does, and clipped to nothing.
fn apart(sample: LightSample, receiver: &[DVec3], verts: &[DVec3], n: DVec3, margin: f64) -> bool {
    let span = |(lo, hi): (f64, f64), p: &DVec3| {
        let d = n.dot(*p);
        (lo.min(d), hi.max(d))
    };
    let none = (f64::INFINITY, f64::NEG_INFINITY);
    let (lo, hi) = verts.iter().fold(none, span);
    let (mut rlo, mut rhi) = receiver.iter().fold(none, span);
    match sample {
        LightSample::Point(s) => (rlo, rhi) = span((rlo, rhi), &s),
        // The prism runs from the receiver against `d`, toward the light.
        LightSample::Directional(d) => {
            let along = n.dot(d);
            if along < 0.0 {
                rhi = f64::INFINITY;
            } else if along > 0.0 {
                rlo = f64::NEG_INFINITY;
            }
        }
    }
    rlo > hi + margin || rhi < lo - margin
}

/// An extent's boxes in the 2D domain of the [`SphereGrid`] (two when the azimuth wraps).
type Boxes = [Option<[f64; 4]>; 2];

/// A bounding cone from the light: its axis and its half-angle's cosine and sine, so that
/// cones are compared, and their boxes on the sphere found, without an arccosine, a sine or
/// a cosine per polygon (ours). A half-angle of 90° or more is the whole sphere (a negative
/// cosine). Kept apart from the boxes, in a list the pair loop reads at random, so that a
/// caster's cone is one read.
#[derive(Debug, Clone, Copy)]
struct Cone {
    axis: DVec3,
    cos: f64,
    sin: f64,
}

impl Cone {
    /// The cone of a polygon that is neither caster nor receiver (never asked about).
    const NONE: Cone = Cone { axis: DVec3::Y, cos: 1.0, sin: 0.0 };
    /// The whole sphere.
    const WHOLE: Cone = Cone { axis: DVec3::Y, cos: -1.0, sin: 0.0 };

    /// The cone around `axis` whose half-angle has cosine `cos` (in `0..=1`); the sine is
    /// taken as `sqrt((1 − cos)(1 + cos))`, where `1 − cos` is exact for a cosine above ½.
    fn new(axis: DVec3, cos: f64) -> Cone {
        Cone { axis, cos, sin: ((1.0 - cos) * (1.0 + cos)).sqrt() }
    }

    fn whole(&self) -> bool {
        self.cos < 0.0
    }
}

/// Step 2, the sphere prefilter: every caster's and receiver's extent on the sphere around
/// the light (on the plane across a directional light). What the pair test reads is kept, one
/// entry per polygon: a point light's cones, a directional light's boxes. A point light's
/// boxes (in height and pseudo-azimuth) only place polygons in the [`SphereGrid`], which works
/// them out from the cones where it needs them ([`sphere_boxes`]; kept, they would cost 80
/// bytes a polygon).
struct Extents {
    /// A directional light: each polygon's box on the plane across the light.
    boxes: Vec<[f64; 4]>,
    /// A point light: each polygon's cone.
    cones: Vec<Cone>,
    /// The polygons asked about: the casters and the receivers.
    wanted: Vec<bool>,
    sample: LightSample,
}

impl Extents {
    fn new(scene: &Scene, sample: LightSample, casters: &[u32], receivers: &[u32]) -> Self {
        let n = scene.polygons.len();
        // Only casters and receivers are asked about.
        let wanted = crate::pieces::marked(n, casters.par_iter().chain(receivers).map(|&i| i as usize));
        let (mut boxes, mut cones) = (Vec::new(), Vec::new());
        let asked = (0..n).into_par_iter().map(|i| wanted[i].then(|| scene.verts(i)));
        match sample {
            LightSample::Point(s) => cones.par_extend(asked.map(|v| v.map_or(Cone::NONE, |v| cone(v, s)))),
            LightSample::Directional(d) => boxes.par_extend(asked.map(|v| v.map_or(NO_BOX, |v| plane_box(v, d)))),
        }
        Extents { boxes, cones, wanted, sample }
    }

    fn point(&self) -> bool {
        matches!(self.sample, LightSample::Point(_))
    }

    /// Polygon `i`'s boxes (one asked about), from its cone for a point light.
    fn boxes_of(&self, i: u32) -> Boxes {
        match self.sample {
            LightSample::Point(_) => sphere_boxes(&self.cones[i as usize]),
            LightSample::Directional(_) => [Some(self.boxes[i as usize]), None],
        }
    }

    /// Whether the extents of polygons `a` and `b` overlap: for a point light, their cones
    /// (the angle between their axes is at most the sum of their half-angles: `acos(ac·bc)
    /// <= ah + bh`, that is, the sum below π, where the cosine falls, `ac·bc >= cos(ah +
    /// bh)`, with a hair of slack so that rounding can only keep a pair, never drop one);
    /// for a directional light, their boxes.
    #[inline(always)]
    fn overlap(&self, a: u32, b: u32) -> bool {
        if self.point() {
            let (ac, bc) = (self.cones[a as usize], self.cones[b as usize]);
            return ac.whole() || bc.whole() || ac.axis.dot(bc.axis) >= ac.cos * bc.cos - ac.sin * bc.sin - 1e-12;
        }
        let (p, q) = (self.boxes[a as usize], self.boxes[b as usize]);
        p[0] <= q[2] && q[0] <= p[2] && p[1] <= q[3] && q[1] <= p[3]
    }

    /// The paper's prefilter for receiver `b`: every caster's extent compared with `b`'s,
    /// the overlapping ones into `out`. Returns the pairs tested.
    fn every_pair(&self, b: u32, casters: &[u32], out: &mut Vec<u32>) -> u64 {
        out.clear();
        out.extend(casters.iter().copied().filter(|&a| a != b && self.overlap(a, b)));
        casters.iter().filter(|&&a| a != b).count() as u64
    }
}

/// Step 2 found in a grid (ours): a grid over the extents' domain (height × pseudo-azimuth, or
/// the plane's two axes) in which each caster is binned in every cell its extent touches,
/// so that a receiver meets only the casters in its cells.
struct SphereGrid {
    extents: Extents,
    g: usize,
    /// Each caster's and receiver's cells: one or two rectangles of them (column range,
    /// then row range, inclusive; an empty one has its first column past its last), found
    /// once, 16 bytes a polygon.
    cells: Vec<[Cells; 2]>,
    /// `caster[i]`: whether polygon `i` is binned (a caster).
    caster: Vec<bool>,
    /// The casters binned in cell `k` (column-major, `c * g + r`) are
    /// `binned[first[k]..first[k + 1]]`, in increasing order.
    first: Vec<u32>,
    binned: Vec<u32>,
}

/// A rectangle of grid cells: columns `c0..=c1`, rows `r0..=r1`.
type Cells = [u16; 4];

/// No cells.
const NO_CELLS: Cells = [1, 0, 1, 0];

impl SphereGrid {
    fn new(extents: Extents, casters: &[u32]) -> Self {
        let domain = match extents.sample {
            LightSample::Point(_) => SPHERE,
            LightSample::Directional(_) => extents
                .boxes
                .iter()
                .filter(|b| b[0] <= b[2])
                .fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |d, b| {
                    [d[0].min(b[0]), d[1].min(b[1]), d[2].max(b[2]), d[3].max(b[3])]
                }),
        };
        let g = ((casters.len() as f64).sqrt().ceil() as usize).clamp(4, 1024);
        let (lo, size) = (
            DVec2::new(domain[0], domain[1]),
            DVec2::new(domain[2] - domain[0], domain[3] - domain[1]).max(DVec2::splat(1e-300)),
        );
        let rectangle = |b: Option<[f64; 4]>| {
            let Some(b) = b else { return NO_CELLS };
            let (c0, c1, r0, r1) = grid_rectangle(lo, size, (g, g), (DVec2::new(b[0], b[1]), DVec2::new(b[2], b[3])));
            [c0, c1, r0, r1].map(|k| k as u16)
        };
        let cells = (0..extents.wanted.len())
            .into_par_iter()
            .map(|i| match extents.wanted[i] {
                true => extents.boxes_of(i as u32).map(rectangle),
                false => [NO_CELLS; 2],
            })
            .collect();
        let caster = crate::pieces::marked(extents.wanted.len(), casters.par_iter().map(|&i| i as usize));
        let mut grid = SphereGrid { extents, g, cells, caster, first: Vec::new(), binned: Vec::new() };
        // Every (cell, caster) pair as one key, cell first: each chunk of casters
        // ([`KEY_CHUNK`]) counts their cells and fills its own stretch, and the keys are
        // sorted, all by all threads (a million casters' pairs collected and counted into the
        // cells on one thread were most of the grid's time; a stretch cut for each caster, a
        // million on one thread, was a seventh of it). The casters come in increasing order,
        // so a radix sort of the keys by cell alone, which keeps each cell's keys in the order
        // they came, lists each cell's casters in increasing order (ours: two passes over s3's
        // keys, where a comparison sort made about twenty).
        let chunks: Vec<&[u32]> = casters.chunks(KEY_CHUNK).collect();
        let counts: Vec<usize> =
            chunks.par_iter().map(|chunk| chunk.iter().map(|&i| grid.cell_count(i)).sum()).collect();
        let mut keys = vec![0u64; counts.iter().sum()];
        crate::pieces::stretches(&mut keys, counts.iter().copied()).into_par_iter().zip(chunks).for_each(
            |(keys, chunk)| {
                let mut k = 0;
                for &i in chunk {
                    grid.each_cell(i, |c, r| {
                        keys[k] = ((c * g + r) as u64) << 32 | i as u64;
                        k += 1;
                    });
                }
            },
        );
        debug_assert!(casters.windows(2).all(|w| w[0] < w[1]));
        crate::pieces::sort_by_high_half(&mut keys, (g * g).next_power_of_two().trailing_zeros());
        // Where each cell's keys start: each stretch of cells finds its first by bisection and
        // walks the keys from there (a bisection for every cell was a sixth of the grid).
        grid.first = vec![0; g * g + 1];
        grid.first.par_chunks_mut(CELL_CHUNK).enumerate().for_each(|(j, first)| {
            let k0 = j * CELL_CHUNK;
            let mut at = keys.partition_point(|&key| key >> 32 < k0 as u64);
            for (k, start) in (k0..).zip(first.iter_mut()) {
                while keys.get(at).is_some_and(|&key| key >> 32 < k as u64) {
                    at += 1;
                }
                *start = at as u32;
            }
        });
        grid.binned = keys.par_iter().map(|&key| key as u32).collect();
        grid
    }

    /// The casters binned in cell `(c, r)`.
    fn cell(&self, c: usize, r: usize) -> &[u32] {
        let k = c * self.g + r;
        &self.binned[self.first[k] as usize..self.first[k + 1] as usize]
    }

    /// Calls `f` with each grid cell (column, row) that polygon `i`'s extent touches (a
    /// caster or a receiver), in nested loops (ours: an iterator of iterators asks at every
    /// step which one it is in, as a chain does).
    #[inline(always)]
    fn each_cell(&self, i: u32, mut f: impl FnMut(usize, usize)) {
        for &[c0, c1, r0, r1] in &self.cells[i as usize] {
            for c in c0 as usize..=c1 as usize {
                for r in r0 as usize..=r1 as usize {
                    f(c, r);
                }
            }
        }
    }

    /// How many grid cells polygon `i`'s extent touches.
    fn cell_count(&self, i: u32) -> usize {
        let span = |lo: u16, hi: u16| (hi as usize + 1).saturating_sub(lo as usize);
        self.cells[i as usize].iter().map(|&[c0, c1, r0, r1]| span(c0, c1) * span(r0, r1)).sum()
    }

    /// The casters whose extents overlap receiver `b`'s: those sharing a grid cell with it
    /// whose bounding cones overlap (for a point light; shared cells suffice for a
    /// directional light, whose boxes are the cells' own test), less those of `b`'s own
    /// solid that `own` passes over (by `solid_of`; in a cell, as one stretch where the
    /// solid's polygons are one range). `stamp` is scratch, one entry per polygon, that keeps
    /// each caster from being listed twice.
    fn candidates(&self, b: u32, own: Option<Own>, solid_of: &[u32], stamp: &mut [u32], out: &mut Vec<u32>) {
        out.clear();
        self.each_cell(b, |c, r| {
            let cell = self.cell(c, r);
            match own.and_then(|o| Some((o, o.stretch(cell)?))) {
                // Three loops, not one over the three lists chained: a chained iterator asks
                // which list it is in at every step (ours).
                Some((o, (start, end))) => {
                    for &a in &cell[..start] {
                        self.offer(a, b, stamp, out);
                    }
                    for &a in o.front.iter().filter(|&&f| self.holds(f, c, r)) {
                        self.offer(a, b, stamp, out);
                    }
                    for &a in &cell[end..] {
                        self.offer(a, b, stamp, out);
                    }
                }
                None => {
                    for &a in cell {
                        if !own.is_some_and(|o| o.skips(a, solid_of[a as usize])) {
                            self.offer(a, b, stamp, out);
                        }
                    }
                }
            }
        });
    }

    /// Whether cell `(c, r)` lists polygon `a`: a caster whose cells take the cell in.
    #[inline]
    fn holds(&self, a: u32, c: usize, r: usize) -> bool {
        let within = |&[c0, c1, r0, r1]: &Cells| {
            (c0 as usize..=c1 as usize).contains(&c) && (r0 as usize..=r1 as usize).contains(&r)
        };
        self.caster[a as usize] && self.cells[a as usize].iter().any(within)
    }

    /// Lists caster `a` for receiver `b` unless it is listed already or its cone misses
    /// `b`'s.
    #[inline(always)]
    fn offer(&self, a: u32, b: u32, stamp: &mut [u32], out: &mut Vec<u32>) {
        if stamp[a as usize] == b {
            return;
        }
        stamp[a as usize] = b;
        // Shared cells are a directional light's box test; a point light's cones are
        // compared.
        if !self.extents.point() || self.extents.overlap(a, b) {
            out.push(a);
        }
    }
}

/// No box: a polygon never asked about (its first coordinate past its last).
const NO_BOX: [f64; 4] = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];

/// The box of `verts` on the plane across a directional light along `d`.
fn plane_box(verts: &[DVec3], d: DVec3) -> [f64; 4] {
    let u = d.any_orthonormal_vector();
    let v = d.cross(u);
    verts.iter().fold(NO_BOX, |b, p| {
        let (x, y) = (p.dot(u), p.dot(v));
        [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)]
    })
}

/// The bounding cone, from a point light at `s`, of the directions to `verts` (a polygon's
/// directions all lie inside a cone of half-angle under 90° that holds its vertices'
/// directions; the whole sphere where they do not fit in one). The least cosine between the
/// axis and a vertex direction, less a hair so that rounding can only widen the cone, is the
/// half-angle's cosine.
fn cone(verts: &[DVec3], s: DVec3) -> Cone {
    let dir = |&v: &DVec3| (v - s).normalize_or_zero();
    // A triangle's directions in an array (ours: collected into a small vector, which asks
    // at every push whether it has room, a cone took about 360 instructions on s3; in an
    // array, about 200). The arithmetic is the same, so the cones are the same to the bit.
    match <&[DVec3; 3]>::try_from(verts) {
        Ok(triangle) => cone_of(&triangle.each_ref().map(dir)),
        Err(_) => cone_of(&verts.iter().map(dir).collect::<smallvec::SmallVec<[DVec3; 8]>>()),
    }
}

/// The bounding cone of the unit directions `dirs` ([`cone`]).
#[inline(always)]
fn cone_of(dirs: &[DVec3]) -> Cone {
    let axis = dirs.iter().sum::<DVec3>().normalize_or_zero();
    if axis == DVec3::ZERO || dirs.contains(&DVec3::ZERO) {
        return Cone::WHOLE;
    }
    let least = dirs.iter().map(|d| d.dot(axis)).fold(1.0, f64::min).min(1.0) - 1e-12;
    if least <= 0.0 {
        return Cone::WHOLE;
    }
    Cone::new(axis, least)
}

/// The domain of a point light's boxes: the height `y` of a direction (the cosine of its
/// polar angle from +Y) × its [`pseudo_azimuth`].
const SPHERE: [f64; 4] = [-1.0, -2.0, 1.0, 2.0];

/// Widens a point light's boxes so that rounding can only keep a cell, never drop one.
const BOX_SLACK: f64 = 1e-9;

/// A cone's boxes in the [`SPHERE`] domain, height × pseudo-azimuth (two where the azimuth
/// wraps; the whole domain for the whole sphere), found without an arccosine or an
/// arctangent (ours). For a cone of half-angle `h` round an axis of polar angle `θ`:
/// - the heights run from `cos(θ + h)` to `cos(θ − h)`, that is `y cos h ∓ sin θ sin h`,
///   out to ±1 where a pole lies inside the cone;
/// - the azimuths run `asin(x)` either side of the axis's, `x = sin h / sin θ`; its two
///   ends are the axis's azimuth turned by that angle, whose cosine is `sqrt(1 − x²)`,
///   and are placed by [`pseudo_azimuth`], which grows with the azimuth. From `x` = 1 (a
///   pole inside the cone) they are the whole circle.
fn sphere_boxes(cone: &Cone) -> Boxes {
    if cone.whole() {
        return [Some(SPHERE), None];
    }
    let (a, c, s) = (cone.axis, cone.cos, cone.sin);
    let sin_theta = (a.x * a.x + a.z * a.z).sqrt();
    let y1 = if a.y >= c - BOX_SLACK { 1.0 } else { (a.y * c + sin_theta * s + BOX_SLACK).min(1.0) };
    let y0 = if -a.y >= c - BOX_SLACK { -1.0 } else { (a.y * c - sin_theta * s - BOX_SLACK).max(-1.0) };
    let x = s / sin_theta;
    if x.is_nan() || x >= 1.0 - BOX_SLACK {
        return [Some([y0, -2.0, y1, 2.0]), None];
    }
    let (u, v) = (a.x / sin_theta, a.z / sin_theta);
    let (sd, cd) = (x, ((1.0 - x) * (1.0 + x)).sqrt());
    let lo = pseudo_azimuth(u * cd + v * sd, v * cd - u * sd) - BOX_SLACK;
    let hi = pseudo_azimuth(u * cd - v * sd, v * cd + u * sd) + BOX_SLACK;
    if lo > hi {
        // The arc crosses the wrap, where the pseudo-azimuth jumps from 2 to -2.
        [Some([y0, lo, y1, 2.0]), Some([y0, -2.0, y1, hi])]
    } else if lo < -2.0 {
        [Some([y0, lo + 4.0, y1, 2.0]), Some([y0, -2.0, y1, hi])]
    } else if hi > 2.0 {
        [Some([y0, lo, y1, 2.0]), Some([y0, -2.0, y1, hi - 4.0])]
    } else {
        [Some([y0, lo, y1, hi]), None]
    }
}

/// A stand-in for the azimuth `atan2(z, x)` of a direction `(x, z)` across +Y, in `-2..=2`,
/// that grows with it and needs no arctangent: `1 − x/(|x| + |z|)` for `z ≥ 0`, `x/(|x| +
/// |z|) − 1` below (ours). It jumps from 2 to -2 where the azimuth does, at -x.
fn pseudo_azimuth(x: f64, z: f64) -> f64 {
    let r = x / (x.abs() + z.abs());
    if z >= 0.0 {
        1.0 - r
    } else {
        r - 1.0
    }
}

impl ShadowStage for BouknightKelley<'_> {
    /// The shadow polygons' overlays (what became of the pairs, kept for traces, is not
    /// counted).
    fn bytes(&self) -> usize {
        self.shadows.iter().map(Overlay::bytes).sum()
    }

    fn outlines(&self) -> Vec<Vec<DVec2>> {
        self.shadows.first().map_or_else(Vec::new, |o| o.rings().to_vec())
    }

    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        Box::new(Walker {
            walkers: self.shadows.iter().map(|o| o.walker(0..self.ctx.view.height)).collect(),
            stage: self,
            intervals: Vec::new(),
            segments: 0,
            splits: 0,
            depth_max: 0,
            last: (0, 0, 0, 0, 0, 0),
        })
    }
}

struct Walker<'s> {
    stage: &'s BouknightKelley<'s>,
    walkers: Vec<OverlayWalker<'s>>,
    intervals: Vec<Interval>,
    segments: u64,
    splits: u64,
    depth_max: u32,
    /// The last run, its segments and splits, its sample and its polygon.
    last: (u32, u32, u64, u64, usize, u32),
}

/// Step 4 on segment `a..b`, given the shadow polygons' intervals that may touch it: calls
/// `visit(a, b, depth, outcome)` for every segment examined, parents before their parts.
fn examine(a: u32, b: u32, candidates: &[Interval], depth: u32, visit: &mut impl FnMut(u32, u32, u32, Outcome)) {
    let touching: smallvec::SmallVec<[Interval; 8]> =
        candidates.iter().copied().filter(|iv| iv.start < b && iv.end > a).collect();
    // No shadow polygon touches the segment: normal (lit).
    let Some(first) = touching.first() else {
        return visit(a, b, depth, Outcome::Lit);
    };
    // One covers it fully: in shadow.
    if touching.iter().any(|iv| iv.start <= a && iv.end >= b) {
        return visit(a, b, depth, Outcome::Shadow);
    }
    // One covers it partly: split at its edges and examine the parts.
    visit(a, b, depth, Outcome::Split);
    let cuts = [a, first.start.max(a), first.end.min(b), b];
    for w in cuts.windows(2) {
        if w[0] < w[1] {
            examine(w[0], w[1], &touching, depth + 1, visit);
        }
    }
}

impl ShadowWalker for Walker<'_> {
    fn start_line(&mut self, line: u32) {
        for w in &mut self.walkers {
            w.advance_to(line);
        }
    }

    fn lit(&mut self, light: usize, sample: usize, _line: u32, run: &Run, lit: &mut [f32]) {
        let k = self.stage.ctx.sample_index(light, sample);
        self.walkers[k].intervals(run.poly, run.x0, run.x1, &mut self.intervals);
        let (mut segments, mut splits, mut depth_max) = (0, 0, 0);
        examine(run.x0, run.x1, &self.intervals, 0, &mut |a, b, depth, outcome| {
            segments += 1;
            depth_max = depth_max.max(depth);
            let range = (a - run.x0) as usize..(b - run.x0) as usize;
            match outcome {
                Outcome::Lit => lit[range].fill(1.0),
                Outcome::Shadow => lit[range].fill(0.0),
                Outcome::Split => splits += 1,
            }
        });
        self.segments += segments;
        self.splits += splits;
        self.depth_max = self.depth_max.max(depth_max);
        self.last = (run.x0, run.x1, segments, splits, k, run.poly);
    }

    fn decision(&self) -> Decision {
        let covers: Vec<Cover> =
            self.intervals.iter().map(|i| Cover { polygon: i.tag, start: i.start, end: i.end }).collect();
        let on: Vec<String> = covers.iter().map(|c| format!("#{} covers {}..{}", c.polygon, c.start, c.end)).collect();
        let mut segments = Vec::new();
        examine(self.last.0, self.last.1, &self.intervals, 0, &mut |start, end, depth, outcome| {
            segments.push(Segment { start, end, depth, outcome })
        });
        Decision {
            tested: self.intervals.iter().map(|i| (i.start, i.end, 1)).collect(),
            note: format!(
                "{} shadow polygon(s) on this polygon touch the run [{}]; {} segment(s) examined, {} split(s)",
                covers.len(),
                on.join(", "),
                self.last.2,
                self.last.3
            ),
            detail: Detail::Segments {
                covers,
                segments,
                pairs: self.stage.pairs.get(self.last.4).and_then(|p| p.get(&self.last.5)).cloned(),
            },
        }
    }

    fn finish(&mut self, counters: &mut Counters) {
        counters.add(crate::stats::Counter::SegmentsExamined, self.segments);
        counters.add(crate::stats::Counter::SegmentSplits, self.splits);
        counters.add(crate::stats::Counter::RecursionDepthMax, self.depth_max as u64);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Light, Material, Mesh, Object};
    use rand::{Rng, SeedableRng};

    /// No segment from a point of a receiver to the light meets a caster the slab test sets
    /// apart, under point and directional lights; a floor under the receiver is set apart
    /// from every light above it; and the test finds both kinds of caster.
    #[test]
    fn the_slab_test_sets_apart_only_casters_no_shadow_ray_meets() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1970);
        let tri = |rng: &mut rand_chacha::ChaCha8Rng, centre: DVec3, size: f64| {
            let n = DVec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0))
                .normalize_or(DVec3::X);
            let (u, v) = (n.any_orthonormal_vector(), n.cross(n.any_orthonormal_vector()));
            let (a, b) = (rng.gen_range(0.1..size), rng.gen_range(0.1..size));
            [centre - u * a, centre + v * b, centre + u * a * 0.5 - v * b * 0.7]
        };
        let floor = [[-50.0, -50.0], [50.0, -50.0], [50.0, 50.0], [-50.0, 50.0]].map(|[x, y]| DVec3::new(x, y, -1.0));
        let (mut set_apart, mut shadowing, tried) = (0, 0, 3000);
        for k in 0..tried {
            let up = DVec3::new(rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0), rng.gen_range(0.5..8.0));
            let (sample, light) = match k % 2 {
                0 => (LightSample::Point(up), up),
                _ => (LightSample::Directional(-up.normalize()), up.normalize() * 1e4),
            };
            let receiver = tri(&mut rng, DVec3::ZERO, 1.0);
            assert!(apart(sample, &receiver, &floor, DVec3::Z, 1e-9), "the floor under {receiver:?}");
            // A third of the casters between the receiver and the light.
            let centre = match rng.gen_bool(0.3) {
                true => up * rng.gen_range(0.2..0.8),
                false => DVec3::new(rng.gen_range(-2.5..2.5), rng.gen_range(-2.5..2.5), rng.gen_range(-2.0..5.0)),
            };
            let caster = tri(&mut rng, centre, 2.0);
            let is_apart = apart(sample, &receiver, &caster, newell_normal(&caster).normalize(), 1e-9);
            set_apart += is_apart as u32;
            let met = (0..100).any(|_| {
                let (u, v) = (rng.gen_range(0.0..1.0f64), rng.gen_range(0.0..1.0f64));
                let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                let p = receiver[0] + (receiver[1] - receiver[0]) * u + (receiver[2] - receiver[0]) * v;
                crosses(p, light, &caster)
            });
            shadowing += met as u32;
            assert!(!(is_apart && met), "{caster:?} set apart from {receiver:?} under {sample:?}, yet shadows it");
        }
        assert!(
            set_apart * 5 > tried && shadowing * 10 > tried,
            "{set_apart} apart, {shadowing} shadowing, of {tried}"
        );
    }

    /// The pseudo-azimuth grows with the azimuth all the way round, from -2 just past -x
    /// to 2 at -x.
    #[test]
    fn pseudo_azimuth_grows_with_the_azimuth() {
        let steps = 100_000;
        let at = |k: i32| {
            let phi = -std::f64::consts::PI + 2.0 * std::f64::consts::PI * k as f64 / steps as f64;
            pseudo_azimuth(phi.cos(), phi.sin())
        };
        for k in 1..steps {
            assert!(at(k) < at(k + 1), "step {k}: {} then {}", at(k), at(k + 1));
        }
        assert_eq!((pseudo_azimuth(1.0, 0.0), pseudo_azimuth(0.0, 1.0), pseudo_azimuth(-1.0, 0.0)), (0.0, 1.0, 2.0));
        assert_eq!(pseudo_azimuth(0.0, -1.0), -1.0);
        assert!(at(1) > -2.0 && at(1) < -1.99);
    }

    /// Every direction inside a cone lies in one of its boxes, for cones anywhere on the
    /// sphere: across the azimuth's wrap, round the poles, wide and narrow, and on the edge
    /// of the cone (where rounding decides).
    #[test]
    fn a_cones_boxes_hold_every_direction_inside_it() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1968);
        let inside =
            |b: &Boxes, y: f64, p: f64| b.iter().flatten().any(|b| b[0] <= y && y <= b[2] && b[1] <= p && p <= b[3]);
        let mut tested = 0;
        for round in 0..20_000 {
            let axis = match round % 4 {
                // Toward -x (the wrap), near a pole, anywhere.
                0 => DVec3::new(-1.0, rng.gen_range(-0.5..0.5), rng.gen_range(-0.01..0.01)),
                1 => DVec3::new(
                    rng.gen_range(-0.05..0.05),
                    if rng.gen_bool(0.5) { 1.0 } else { -1.0 },
                    rng.gen_range(-0.05..0.05),
                ),
                _ => DVec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)),
            }
            .normalize_or(DVec3::X);
            let cos =
                if rng.gen_bool(0.5) { rng.gen_range(0.0..1.0) } else { 1.0 - 10f64.powf(rng.gen_range(-12.0..-1.0)) };
            let cone = Cone::new(axis, cos);
            let boxes = sphere_boxes(&cone);
            let (u, v) = (axis.any_orthonormal_vector(), axis.cross(axis.any_orthonormal_vector()));
            for _ in 0..20 {
                // A direction at the cone's edge or inside it.
                let t = rng.gen_range(0.0..2.0 * std::f64::consts::PI);
                let edge = rng.gen_bool(0.5);
                let c = if edge { cos } else { rng.gen_range(cos..1.0) };
                let sin = ((1.0 - c) * (1.0 + c)).sqrt();
                let d = (axis * c + (u * t.cos() + v * t.sin()) * sin).normalize();
                if d.dot(axis) < cos {
                    continue;
                }
                tested += 1;
                let (y, p) = (d.y, pseudo_azimuth(d.x, d.z));
                assert!(
                    inside(&boxes, y, p),
                    "round {round}: {d} (y {y}, p {p}) inside the cone {cone:?} is outside its boxes {boxes:?}"
                );
            }
        }
        assert!(tested > 300_000);
    }

    /// Whether the segment from `p` to `s` crosses triangle `t` (Möller-Trumbore).
    fn crosses(p: DVec3, s: DVec3, t: &[DVec3]) -> bool {
        let (d, e1, e2) = (s - p, t[1] - t[0], t[2] - t[0]);
        let h = d.cross(e2);
        let det = e1.dot(h);
        if det.abs() < 1e-12 {
            return false;
        }
        let q = p - t[0];
        let u = q.dot(h) / det;
        let w = q.cross(e1);
        let v = d.dot(w) / det;
        let along = e2.dot(w) / det;
        u > 0.0 && v > 0.0 && u + v < 1.0 && along > 1e-9 && along < 1.0 - 1e-9
    }

    /// The sphere prefilter drops only pairs that cannot shadow: for random triangles around
    /// a point light, many of them straddling the azimuth's wrap (directions toward -x, where
    /// φ jumps from π to -π) or near the poles, every caster that a ray from a point of a
    /// receiver to the light meets is among the receiver's candidates.
    #[test]
    fn prefilter_keeps_every_pair_a_shadow_ray_finds_including_across_the_azimuth_wrap() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1970);
        for round in 0..20 {
            let light = DVec3::ZERO;
            let mut tris = Vec::new();
            for k in 0..40 {
                // Half the triangles toward -x (the wrap), a few near the poles.
                let pole = if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
                let dir = match k % 4 {
                    0 | 1 => DVec3::new(-1.0, rng.gen_range(-0.3..0.3), rng.gen_range(-0.2..0.2)),
                    2 => DVec3::new(rng.gen_range(-0.2..0.2), pole, rng.gen_range(-0.2..0.2)),
                    _ => DVec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)),
                }
                .normalize_or(DVec3::X);
                let c = dir * rng.gen_range(1.0..4.0);
                let r = rng.gen_range(0.2..0.9);
                let mut v = || c + DVec3::new(rng.gen_range(-r..r), rng.gen_range(-r..r), rng.gen_range(-r..r));
                tris.push(vec![v(), v(), v()]);
            }
            let camera = Camera { width: 8, height: 8, ..Camera::new(DVec3::new(0.0, 0.0, 9.0), DVec3::ZERO) };
            let scene = Scene::builder(camera)
                .material(Material::new("m"))
                .light(Light::point(light))
                .object(Object::new(Mesh::from_polygons(&tris)), "m")
                .build()
                .unwrap();
            let n = scene.polygons.len();
            let casters: Vec<u32> = (0..n as u32).collect();
            let sample = LightSample::Point(light);
            let grid = SphereGrid::new(Extents::new(&scene, sample, &casters, &casters), &casters);
            let mut stamp = vec![u32::MAX; n];
            let (mut found, mut kept) = (0, Vec::new());
            for b in 0..n as u32 {
                grid.candidates(b, None, &scene.solid_of, &mut stamp, &mut kept);
                let t = scene.verts(b as usize);
                for _ in 0..200 {
                    let (u, v) = (rng.gen_range(0.0..1.0f64), rng.gen_range(0.0..1.0f64));
                    let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                    let p = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
                    for a in (0..n as u32).filter(|&a| a != b) {
                        if crosses(p, light, scene.verts(a as usize)) {
                            found += 1;
                            assert!(kept.contains(&a), "round {round}: caster {a} shadows {b} at {p} but was dropped");
                        }
                    }
                }
            }
            assert!(found > 0, "round {round}: the test found no shadowing pair");
        }
    }
}
