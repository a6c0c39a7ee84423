//! Shadow volumes (Crow 1977): the region a polygon hides from a light sample, bounded by
//! *shadow polygons*. Shared by Crow's per-span counting and by the stencil-buffer stage.
//!
//! Every casting polygon has a volume: the points behind it as seen from the light sample,
//! bounded by a *side* on each of its edges (the edge pushed away from the light), a *front
//! cap* (the polygon itself) and a *back cap* (the polygon pushed away to infinity). A point
//! is in shadow when it lies inside at least one volume, so the count of volumes holding a
//! point is exactly the number of casting polygons that cross its segment to the light:
//! this holds whatever the meshes are (open, closed, non-manifold, wound either way) and
//! wherever the light is (outside a closed mesh, inside it, on its surface).
//!
//! The sides of neighbouring polygons on a shared edge lie in one plane, so they are merged
//! (Bergeron 1986, "A general version of Crow's shadow volumes"): on each edge the sides of
//! the polygons sharing it are summed with their orientations, and one side is kept with the
//! net weight. Between two polygons that both face the light (or both face away) the two
//! sides cancel; on a silhouette edge of a closed mesh they add up to weight 2 (the volumes of
//! the polygon turned to the light and of the one turned away both end there); on an open
//! mesh's boundary the weight is 1. Only silhouette and boundary edges make sides, as in
//! Crow's closed-mesh construction, without its assumptions: Crow's single volume per object
//! (sides on the silhouette, caps on the polygons facing the light) counts zero for a light
//! inside the mesh, for points seen on the inside of an inward-wound mesh, and for a light on
//! the mesh's surface, where the summed volumes count right.
//!
//! Kept apart, each with a volume of its own that never counts on its own face: the pieces
//! of a non-planar face split into a fan (section 2: they never shadow each other), and a
//! self-intersecting polygon, whose inside is decided by the even-odd rule: it is cut into
//! trapezoids covering its even-odd region ([`crate::geometry::even_odd`]), since sides on its
//! own edges would count its doubly wound parts twice (the nonzero rule).
//!
//! Volumes are extruded to infinity in homogeneous coordinates: a side on edge `a → b` is
//! `[a, b, (b − L, 0), (a − L, 0)]` (for a directional light `[a, b, (d, 0)]`, the two far
//! corners being the one point at infinity along `d`), and a back cap is its front cap's
//! directions from the light, on the plane at infinity, behind everything. Nothing is cut
//! short, whatever the scene's size or how close the light is to a polygon. Each shadow
//! polygon knows its outward side, which gives its sign in the count: +weight where the eye
//! sees it from outside (entering the volume), −weight from inside.
//!
//! Which polygons a count needs: z-pass counts what lies between the eye and the visible
//! point, so it needs the sides and the **near caps** — each volume's cross-section with the
//! near plane, found by projecting its front cap from the light onto the part of the near
//! plane the image sees (the eye's own count, pixel by pixel: Bergeron 1986). The front caps
//! are scene polygons (never in front of a visible point) and the back caps lie beyond
//! everything, so z-pass needs neither. Z-fail counts what lies behind the visible point, so
//! it needs the sides and both caps, and no near caps. Naive z-pass leaves the near caps out.
//!
//! Two cuts are ours: z-pass's sides are cut to the hull of the eye and the scene's bounds
//! ([`SightHull`]), and z-fail's volumes are closed at a plane beyond the scene, with *far
//! caps* there instead of back caps at infinity, where there is such a plane ([`FarPlane`]).

use super::far_outline::{self, FarEdge};
use super::projection::{light_side, unseen, Projector, Target};
use super::ShadowContext;
use crate::geometry::{box_corners, dominant_axis, drop_axis, even_odd, newell_normal, Plane, RingPieces, Rings};
use crate::pieces::joined;
use crate::pool::Stash;
use crate::scene::LightSample;
use crate::stats::Counters;
use crate::view::DepthPlane;
use glam::{DVec2, DVec3, DVec4};
use rayon::prelude::*;
use smallvec::{smallvec, SmallVec};
use std::sync::atomic::{AtomicI8, Ordering};
use std::sync::Arc;

/// How a count is taken along the line of sight.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum Counting {
    /// From the eye to the visible point, starting from the eye's own count (near caps).
    #[default]
    ZPass,
    /// From the visible point to infinity (Carmack's reverse / Everitt & Kilgard's z-fail).
    ZFail,
    /// From the eye to the visible point starting at zero: wrong where the eye (or the near
    /// plane) is in shadow, as the "Rendering 6: Shadow" notes describe; kept to show that failure.
    NaiveZPass,
}

impl Counting {
    /// Every counting rule.
    pub const ALL: [Counting; 3] = [Counting::ZPass, Counting::ZFail, Counting::NaiveZPass];

    /// The rule's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Counting::ZPass => "zpass",
            Counting::ZFail => "zfail",
            Counting::NaiveZPass => "naive-zpass",
        }
    }
}

crate::error::named!(Counting, "count");

/// What part of a volume's boundary a shadow polygon is (the counters by part follow this
/// order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// A side, on an edge pushed away from the light.
    Side,
    /// A polygon facing the light (the volume's front).
    FrontCap,
    /// A front-cap polygon pushed to infinity away from the light.
    BackCap,
    /// The volume's cross-section with the near plane.
    NearCap,
    /// The volume's cross-section with the far plane that closes z-fail's volumes (ours).
    FarCap,
}

/// One shadow polygon in world space.
#[derive(Debug, Clone)]
pub struct ShadowPolygon {
    /// Its vertices in homogeneous coordinates (`w = 0`: a point at infinity), kept inline
    /// up to four (a million caps a frame on s3, none of them allocated).
    pub verts: SmallVec<[DVec4; 4]>,
    /// Its plane; `None` for a back cap, which lies on the plane at infinity.
    pub plane: Option<Plane>,
    /// The polygon's weight in the count (how many volumes it bounds: 1, or 2 on a merged
    /// silhouette edge), positive when the eye sees the side facing out of the volume,
    /// negative when it sees the inside.
    pub sign: i32,
    /// Which part of the boundary it is.
    pub part: Part,
    /// For a front cap: the scene polygon it coincides with.
    pub lies_on: Option<u32>,
    /// For a volume kept apart (a fan piece, a piece of a self-intersecting polygon): the
    /// face whose volume it bounds, which it never shadows.
    pub owner_face: Option<u32>,
}

/// The most items (edges, polygons, shadow polygons) one piece of a parallel loop takes.
/// Their costs differ from place to place in the scene (a culled polygon costs nothing), and
/// rayon's own cut leaves a few long pieces: a thread that runs out of work would wait for
/// the last.
const PIECE: usize = 4096;

