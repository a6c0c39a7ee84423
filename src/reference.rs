//! The exact answer of `docs/scene-format.md` §3 at any point of the image plane, computed
//! directly (one ray for the visible surface, one shadow ray per light sample), and the
//! definition of a *tie* that the exactness tests use.
//!
//! A pixel is a **tie** when
//!
//! - the answer at its centre (the face seen, and each light's lit fraction) is not the
//!   answer at every point within [`TIE_DELTA`] of a pixel around it (the eight points at
//!   `±TIE_DELTA` in x, y or both): the centre then lies, to within floating-point rounding,
//!   on a polygon's edge, on a shadow's edge, or on two coincident surfaces; or
//! - a light sample lies in the plane of the polygon it sees (within [`PLANE_TIE`] of the
//!   scene's size), where the scene format's same-side rule has no sign to go by.
//!
//! The contract lets either answer stand at a tie. Every other pixel has one right answer,
//! and an exact stage must give it.

use crate::bvh::Bvh;
use crate::frame::BACKGROUND;
use crate::scene::{LightSample, Scene};
use crate::shadow::blocked;
use crate::view::View;
use glam::DVec2;

/// How far (in pixels) a sample point moves to test for a tie.
pub const TIE_DELTA: f64 = 1e-6;

/// How close (relative to the scene's size) a light sample must be to the plane of the
/// polygon a pixel sees for the pixel to be a tie.
pub const PLANE_TIE: f64 = 1e-9;

/// The two kinds of tie.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tie {
    /// The answer changes within [`TIE_DELTA`] of a pixel of the centre: an edge.
    Edge,
    /// A light sample lies in the plane of the polygon seen.
    LightInPlane,
}

/// What a point of the image plane sees.
#[derive(Debug, Clone, PartialEq)]
pub struct Answer {
    /// The face id seen (`u32::MAX`: background).
    pub face: u32,
    /// Each light's lit fraction there (0 on background).
    pub lit: Vec<f32>,
}

/// The exact answer at any image point, for checking the stages.
pub struct Reference<'a> {
    scene: &'a Scene,
    view: View,
    all: Bvh,
    casters: Bvh,
    samples: Vec<Vec<LightSample>>,
    extent: f64,
}

