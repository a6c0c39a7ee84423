//! Shadow volumes (Crow 1977): the region a polygon hides from a light sample, bounded by
//! *shadow polygons*. Shared by Crow's per-span counting and by the stencil-buffer stage.
//!
//! - **Closed meshes** (every edge shared by exactly two of the object's polygons, running
//!   opposite ways, and no face split into a fan): one volume per object, its sides built on
//!   the *silhouette edges* only (an edge between a polygon facing the light and one facing
//!   away), capped in front by the polygons facing the light and at the back by those
//!   polygons pushed away from the light.
//! - **Everything else** (open meshes, edges shared by more than two polygons, inconsistent
//!   winding, loose polygons): one volume per polygon, bounded by a side on each of its
//!   edges and capped by the polygon itself and by its copy pushed away — a per-polygon
//!   volume never leaks, whatever its neighbours.
//!
//! Volumes are extruded to infinity in homogeneous coordinates: a side on edge `a → b` is
//! `[a, b, (b − L, 0), (a − L, 0)]` (for a directional light `[a, b, (d, 0)]`, the two far
//! corners being the one point at infinity along `d`), and a back cap is its front cap's
//! directions from the light, on the plane at infinity, behind everything. Nothing is cut
//! short, whatever the scene's size or how close the light is to a polygon. Each shadow
//! polygon knows its outward side, which gives its sign in the count: +1 where the eye sees
//! it from outside (entering the volume), −1 from inside.
//!
//! Which polygons a count needs: z-pass counts what lies between the eye and the visible
//! point, so it needs the sides and the **near caps** — each volume's cross-section with the
//! near plane, found by projecting its front-cap polygons from the light onto the part of the
//! near plane the image sees (the eye's own count, pixel by pixel: Bergeron 1986). The front
//! caps are scene polygons (never in front of a visible point) and the back caps lie beyond
//! everything, so z-pass needs neither. Z-fail counts what lies behind the visible point, so
//! it needs the sides and both caps, and no near caps. Naive z-pass leaves the near caps out.

use super::projection::{edge_on, light_side, Projector};
use super::ShadowContext;
use crate::geometry::Plane;
use crate::scene::LightSample;
use crate::stats::Counters;
use crate::view::DepthPlane;
use glam::{DVec2, DVec3, DVec4};

/// How a count is taken along the line of sight.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Counting {
    /// From the eye to the visible point, starting from the eye's own count (near caps).
    #[default]
    ZPass,
    /// From the visible point to infinity (Carmack's reverse / Everitt & Kilgard's z-fail).
    ZFail,
    /// From the eye to the visible point starting at zero: wrong where the eye (or the near
    /// plane) is in shadow, as seed 000 describes; kept to show that failure.
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

impl std::str::FromStr for Counting {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        crate::error::parse_named(s, &Self::ALL, Self::name, "count")
    }
}

/// What part of a volume's boundary a shadow polygon is.
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
}

/// One shadow polygon in world space.
#[derive(Debug, Clone)]
pub struct ShadowPolygon {
    /// Its vertices in homogeneous coordinates (`w = 0`: a point at infinity).
    pub verts: Vec<DVec4>,
    /// Its plane; `None` for a back cap, which lies on the plane at infinity.
    pub plane: Option<Plane>,
    /// +1 when the eye sees the side facing out of the volume, −1 when it sees the inside.
    pub sign: i32,
    /// Which part of the boundary it is.
    pub part: Part,
    /// For a front cap: the scene polygon it coincides with.
    pub lies_on: Option<u32>,
    /// For a per-polygon volume: the face id whose volume it bounds (a face never shadows
    /// itself, fan pieces included).
    pub owner_face: Option<u32>,
}

