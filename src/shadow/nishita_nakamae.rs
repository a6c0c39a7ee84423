//! Exact shadows from polygonal lights, after T. Nishita and E. Nakamae, "Half-tone
//! representation of 3-D objects illuminated by area sources or polyhedron sources" (IEEE
//! COMPSAC 1983) and "Continuous tone representation of three-dimensional objects taking
//! account of shadows and interreflection" (SIGGRAPH 1985); `docs/algorithms/nishita-nakamae.md`.
//!
//! The umbra of an occluder is where it hides the whole light; its penumbra where it hides
//! some of it (seed 000's construction, from the light's points). For a convex light and an
//! occluder lying between the light and a receiver's plane, both are found from the light's
//! vertices alone. For each light and each polygon seen at some pixel (a receiver F):
//!
//! 1. **Shadows from the light's vertices.** Each caster O that can come between F and the
//!    light is projected onto F's plane from each vertex of the light.
//! 2. **Penumbra polygon**: the convex hull of those projections. Outside it, O hides no point
//!    of the light from F.
//! 3. **Umbra polygon**: their intersection, for a convex O. Inside it, O hides all of it.
//! 4. **The scan.** Along each visible run, the umbra and penumbra polygons on its polygon
//!    are walked with edge and active-edge tables (as Bouknight-Kelley's shadow polygons):
//!    a pixel inside an umbra polygon is dark, one inside no penumbra polygon fully lit, both
//!    at once for a whole interval.
//! 5. **Penumbra pixels.** Only there is the visible part of the light found: the light cut
//!    by F's plane (the same-side rule), less the projection from the pixel's point of every
//!    occluder whose penumbra holds it (Weiler and Atherton's clipper); the lit fraction is
//!    its area over the light's, `docs/scene-format.md` §3's exact fraction.
//! 6. **Irradiance.** With the area, the irradiance vector of the visible part, by Lambert's
//!    contour formula (`crate::geometry::lambert`): the papers' illuminance, from which the
//!    shading takes the light's diffuse term (ours, `lambert` off: the grid's shading).
//!
//! Where step 1's premise fails for a pair (O reaches across F's plane, or no nearer F than
//! every vertex of the light, or the light itself is cut by F's plane), O is kept as an
//! occluder of every pixel of F, and step 5 runs there: exact, not fast (ours: the papers
//! take the premise for granted).
//!
//! A point light (or one sample of a spot light, or a directional light) is a light of one
//! vertex: its penumbra and umbra are one shadow polygon, the projection of O from it, and
//! every pixel is lit or dark at once (the shadow polygons of Bouknight and Kelley).
//!
//! Ours, marked as such in the page: the casters of a receiver are those whose bounding box
//! meets the box of the receiver and the light (a BVH query); the penumbra and umbra polygons
//! are kept within a rectangle around the receiver.

use super::overlay::{Interval, Overlay, OverlayWalker, ReceiverTable};
use super::projection::{bounding_rectangle, edge_on, Projector, Target};
use super::{Decision, NishitaNakamaeOptions, ShadowContext, ShadowStage, ShadowWalker};
use crate::bvh::Bvh;
use crate::geometry::convex_split::is_convex;
use crate::geometry::{clip_polygon, lambert, Plane};
use crate::scene::{LightKind, LightSample, Scene};
use crate::stats::Counters;
use crate::visibility::Run;
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

/// A parallelogram light: `corner + a·edge_u + b·edge_v` for `a, b` in [0, 1].
#[derive(Debug, Clone, Copy)]
pub(crate) struct AreaLight {
    corner: DVec3,
    edge_u: DVec3,
    edge_v: DVec3,
}

impl AreaLight {
    /// The scene's light `light`, if it is an area light.
    pub(crate) fn of(scene: &Scene, light: usize) -> Option<AreaLight> {
        match scene.lights.get(light)?.kind {
            LightKind::Area { corner, edge_u, edge_v, .. } => Some(AreaLight { corner, edge_u, edge_v }),
            _ => None,
        }
    }

    /// Its four corners, in order round it.
    pub(crate) fn vertices(&self) -> [DVec3; 4] {
        let (c, u, v) = (self.corner, self.edge_u, self.edge_v);
        [c, c + u, c + u + v, c + v]
    }