impl<'a> Reference<'a> {
    /// Builds the two ray-casting structures (every polygon; the shadow casters).
    ///
    /// ```
    /// let scene = umbra::generate::cubes(1, umbra::generate::Faces::Quads, 32, 24)?;
    /// let oracle = umbra::reference::Reference::new(&scene);
    /// let centre = oracle.at(16.5, 12.5);
    /// assert_eq!(centre.lit.len(), scene.lights().len());
    /// # Ok::<(), umbra::Error>(())
    /// ```
    pub fn new(scene: &'a Scene) -> Self {
        let n = scene.polygons.len() as u32;
        let casters = (0..n).filter(|&i| scene.casts_shadows(i as usize)).collect();
        let extent = scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length().max(1e-300));
        Reference {
            scene,
            view: View::new(&scene.camera),
            all: Bvh::new(scene, (0..n).collect()),
            casters: Bvh::new(scene, casters),
            samples: scene.lights.iter().map(|l| l.samples()).collect(),
            extent,
        }
    }

    /// The answer at image point `(x, y)` (pixel units; pixel `(px, py)`'s centre is
    /// `(px + 0.5, py + 0.5)`).
    pub fn at(&self, x: f64, y: f64) -> Answer {
        let d = self.view.ray(x, y);
        let far = self.view.far.unwrap_or(f64::INFINITY);
        let Some((poly, _)) = self.all.closest(self.scene, self.view.eye, d, self.view.near, far) else {
            return Answer { face: u32::MAX, lit: vec![0.0; self.samples.len()] };
        };
        let polygon = &self.scene.polygons[poly as usize];
        let p = self.view.point_on(&polygon.plane, x, y);
        let lit = self
            .samples
            .iter()
            .map(|samples| {
                let reached = samples
                    .iter()
                    .filter(|&&s| {
                        s.on_seen_side(&polygon.plane, self.view.eye)
                            && !blocked(&self.casters, self.scene, p, s, polygon.face, self.extent)
                    })
                    .count();
                reached as f32 / samples.len() as f32
            })
            .collect();
        Answer { face: polygon.face, lit }
    }

    /// The polygon seen at image point `(x, y)` and the visible point on it, if any.
    pub fn visible(&self, x: f64, y: f64) -> Option<(usize, glam::DVec3)> {
        let d = self.view.ray(x, y);
        let far = self.view.far.unwrap_or(f64::INFINITY);
        let (poly, _) = self.all.closest(self.scene, self.view.eye, d, self.view.near, far)?;
        let polygon = &self.scene.polygons[poly as usize];
        Some((poly as usize, self.view.point_on(&polygon.plane, x, y)))
    }

    /// [`exact_fraction`] of area light `light` at the point seen at image point `(x, y)`,
    /// with the casters found through the BVH (those whose boxes meet the box around the
    /// point and the light); `None` on background, for a light that is not an area light,
    /// or where a clip fails.
    pub fn exact_fraction_at(&self, light: usize, x: f64, y: f64) -> Option<f64> {
        Some(self.seen_at(light, x, y, false)?.fraction)
    }

    /// Whether pixel `(px, py)` is a tie (see the module's definition).
    pub fn is_tie(&self, px: u32, py: u32) -> bool {
        self.tie(px, py).is_some()
    }

    /// Which kind of tie pixel `(px, py)` is, if it is one.
    pub fn tie(&self, px: u32, py: u32) -> Option<Tie> {
        let (x, y) = (px as f64 + 0.5, py as f64 + 0.5);
        if self.light_in_seen_plane(x, y) {
            return Some(Tie::LightInPlane);
        }
        let centre = self.at(x, y);
        let t = TIE_DELTA;
        [(-t, -t), (0.0, -t), (t, -t), (-t, 0.0), (t, 0.0), (-t, t), (0.0, t), (t, t)]
            .iter()
            .any(|&(dx, dy)| self.at(x + dx, y + dy) != centre)
            .then_some(Tie::Edge)
    }

    /// Whether a light sample lies in the plane of the polygon seen at `(x, y)`.
    fn light_in_seen_plane(&self, x: f64, y: f64) -> bool {
        let d = self.view.ray(x, y);
        let far = self.view.far.unwrap_or(f64::INFINITY);
        let Some((poly, _)) = self.all.closest(self.scene, self.view.eye, d, self.view.near, far) else {
            return false;
        };
        let plane = &self.scene.polygons[poly as usize].plane;
        self.samples.iter().flatten().any(|s| match *s {
            LightSample::Point(l) => plane.distance(l).abs() <= PLANE_TIE * self.extent,
            LightSample::Directional(dir) => plane.n.dot(dir).abs() <= PLANE_TIE,
        })
    }
}