/// The shadow polygons of one light sample for a count taken by `counting`, each put
/// through `camera` as soon as it is made: by pieces, in order. With `far_outline`, the far
/// caps of the merged polygons are kept as the edges of their union instead
/// ([`super::far_outline`]).
fn shadow_polygons(
    ctx: &ShadowContext,
    adjacency: &Adjacency,
    sample: LightSample,
    counting: Counting,
    far: Option<&FarPlane>,
    (far_outline, front_outline): (bool, bool),
    camera: &Camera,
) -> Vec<Piece> {
    let far_outline = far_outline && far.is_some();
    let front_outline = far_outline && front_outline;
    let b = Builder::new(ctx, sample, counting, far);
    // With merged volumes, a closed solid's polygons turned away from the light are left out
    // (ours): every shadow ray crossing one has crossed, nearer the light, one of the same
    // solid turned toward it, so the counts change but never between zero and not zero.
    // Decided once a polygon: each is asked for on every edge it has.
    let unseen = unseen(ctx.scene, sample, ctx.extent, adjacency.merged_volumes);
    let casts = |i: usize| !unseen[i];
    // Step 1: the merged sides, one per edge whose net weight is not zero. Each edge and
    // each polygon is decided on its own, so they are worked out in parallel, in order.
    let mut pieces: Vec<Piece> = adjacency
        .edge_pieces()
        .map_init(Scratch::default, |scratch, edges| {
            let mut piece = Piece::default();
            for (e, sharing) in edges {
                if !sharing.iter().any(|s| casts(s.poly())) {
                    continue; // no polygon on it casts: no side
                }
                let (ea, eb) = e.ends(ctx.scene);
                let w = b.net_weight(ea, eb, sharing.iter().filter(|s| casts(s.poly())));
                let side = b.side(ea, eb, w, None);
                if side.is_some() {
                    piece.weights[usize::from(w.abs() != 1)] += 1;
                }
                piece.add(camera, scratch, side);
            }
            piece
        })
        .collect();
    // Step 2: the caps of every merged polygon. For the far outline, a far cap whose outline
    // on screen is its corners' images, uncut, leaves only the way it winds (`wound`) for
    // step 2b; any other far cap leaves its edges.
    let wound: Vec<AtomicI8> =
        (0..if far_outline { ctx.scene.polygons.len() } else { 0 }).map(|_| AtomicI8::new(0)).collect();
    // The same for the front caps (ours, `front_outline`): a front cap whole on screen leaves
    // the times it winds for the edges' pass.
    let front_wound: Vec<AtomicI8> =
        (0..if front_outline { ctx.scene.polygons.len() } else { 0 }).map(|_| AtomicI8::new(0)).collect();
    let caps = adjacency.merged.par_chunks(PIECE).zip(&adjacency.merged_boxes).map_init(
        || (Scratch::default(), Projector::default()),
        |(scratch, proj), (polys, &bounds)| {
            let mut piece = Piece::default();
            if b.caps_miss(bounds) {
                return piece;
            }
            for &p in polys.iter().filter(|&&p| casts(p as usize)) {
                let verts = ctx.scene.verts(p as usize);
                if !far_outline {
                    for cap in b.caps(proj, verts, p as usize, None) {
                        piece.add(camera, scratch, cap);
                    }
                    continue;
                }
                let front = b.front_cap(verts, p as usize, None);
                match front_outline {
                    true => {
                        if let Some(w) = piece.add_front(camera, scratch, front, verts) {
                            front_wound[p as usize].store(w, Ordering::Relaxed);
                        }
                    }
                    false => piece.add(camera, scratch, Some(front)),
                }
                if let Some(w) = piece.add_far(camera, scratch, &b, proj, verts) {
                    wound[p as usize].store(w, Ordering::Relaxed);
                }
            }
            piece
        },
    );
    pieces.par_extend(caps);
    // Step 2b, the far outline's edges of the whole far caps: the two caps on an edge of a
    // closed mesh run its image once each way and leave nothing; an edge they run more one
    // way than the other is kept, run that many times (the far end of a side).
    if let (Some(far), true) = (&b.far, far_outline) {
        let view = ctx.view;
        let edges = adjacency.edge_pieces().map(|edges| {
            let mut piece = Piece::default();
            for (e, sharing) in edges {
                // The times the whole caps of `wound` run the edge, each the way its polygon
                // runs it (the front caps' list is empty without their outline).
                let runs = |wound: &[AtomicI8]| -> i32 {
                    let way = |s: &Sharing| wound.get(s.poly()).map_or(0, |w| i32::from(w.load(Ordering::Relaxed)));
                    sharing.iter().map(|s| way(s) * if s.forward() { 1 } else { -1 }).sum()
                };
                let (far_runs, front_runs) = (runs(&wound), runs(&front_wound));
                if far_runs == 0 && front_runs == 0 {
                    continue;
                }
                let (ea, eb) = e.ends(ctx.scene);
                if far_runs != 0 {
                    piece.far.push(FarEdge::run(view.image(far.onto(ea)), view.image(far.onto(eb)), far_runs));
                }
                if front_runs != 0 {
                    piece.far.push(FarEdge::run(view.image(ea), view.image(eb), front_runs));
                }
            }
            piece
        });
        pieces.par_extend(edges);
    }
    // Step 3: the volumes kept apart, each with its own sides and caps.
    let (mut piece, mut scratch, mut proj) = (Piece::default(), Scratch::default(), Projector::default());
    for apart in adjacency.apart.iter().filter(|apart| casts(apart.poly as usize)) {
        b.apart_into(apart, true, &mut piece, camera, &mut scratch, &mut proj);
    }
    pieces.push(piece);
    pieces
}

/// Crow's 1977 construction (the paper path, [`Construction::Crow1977`]) for one light
/// sample, as published:
///
/// 1. The polygons *turned to the light*: those that cast shadows and have the light on
///    their front side (the side their winding's normal points to).
/// 2. Each object's *contour edges*, its outline as the light sees it: the edges between
///    one of its polygons turned to the light and one turned away, and the edges of a
///    polygon turned to the light that no other polygon of the object shares (an open
///    mesh's boundary). Each gets a side, facing out of the volume of the polygons turned
///    to the light. A polygon turned away from the light bounds no volume: on an open mesh
///    (a single polygon seen from behind, a box without its bottom) its shadow is lost.
/// 3. The caps: the polygons turned to the light are the volume's front (z-fail also closes
///    it with their back caps at infinity).
/// 4. Z-pass's starting count: the number of volumes that hold the eye, found as the
///    polygons turned to the light that the segment from the eye to the light crosses (the
///    sides lie in planes through the light, so the segment leaves a volume only through
///    its front). One count for the whole image, entered as one polygon over the whole near
///    plane.
///
/// The pieces of a non-planar face and self-crossing polygons keep their own volumes
/// (section 2 of `docs/scene-format.md`; Crow's objects have no such polygons).
fn crow_1977(
    ctx: &ShadowContext,
    adjacency: &Adjacency,
    sample: LightSample,
    counting: Counting,
    camera: &Camera,
) -> Vec<Piece> {
    let (scene, b) = (ctx.scene, Builder::new(ctx, sample, counting, None));
    // Step 1.
    let facing: Vec<bool> = (0..scene.polygons.len())
        .into_par_iter()
        .map(|i| scene.casts_shadows(i) && sample.side_of(&scene.polygons[i].plane) > 0.0)
        .collect();
    let object = |s: &Sharing| scene.polygons[s.poly()].object;
    // Step 2, edge by edge and object by object.
    let mut pieces: Vec<Piece> = adjacency
        .edge_pieces()
        .map_init(Scratch::default, |scratch, edges| {
            let mut piece = Piece::default();
            for (e, sharing) in edges {
                for (k, first) in sharing.iter().enumerate() {
                    if sharing[..k].iter().any(|s| object(s) == object(first)) {
                        continue; // this object's contour was decided already
                    }
                    let of_object = || sharing.iter().filter(|s| object(s) == object(first));
                    let lit = || of_object().filter(|s| facing[s.poly()]);
                    let (lit_count, all) = (lit().count(), of_object().count());
                    // A contour edge: one turned to the light meets one turned away, or
                    // an edge of one polygon turned to the light meets nothing.
                    if lit_count == 0 || (lit_count == all && all > 1) {
                        continue;
                    }
                    let (ea, eb) = e.ends(scene);
                    let w = b.net_weight(ea, eb, lit());
                    piece.weights[usize::from(w.abs() != 1)] += u64::from(w != 0);
                    piece.add(camera, scratch, b.side(ea, eb, w, None));
                }
            }
            piece
        })
        .collect();
    // Step 3.
    let mut piece = Piece::default();
    let (mut scratch, mut proj) = (Scratch::default(), Projector::default());
    if counting == Counting::ZFail {
        for &p in adjacency.merged.iter().filter(|&&p| facing[p as usize]) {
            for cap in b.caps(&mut proj, scene.verts(p as usize), p as usize, None) {
                piece.add(camera, &mut scratch, cap);
            }
        }
    }
    for apart in adjacency.apart.iter().filter(|apart| facing[apart.poly as usize]) {
        b.apart_into(apart, counting == Counting::ZFail, &mut piece, camera, &mut scratch, &mut proj);
    }
    // Step 4.
    if counting == Counting::ZPass {
        let eye = ctx.view.eye;
        let merged = adjacency.merged.par_iter().filter(|&&p| facing[p as usize]);
        let crossed = merged.filter(|&&p| crosses_to_light(scene.verts(p as usize), eye, sample)).count();
        let apart =
            adjacency.apart.iter().filter(|a| facing[a.poly as usize] && crosses_to_light(&a.verts, eye, sample));
        let count = (crossed + apart.count()) as i32;
        piece.eye_count = count;
        if count != 0 {
            let (plane, rect) = ctx.view.near_rectangle();
            let over_the_image = ShadowPolygon {
                verts: rect.iter().map(|&v| finite(v)).collect(),
                plane: Some(plane),
                sign: count,
                part: Part::NearCap,
                lies_on: None,
                owner_face: None,
            };
            piece.add(camera, &mut scratch, Some(over_the_image));
        }
    }
    pieces.push(piece);
    pieces
}