/// The shadow polygons of one light sample for a count taken by `counting`.
pub fn shadow_polygons(
    ctx: &ShadowContext,
    adjacency: &Adjacency,
    sample: LightSample,
    counting: Counting,
    counters: &mut Counters,
) -> Vec<ShadowPolygon> {
    let scene = ctx.scene;
    let eye = ctx.view.eye;
    let casts = |i: usize| !edge_on(scene, i, sample, ctx.extent);
    let finite = |v: DVec3| v.extend(1.0);
    let away = |v: DVec3| match sample {
        LightSample::Point(s) => (v - s).extend(0.0),
        LightSample::Directional(d) => d.extend(0.0),
    };
    // The sign of a finite polygon through `at` whose outward normal is `outward`.
    let sign = |outward: DVec3, at: DVec3| if outward.dot(eye - at) > 0.0 { 1 } else { -1 };
    let mut out = Vec::new();
    let (near_plane, near_rect) = ctx.view.near_rectangle();
    let mut proj = Projector::default();
    let mut add_caps = |out: &mut Vec<ShadowPolygon>, poly: usize, owner: Option<u32>| {
        let verts = scene.verts(poly);
        let plane = scene.polygons[poly].plane;
        match counting {
            Counting::ZFail => {
                let toward = plane.n * light_side(&plane, sample);
                out.push(ShadowPolygon {
                    verts: verts.iter().map(|&v| finite(v)).collect(),
                    plane: Some(plane),
                    sign: sign(toward, verts[0]),
                    part: Part::FrontCap,
                    lies_on: Some(poly as u32),
                    owner_face: owner,
                });
                // For a directional light every direction away is the same point at
                // infinity: the sides close the volume there and no back cap is needed.
                if let LightSample::Point(_) = sample {
                    out.push(ShadowPolygon {
                        verts: verts.iter().map(|&v| away(v)).collect(),
                        plane: None,
                        sign: -1,
                        part: Part::BackCap,
                        lies_on: None,
                        owner_face: owner,
                    });
                }
            }
            Counting::ZPass => {
                if proj.project(verts, &near_plane, &near_rect, sample) {
                    out.push(ShadowPolygon {
                        verts: proj.shadow.iter().map(|&v| finite(v)).collect(),
                        plane: Some(near_plane),
                        sign: 1,
                        part: Part::NearCap,
                        lies_on: None,
                        owner_face: owner,
                    });
                }
            }
            Counting::NaiveZPass => {}
        }
    };
    // A side on edge a -> b of polygon `poly` (whose interior lies left of a -> b about its
    // normal): outward is away from the polygon's interior.
    let side = |a: DVec3, b: DVec3, poly: usize, owner: Option<u32>| {
        let n = scene.polygons[poly].plane.n;
        let inward = n.cross(b - a);
        let (m, verts) = match sample {
            LightSample::Point(s) => ((b - a).cross(s - a), vec![finite(a), finite(b), away(b), away(a)]),
            LightSample::Directional(d) => ((b - a).cross(d), vec![finite(a), finite(b), away(a)]),
        };
        let outward = if m.dot(inward) <= 0.0 { m } else { -m };
        ShadowPolygon {
            verts,
            plane: Some(Plane::new(outward.normalize(), a)),
            sign: sign(outward, a),
            part: Part::Side,
            lies_on: None,
            owner_face: owner,
        }
    };

    let (mut closed, mut open, mut silhouette) = (0u64, 0u64, 0u64);
    for (polys, edges) in &adjacency.objects {
        match edges {
            Some(edges) => {
                closed += 1;
                // Turned to the light: the light strictly on the polygon's front side.
                let faces_light = |p: usize| {
                    let plane = &scene.polygons[p].plane;
                    match sample {
                        LightSample::Point(s) => plane.distance(s) > 0.0,
                        LightSample::Directional(d) => plane.n.dot(d) < 0.0,
                    }
                };
                for &(p, q, a, b) in edges {
                    let (lp, lq) = (faces_light(p), faces_light(q));
                    if lp != lq {
                        silhouette += 1;
                        out.push(if lp { side(a, b, p, None) } else { side(b, a, q, None) });
                    }
                }
                for &p in polys.iter().filter(|&&p| faces_light(p) && casts(p)) {
                    add_caps(&mut out, p, None);
                }
            }
            None => {
                open += 1;
                for &p in polys.iter().filter(|&&p| casts(p)) {
                    let owner = Some(scene.polygons[p].face);
                    let v = scene.verts(p);
                    for k in 0..v.len() {
                        out.push(side(v[k], v[(k + 1) % v.len()], p, owner));
                    }
                    add_caps(&mut out, p, owner);
                }
            }
        }
    }
    counters.add("closed_objects", closed);
    counters.add("open_objects", open);
    counters.add("silhouette_edges", silhouette);
    for (part, name) in [
        (Part::Side, "shadow_polygons_side"),
        (Part::FrontCap, "shadow_polygons_front_cap"),
        (Part::BackCap, "shadow_polygons_back_cap"),
        (Part::NearCap, "shadow_polygons_near_cap"),
    ] {
        counters.add(name, out.iter().filter(|p| p.part == part).count() as u64);
    }
    // The volumes (one per casting face) that hold the eye: what naive z-pass gets wrong.
    let (dir, tmax) = match sample {
        LightSample::Point(s) => (s - eye, 1.0),
        LightSample::Directional(d) => (-d, f64::INFINITY),
    };
    let holding = adjacency
        .objects
        .iter()
        .flat_map(|o| &o.0)
        .filter(|&&i| casts(i) && crate::bvh::hit(scene, i, eye, dir).is_some_and(|t| t > 0.0 && t < tmax));
    counters.add("volumes_containing_eye", holding.count() as u64);
    out
}