    /// `closed[s]`: whether solid `s` is closed as seen from every point of the light (the
    /// light's bounding box is apart from the solid's).
    fn closed_solids(&self, scene: &Scene) -> Vec<bool> {
        let v = self.vertices();
        let (lo, hi) = v.iter().fold((v[0], v[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        scene.solids.iter().map(|s| hi.cmplt(s.lo).any() || lo.cmpgt(s.hi).any()).collect()
    }

    /// A point's coordinates `(a, b)` on the light (an affine map: areas keep their ratio).
    fn coordinates(&self, q: DVec3) -> DVec2 {
        let (u, v) = (self.edge_u, self.edge_v);
        let d = q - self.corner;
        let (uu, uv, vv) = (u.dot(u), u.dot(v), v.dot(v));
        let (du, dv) = (d.dot(u), d.dot(v));
        let det = uu * vv - uv * uv;
        DVec2::new((du * vv - dv * uv) / det, (dv * uu - du * uv) / det)
    }

    /// The light's plane, and a projection target over the light from point `p`.
    pub(crate) fn target_from(&self, p: DVec3) -> Target {
        let plane = Plane::new(self.edge_u.cross(self.edge_v).normalize(), self.corner);
        super::projection_target(plane, self.vertices(), p)
    }

    /// The part of the light, as the unit square of its coordinates, on the far side of
    /// `plane` from the side `seen` (+1 or −1), into `out` (empty when none).
    pub(crate) fn cut_away(&self, plane: &Plane, seen: f64, out: &mut Vec<DVec2>) {
        let (c, u, v) = (self.corner, self.edge_u, self.edge_v);
        let square = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
        clip_polygon(&square, |ab: DVec2| -seen * plane.distance(c + u * ab.x + v * ab.y), out);
        if out.len() < 3 {
            out.clear();
        }
    }

    /// The shadow in `proj.shadow` (on the light's plane) in the light's coordinates.
    pub(crate) fn shadow_ab(&self, proj: &Projector) -> Vec<DVec2> {
        proj.shadow.iter().map(|&q| self.coordinates(q)).collect()
    }

    /// Step 5 at point `p` of a polygon with plane `plane`, seen from the side `seen`: the
    /// part of the light cut away by the plane, and the projection from `p` of each of
    /// `occluders` onto the light, gathered in `hidden`; what they leave of the light
    /// ([`unhidden`]), with its irradiance vector when `lambert`.
    #[allow(clippy::too_many_arguments)]
    fn visible(
        &self,
        p: DVec3,
        plane: &Plane,
        seen: f64,
        occluders: impl IntoIterator<Item = u32>,
        (scene, bodies): (&Scene, &[bool]),
        lambert: bool,
        scratch: &mut Scratch,
    ) -> Seen {
        scratch.hidden.clear();
        scratch.bodies.clear();
        let mut cut = Vec::new();
        self.cut_away(plane, seen, &mut cut);
        if !cut.is_empty() {
            scratch.hidden.push(cut);
        }
        let target = self.target_from(p);
        for a in occluders {
            if !scratch.proj.project(scene.verts(a as usize), &target) {
                continue;
            }
            let shadow = self.shadow_ab(&scratch.proj);
            // A convex solid's polygons hide together what the solid hides: the hull of
            // their shadows' corners (see `body_shadows`).
            match bodies.get(scene.solid_of[a as usize] as usize) {
                Some(true) => body_shadows(&mut scratch.bodies, scene.solid_of[a as usize], shadow),
                _ => scratch.hidden.push(shadow),
            }
        }
        scratch.body_hulls += scratch.bodies.len() as u64;
        for (_, corners) in scratch.bodies.iter_mut() {
            let mut hull = Vec::new();
            convex_hull(corners, &mut hull);
            scratch.hidden.push(hull);
        }
        scratch.clips += scratch.hidden.len() as u64;
        let contour = lambert.then_some(Contour { p, light: *self });
        unhidden(&scratch.hidden, &mut scratch.sweep, contour.as_ref())
    }

    /// The irradiance vector of what `p` sees of the light (`seen`, wound as the light's
    /// coordinates run), turned toward the light and scaled by `d² / A` (`d` from `p` to the
    /// light's centre, `A` the light's area): so that for a small light far away it is the
    /// unit vector toward it times the cosine at the light, and a shader's `N · vector`
    /// times the light's intensity is what a point light there would give, by that cosine
    /// (ours: the papers' source has a luminance in physical units).
    fn normalised(&self, p: DVec3, seen: &Seen) -> [f32; 3] {
        let n = self.edge_u.cross(self.edge_v);
        let centre = self.corner + 0.5 * (self.edge_u + self.edge_v);
        // Wound counter-clockwise as seen from p, a ring's vector points away from it.
        let toward = -n.dot(p - self.corner).signum();
        (seen.vector * (toward * (centre - p).length_squared() / n.length())).as_vec3().to_array()
    }
}

/// Adds `shadow`'s corners to solid `solid`'s in `bodies`. Ours: for a convex closed solid
/// apart from the light, the shadows from P of its polygons whose penumbra holds P cover,
/// within the light, what the whole solid's shadow covers (the others hide no part of the
/// light from P, or lie behind polygons of the solid that do), and the solid's shadow is
/// convex and holds every such corner: so the hull of the corners is the solid's shadow
/// within the light, one convex part where there were hundreds of polygons.
fn body_shadows(bodies: &mut Vec<(u32, Vec<DVec2>)>, solid: u32, shadow: Vec<DVec2>) {
    match bodies.iter_mut().find(|(s, _)| *s == solid) {
        Some((_, corners)) => corners.extend(shadow),
        None => bodies.push((solid, shadow)),
    }
}

/// `convex[s]`: whether solid `s` of `scene` is convex (every vertex of it on or behind the
/// plane of each of its polygons, to a relative 1e-9 of the scene's size), found in parallel.
fn convex_solids(scene: &Scene, extent: f64) -> Vec<bool> {
    scene
        .solid_members()
        .par_iter()
        .zip(&scene.solids)
        .map(|(polys, solid)| {
            // Each corner once (a vertex is shared by several polygons).
            let mut verts: Vec<[u64; 3]> = polys
                .iter()
                .flat_map(|&i| scene.verts(i as usize).iter().map(|v| v.to_array().map(f64::to_bits)))
                .collect();
            verts.sort_unstable();
            verts.dedup();
            let verts: Vec<DVec3> = verts.into_iter().map(|v| DVec3::from_array(v.map(f64::from_bits))).collect();
            polys.iter().all(|&i| {
                let plane = &scene.polygons[i as usize].plane;
                verts.iter().all(|&v| solid.sign * plane.distance(v) <= 1e-9 * extent)
            })
        })
        .collect()
}

/// A walker's scratch for step 5.
#[derive(Debug, Default)]
struct Scratch {
    proj: Projector,
    hidden: Vec<Vec<DVec2>>,
    /// Convex solids' shadow corners, by solid, and how many hulls were made of them.
    bodies: Vec<(u32, Vec<DVec2>)>,
    body_hulls: u64,
    sweep: Sweep,
    clips: u64,
}

/// Scratch for [`unhidden`].
#[derive(Debug, Default)]
struct Sweep {
    parts: Vec<Vec<DVec2>>,
    xs: Vec<f64>,
    spans: Vec<Span>,
    crossings: Vec<Crossing>,
    clipped: Vec<DVec2>,
    tmp: Vec<DVec2>,
    /// The covered part cut into trapezoids by the sweep, when asked for.
    trapezoids: Vec<[DVec2; 4]>,
}

/// What a point sees of the light: its fraction of the light's area, and the irradiance
/// vector of that part (`crate::geometry::lambert`), wound as the light's coordinates run
/// (zero where not asked for).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Seen {
    fraction: f64,
    vector: DVec3,
}

/// Lambert's contour formula over parts of the light, in the light's coordinates, seen from
/// a point.
struct Contour {
    p: DVec3,
    light: AreaLight,
}

impl Contour {
    /// The irradiance vector of `ring` (simple, in the light's coordinates), wound as the
    /// coordinates run (counter-clockwise) whichever way `ring` is.
    fn of(&self, ring: &[DVec2]) -> DVec3 {
        let AreaLight { corner, edge_u, edge_v } = self.light;
        let phi = lambert::irradiance_vector(self.p, ring.iter().map(|q| corner + edge_u * q.x + edge_v * q.y));
        phi * crate::geometry::weiler_atherton::signed_area(ring).signum()
    }
}

/// What none of the polygons `hidden` (each simple, convex or not, in the light's
/// coordinates) covers of the unit square: its area, and with a `contour`, its irradiance
/// vector (ours: where the papers clip polygon by polygon). Each is first clipped to the
/// square. One left: the square less it. Two convex: less both, plus their intersection.
/// More: a sweep across the square ([`covered_area`]), whose trapezoids the vector sums.
fn unhidden(hidden: &[Vec<DVec2>], sweep: &mut Sweep, contour: Option<&Contour>) -> Seen {
    let square = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    let area = |ring: &[DVec2]| crate::geometry::weiler_atherton::signed_area(ring).abs();
    let none = Seen { fraction: 0.0, vector: DVec3::ZERO };
    let Sweep { parts, clipped, tmp, xs, spans, crossings, trapezoids } = sweep;
    let mut k = 0;
    for ring in hidden {
        clip_convex(ring, &square, clipped, tmp);
        if clipped.len() < 3 {
            continue;
        }
        if area(clipped) >= 1.0 - 1e-12 && is_convex(clipped) {
            return none;
        }
        if parts.len() == k {
            parts.push(Vec::new());
        }
        parts[k].clone_from(clipped);
        k += 1;
    }
    let parts = &parts[..k];
    // The area first; the vector (dearer) only where some but not all of the light is seen.
    trapezoids.clear();
    let convex_pair = matches!(parts, [a, b] if is_convex(a) && is_convex(b));
    let covered = match parts {
        [] => 0.0,
        [a] => area(a),
        [a, b] if convex_pair => {
            clip_convex(a, b, clipped, tmp);
            area(a) + area(b) - area(clipped)
        }
        _ => covered_area(parts, (xs, spans, crossings), contour.map(|_| &mut *trapezoids)),
    };
    // Slivers of a part touching the light's edge, and rounding, leave areas of 1e-12 and
    // less: within `SLIVER` of none or all of the light is none or all of it.
    let fraction = match 1.0 - covered {
        f if f <= SLIVER => return none,
        f if f >= 1.0 - SLIVER => 1.0,
        f => f,
    };
    let Some(contour) = contour else { return Seen { fraction, vector: DVec3::ZERO } };
    let whole = lambert::irradiance_vector(contour.p, contour.light.vertices());
    if fraction == 1.0 {
        return Seen { fraction, vector: whole };
    }
    let hidden_vector = match parts {
        [a] => contour.of(a),
        [a, b] if convex_pair => {
            let both = if clipped.len() < 3 { DVec3::ZERO } else { contour.of(clipped) };
            contour.of(a) + contour.of(b) - both
        }
        _ => trapezoids.iter().map(|t| contour.of(t)).sum(),
    };
    Seen { fraction, vector: whole - hidden_vector }
}

/// A share of the light's area below which a part left or hidden counts as nothing
/// (far below an 8-bit grey level's 1/255).
const SLIVER: f64 = 1e-9;

/// Scratch of [`covered_area`]: the slabs' bounds, the covered spans of one slab, and one
/// polygon's crossings with it.
type SweepScratch<'s> = (&'s mut Vec<f64>, &'s mut Vec<Span>, &'s mut Vec<Crossing>);

/// Where an edge crosses a slab `x0..x1` of the sweep: its `y` at the slab's middle, and at
/// either side.
#[derive(Debug, Clone, Copy, Default)]
struct Crossing {
    mid: f64,
    at0: f64,
    at1: f64,
}

/// A covered span of a slab: its lower and upper edge's crossings.
type Span = (Crossing, Crossing);

/// The area of the unit square covered by the union of `polygons` (even-odd within each),
/// and, into `trapezoids`, the union cut into trapezoids (counter-clockwise), one per slab
/// between successive corners and crossings and per covered span of it.
fn covered_area(
    polygons: &[Vec<DVec2>],
    (xs, spans, crossings): SweepScratch,
    mut trapezoids: Option<&mut Vec<[DVec2; 4]>>,
) -> f64 {
    // A polygon's own edges meet only at its corners (it is simple): only pairs of edges of
    // two polygons can cross.
    let edges =
        || polygons.iter().enumerate().flat_map(|(i, p)| (0..p.len()).map(move |k| (i, p[k], p[(k + 1) % p.len()])));
    xs.clear();
    xs.extend([0.0, 1.0]);
    xs.extend(polygons.iter().flatten().map(|v| v.x).filter(|x| (0.0..=1.0).contains(x)));
    let all: Vec<(usize, DVec2, DVec2)> = edges().collect();
    for (i, &(pa, a, b)) in all.iter().enumerate() {
        for &(pc, c, d) in &all[i + 1..] {
            if pa == pc || a.x.max(b.x) < c.x.min(d.x) || c.x.max(d.x) < a.x.min(b.x) {
                continue;
            }
            let (r, s) = (b - a, d - c);
            let den = r.perp_dot(s);
            if den == 0.0 {
                continue;
            }
            let t = (c - a).perp_dot(s) / den;
            let u = (c - a).perp_dot(r) / den;
            if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u) {
                let x = a.x + r.x * t;
                if (0.0..=1.0).contains(&x) {
                    xs.push(x);
                }
            }
        }
    }
    xs.sort_unstable_by(f64::total_cmp);
    xs.dedup();
    let mut area = 0.0;
    for w in xs.windows(2) {
        let (x0, x1) = (w[0], w[1]);
        if x1 <= x0 {
            continue;
        }
        let x = 0.5 * (x0 + x1);
        spans.clear();
        for poly in polygons {
            crossings.clear();
            for k in 0..poly.len() {
                let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
                if (a.x <= x) != (b.x <= x) {
                    let y = |x: f64| (a.y + (b.y - a.y) * (x - a.x) / (b.x - a.x)).clamp(0.0, 1.0);
                    crossings.push(Crossing { mid: y(x), at0: y(x0), at1: y(x1) });
                }
            }
            crossings.sort_unstable_by(|a, b| a.mid.total_cmp(&b.mid));
            for pair in crossings.chunks_exact(2) {
                if pair[1].mid > pair[0].mid {
                    spans.push((pair[0], pair[1]));
                }
            }
        }
        spans.sort_unstable_by(|a, b| a.0.mid.total_cmp(&b.0.mid));
        // The union of the spans, one merged span at a time.
        let mut merged: Option<Span> = None;
        let mut close = |(lo, hi): Span, area: &mut f64| {
            *area += (hi.mid - lo.mid) * (x1 - x0);
            if let Some(t) = trapezoids.as_mut() {
                t.push([
                    DVec2::new(x0, lo.at0),
                    DVec2::new(x1, lo.at1),
                    DVec2::new(x1, hi.at1),
                    DVec2::new(x0, hi.at0),
                ]);
            }
        };
        for &(lo, hi) in spans.iter() {
            match merged.as_mut() {
                Some(m) if lo.mid <= m.1.mid => {
                    if hi.mid > m.1.mid {
                        m.1 = hi;
                    }
                }
                _ => {
                    if let Some(m) = merged.replace((lo, hi)) {
                        close(m, &mut area);
                    }
                }
            }
        }
        if let Some(m) = merged {
            close(m, &mut area);
        }
    }
    area
}