/// Whether the segment from `eye` to the light sample (the ray toward a directional light)
/// crosses polygon `verts` strictly inside, its ends off the polygon's plane.
fn crosses_to_light(verts: &[DVec3], eye: DVec3, sample: LightSample) -> bool {
    let plane = Plane::new(newell_normal(verts).normalize_or_zero(), verts[0]);
    let de = plane.distance(eye);
    let t = match sample {
        LightSample::Point(s) => {
            let ds = plane.distance(s);
            if de * ds >= 0.0 {
                return false;
            }
            (s - eye) * (de / (de - ds))
        }
        LightSample::Directional(d) => {
            let along = -plane.n.dot(d);
            if de == 0.0 || along == 0.0 || (de > 0.0) == (along > 0.0) {
                return false;
            }
            -d * (-de / along)
        }
    };
    let axis = dominant_axis(plane.n);
    let ring: Vec<DVec2> = verts.iter().map(|&v| drop_axis(v, axis)).collect();
    crate::geometry::inside_even_odd(&ring, drop_axis(eye + t, axis))
}

/// The shadow polygons one piece made, as they came out of the camera, with their tally.
#[derive(Default)]
struct Piece {
    /// The polygons on screen, in order.
    polys: Vec<ScreenShadowPolygon>,
    /// Their outlines, parallel to `polys`.
    rings: Rings,
    /// Every shadow polygon made, by part (in the order `Part` lists them).
    made: [u64; 5],
    /// The merged sides made of weight 1 and of weight 2 or more.
    weights: [u64; 2],
    /// The sides wholly outside the sight hull.
    outside: u64,
    /// Crow 1977's starting count: the volumes that hold the eye.
    eye_count: i32,
    /// The far caps' screen edges, wound alike, for the far outline.
    far: Vec<FarEdge>,
}

impl Piece {
    /// Puts `sp` (if one was made) through `camera` and keeps it if it is on screen.
    fn add(&mut self, camera: &Camera, scratch: &mut Scratch, sp: Option<ShadowPolygon>) {
        let Some(sp) = sp else { return };
        self.made[sp.part as usize] += 1;
        match scratch.screen(camera, &sp) {
            Screened::On(poly) => {
                self.polys.push(poly);
                self.rings.push(&scratch.ring);
            }
            Screened::OutOfSight => self.outside += 1,
            Screened::Off => {}
        }
    }

    /// Puts front cap `front` through `camera` for the outline of the caps' union (ours,
    /// `front_outline`): a front cap is a scene polygon, so on screen it never lies in front
    /// of the visible point (a polygon nearer would be the one seen), and z-fail counts it,
    /// with the opposite of its sign, at every pixel it covers, its own polygon's included
    /// (`ScreenShadowPolygon::count_at`). Its screen edges go with the far caps', wound so
    /// that its inside winds that many times: the way its corners run on screen is the way
    /// its plane faces the eye ([`far_outline::facing`]), times the way its corners `verts`
    /// run round the plane's normal (its Newell normal's side: a reflected scene's polygons
    /// run the other way round their planes).
    /// A cap whole on screen (found from its corners first, as a far cap is) leaves only the
    /// times it winds, returned, for the edges' pass.
    fn add_front(
        &mut self,
        camera: &Camera,
        scratch: &mut Scratch,
        front: ShadowPolygon,
        verts: &[DVec3],
    ) -> Option<i8> {
        self.made[front.part as usize] += 1;
        let wound = front.plane.map_or(0, |plane| {
            far_outline::wound(newell_normal(verts), &plane, far_outline::facing(camera.view, &plane))
        });
        let winding = -front.sign * wound;
        if winding != 0 && camera.view.whole_on_screen(front.verts.iter().copied()) {
            return Some(winding as i8);
        }
        match scratch.screen(camera, &front) {
            Screened::On(_) if scratch.whole => return Some(winding as i8),
            Screened::On(_) => far_outline::push_ring(&scratch.ring, winding, &mut self.far),
            Screened::OutOfSight => self.outside += 1,
            Screened::Off => {}
        }
        None
    }

    /// Makes the far cap of polygon `verts` (`b` has the far plane; `proj` is scratch) and
    /// puts it through `camera`, for the far outline. A cap whole on screen too gives the way
    /// it winds (+1: counter-clockwise), and its edges are left to the edges' pass; any other
    /// keeps its screen edges here, wound so that its inside winds +1. A cap with no area
    /// about the far plane's normal (which the projection never gives) is kept as a polygon.
    /// Whether a cap is whole is found from its corners first, without its outline, which a
    /// whole cap does not keep.
    fn add_far(
        &mut self,
        camera: &Camera,
        scratch: &mut Scratch,
        b: &Builder,
        proj: &mut Projector,
        verts: &[DVec3],
    ) -> Option<i8> {
        let far = b.far.as_ref()?;
        if !proj.project(verts, far) {
            return None;
        }
        // A winding of zero also stands for a far plane seen edge-on, which the camera's trip
        // would refuse: a cap found whole here is one it would take whole.
        let winding = far_outline::wound(newell_normal(&proj.shadow), &far.plane, b.far_facing);
        if winding != 0 && !proj.clipped && camera.view.whole_on_screen(proj.shadow.iter().map(|&v| finite(v))) {
            self.made[Part::FarCap as usize] += 1;
            return Some(winding as i8);
        }
        let sp = b.far_cap(proj, far, None);
        if winding == 0 {
            self.add(camera, scratch, Some(sp));
            return None;
        }
        self.made[sp.part as usize] += 1;
        if let Screened::On(_) = scratch.screen(camera, &sp) {
            if !proj.clipped && scratch.whole {
                return Some(winding as i8);
            }
            far_outline::push_ring(&scratch.ring, winding, &mut self.far);
        }
        None
    }
}

/// Builds one light sample's shadow polygons.
struct Builder<'c> {
    ctx: &'c ShadowContext<'c>,
    sample: LightSample,
    counting: Counting,
    /// The near rectangle, for the near caps.
    near: Target,
    /// Z-fail's far plane and the part of it behind the scene, for the far caps (none:
    /// back caps at infinity).
    far: Option<Target>,
    /// How the far plane's patches wind on screen ([`far_outline::facing`]; 0 without it).
    far_facing: i32,
}

impl<'c> Builder<'c> {
    fn new(ctx: &'c ShadowContext<'c>, sample: LightSample, counting: Counting, far: Option<&FarPlane>) -> Self {
        let (plane, rect) = ctx.view.near_rectangle();
        let far = far.map(|f| Target::new(f.plane, f.rect, sample));
        let far_facing = far.as_ref().map_or(0, |f| far_outline::facing(ctx.view, &f.plane));
        Builder { ctx, sample, counting, near: Target::new(plane, rect, sample), far, far_facing }
    }

    /// The normal of the plane through edge `a → b` and the light (not normalised; zero when
    /// the light lies on the edge's line).
    fn edge_plane(&self, a: DVec3, b: DVec3) -> DVec3 {
        match self.sample {
            LightSample::Point(s) => (b - a).cross(s - a),
            LightSample::Directional(d) => (b - a).cross(d),
        }
    }

    /// +1 when the side of polygon `poly` on its edge `from → to` (its interior on the left
    /// of `from → to` about its normal) faces out along `m`, the edge plane of `a → b`, −1
    /// when it faces the other way. The side faces out of the volume, away from the
    /// polygon's interior.
    fn orientation(&self, m: DVec3, from: DVec3, to: DVec3, poly: usize) -> i32 {
        let inward = self.ctx.scene.polygons[poly].plane.n.cross(to - from);
        if m.dot(inward) <= 0.0 {
            1
        } else {
            -1
        }
    }