/// The exact lit fraction of area light `light` at point `p` of polygon `poly`
/// (`docs/scene-format.md` §3, the area-light rule): the area of the points Q of the light's
/// parallelogram for which `N·(Q − P)` and `N·(eye − P)` are non-zero and of one sign and no
/// casting polygon other than `poly`'s face crosses the open segment PQ, over the light's
/// area. The limit of the grid's fraction as its samples grow.
///
/// Brute force, in f64, step by step: the light is taken as the unit square of its own
/// coordinates `(a, b)` (`corner + a·edge_u + b·edge_v`: an affine map, so areas keep their
/// ratio); it is cut by the plane of `poly` to the side the eye sees; then every casting
/// polygon of another face is cut to the part between P and the light and projected from P
/// onto the light's plane ([`crate::shadow`]'s projection, the one Bouknight-Kelley uses),
/// and that shadow is subtracted from what is left, with Weiler and Atherton's clipper. A
/// light that is not an area light gives `None`, as does a clip that fails.
///
/// ```
/// use umbra::glam::DVec3;
/// use umbra::{Camera, Light, Material, Mesh, Object, Scene};
/// // A 2×2 light at height 2 over the origin, a 0.5×0.5 occluder at height 1: seen from the
/// // origin its shadow on the light's plane is a 1×1 square, a quarter of the light.
/// let occluder = Mesh::quad([
///     DVec3::new(-0.25, 1.0, -0.25), DVec3::new(-0.25, 1.0, 0.25),
///     DVec3::new(0.25, 1.0, 0.25), DVec3::new(0.25, 1.0, -0.25),
/// ]);
/// let floor = Mesh::quad([
///     DVec3::new(-3.0, 0.0, -3.0), DVec3::new(-3.0, 0.0, 3.0),
///     DVec3::new(3.0, 0.0, 3.0), DVec3::new(3.0, 0.0, -3.0),
/// ]);
/// let light = Light::area(DVec3::new(-1.0, 2.0, -1.0), DVec3::new(2.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 2.0), [4, 4]);
/// let scene = Scene::builder(Camera::new(DVec3::new(0.0, 4.0, 6.0), DVec3::ZERO))
///     .material(Material::new("m"))
///     .light(light)
///     .object(Object::new(floor), "m")
///     .object(Object::new(occluder), "m")
///     .build()?;
/// let f = umbra::reference::exact_fraction(&scene, 0, DVec3::ZERO, 0).unwrap();
/// assert!((f - 0.75).abs() < 1e-12, "{f}");
/// # Ok::<(), umbra::Error>(())
/// ```
pub fn exact_fraction(scene: &Scene, light: usize, p: glam::DVec3, poly: usize) -> Option<f64> {
    let casters = (0..scene.polygons.len()).filter(|&i| scene.casts_shadows(i));
    Some(view_among(scene, &View::new(&scene.camera), light, p, poly, casters, false)?.fraction)
}

/// What a point sees of an area light, in the light's own coordinates: the light is the unit
/// square of `(a, b)` (`corner + a·edge_u + b·edge_v`), as [`exact_fraction`] takes it.
#[derive(Debug, Clone, PartialEq)]
pub struct LightView {
    /// The part of the light the plane of the point's polygon cuts away (on the side the eye
    /// does not see); empty when none.
    pub cut: Vec<DVec2>,
    /// Each casting polygon's shadow from the point on the light's plane: the polygon, and
    /// its projection (it may reach beyond the square).
    pub hidden: Vec<(usize, Vec<DVec2>)>,
    /// What is left of the square: the visible part, as rings (a hole wound the other way).
    pub visible: Vec<Vec<DVec2>>,
    /// Its area: the exact lit fraction.
    pub fraction: f64,
}

impl Reference<'_> {
    /// What the point seen at image point `(x, y)` sees of area light `light`, and its exact
    /// fraction, step by step as [`exact_fraction`] finds it (`umbra explore` draws it for a
    /// picked pixel). `None` when nothing is seen there or the light is not an area light.
    pub fn light_view_at(&self, light: usize, x: f64, y: f64) -> Option<LightView> {
        self.seen_at(light, x, y, true)
    }

    /// The steps at image point `(x, y)`, with the casters found through the BVH (those
    /// whose boxes meet the box around the point and the light), in polygon order; the cut
    /// and the shadows kept when `keep`.
    fn seen_at(&self, light: usize, x: f64, y: f64, keep: bool) -> Option<LightView> {
        let (poly, p) = self.visible(x, y)?;
        let area = crate::shadow::AreaLight::of(self.scene, light)?;
        let (lo, hi) = area.vertices().iter().fold((p, p), |(lo, hi), &q| (lo.min(q), hi.max(q)));
        let mut near = Vec::new();
        self.casters.overlapping(lo, hi, |i| near.push(i as usize));
        near.sort_unstable();
        view_among(self.scene, &self.view, light, p, poly, near.into_iter(), keep)
    }
}