/// The prepared stage.
pub(crate) struct NishitaNakamae<'a> {
    ctx: &'a ShadowContext<'a>,
    lights: Vec<LightShadows>,
    /// Whether the walk gives each pixel's irradiance vector of an area light too.
    lambert: bool,
}

/// What a light's walk needs.
enum Source {
    /// A light of one vertex (a point, spot or directional light): its shadow polygons.
    Vertex,
    /// An area light.
    Area(AreaLight),
}

/// One light's umbra and penumbra polygons on every receiver.
struct LightShadows {
    source: Source,
    umbra: Overlay,
    penumbra: Overlay,
    /// `occluder[tag]`: the caster whose penumbra polygon has tag `tag`.
    occluder: Vec<u32>,
    /// For receivers where step 5 must look beyond the penumbra polygons: the casters it
    /// takes at every pixel, and whether the light is cut by the receiver's plane.
    everywhere: FxHashMap<u32, (Vec<u32>, bool)>,
    /// `bodies[s]`: whether solid `s` is convex and closed from all of the light.
    bodies: Vec<bool>,
}

/// One receiver's polygons, gathered in parallel.
struct OnReceiver {
    umbra: ReceiverTable,
    penumbra: ReceiverTable,
    occluders: Vec<u32>,
    everywhere: Option<(Vec<u32>, bool)>,
    dark: bool,
    pairs: u64,
}