    /// The summed orientation, along the edge plane of `a → b`, of the sides that the
    /// polygons in `sharing` put on that edge.
    fn net_weight<'s>(&self, a: DVec3, b: DVec3, sharing: impl Iterator<Item = &'s Sharing>) -> i32 {
        let m = self.edge_plane(a, b);
        sharing
            .map(|&s| {
                let (from, to) = if s.forward() { (a, b) } else { (b, a) };
                self.orientation(m, from, to, s.poly())
            })
            .sum()
    }

    /// The orientation of one polygon's side on its edge `a → b`.
    fn net_weight_one(&self, a: DVec3, b: DVec3, poly: usize) -> i32 {
        self.orientation(self.edge_plane(a, b), a, b, poly)
    }

    /// The side on edge `a → b` of weight `|w|`, facing out along the edge plane of `a → b`
    /// times the sign of `w`; none when `w` is zero or the light lies on the edge's line.
    fn side(&self, a: DVec3, b: DVec3, w: i32, owner: Option<u32>) -> Option<ShadowPolygon> {
        if w == 0 {
            return None;
        }
        let m = self.edge_plane(a, b) * w.signum() as f64;
        let n = m.normalize();
        if !n.is_finite() {
            return None; // the light lies on the edge's line: the side has no area
        }
        let verts = match self.sample {
            LightSample::Point(_) => smallvec![finite(a), finite(b), self.away(b), self.away(a)],
            LightSample::Directional(_) => smallvec![finite(a), finite(b), self.away(a)],
        };
        let sign = self.eye_sign(n, a) * w.abs();
        Some(ShadowPolygon {
            verts,
            plane: Some(Plane::new(n, a)),
            sign,
            part: Part::Side,
            lies_on: None,
            owner_face: owner,
        })
    }

    /// The caps of the volume of `verts` (on scene polygon `poly`) that `self.counting` needs
    /// (`proj` is scratch for the near cap).
    fn caps(
        &self,
        proj: &mut Projector,
        verts: &[DVec3],
        poly: usize,
        owner: Option<u32>,
    ) -> [Option<ShadowPolygon>; 2] {
        match self.counting {
            Counting::ZFail => {
                let front = self.front_cap(verts, poly, owner);
                let back = match &self.far {
                    // Closed at the far plane: the volume's cross-section there, which
                    // every count behind a visible point starts from.
                    Some(far) => proj.project(verts, far).then(|| self.far_cap(proj, far, owner)),
                    // For a directional light every direction away is the same point at
                    // infinity: the sides close the volume there and no back cap is needed.
                    None => matches!(self.sample, LightSample::Point(_)).then(|| ShadowPolygon {
                        verts: verts.iter().map(|&v| self.away(v)).collect(),
                        plane: None,
                        sign: -1,
                        part: Part::BackCap,
                        lies_on: None,
                        owner_face: owner,
                    }),
                };
                [Some(front), back]
            }
            Counting::ZPass => {
                if self.near.misses(verts) {
                    return [None, None];
                }
                let cap = proj.project(verts, &self.near).then(|| ShadowPolygon {
                    verts: proj.shadow.iter().map(|&v| finite(v)).collect(),
                    plane: Some(self.near.plane),
                    sign: 1,
                    part: Part::NearCap,
                    lies_on: None,
                    owner_face: owner,
                });
                [cap, None]
            }
            Counting::NaiveZPass => [None, None],
        }
    }

    /// Whether [`Builder::caps`] makes no cap for any polygon whose corners lie in the box
    /// `bounds`: z-pass's near caps, whose pyramid misses it.
    fn caps_miss(&self, bounds: (DVec3, DVec3)) -> bool {
        self.counting == Counting::ZPass && self.near.misses_box(bounds)
    }

    /// Z-fail's front cap of the volume of `verts` (on scene polygon `poly`): the polygon
    /// itself.
    fn front_cap(&self, verts: &[DVec3], poly: usize, owner: Option<u32>) -> ShadowPolygon {
        let plane = self.ctx.scene.polygons[poly].plane;
        let toward = plane.n * light_side(&plane, self.sample);
        ShadowPolygon {
            verts: verts.iter().map(|&v| finite(v)).collect(),
            plane: Some(plane),
            sign: self.eye_sign(toward, verts[0]),
            part: Part::FrontCap,
            lies_on: Some(poly as u32),
            owner_face: owner,
        }
    }

    /// Z-fail's far cap on `far`, the shadow `proj` has just made there.
    fn far_cap(&self, proj: &Projector, far: &Target, owner: Option<u32>) -> ShadowPolygon {
        ShadowPolygon {
            verts: proj.shadow.iter().map(|&v| finite(v)).collect(),
            plane: Some(far.plane),
            sign: -1,
            part: Part::FarCap,
            lies_on: None,
            owner_face: owner,
        }
    }

    /// The volume kept apart of `apart` into `piece`, put through `camera`: a side on each
    /// of its edges, and its caps when `caps` (`proj` is scratch for a near cap).
    fn apart_into(
        &self,
        apart: &Apart,
        caps: bool,
        piece: &mut Piece,
        camera: &Camera,
        scratch: &mut Scratch,
        proj: &mut Projector,
    ) {
        let (poly, v) = (apart.poly as usize, &apart.verts);
        let owner = Some(self.ctx.scene.polygons[poly].face);
        for k in 0..v.len() {
            let (a, c) = (v[k], v[(k + 1) % v.len()]);
            piece.add(camera, scratch, self.side(a, c, self.net_weight_one(a, c, poly), owner));
        }
        if caps {
            for cap in self.caps(proj, v, poly, owner) {
                piece.add(camera, scratch, cap);
            }
        }
    }

    /// `v` pushed away from the light to infinity.
    fn away(&self, v: DVec3) -> DVec4 {
        match self.sample {
            LightSample::Point(s) => (v - s).extend(0.0),
            LightSample::Directional(d) => d.extend(0.0),
        }
    }

    /// The sign of a finite polygon through `at` whose outward normal is `outward`: +1 when
    /// the eye is on its outward side.
    fn eye_sign(&self, outward: DVec3, at: DVec3) -> i32 {
        if outward.dot(self.ctx.view.eye - at) > 0.0 {
            1
        } else {
            -1
        }
    }
}

fn finite(v: DVec3) -> DVec4 {
    v.extend(1.0)
}

/// The casting polygons' edges merged by position, worked out once per scene, whatever the
/// light.
#[derive(Debug, Clone, Default)]
pub struct Adjacency {
    /// Whether coincident sides are merged (else every polygon keeps its own volume).
    merged_volumes: bool,
    /// Every edge of a merged polygon, once.
    edges: Vec<MergedEdge>,
    /// The polygons sharing each edge: edge `i`'s from `edges[i].first` to the next edge's
    /// first.
    sharing: Vec<Sharing>,
    /// The merged polygons (their caps).
    merged: Vec<u32>,
    /// The bounds of the corners of each [`PIECE`] of `merged`, in order (ours: a near cap's
    /// test passes over a piece whose box the near rectangle's pyramid misses).
    merged_boxes: Vec<(DVec3, DVec3)>,
    /// The volumes kept apart.
    apart: Vec<Apart>,
}

/// An edge between two vertex positions, the lesser (by their bits) first: `a` and `b` index
/// [`Scene::vertices`](crate::scene::Scene) (a corner of one polygon on it), so that the edge
/// costs 12 bytes, not 56; `first`, where its polygons start in [`Adjacency::sharing`].
#[derive(Debug, Clone, Copy)]
struct MergedEdge {
    a: u32,
    b: u32,
    first: u32,
}

impl MergedEdge {
    /// Its two end positions.
    fn ends(&self, scene: &crate::scene::Scene) -> (DVec3, DVec3) {
        (scene.vertices[self.a as usize], scene.vertices[self.b as usize])
    }
}

/// A polygon on an edge, and whether it runs the edge `a → b` (forward) or `b → a`: the
/// polygon's index in the low 31 bits, the direction in the top bit (four bytes, not
/// eight: s3's three million are 12 MB; a polygon numbered past 2³¹ keeps its own volume).
#[derive(Debug, Clone, Copy)]
struct Sharing(u32);

impl Sharing {
    const FORWARD: u32 = 1 << 31;

    fn new(poly: u32, forward: bool) -> Sharing {
        Sharing(poly | if forward { Sharing::FORWARD } else { 0 })
    }