/// The steps of [`exact_fraction`] with the casters among `casters` (a superset of those
/// that can cross a segment from `p` to the light), keeping the cut and the shadows when
/// `keep`.
fn view_among(
    scene: &Scene,
    view: &View,
    light: usize,
    p: glam::DVec3,
    poly: usize,
    casters: impl Iterator<Item = usize>,
    keep: bool,
) -> Option<LightView> {
    use crate::geometry::weiler_atherton::{clip, Region};
    let area = crate::shadow::AreaLight::of(scene, light)?;
    let polygon = scene.polygons.get(poly)?;
    let mut out = LightView { cut: Vec::new(), hidden: Vec::new(), visible: Vec::new(), fraction: 0.0 };
    let seen = polygon.plane.distance(view.eye).signum();
    if seen == 0.0 {
        return Some(out);
    }
    // Step 1: the unit square cut by the plane of `poly`, to the side the eye sees.
    let square = Region::from_ring(vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y]);
    area.cut_away(&polygon.plane, seen, &mut out.cut);
    let mut region =
        if out.cut.is_empty() { square } else { clip(&square, &Region::from_ring(out.cut.clone())).ok()?.outside };
    // Step 2: each other face's casting polygons' shadows from P on the light, subtracted.
    let target = area.target_from(p);
    let mut proj = crate::shadow::Projector::default();
    for i in casters.filter(|&i| scene.polygons[i].face != polygon.face) {
        if region.rings.is_empty() && !keep {
            return Some(out);
        }
        if proj.project(scene.verts(i), &target) {
            let shadow = area.shadow_ab(&proj);
            let kept = keep.then(|| shadow.clone());
            if !region.rings.is_empty() {
                region = clip(&region, &Region::from_ring(shadow)).ok()?.outside;
            }
            out.hidden.extend(kept.map(|s| (i, s)));
        }
    }
    out.fraction = region.area().abs().min(1.0);
    if keep {
        out.visible = region.rings.into_vec();
    }
    Some(out)
}

/// The reference for planar mirrors: for each pixel whose visible polygon is a mirror seen from the front, the
/// face id the ray reflected there sees first (one bounce, by ray casting), else background.
pub fn mirror_ids(scene: &Scene) -> Vec<u32> {
    let view = View::new(&scene.camera);
    let all = Bvh::new(scene, (0..scene.polygons.len() as u32).collect());
    let mut out = vec![BACKGROUND; (view.width * view.height) as usize];
    let far = view.far.unwrap_or(f64::INFINITY);
    for y in 0..view.height {
        for x in 0..view.width {
            let d = view.ray(x as f64 + 0.5, y as f64 + 0.5);
            let Some((p, t)) = all.closest(scene, view.eye, d, view.near, far) else { continue };
            let poly = &scene.polygons[p as usize];
            if scene.material(p as usize).mirror <= 0.0 || poly.plane.distance(view.eye) <= 0.0 {
                continue;
            }
            let hit = view.eye + d * t;
            let n = poly.plane.n;
            let r = d - 2.0 * d.dot(n) * n;
            // Mirrors are left out of the reflection (one level), and so is what lies behind
            // the mirror's plane: the reflected ray never goes there. The far plane cuts what
            // the eye sees, the virtual image behind the mirror: `r` is as long as `d` (one
            // unit of camera depth), so a point at `s` along it has its image at depth t + s.
            let mut best: Option<(u32, f64)> = None;
            let mut tmin = 1e-9;
            while let Some((q, s)) = all.closest(scene, hit, r, tmin, far - t) {
                if scene.material(q as usize).mirror > 0.0 {
                    tmin = s * (1.0 + 1e-12) + 1e-12;
                    continue;
                }
                best = Some((q, s));
                break;
            }
            if let Some((q, _)) = best {
                out[(y * view.width + x) as usize] = scene.polygons[q as usize].face;
            }
        }
    }
    out
}