impl<'a> NishitaNakamae<'a> {
    /// Steps 1 to 3 for every light and receiver.
    pub(crate) fn new(ctx: &'a ShadowContext<'a>, options: NishitaNakamaeOptions, counters: &mut Counters) -> Self {
        let scene = ctx.scene;
        let n = scene.polygons.len() as u32;
        let casters = Bvh::new(scene, (0..n).filter(|&i| scene.casts_shadows(i as usize)).collect());
        let receivers: Vec<u32> = (0..n).filter(|&i| ctx.visible[i as usize]).collect();
        let convex = convex_solids(scene, ctx.extent);
        let lights = (0..scene.lights.len())
            .map(|l| {
                let source = match AreaLight::of(scene, l) {
                    Some(area) => Source::Area(area),
                    None => Source::Vertex,
                };
                let sample = ctx.samples[l].first().copied();
                let closed = match &source {
                    Source::Area(area) => area.closed_solids(scene),
                    Source::Vertex => Vec::new(),
                };
                let solids = Solids { closed: &closed, convex: &convex, options };
                let per: Vec<(u32, OnReceiver)> = receivers
                    .par_iter()
                    .map(|&b| (b, on_receiver(ctx, &casters, &source, sample, &solids, b)))
                    .collect();
                let bodies = closed.iter().zip(&convex).map(|(&c, &v)| c && v && options.convex_bodies).collect();
                gather(ctx, source, per, bodies, counters)
            })
            .collect();
        counters.add(crate::stats::Counter::Receivers, receivers.len() as u64 * scene.lights.len() as u64);
        NishitaNakamae { ctx, lights, lambert: options.lambert }
    }
}

/// Every receiver's polygons into one light's overlays.
fn gather(
    ctx: &ShadowContext,
    source: Source,
    per: Vec<(u32, OnReceiver)>,
    bodies: Vec<bool>,
    counters: &mut Counters,
) -> LightShadows {
    let height = ctx.view.height;
    let (mut umbras, mut penumbras, mut occluder, mut dark) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut everywhere = FxHashMap::default();
    let mut pairs = 0;
    for (b, r) in per {
        pairs += r.pairs;
        if r.dark {
            dark.push(b);
            continue;
        }
        if r.penumbra.len() > 0 {
            occluder.extend(r.occluders);
        }
        umbras.push(r.umbra);
        penumbras.push(r.penumbra);
        if let Some(e) = r.everywhere {
            everywhere.insert(b, e);
        }
    }
    let mut umbra = Overlay::from_tables(height, false, umbras.into_par_iter());
    umbra.add_wholes(&dark);
    let penumbra = Overlay::from_tables(height, false, penumbras.into_par_iter());
    counters.add(crate::stats::Counter::Pairs, pairs);
    counters.add(crate::stats::Counter::UmbraPolygons, umbra.len() as u64);
    counters.add(crate::stats::Counter::PenumbraPolygons, penumbra.len() as u64);
    counters.add(crate::stats::Counter::ReceiversSearchedEverywhere, everywhere.len() as u64);
    LightShadows { source, umbra, penumbra, occluder, everywhere, bodies }
}

/// What steps 1 to 3 know of the scene's solids, and the switches of the steps of ours.
struct Solids<'s> {
    /// `closed[s]`: solid `s` is closed from the whole light (area lights only).
    closed: &'s [bool],
    /// `convex[s]`: solid `s` is convex.
    convex: &'s [bool],
    options: NishitaNakamaeOptions,
}

impl Solids<'_> {
    /// Whether caster `a` is left out for receiver `b` by a step of ours: its solid turns
    /// its back on the whole light (`corners`), or it belongs to `b`'s own convex solid.
    fn skip(&self, ctx: &ShadowContext, corners: Option<&[DVec3; 4]>, a: u32, b: u32) -> bool {
        let o = &self.options;
        (o.solid_cull && corners.is_some_and(|c| turned_away(ctx.scene, self.closed, c, a)))
            || (o.same_solid && same_convex_solid(ctx, self.convex, a, b))
    }
}