/// Which casting objects are closed, and their edges: worked out once per scene, whatever
/// the light.
#[derive(Debug, Clone, Default)]
pub struct Adjacency {
    /// Per object with casting polygons: its polygons, and for a closed, consistently wound
    /// object (every edge shared by exactly two of its polygons, running opposite ways, no
    /// face split into a fan) each edge once as `(p, q, a, b)`: it runs `a -> b` in polygon
    /// `p` and `b -> a` in `q`.
    objects: Vec<(Vec<usize>, Option<Vec<Edge>>)>,
}

/// An edge of a closed object: it runs `a -> b` in polygon `p` and `b -> a` in polygon `q`.
type Edge = (usize, usize, DVec3, DVec3);

impl Adjacency {
    /// The adjacency of the scene's shadow-casting polygons, by object. Vertices are welded
    /// by exact position. Without `silhouettes`, every object is treated as open (one volume
    /// per polygon).
    pub fn new(scene: &crate::Scene, silhouettes: bool) -> Self {
        let casters: Vec<usize> = (0..scene.polygons.len()).filter(|&i| scene.casts_shadows(i)).collect();
        // Weld: one id per distinct position, by sorting.
        let mut keys: Vec<([u64; 3], u32)> = Vec::new();
        for &p in &casters {
            let poly = &scene.polygons[p];
            for k in 0..poly.len {
                let v = scene.vertices[(poly.start + k) as usize];
                keys.push((v.to_array().map(f64::to_bits), poly.start + k));
            }
        }
        keys.sort_unstable();
        let mut id = vec![0u32; scene.vertices.len()];
        let mut next = 0u32;
        for (i, (key, v)) in keys.iter().enumerate() {
            if i > 0 && keys[i - 1].0 != *key {
                next += 1;
            }
            id[*v as usize] = next;
        }
        let mut objects: Vec<(u32, Vec<usize>)> = Vec::new();
        for &p in &casters {
            let o = scene.polygons[p].object;
            match objects.last_mut() {
                Some((last, polys)) if *last == o => polys.push(p),
                _ => objects.push((o, vec![p])),
            }
        }
        let objects = objects
            .into_iter()
            .map(|(_, polys)| {
                let edges = if silhouettes { closed_edges(scene, &polys, &id) } else { None };
                (polys, edges)
            })
            .collect();
        Adjacency { objects }
    }
}