    fn poly(self) -> usize {
        (self.0 & !Sharing::FORWARD) as usize
    }

    fn forward(self) -> bool {
        self.0 & Sharing::FORWARD != 0
    }
}

/// A volume kept apart: a fan piece, or one trapezoid of a self-intersecting polygon.
#[derive(Debug, Clone)]
struct Apart {
    poly: u32,
    verts: Vec<DVec3>,
}

/// One merged polygon's edge, to be grouped by its two end positions: sorted by a hash of
/// them, then checked against the positions read from the corners. Sixteen bytes an edge,
/// not a copy of both positions: s3's three million edges sort in 48 MB.
#[derive(Clone, Copy)]
struct KeyedEdge {
    hash: u64,
    /// The corner (an index into the scene's vertices) the edge starts from.
    corner: u32,
    poly: u32,
}

/// A hash of an edge's end positions' bits, the lesser end first (a fixed mix, so that the
/// order of the merged edges is the same on every run).
fn edge_hash(a: [u64; 3], b: [u64; 3]) -> u64 {
    a.iter().chain(&b).fold(0u64, |h, &w| (h.rotate_left(5) ^ w).wrapping_mul(0x517c_c1b7_2722_0a95))
}

/// The bits of a position, by which edges are welded and ordered.
fn bits(v: DVec3) -> [u64; 3] {
    v.to_array().map(f64::to_bits)
}

/// An adjacency kept by a renderer: for which polygons ([`Scene::polygons_id`]), merged or
/// not.
///
/// [`Scene::polygons_id`]: crate::scene::Scene
type KeptAdjacency = (u64, bool, Arc<Adjacency>);

impl Adjacency {
    /// The adjacency of `scene` (as [`Adjacency::new`]), from `kept` when an earlier frame of
    /// the same polygons built it: it depends on the polygons alone, not on the camera or
    /// the lights.
    pub(crate) fn kept(scene: &crate::scene::Scene, merge: bool, kept: &Stash) -> Arc<Adjacency> {
        let id = scene.polygons_id;
        let is = |k: &KeptAdjacency| k.0 == id && k.1 == merge;
        // A few scenes: a frame and the scenes its mirrors show.
        kept.find_or_make::<KeptAdjacency>(is, || (id, merge, Arc::new(Adjacency::new(scene, merge))), 4).2
    }

    /// The adjacency of the scene's shadow-casting polygons. Vertices are welded by exact
    /// position. Without `merge`, every polygon keeps its own volume (to measure the saving).
    pub fn new(scene: &crate::scene::Scene, merge: bool) -> Self {
        let mut adjacency = Adjacency { merged_volumes: merge, ..Default::default() };
        let mut keyed = Vec::with_capacity(scene.vertices.len());
        for (p, poly) in scene.polygons.iter().enumerate() {
            if !scene.casts_shadows(p) {
                continue;
            }
            let verts = scene.verts(p);
            let fan_piece = scene.fan_piece(p);
            // Only a polygon of four or more corners can cross itself (most meshes are
            // triangles: no ring is built for them).
            let axis = dominant_axis(poly.plane.n);
            let ring = || verts.iter().map(|&v| drop_axis(v, axis)).collect::<Vec<DVec2>>();
            let crossing = (verts.len() >= 4).then(ring).filter(|r| even_odd::self_intersects(r));
            if let Some(ring) = crossing {
                adjacency.keep_apart_even_odd(p, &ring, axis, &poly.plane);
            } else if !merge || fan_piece || p >= Sharing::FORWARD as usize {
                adjacency.apart.push(Apart { poly: p as u32, verts: verts.to_vec() });
            } else {
                adjacency.merged.push(p as u32);
                for k in 0..verts.len() {
                    let (a, b) = (bits(verts[k]), bits(verts[(k + 1) % verts.len()]));
                    let corner = poly.start + k as u32;
                    keyed.push(KeyedEdge { hash: edge_hash(a.min(b), a.max(b)), corner, poly: p as u32 });
                }
            }
        }
        adjacency.group(scene, keyed);
        adjacency.merged_boxes = adjacency
            .merged
            .par_chunks(PIECE)
            .map(|polys| {
                let corners = polys.iter().flat_map(|&p| scene.verts(p as usize));
                corners.fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)))
            })
            .collect();
        adjacency
    }

    /// Keeps the even-odd region of self-intersecting polygon `p` (its ring `ring`, in the
    /// plane's coordinates dropping `axis`) apart, as trapezoids.
    fn keep_apart_even_odd(&mut self, p: usize, ring: &[DVec2], axis: usize, plane: &Plane) {
        for t in even_odd::trapezoids(ring) {
            let mut v: Vec<DVec3> = t.iter().map(|&q| lift(q, axis, plane)).collect();
            v.dedup();
            if v.len() < 3 {
                continue; // no area
            }
            // Wound as the polygon is, so that its sides know their inside.
            if newell_normal(&v).dot(plane.n) < 0.0 {
                v.reverse();
            }
            self.apart.push(Apart { poly: p as u32, verts: v });
        }
    }

    /// Groups the keyed edges by position: one merged edge each, with the polygons on it
    /// (the keys sorted by their hashes, by all threads; edges whose hashes collide are told
    /// apart by their positions), the merged edges and the polygons on them in the order of
    /// their first corners.
    fn group(&mut self, scene: &crate::scene::Scene, mut keyed: Vec<KeyedEdge>) {
        // The edge's ends as corners (indices into the scene's vertices), the lesser first,
        // and whether the polygon runs it that way.
        let ends = |k: &KeyedEdge| {
            let poly = &scene.polygons[k.poly as usize];
            let next = poly.start + (k.corner + 1 - poly.start) % poly.len;
            let (a, b) = (scene.vertices[k.corner as usize], scene.vertices[next as usize]);
            match bits(a) <= bits(b) {
                true => (k.corner, next, true),
                false => (next, k.corner, false),
            }
        };
        let key = |k: &KeyedEdge| {
            let (a, b, _) = ends(k);
            (bits(scene.vertices[a as usize]), bits(scene.vertices[b as usize]))
        };
        keyed.par_sort_unstable_by_key(|k| (k.hash, k.corner));
        // A run of one hash holding more than one edge position (a collision) is sorted by
        // position, so that each position's edges lie together.
        for run in keyed.chunk_by_mut(|x, y| x.hash == y.hash).filter(|run| run.len() > 1) {
            if run.iter().any(|k| key(k) != key(&run[0])) {
                run.sort_by(|x, y| key(x).cmp(&key(y)).then(x.corner.cmp(&y.corner)));
            }
        }
        // Each position's edges take its first edge's corners as their key, and are sorted
        // by them: a pass over the merged edges then reads the scene's vertices, and the
        // polygons on each edge, in order, not at random as the hashes fall.
        let mut i = 0;
        while i < keyed.len() {
            let (a, b, _) = ends(&keyed[i]);
            let n = keyed[i..].iter().take_while(|k| k.hash == keyed[i].hash && key(k) == key(&keyed[i])).count();
            keyed[i..i + n].iter_mut().for_each(|k| k.hash = u64::from(a) << 32 | u64::from(b));
            i += n;
        }
        keyed.par_sort_unstable_by_key(|k| (k.hash, k.corner));
        let distinct = 1 + keyed.par_windows(2).filter(|w| w[0].hash != w[1].hash).count();
        self.edges.reserve_exact(distinct);
        self.sharing.reserve_exact(keyed.len());
        for (i, k) in keyed.iter().enumerate() {
            let (_, _, forward) = ends(k);
            if i == 0 || keyed[i - 1].hash != k.hash {
                let (a, b) = ((k.hash >> 32) as u32, k.hash as u32);
                let first = self.sharing.len() as u32;
                self.edges.push(MergedEdge { a, b, first });
            }
            self.sharing.push(Sharing::new(k.poly, forward));
        }
    }

    /// The polygons on merged edge `i`.
    fn sharing_of(&self, i: usize) -> &[Sharing] {
        let end = self.edges.get(i + 1).map_or(self.sharing.len(), |e| e.first as usize);
        &self.sharing[self.edges[i].first as usize..end]
    }

    /// The merged edges with the polygons on each, in pieces of at most [`PIECE`], in order.
    fn edge_pieces(&self) -> impl IndexedParallelIterator<Item = impl Iterator<Item = (&MergedEdge, &[Sharing])>> {
        let n = self.edges.len();
        (0..n.div_ceil(PIECE))
            .into_par_iter()
            .map(move |c| (c * PIECE..n.min((c + 1) * PIECE)).map(move |i| (&self.edges[i], self.sharing_of(i))))
    }
}