/// Steps 1 to 3 on receiver `b`.
fn on_receiver(
    ctx: &ShadowContext,
    casters: &Bvh,
    source: &Source,
    sample: Option<LightSample>,
    solids: &Solids,
    b: u32,
) -> OnReceiver {
    let scene = ctx.scene;
    let height = ctx.view.height;
    let mut r = OnReceiver {
        umbra: ReceiverTable::new(b, height, false),
        penumbra: ReceiverTable::new(b, height, false),
        occluders: Vec::new(),
        everywhere: None,
        dark: false,
        pairs: 0,
    };
    let polygon = &scene.polygons[b as usize];
    let (plane, face) = (polygon.plane, polygon.face);
    let b_verts = scene.verts(b as usize);
    let rect = bounding_rectangle(b_verts, &plane);
    let (mut proj, mut scratch, mut ring) = (Projector::default(), [Vec::new(), Vec::new()], Vec::new());
    match (source, sample) {
        (Source::Vertex, Some(sample)) => {
            let target = Target::new(plane, rect, sample);
            let reach = match sample {
                LightSample::Point(s) => Some(s),
                LightSample::Directional(_) => None,
            };
            let skip = |a: u32| solids.skip(ctx, None, a, b);
            let hull = solids.options.hull_cull;
            for a in candidates(scene, casters, b_verts, reach.as_slice(), face, skip, hull, ctx.extent) {
                r.pairs += 1;
                if edge_on(scene, a as usize, sample, ctx.extent) || !proj.project(scene.verts(a as usize), &target) {
                    continue;
                }
                if ctx.view.clip_project(&proj.shadow, &mut scratch, &mut ring) {
                    r.umbra.add(&ring);
                }
            }
        }
        (Source::Area(light), _) => area_on_receiver(ctx, casters, light, solids, b, &mut r),
        (Source::Vertex, None) => {}
    }
    r.umbra.finish();
    r.penumbra.finish();
    r
}

/// Steps 1 to 3 of an area light on receiver `b`, into `r`.
fn area_on_receiver(
    ctx: &ShadowContext,
    casters: &Bvh,
    light: &AreaLight,
    solids: &Solids,
    b: u32,
    r: &mut OnReceiver,
) {
    let scene = ctx.scene;
    let polygon = &scene.polygons[b as usize];
    let plane = polygon.plane;
    let b_verts = scene.verts(b as usize);
    let seen = plane.distance(ctx.view.eye).signum();
    let lv = light.vertices();
    // Each vertex's height above the plane, on the seen side.
    let dl = lv.map(|v| seen * plane.distance(v));
    if seen == 0.0 || dl.iter().all(|&d| d <= 0.0) {
        r.dark = true;
        return;
    }
    let cut = dl.iter().any(|&d| d <= 0.0);
    let nearest = dl.iter().copied().fold(f64::INFINITY, f64::min);
    let rect = bounding_rectangle(b_verts, &plane);
    let frame = PlaneFrame::new(&plane, rect[0]);
    let rect2 = rect.map(|q| frame.to_2d(q));
    let targets = lv.map(|v| Target::new(plane, rect, LightSample::Point(v)));
    let (mut proj, mut scratch, mut ring) = (Projector::default(), [Vec::new(), Vec::new()], Vec::new());
    let mut everywhere = Vec::new();
    let (mut points, mut hull, mut a2, mut b2) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut part = Vec::new();
    let skip = |a: u32| solids.skip(ctx, Some(&lv), a, b);
    let cull = solids.options.hull_cull;
    for a in candidates(scene, casters, b_verts, &lv, polygon.face, skip, cull, ctx.extent) {
        r.pairs += 1;
        let whole = scene.verts(a as usize);
        if whole.iter().all(|&o| seen * plane.distance(o) <= 0.0) {
            continue; // on or behind F's plane: it cannot cross a segment from F to the light
        }
        // Only the part of O on the lit side of F's plane can cross such a segment.
        clip_polygon(whole, |o| seen * plane.distance(o), &mut part);
        let verts = &part[..];
        let d: smallvec::SmallVec<[f64; 8]> = verts.iter().map(|&o| (seen * plane.distance(o)).max(0.0)).collect();
        if cut || d.iter().any(|&h| h >= nearest) {
            // The premise fails: step 5 takes it at every pixel (ours), or it is left out.
            if solids.options.premise_fallback {
                everywhere.push(a);
            }
            continue;
        }
        // Step 2: the hull of the projections of O's vertices from the light's vertices.
        points.clear();
        for (v, &dv) in lv.iter().zip(&dl) {
            for (&o, &h) in verts.iter().zip(&d) {
                points.push(frame.to_2d(*v + (o - *v) * (dv / (dv - h))));
            }
        }
        convex_hull(&mut points, &mut hull);
        clip_convex(&hull, &rect2, &mut a2, &mut b2);
        if a2.len() < 3 {
            continue;
        }
        let hull3: Vec<DVec3> = a2.iter().map(|&q| frame.to_3d(q)).collect();
        if !ctx.view.clip_project(&hull3, &mut scratch, &mut ring) {
            continue;
        }
        r.penumbra.add(&ring);
        r.occluders.push(a);
        // Step 3: for a convex O, the intersection of its shadows from the four vertices.
        if !convex(verts) {
            continue;
        }
        let mut umbra: Option<Vec<DVec2>> = None;
        for target in &targets {
            if !proj.project(verts, target) {
                umbra = Some(Vec::new());
                break;
            }
            let shadow: Vec<DVec2> = proj.shadow.iter().map(|&q| frame.to_2d(q)).collect();
            umbra = Some(match umbra {
                None => shadow,
                Some(u) => {
                    clip_convex(&u, &shadow, &mut a2, &mut b2);
                    a2.clone()
                }
            });
        }
        let Some(u) = umbra.filter(|u| u.len() >= 3) else { continue };
        let u3: Vec<DVec3> = u.iter().map(|&q| frame.to_3d(q)).collect();
        if ctx.view.clip_project(&u3, &mut scratch, &mut ring) {
            r.umbra.add(&ring);
        }
    }
    if cut || !everywhere.is_empty() {
        r.everywhere = Some((everywhere, cut));
    }
}