fn closed_edges(scene: &crate::Scene, polys: &[usize], id: &[u32]) -> Option<Vec<Edge>> {
    if polys.windows(2).any(|w| scene.polygons[w[0]].face == scene.polygons[w[1]].face) {
        return None; // a face split into a fan (its pieces are consecutive)
    }
    // Directed edges (from, to, polygon, index of `from` in the vertex array).
    let mut directed: Vec<(u32, u32, usize, u32)> = Vec::new();
    for &p in polys {
        let poly = &scene.polygons[p];
        for k in 0..poly.len {
            let (a, b) = (poly.start + k, poly.start + (k + 1) % poly.len);
            directed.push((id[a as usize], id[b as usize], p, a));
        }
    }
    directed.sort_unstable();
    if directed.windows(2).any(|w| (w[0].0, w[0].1) == (w[1].0, w[1].1)) {
        return None; // the same edge twice the same way
    }
    let mut edges = Vec::new();
    for &(a, b, p, va) in &directed {
        let i = directed.binary_search_by(|e| (e.0, e.1).cmp(&(b, a))).ok()?;
        if a < b {
            let poly = &scene.polygons[p];
            let vb = poly.start + (va - poly.start + 1) % poly.len;
            edges.push((p, directed[i].2, scene.vertices[va as usize], scene.vertices[vb as usize]));
        }
    }
    Some(edges)
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
        if self.owner_face == face {
            return 0;
        }
        let in_front = self.near_cap || (self.lies_on != poly && self.depth.inv_z(x, y) > surface);
        match counting {
            Counting::ZFail if !in_front => -self.sign,
            Counting::ZFail => 0,
            _ if in_front => self.sign,
            _ => 0,
        }
    }
}

/// One light sample's shadow polygons in screen space, with their outlines.
pub struct ScreenVolumes {
    /// The polygons.
    pub polys: Vec<ScreenShadowPolygon>,
    /// Their screen outlines, parallel to `polys`.
    pub rings: Vec<Vec<DVec2>>,
}

impl ScreenVolumes {
    /// The shadow polygons of `sample` for `counting`, put through the camera: clipped to the
    /// near plane in homogeneous coordinates (never to the far plane) and projected.
    pub fn new(
        ctx: &ShadowContext,
        adjacency: &Adjacency,
        sample: LightSample,
        counting: Counting,
        counters: &mut Counters,
    ) -> Self {
        let view = ctx.view;
        let mut out = ScreenVolumes { polys: Vec::new(), rings: Vec::new() };
        let (mut scratch, mut ring) = ([Vec::new(), Vec::new()], Vec::new());
        for sp in shadow_polygons(ctx, adjacency, sample, counting, counters) {
            // A back cap lies on the plane at infinity: inverse depth 0, behind everything.
            let depth = match &sp.plane {
                Some(plane) => match view.depth_plane(plane) {
                    Some(d) => d,
                    None => continue, // edge-on to the eye
                },
                None => DepthPlane { a: 0.0, b: 0.0, c: 0.0 },
            };
            if sp.part == Part::NearCap {
                // On the near plane by construction: projected as it is (clipping it there
                // would let rounding throw it away).
                ring.clear();
                ring.extend(sp.verts.iter().map(|&v| view.project(view.to_camera(v.truncate()))));
            } else if !view.clip_project_homogeneous(&sp.verts, &mut scratch, &mut ring) {
                continue;
            }
            out.rings.push(ring.clone());
            out.polys.push(ScreenShadowPolygon {
                depth,
                sign: sp.sign,
                near_cap: sp.part == Part::NearCap,
                lies_on: sp.lies_on.unwrap_or(NONE),
                owner_face: sp.owner_face.unwrap_or(NONE),
            });
        }
        counters.add("screen_shadow_polygons", out.polys.len() as u64);
        out
    }
}