/// The point of `plane` whose projection dropping `axis` is `q`.
fn lift(q: DVec2, axis: usize, plane: &Plane) -> DVec3 {
    let n = plane.n;
    match axis {
        0 => DVec3::new(-(n.y * q.x + n.z * q.y + plane.d) / n.x, q.x, q.y),
        1 => DVec3::new(q.y, -(n.z * q.x + n.x * q.y + plane.d) / n.y, q.x),
        _ => DVec3::new(q.x, q.y, -(n.x * q.x + n.y * q.y + plane.d) / n.z),
    }
}

/// A shadow polygon in screen space.
#[derive(Debug, Clone, Copy)]
pub struct ScreenShadowPolygon {
    /// Its inverse depth over the screen (all zero on the plane at infinity).
    pub depth: DepthPlane,
    /// +1 when the eye sees its outward side.
    pub sign: i32,
    /// A near cap: in front of every visible point.
    pub near_cap: bool,
    /// For a front cap, the scene polygon it is ([`NONE`] otherwise).
    pub lies_on: u32,
    /// For a per-polygon volume, its face ([`NONE`] otherwise).
    pub owner_face: u32,
}

/// No polygon.
pub const NONE: u32 = u32::MAX;

impl ScreenShadowPolygon {
    /// What this polygon adds to the count at screen position `(x, y)` where polygon `poly`
    /// (of face `face`, inverse depth `surface` there) is seen: z-pass counts it with its sign
    /// when it lies in front of the visible point, z-fail with the opposite sign when it lies
    /// behind. A front cap that is the visible polygon lies exactly at the point: not in front
    /// (z-pass), behind (z-fail), as a depth test `<` has it. A per-polygon volume never
    /// counts on its own face.
    #[inline]
    pub fn count_at(&self, counting: Counting, poly: u32, face: u32, x: f64, y: f64, surface: f64) -> i32 {
        // Without branches: which way a depth comparison goes is data, and on a deep stack
        // of volumes (s4) a mispredicted branch here cost more than the comparison.
        let in_front = self.near_cap | ((self.lies_on != poly) & (self.depth.inv_z(x, y) > surface));
        let (counts, sign) = match counting {
            Counting::ZFail => (!in_front, -self.sign),
            _ => (in_front, self.sign),
        };
        i32::from(counts & (self.owner_face != face)) * sign
    }
}

/// The far plane that closes z-fail's volumes (ours): a face of the scene's bounds, grown by
/// a margin, that every sight line crosses beyond every point of the bounds. Z-fail counts a
/// visible point P from infinity; the sight line beyond P crosses the far plane once, at Q,
/// so P's count is Q's count (the volumes holding Q: the far caps, each volume's
/// cross-section with the plane, found by projecting its front cap from the light) plus
/// the shadow polygons crossed between P and Q. The sides are cut at the plane and the
/// back caps at infinity are not needed: on a floor lit from above, a side stops at the
/// floor instead of running down the screen to its vanishing point. It mirrors the near
/// caps that z-pass starts from (Bergeron 1986).
struct FarPlane {
    /// The plane, its normal pointing back into the bounds (toward the eye).
    plane: Plane,
    /// A rectangle of it holding every point a sight line through the bounds meets.
    rect: [DVec3; 4],
}

impl FarPlane {
    /// The face of the bounds (grown as [`SightHull`]'s are) that faces away from the
    /// light sample the most among those the eye lies beyond the opposite face of (so that
    /// every sight line through the bounds goes on to cross it); none when the eye is
    /// within the bounds' slab along every axis.
    fn new(bounds: (DVec3, DVec3), eye: DVec3, sample: LightSample) -> Option<FarPlane> {
        let (lo, hi) = grown(bounds, eye);
        let away = match sample {
            LightSample::Point(p) => ((lo + hi) * 0.5 - p).normalize_or_zero(),
            LightSample::Directional(d) => d,
        };
        // Each face as (axis, its coordinate, its outward normal), when the eye lies beyond
        // the opposite face.
        let faces = (0..3).flat_map(|i| {
            let e = DVec3::AXES[i];
            [(i, lo[i], -e, eye[i] > hi[i]), (i, hi[i], e, eye[i] < lo[i])]
        });
        let (axis, at, out, _) = faces.filter(|f| f.3).max_by(|f, g| f.2.dot(away).total_cmp(&g.2.dot(away)))?;
        // Every sight line through the bounds meets the plane within the hull of the
        // corners' shadows from the eye on it.
        let (mut a, mut b) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for c in box_corners(lo, hi) {
            let q = eye + (c - eye) * ((at - eye[axis]) / (c[axis] - eye[axis]));
            (a, b) = (a.min(q), b.max(q));
        }
        let grow = (b - a).max_element() * 1e-9 + margin(bounds, eye);
        let (a, b) = (a - DVec3::splat(grow), b + DVec3::splat(grow));
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let rect = [(a[u], a[v]), (b[u], a[v]), (b[u], b[v]), (a[u], b[v])].map(|(x, y)| {
            let mut p = DVec3::ZERO;
            (p[axis], p[u], p[v]) = (at, x, y);
            p
        });
        Some(FarPlane { plane: Plane::new(-out, rect[0]), rect })
    }
}

/// The bounds `lo..hi` grown, for the cuts, by a millionth of the size of the coordinates
/// involved (box and eye: far above the clip's rounding).
fn grown((lo, hi): (DVec3, DVec3), eye: DVec3) -> (DVec3, DVec3) {
    let margin = margin((lo, hi), eye);
    (lo - DVec3::splat(margin), hi + DVec3::splat(margin))
}

/// What [`grown`] grows the bounds by.
fn margin((lo, hi): (DVec3, DVec3), eye: DVec3) -> f64 {
    1e-6 * ((hi - lo).length() + lo.abs().max(hi.abs()).max(eye.abs()).max_element())
}

/// The region every sight line a count follows stays in (ours), which the sides are cut to.
/// For z-pass, the convex hull of the eye and the scene's bounds, grown by a margin: a
/// z-pass count at a visible point P sums the shadow polygons crossed between the eye (its
/// near point) and P; P lies in the bounds, so that segment lies in the hull, and the part
/// of a side outside the hull is crossed by no such segment. Cutting the sides to the hull
/// therefore changes no count, and a side no longer runs on screen from its edge to the
/// image border: on a floor lit from above it stops at the floor. For z-fail closed at a
/// far plane ([`FarPlane`]), the plane's inner side, where the count from P to the plane
/// is taken.
pub(crate) struct SightHull {
    /// Half-spaces `n · x + d · w >= 0` (homogeneous `x`, `w`) whose intersection holds the
    /// hull.
    planes: Vec<(DVec3, f64)>,
}

impl SightHull {
    /// The hull of `eye` and the box `lo..hi` grown by a millionth of the size of the
    /// coordinates involved (far above the clip's rounding): the faces of the box the eye
    /// does not see, and the planes through the eye and each box edge between a face it sees
    /// and one it does not. A plane that rounding leaves cutting the box is dropped (fewer
    /// planes only make the region larger, never wrong).
    pub(crate) fn new(bounds: (DVec3, DVec3), eye: DVec3) -> Self {
        let (lo, hi) = grown(bounds, eye);
        let corners = box_corners(lo, hi);
        // The six faces, inward: (axis, coordinate, inward normal, offset).
        let faces: Vec<(usize, f64, DVec3, f64)> = (0..3)
            .flat_map(|i| {
                let e = DVec3::AXES[i];
                [(i, lo[i], e, -lo[i]), (i, hi[i], -e, hi[i])]
            })
            .collect();
        let sees = |&(_, _, n, d): &(usize, f64, DVec3, f64)| n.dot(eye) + d < 0.0;
        let mut planes: Vec<(DVec3, f64)> = faces.iter().filter(|f| !sees(f)).map(|f| (f.2, f.3)).collect();
        let size = (hi - lo).length() + (eye - (lo + hi) * 0.5).length();
        for f in faces.iter().filter(|f| sees(f)) {
            for g in faces.iter().filter(|g| g.0 != f.0 && !sees(g)) {
                let k = 3 - f.0 - g.0;
                let mut q = (lo + hi) * 0.5;
                (q[f.0], q[g.0]) = (f.1, g.1);
                let mut n = DVec3::AXES[k].cross(eye - q);
                if corners.iter().map(|&c| n.dot(c - eye)).sum::<f64>() < 0.0 {
                    n = -n;
                }
                let tolerance = 1e-9 * n.length() * size;
                if n.length() > 0.0 && corners.iter().all(|&c| n.dot(c - eye) >= -tolerance) {
                    planes.push((n, -n.dot(eye)));
                }
            }
        }
        SightHull { planes }
    }