/// The casters (not of face `face`, not `skip`ped) that can cross a segment from receiver
/// `verts` to a point of `reach` (the light's corners; every caster when the light has no
/// position). Ours, when `hull`: a caster is left out when it lies wholly outside one face of
/// the convex hull of the receiver and the light, which holds every such segment (found in
/// the BVH, then polygon by polygon); without it, every caster.
#[allow(clippy::too_many_arguments)]
fn candidates(
    scene: &Scene,
    casters: &Bvh,
    verts: &[DVec3],
    reach: &[DVec3],
    face: u32,
    skip: impl Fn(u32) -> bool,
    hull: bool,
    extent: f64,
) -> Vec<u32> {
    let mut out = Vec::new();
    let keep = |i: u32| scene.polygons[i as usize].face != face && !skip(i);
    if reach.is_empty() || !hull {
        casters.each(|i| {
            if keep(i) {
                out.push(i)
            }
        });
        return out;
    }
    let mut points: smallvec::SmallVec<[DVec3; 12]> = smallvec::SmallVec::new();
    if verts.len() <= 6 {
        points.extend_from_slice(verts);
    } else {
        points.extend_from_slice(&bounding_rectangle(verts, &scene_plane(verts)));
    }
    points.extend_from_slice(reach);
    let planes = hull_planes(&points, 1e-9 * extent);
    casters.within(&planes, |i| {
        let outside = |&(n, d): &(DVec3, f64)| scene.verts(i as usize).iter().all(|&x| n.dot(x) > d);
        if keep(i) && !planes.iter().any(outside) {
            out.push(i)
        }
    });
    out
}

/// A polygon's plane from its vertices.
fn scene_plane(verts: &[DVec3]) -> Plane {
    Plane::new(crate::geometry::newell_normal(verts).normalize_or_zero(), verts[0])
}

/// The planes of the faces of the convex hull of `points` (a few: every plane through three
/// of them with all on one side), each as `(n, d)` with the hull where `n·x <= d`, moved out
/// by `margin`. Points that are all on one plane give that plane both ways.
fn hull_planes(points: &[DVec3], margin: f64) -> Vec<(DVec3, f64)> {
    let mut planes = Vec::new();
    let m = points.len();
    for i in 0..m {
        for j in i + 1..m {
            for k in j + 1..m {
                let n = (points[j] - points[i]).cross(points[k] - points[i]);
                let len = n.length();
                if len == 0.0 || !len.is_finite() {
                    continue;
                }
                let n = n / len;
                let d = n.dot(points[i]);
                let (mut above, mut below) = (false, false);
                for p in points {
                    let s = n.dot(*p) - d;
                    above |= s > margin;
                    below |= s < -margin;
                }
                match (above, below) {
                    (false, _) => planes.push((n, d + margin)),
                    (true, false) => planes.push((-n, -d + margin)),
                    _ => {}
                }
            }
        }
    }
    planes
}

/// Whether caster `a` is a polygon of a solid closed from the whole light (`closed`) that
/// turns its back to every corner of the light `corners`, so to all of it: a segment from the
/// light crossing it has crossed the solid nearer the light (ours, as Bouknight-Kelley's
/// solid cull, `Scene::turned_away_on_solid`).
fn turned_away(scene: &Scene, closed: &[bool], corners: &[DVec3; 4], a: u32) -> bool {
    corners.iter().all(|&c| scene.turned_away_on_solid(a as usize, LightSample::Point(c), closed))
}

/// Whether caster `a` is a polygon of the convex solid that receiver `b` belongs to, `b` seen
/// from outside (ours): every polygon of the solid lies on or behind `b`'s plane, and a
/// segment from a point of `b` to a point of the light in front of it lies in front of that
/// plane but for its end on `b`, so no polygon of the solid can cross it. (A sphere's
/// triangles near its terminator, whose neighbours rise above their plane by rounding alone,
/// are the receivers this spares.)
fn same_convex_solid(ctx: &ShadowContext, convex: &[bool], a: u32, b: u32) -> bool {
    let scene = ctx.scene;
    let s = scene.solid_of[b as usize];
    let (Some(true), Some(solid)) = (convex.get(s as usize), scene.solids.get(s as usize)) else {
        return false;
    };
    scene.solid_of[a as usize] == s && solid.sign * scene.polygons[b as usize].plane.distance(ctx.view.eye) > 0.0
}

/// Coordinates in a plane: an origin and two unit axes across its normal.
struct PlaneFrame {
    origin: DVec3,
    u: DVec3,
    v: DVec3,
}

impl PlaneFrame {
    fn new(plane: &Plane, origin: DVec3) -> Self {
        let u = plane.n.any_orthonormal_vector();
        PlaneFrame { origin, u, v: plane.n.cross(u) }
    }

    fn to_2d(&self, p: DVec3) -> DVec2 {
        let d = p - self.origin;
        DVec2::new(d.dot(self.u), d.dot(self.v))
    }

    fn to_3d(&self, q: DVec2) -> DVec3 {
        self.origin + self.u * q.x + self.v * q.y
    }
}

/// Whether a planar polygon is convex (every turn the same way round its normal).
fn convex(verts: &[DVec3]) -> bool {
    let n = verts.len();
    if n <= 3 {
        return true;
    }
    let normal = crate::geometry::newell_normal(verts);
    (0..n).all(|k| {
        let (a, b, c) = (verts[k], verts[(k + 1) % n], verts[(k + 2) % n]);
        (b - a).cross(c - b).dot(normal) >= 0.0
    })
}