    /// Z-fail's region: the inner side of its far plane.
    fn before(far: &FarPlane) -> Self {
        SightHull { planes: vec![(far.plane.n, far.plane.d)] }
    }

    /// The near side of the camera's far plane, at depth `far` along the view direction.
    fn before_far(view: &crate::view::View, far: f64) -> Self {
        SightHull { planes: vec![(-view.f, view.f.dot(view.eye) + far)] }
    }

    /// Cuts `verts` (homogeneous) to the hull in place; `scratch` is scratch. Fewer than
    /// three vertices left means nothing of it is inside.
    pub(crate) fn clip(&self, verts: &mut Vec<DVec4>, scratch: &mut Vec<DVec4>) {
        for &(n, d) in &self.planes {
            crate::geometry::clip_in_place(verts, scratch, |h: DVec4| n.dot(h.truncate()) + d * h.w);
            if verts.len() < 3 {
                return;
            }
        }
    }
}

/// One light sample's shadow polygons in screen space, with their outlines.
pub struct ScreenVolumes {
    /// The polygons.
    pub polys: Vec<ScreenShadowPolygon>,
    /// Their screen outlines, parallel to `polys`, in the pieces that made them.
    pub rings: RingPieces,
    /// The far caps' outline (z-fail's far outline, ours): the edges left once those two
    /// caps share cancel, each with its weight; empty without it.
    pub(crate) far: Vec<FarEdge>,
}

impl ScreenVolumes {
    /// The bytes it holds: the polygons and their outlines.
    pub(crate) fn bytes(&self) -> usize {
        crate::pool::held(&self.polys) + self.rings.bytes() + crate::pool::held(&self.far)
    }

    /// The shadow polygons of `sample` built and counted as `options` say, put through the
    /// camera: clipped to the near plane in homogeneous coordinates and projected. With the
    /// sight cuts (ours) they are never clipped to the camera's far plane; without them, as
    /// a z-buffer renders them, they are.
    pub fn new(
        ctx: &ShadowContext,
        adjacency: &Adjacency,
        sample: LightSample,
        options: super::VolumeOptions,
        counters: &mut Counters,
    ) -> Self {
        let (view, counting) = (ctx.view, options.counting);
        // Z-pass counts between the eye and the visible point: its sides are cut to the hull
        // of the two. Z-fail, closed at a far plane, counts between the visible point and
        // that plane: its sides are cut there.
        let bounds = ctx.scene.bounds().filter(|_| options.sight_cuts);
        let (far, hull) = match counting {
            Counting::ZFail => {
                let far = bounds.and_then(|b| FarPlane::new(b, view.eye, sample));
                let hull = far.as_ref().map(SightHull::before);
                (far, hull)
            }
            Counting::ZPass | Counting::NaiveZPass => (None, bounds.map(|b| SightHull::new(b, view.eye))),
        };
        let far_clip = if options.sight_cuts { None } else { view.far.map(|f| SightHull::before_far(view, f)) };
        let camera = Camera { view, hull, far_clip };
        let pieces = match options.construction {
            super::Construction::Crow1977 => crow_1977(ctx, adjacency, sample, counting, &camera),
            _ => {
                let outlines = (options.far_outline, options.front_outline);
                shadow_polygons(ctx, adjacency, sample, counting, far.as_ref(), outlines, &camera)
            }
        };
        let eye_count = pieces.iter().map(|p| p.eye_count).sum::<i32>();
        if options.construction == super::Construction::Crow1977 && counting == Counting::ZPass {
            counters.add(crate::stats::Counter::EyeCount, eye_count.max(0) as u64);
        }
        let sum = |of: &dyn Fn(&Piece) -> u64| pieces.iter().map(of).sum::<u64>();
        counters.add(crate::stats::Counter::MergedEdges, adjacency.edges.len() as u64);
        counters.add(crate::stats::Counter::PolygonsApart, adjacency.apart.len() as u64);
        counters.add(crate::stats::Counter::SidesWeight1, sum(&|p| p.weights[0]));
        counters.add(crate::stats::Counter::SidesWeight2, sum(&|p| p.weights[1]));
        use crate::stats::Counter;
        let kinds = [
            Counter::ShadowPolygonsSide,
            Counter::ShadowPolygonsFrontCap,
            Counter::ShadowPolygonsBackCap,
            Counter::ShadowPolygonsNearCap,
            Counter::ShadowPolygonsFarCap,
        ];
        for (k, counter) in kinds.into_iter().enumerate() {
            counters.add(counter, sum(&|p| p.made[k]));
        }
        let outside = sum(&|p| p.outside);
        let out = ScreenVolumes::joined(pieces);
        counters.add(crate::stats::Counter::ScreenShadowPolygons, out.polys.len() as u64);
        counters.add(crate::stats::Counter::FarOutlineEdges, out.far.len() as u64);
        counters.add(crate::stats::Counter::SidesOutsideSight, outside);
        out
    }

    /// The pieces' polygons in one list, in order (each piece copies its own into its
    /// stretch, in parallel); their outlines stay in their pieces. The far edges the pieces
    /// left are cancelled once more, across the pieces.
    fn joined(mut pieces: Vec<Piece>) -> ScreenVolumes {
        let far = far_outline::cancel(pieces.iter_mut().flat_map(|p| std::mem::take(&mut p.far)).collect());
        let polys: Vec<&[ScreenShadowPolygon]> = pieces.iter().map(|p| p.polys.as_slice()).collect();
        let polys = joined(&polys, |_, &p| p);
        let rings = RingPieces::new(pieces.into_iter().map(|p| p.rings).collect());
        ScreenVolumes { polys, rings, far }
    }
}

/// Puts shadow polygons through the camera.
struct Camera<'v> {
    view: &'v crate::view::View,
    /// The hull that sides are cut to first (none: not cut).
    hull: Option<SightHull>,
    /// The camera's far plane, which clips every shadow polygon but the near caps (the
    /// paper path, without the sight cuts; none: no far plane, or the cuts are on).
    far_clip: Option<SightHull>,
}

/// What became of one shadow polygon put through the camera.
enum Screened {
    /// On screen: the polygon (its outline is in the scratch's `ring`).
    On(ScreenShadowPolygon),
    /// A side wholly outside the sight hull.
    OutOfSight,
    /// Edge-on to the eye, or wholly behind the near plane.
    Off,
}

/// One thread's scratch for putting shadow polygons through the camera.
#[derive(Default)]
struct Scratch {
    cut: Vec<DVec4>,
    cut_scratch: Vec<DVec4>,
    clip: [Vec<DVec4>; 2],
    /// The outline of the polygon last put on screen.
    ring: Vec<DVec2>,
    /// Whether that outline is the polygon's corners, each put on screen alone (nothing was
    /// cut).
    whole: bool,
}