/// The convex hull of `points` (Andrew's monotone chain), counter-clockwise, into `hull`.
fn convex_hull(points: &mut [DVec2], hull: &mut Vec<DVec2>) {
    hull.clear();
    points.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let turn = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    for pass in 0..2 {
        let start = hull.len();
        let it: Box<dyn Iterator<Item = &DVec2>> =
            if pass == 0 { Box::new(points.iter()) } else { Box::new(points.iter().rev()) };
        for &p in it {
            while hull.len() >= start + 2 && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
}

/// `subject` clipped by the convex polygon `by` (either winding), into `out`; `tmp` is
/// scratch.
fn clip_convex(subject: &[DVec2], by: &[DVec2], out: &mut Vec<DVec2>, tmp: &mut Vec<DVec2>) {
    out.clear();
    out.extend_from_slice(subject);
    let wind = crate::geometry::weiler_atherton::signed_area(by).signum();
    for k in 0..by.len() {
        if out.len() < 3 {
            out.clear();
            return;
        }
        let (a, b) = (by[k], by[(k + 1) % by.len()]);
        clip_polygon(out, |p: DVec2| wind * (b - a).perp_dot(p - a), tmp);
        std::mem::swap(out, tmp);
    }
}

impl ShadowStage for NishitaNakamae<'_> {
    /// The umbra and penumbra overlays and what step 5 keeps beside them.
    fn bytes(&self) -> usize {
        use crate::pool::held;
        // The map's slots (an entry and a control byte each) and the casters' lists.
        let slot = std::mem::size_of::<(u32, (Vec<u32>, bool))>() + 1;
        let light = |l: &LightShadows| {
            let everywhere =
                l.everywhere.capacity() * slot + l.everywhere.values().map(|(c, _)| held(c)).sum::<usize>();
            l.umbra.bytes() + l.penumbra.bytes() + held(&l.occluder) + held(&l.bodies) + everywhere
        };
        self.lights.iter().map(light).sum()
    }

    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        let height = self.ctx.view.height;
        Box::new(Walker {
            stage: self,
            walkers: self.lights.iter().map(|l| (l.umbra.walker(0..height), l.penumbra.walker(0..height))).collect(),
            umbra: Vec::new(),
            penumbra: Vec::new(),
            active: Vec::new(),
            ends: Vec::new(),
            vectors: Vec::new(),
            whole: Whole::default(),
            scratch: Scratch::default(),
            line: 0,
            tally: Tally::default(),
            last: String::new(),
        })
    }
}

struct Walker<'s> {
    stage: &'s NishitaNakamae<'s>,
    walkers: Vec<(OverlayWalker<'s>, OverlayWalker<'s>)>,
    umbra: Vec<Interval>,
    penumbra: Vec<Interval>,
    /// The casters whose penumbra intervals hold the current pixel, and where each ends.
    active: Vec<u32>,
    ends: Vec<u32>,
    /// Each pixel's irradiance vector of the light, from the last `lit` of an area light,
    /// and the pixels of it that see all of the light, with their points.
    vectors: Vec<[f32; 3]>,
    whole: Whole,
    scratch: Scratch,
    line: u32,
    tally: Tally,
    last: String,
}

/// The pixels of a run that see all of the light (their places in the run and points), and
/// their irradiance vectors.
#[derive(Debug, Default)]
struct Whole {
    index: Vec<u32>,
    points: Vec<DVec3>,
    out: Vec<DVec3>,
}

/// What the walk did, for the counters.
#[derive(Debug, Default)]
struct Tally {
    dark: u64,
    lit: u64,
    penumbra: u64,
}

impl Walker<'_> {
    /// The irradiance vectors of the pixels in `whole` (which see all of the light), the
    /// light's corners wound as its coordinates run, into `vectors`; `whole` emptied.
    fn whole_light_vectors(&mut self, area: &AreaLight) {
        let Whole { index, points, out } = &mut self.whole;
        out.clear();
        out.resize(points.len(), DVec3::ZERO);
        lambert::irradiance_vectors(&area.vertices(), points, out);
        for ((&i, &p), &vector) in index.iter().zip(points.iter()).zip(out.iter()) {
            self.vectors[i as usize] = area.normalised(p, &Seen { fraction: 1.0, vector });
        }
        index.clear();
        points.clear();
    }
}

impl ShadowWalker for Walker<'_> {
    fn start_line(&mut self, line: u32) {
        self.line = line;
        for (u, p) in &mut self.walkers {
            u.advance_to(line);
            p.advance_to(line);
        }
    }

    fn whole_light(&self, light: usize) -> bool {
        matches!(self.stage.lights[light].source, Source::Area(_))
    }

    fn irradiance(&self, light: usize) -> bool {
        self.stage.lambert && self.whole_light(light)
    }

    fn light_vector(&self, _light: usize, out: [&mut [f32]; 3]) {
        for (c, out) in out.into_iter().enumerate() {
            for (o, v) in out.iter_mut().zip(&self.vectors) {
                *o = v[c];
            }
        }
    }

    fn lit(&mut self, light: usize, _sample: usize, line: u32, run: &Run, lit: &mut [f32]) {
        let shadows = &self.stage.lights[light];
        let (umbra, penumbra) = &mut self.walkers[light];
        umbra.intervals(run.poly, run.x0, run.x1, &mut self.umbra);
        lit.fill(1.0);
        for iv in &self.umbra {
            lit[(iv.start - run.x0) as usize..(iv.end - run.x0) as usize].fill(0.0);
        }
        let Source::Area(area) = &shadows.source else {
            self.last = format!("{} shadow polygon(s) over the run", self.umbra.len());
            return;
        };
        penumbra.intervals(run.poly, run.x0, run.x1, &mut self.penumbra);
        let (always, cut) = shadows.everywhere.get(&run.poly).map_or((&[][..], false), |(a, c)| (&a[..], *c));
        let scene = self.stage.ctx.scene;
        let view = self.stage.ctx.view;
        let plane = scene.polygons[run.poly as usize].plane;
        let seen = plane.distance(view.eye).signum();
        let before = self.tally.penumbra;
        let lambert = self.stage.lambert;
        self.vectors.clear();
        self.vectors.resize(lit.len(), [0.0; 3]);
        // What the receiver's plane leaves of the light, the same at every point of it.
        let cut_away: Vec<Vec<DVec2>> = if cut {
            let mut part = Vec::new();
            area.cut_away(&plane, seen, &mut part);
            vec![part]
        } else {
            Vec::new()
        };
        let unobstructed = unhidden(&cut_away, &mut self.scratch.sweep, None).fraction as f32;
        let point = |x: u32| view.point_on(&plane, x as f64 + 0.5, line as f64 + 0.5);
        // The penumbra intervals come ordered by their starts: those over pixel x are kept
        // in `active` as x moves along the run.
        let (mut active, mut next) = (std::mem::take(&mut self.active), 0);
        active.clear();
        for x in run.x0..run.x1 {
            let i = (x - run.x0) as usize;
            while let Some(iv) = self.penumbra.get(next).filter(|iv| iv.start <= x) {
                active.push(shadows.occluder[iv.tag as usize]);
                self.ends.push(iv.end);
                next += 1;
            }
            if self.ends.iter().any(|&e| e <= x) {
                let mut k = 0;
                active.retain(|_| {
                    k += 1;
                    self.ends[k - 1] > x
                });
                self.ends.retain(|&e| e > x);
            }
            if lit[i] == 0.0 {
                self.tally.dark += 1;
                continue;
            }
            if active.is_empty() && always.is_empty() {
                // No occluder: all of the light on the seen side of the plane reaches it.
                self.tally.lit += 1;
                lit[i] = unobstructed;
                if lambert && cut {
                    let p = point(x);
                    let seen = unhidden(&cut_away, &mut self.scratch.sweep, Some(&Contour { p, light: *area }));
                    self.vectors[i] = area.normalised(p, &seen);
                } else if lambert {
                    // All of the light: found for every such pixel of the run at once.
                    self.whole.index.push(i as u32);
                    self.whole.points.push(point(x));
                }
                continue;
            }
            self.tally.penumbra += 1;
            let p = point(x);
            let occluders = always.iter().chain(&active).copied();
            let bodies = (scene, &shadows.bodies[..]);
            let seen = area.visible(p, &plane, seen, occluders, bodies, lambert, &mut self.scratch);
            lit[i] = seen.fraction as f32;
            if lambert {
                self.vectors[i] = area.normalised(p, &seen);
            }
        }
        self.ends.clear();
        self.active = active;
        self.whole_light_vectors(area);
        self.last = format!(
            "{} umbra and {} penumbra polygon(s) over the run; {} pixel(s) in the penumbra, the visible part of the light clipped there",
            self.umbra.len(),
            self.penumbra.len(),
            self.tally.penumbra - before
        );
    }

    fn decision(&self) -> Decision {
        let tested = self.penumbra.iter().chain(&self.umbra).map(|i| (i.start, i.end, 1)).collect();
        Decision { tested, note: self.last.clone(), detail: super::Detail::None }
    }

    fn finish(&mut self, counters: &mut Counters) {
        counters.add(crate::stats::Counter::UmbraPixelsAtOnce, self.tally.dark);
        counters.add(crate::stats::Counter::LitPixelsAtOnce, self.tally.lit);
        counters.add(crate::stats::Counter::PenumbraPixelsClipped, self.tally.penumbra);
        counters.add(crate::stats::Counter::LightPartsHidden, self.scratch.clips);
        counters.add(crate::stats::Counter::ConvexSolidShadows, self.scratch.body_hulls);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::{random, RandomOptions};
    use crate::reference::Reference;
    use crate::view::View;
    use crate::visibility::{resolve_frame, VisibilityMethod};

    /// Every pixel's irradiance vector from the walk is Lambert's formula over the visible
    /// part of the light that the reference finds by brute force (its rings, a hole wound
    /// the other way), normalised alike: on the lights scene and random scenes.
    #[test]
    fn the_irradiance_vector_is_lamberts_over_the_reference_visible_part() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/lights.toml");
        let mut lights = Scene::load(path).unwrap();
        let mut camera = lights.camera().clone();
        (camera.width, camera.height) = (96, 72);
        lights.set_camera(camera).unwrap();
        let randoms = (0..8).map(|seed| random(seed, RandomOptions { width: 48, height: 36, ..Default::default() }));
        let (mut penumbra, mut checked) = (0, 0);
        for scene in std::iter::once(lights).chain(randoms.map(Result::unwrap)) {
            let view = View::new(&scene.camera);
            let (runs, _) = resolve_frame(&scene, VisibilityMethod::Scanline);
            let ctx = ShadowContext::new(&scene, &view, &runs, false);
            let stage = NishitaNakamae::new(&ctx, NishitaNakamaeOptions::DEFAULT, &mut Counters::default());
            let reference = Reference::new(&scene);
            let mut walker = stage.walker();
            let width = view.width as usize;
            let mut lit = vec![0.0f32; ctx.lit_rows() * width];
            for (y, line) in runs.lines.iter().enumerate() {
                walker.start_line(y as u32);
                crate::render::walk_line(&ctx, walker.as_mut(), y as u32, line, &mut lit, |_, _, _, _, _, _| {});
                for run in line {
                    let plane = scene.polygons[run.poly as usize].plane;
                    for (l, area) in (0..scene.lights.len()).filter_map(|l| Some((l, AreaLight::of(&scene, l)?))) {
                        let row = ctx.vector_row(l) * width;
                        for x in run.x0 as usize..run.x1 as usize {
                            let got = DVec3::from_array([0, 1, 2].map(|c| lit[row + c * width + x] as f64));
                            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                            let Some(seen) = reference.light_view_at(l, px, py) else { continue };
                            let p = view.point_on(&plane, px, py);
                            let contour = Contour { p, light: area };
                            let AreaLight { corner, edge_u, edge_v } = area;
                            let raw: DVec3 = seen
                                .visible
                                .iter()
                                .map(|r| {
                                    lambert::irradiance_vector(
                                        p,
                                        r.iter().map(|q| corner + edge_u * q.x + edge_v * q.y),
                                    )
                                })
                                .sum();
                            let wound: f64 =
                                seen.visible.iter().map(|r| crate::geometry::weiler_atherton::signed_area(r)).sum();
                            let vector = raw * wound.signum();
                            let want = DVec3::from_array(
                                area.normalised(p, &Seen { fraction: seen.fraction, vector }).map(f64::from),
                            );
                            let whole = area.normalised(
                                p,
                                &Seen {
                                    fraction: 1.0,
                                    vector: contour.of(&[DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y]),
                                },
                            );
                            let scale = DVec3::from_array(whole.map(f64::from)).length();
                            assert!(
                                (got - want).length() <= 1e-4 * scale,
                                "pixel ({x}, {y}), light {l}: walk {got}, reference {want} (fraction {})",
                                seen.fraction
                            );
                            // The vector points toward the light where any of it is seen.
                            if seen.fraction > 1e-6 {
                                let centre = corner + 0.5 * (edge_u + edge_v);
                                assert!(got.dot(centre - p) > 0.0, "pixel ({x}, {y}): {got}");
                            }
                            checked += 1;
                            penumbra += (seen.fraction > 0.0 && seen.fraction < 1.0) as usize;
                        }
                    }
                }
            }
        }
        assert!(checked > 5000 && penumbra > 300, "{checked} pixels, {penumbra} in penumbrae");
    }
}