impl Scratch {
    /// Shadow polygon `sp` on screen: a side cut to `hull` first, then clipped to the near
    /// plane in homogeneous coordinates and projected.
    fn screen(&mut self, camera: &Camera, sp: &ShadowPolygon) -> Screened {
        let view = camera.view;
        let mut cut = false;
        if let (Some(hull), Part::Side) = (&camera.hull, sp.part) {
            self.cut.clear();
            self.cut.extend_from_slice(&sp.verts);
            hull.clip(&mut self.cut, &mut self.cut_scratch);
            if self.cut.len() < 3 {
                return Screened::OutOfSight;
            }
            cut = true;
        }
        if let Some(far) = camera.far_clip.as_ref().filter(|_| sp.part != Part::NearCap) {
            if !cut {
                self.cut.clear();
                self.cut.extend_from_slice(&sp.verts);
            }
            far.clip(&mut self.cut, &mut self.cut_scratch);
            if self.cut.len() < 3 {
                return Screened::Off;
            }
            cut = true;
        }
        let verts: &[DVec4] = if cut { &self.cut } else { &sp.verts };
        // A back cap lies on the plane at infinity: inverse depth 0, behind everything.
        let depth = match &sp.plane {
            Some(plane) => match view.depth_plane(plane) {
                Some(d) => d,
                None => return Screened::Off, // edge-on to the eye
            },
            None => DepthPlane { a: 0.0, b: 0.0, c: 0.0 },
        };
        if sp.part == Part::NearCap {
            // On the near plane by construction: projected as it is (clipping it there
            // would let rounding throw it away).
            self.ring.clear();
            self.ring.extend(sp.verts.iter().map(|&v| view.project(view.to_camera(v.truncate()))));
            self.whole = false;
        } else {
            match view.clip_project_homogeneous(verts, &mut self.clip, &mut self.ring) {
                Some(whole) => self.whole = whole && !cut,
                None => return Screened::Off,
            }
        }
        let poly = ScreenShadowPolygon {
            depth,
            sign: sp.sign,
            near_cap: sp.part == Part::NearCap,
            lies_on: sp.lies_on.unwrap_or(NONE),
            owner_face: sp.owner_face.unwrap_or(NONE),
        };
        Screened::On(poly)
    }
}

#[cfg(test)]
mod tests {
    use super::{FarPlane, SightHull};
    use crate::scene::LightSample;
    use glam::{DVec3, DVec4};
    use rand::{Rng, SeedableRng};

    fn inside(hull: &SightHull, p: DVec3) -> f64 {
        hull.planes.iter().map(|&(n, d)| (n.dot(p) + d) / n.length()).fold(f64::INFINITY, f64::min)
    }

    /// The hull holds the eye, the bounds and every sight line between them, and leaves out
    /// what lies beyond the bounds as the eye sees them; wherever the eye is (outside, on a
    /// face's plane, inside).
    #[test]
    fn the_sight_hull_holds_every_sight_line_and_not_what_lies_beyond() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut r = |a: f64, b: f64| rng.gen_range(a..b);
        for case in 0..400 {
            let lo = DVec3::new(r(-5.0, 5.0), r(-5.0, 5.0), r(-5.0, 5.0));
            // Flat boxes too: a floor alone has no height.
            let size = DVec3::new(r(0.0, 8.0), if case % 4 == 0 { 0.0 } else { r(0.0, 8.0) }, r(0.1, 8.0));
            let hi = lo + size;
            let mut eye = DVec3::new(r(-30.0, 30.0), r(-30.0, 30.0), r(-30.0, 30.0));
            if case % 5 == 0 {
                eye.y = hi.y; // on the plane of a face
            }
            let hull = SightHull::new((lo, hi), eye);
            assert!(inside(&hull, eye) >= -1e-9, "case {case}: the eye is outside");
            let in_box = |t: DVec3| lo + size * t;
            for _ in 0..20 {
                let p = in_box(DVec3::new(r(0.0, 1.0), r(0.0, 1.0), r(0.0, 1.0)));
                let on_line = eye + (p - eye) * r(0.0, 1.0);
                assert!(inside(&hull, p) > 0.0, "case {case}: a point of the bounds is outside");
                assert!(inside(&hull, on_line) >= -1e-9, "case {case}: a sight line leaves the hull");
            }
            // Beyond the bounds from the eye: outside unless the eye is inside the bounds.
            let centre = (lo + hi) * 0.5;
            let beyond = centre + (centre - eye).normalize() * (size.length() + 1.0);
            let eye_in = (eye.cmpge(lo) & eye.cmple(hi)).all();
            assert!(eye_in || inside(&hull, beyond) < 0.0, "case {case}: a point beyond is inside");
        }
    }

    /// Z-fail's far plane lies beyond the bounds on every sight line: for random boxes and
    /// eyes outside them, the line from the eye through any point of the box crosses the
    /// plane beyond the point, inside the plane's rectangle; an eye within the box's slabs
    /// gets none; a light overhead picks the floor's face.
    #[test]
    fn every_sight_line_through_the_bounds_crosses_the_far_plane_beyond_them() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut r = |a: f64, b: f64| rng.gen_range(a..b);
        let mut found = 0;
        for case in 0..400 {
            let lo = DVec3::new(r(-5.0, 5.0), r(-5.0, 5.0), r(-5.0, 5.0));
            let size = DVec3::new(r(0.0, 8.0), if case % 4 == 0 { 0.0 } else { r(0.0, 8.0) }, r(0.1, 8.0));
            let hi = lo + size;
            let eye = DVec3::new(r(-30.0, 30.0), r(-30.0, 30.0), r(-30.0, 30.0));
            let light = LightSample::Point(DVec3::new(r(-30.0, 30.0), r(-30.0, 30.0), r(-30.0, 30.0)));
            let Some(far) = FarPlane::new((lo, hi), eye, light) else {
                let margin = 1e-3;
                assert!(
                    (0..3).all(|i| eye[i] >= lo[i] - margin && eye[i] <= hi[i] + margin),
                    "case {case}: no far plane"
                );
                continue;
            };
            found += 1;
            let (rlo, rhi) =
                far.rect.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), &c| (a.min(c), b.max(c)));
            for _ in 0..20 {
                let p = lo + size * DVec3::new(r(0.0, 1.0), r(0.0, 1.0), r(0.0, 1.0));
                let (dp, de) = (far.plane.distance(p), far.plane.distance(eye));
                assert!(dp > 0.0 && de > dp, "case {case}: the box or the eye is not on the plane's inner side");
                let q = eye + (p - eye) * (de / (de - dp));
                assert!(
                    q.cmpge(rlo - DVec3::splat(1e-9)).all() && q.cmple(rhi + DVec3::splat(1e-9)).all(),
                    "case {case}: {q} is outside the rectangle"
                );
            }
        }
        assert!(found > 300, "{found}");
        let (lo, hi) = (DVec3::new(-10.0, 0.0, -10.0), DVec3::new(10.0, 2.0, 10.0));
        let overhead = LightSample::Point(DVec3::new(-16.0, 24.0, 6.0));
        assert!(FarPlane::new((lo, hi), DVec3::new(0.0, 1.0, 0.0), overhead).is_none());
        let far = FarPlane::new((lo, hi), DVec3::new(0.0, 14.0, 17.0), overhead).unwrap();
        assert!(far.plane.n.y > 0.99 && far.rect.iter().all(|c| c.y < 0.0 && c.y > -1e-3), "{:?}", far.rect);
    }

    /// A side hanging from an edge above a floor, lit from above, is cut where it goes
    /// through the floor (and so where it passes out of sight).
    #[test]
    fn a_side_under_a_light_stops_at_the_floor() {
        let hull =
            SightHull::new((DVec3::new(-10.0, 0.0, -10.0), DVec3::new(10.0, 2.0, 10.0)), DVec3::new(0.0, 14.0, 17.0));
        let light = DVec3::new(-16.0, 24.0, 6.0);
        let (a, b) = (DVec3::new(0.0, 1.0, 0.0), DVec3::new(0.5, 1.0, 0.0));
        let mut side = vec![a.extend(1.0), b.extend(1.0), (b - light).extend(0.0), (a - light).extend(0.0)];
        hull.clip(&mut side, &mut Vec::new());
        // The hull's margin: a millionth of the box's diagonal and farthest coordinate.
        let margin = 1e-6 * ((DVec3::new(20.0, 2.0, 20.0)).length() + 17.0);
        assert!(side.len() >= 3);
        for h in &side {
            assert!(h.w > 0.0, "a point at infinity is left: {h}");
            let p = h.truncate() / h.w;
            assert!(p.y >= -1.01 * margin && p.y <= 1.0 + 1e-9, "{p} lies outside the floor's slab");
        }
        assert!(side.iter().any(|h: &DVec4| (h.y / h.w).abs() <= 1.01 * margin), "it reaches the floor");
    }
}
