//! Planar mirrors (the "Special Effect" notes, "Planar Reflect"): one level of reflection, clipped to the
//! mirror's visible spans — the scanline equivalent of the stencil step.
//!
//! A material with `mirror = ρ` (0 < ρ ≤ 1) makes its polygons mirrors; the front side (the
//! Newell normal's) reflects, a mirror seen from behind is an ordinary surface. For each
//! mirror seen from the front:
//!
//! - **Method 1, reflect the eye**: the camera is reflected through the mirror's plane and the
//!   scene rendered from there — lights are not reflected — and the image read back flipped
//!   left to right (a reflected camera is left-handed). Back-face culling would have to be
//!   off; every polygon here is two-sided anyway.
//! - **Method 2, reflect the scene**: the scene *and its lights* are reflected through the
//!   plane and rendered from the real eye.
//!
//! Both render only what lies on the mirror's front side (the rest cannot be seen in it;
//! polygons crossing the plane are clipped) and leave the mirrors out. The chosen shadow
//! stage shades the reflection. The reflected colour is blended into the mirror's own pixels,
//! `(1 − ρ) own + ρ reflected`, and the face ids seen in the mirror fill `mirror_id`.
//!
//! The reflection matrix is built as the "Special Effect" notes derive it, `T · Rᵀ · S(1, −1, 1) · R · T⁻¹`:
//! move the plane to the origin, rotate its normal onto the y axis, mirror y, undo.

use crate::error::Result;
use crate::frame::{Frame, BACKGROUND};
use crate::geometry::{clip_in_place, Plane};
use crate::pool::Pool;
use crate::scene::{Camera, LightKind, Polygon, Scene};
use glam::{DMat3, DMat4, DVec3};
use rayon::prelude::*;

/// How mirrors are rendered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum ReflectionMethod {
    /// Mirrors are ordinary surfaces.
    Off,
    /// Method 1: reflect the eye.
    ReflectEye,
    /// Method 2: reflect the scene and the lights.
    #[default]
    ReflectScene,
}

impl ReflectionMethod {
    /// Every method.
    pub const ALL: [ReflectionMethod; 3] =
        [ReflectionMethod::Off, ReflectionMethod::ReflectEye, ReflectionMethod::ReflectScene];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ReflectionMethod::Off => "off",
            ReflectionMethod::ReflectEye => "eye",
            ReflectionMethod::ReflectScene => "scene",
        }
    }
}

crate::error::named!(ReflectionMethod, "reflection method");

/// The reflection through `plane` (`n·x + d = 0`), built as the "Special Effect" notes derive it:
/// `M = T(p₀) · Rᵀ · S(1, −1, 1) · R · T(−p₀)` with `p₀ = −d n` the plane's point nearest the
/// origin and `R` the rotation whose rows are `U, N, V` (N onto the y axis, U and V across it).
/// (The notes write the plane as `⟨N, P⟩ + d = 0` and the translations as `T(±dN)`; the
/// sign of `d` is its convention.)
pub fn reflection_matrix(plane: &Plane) -> DMat4 {
    let n = plane.n;
    let u = n.any_orthonormal_vector();
    let v = u.cross(n);
    // Rows U, N, V: glam builds from columns, so transpose.
    let r = DMat4::from_mat3(DMat3::from_cols(u, n, v).transpose());
    let s = DMat4::from_scale(DVec3::new(1.0, -1.0, 1.0));
    let p0 = -plane.d * n;
    DMat4::from_translation(p0) * r.transpose() * s * r * DMat4::from_translation(-p0)
}

/// The same reflection in Householder form: `x' = x − 2 (n·x + d) n` (to check the notes'
/// construction against).
#[cfg(test)]
fn householder(plane: &Plane) -> DMat4 {
    let n = plane.n;
    let lin = DMat3::IDENTITY - 2.0 * DMat3::from_cols(n * n.x, n * n.y, n * n.z);
    DMat4::from_cols(
        lin.x_axis.extend(0.0),
        lin.y_axis.extend(0.0),
        lin.z_axis.extend(0.0),
        (-2.0 * plane.d * n).extend(1.0),
    )
}

/// A vertex with its normal, for clipping both together.
#[derive(Debug, Clone, Copy)]
struct Vn(DVec3, DVec3);

impl std::ops::Add for Vn {
    type Output = Vn;
    fn add(self, o: Vn) -> Vn {
        Vn(self.0 + o.0, self.1 + o.1)
    }
}

impl std::ops::Sub for Vn {
    type Output = Vn;
    fn sub(self, o: Vn) -> Vn {
        Vn(self.0 - o.0, self.1 - o.1)
    }
}

impl std::ops::Mul<f64> for Vn {
    type Output = Vn;
    fn mul(self, k: f64) -> Vn {
        Vn(self.0 * k, self.1 * k)
    }
}

/// The scene seen in mirror `plane`: its polygons on the plane's front side (clipped there),
/// mirrors left out, transformed by `m` (for method 2; identity for method 1), with its
/// lights transformed by `m` when `reflect_lights`.
fn mirrored_scene(scene: &Scene, plane: &Plane, m: DMat4, reflect_lights: bool) -> Scene {
    let mut out = scene.clone();
    out.polygons.clear();
    out.vertices.clear();
    out.normals.clear();
    let lin = DMat3::from_mat4(m);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for (i, p) in scene.polygons.iter().enumerate() {
        if scene.material(i).mirror > 0.0 {
            continue;
        }
        a.clear();
        a.extend(scene.verts(i).iter().zip(scene.vertex_normals(i)).map(|(&v, &n)| Vn(v, n)));
        clip_in_place(&mut a, &mut b, |x: Vn| plane.distance(x.0));
        if a.len() < 3 {
            continue;
        }
        let start = out.vertices.len() as u32;
        for x in &a {
            out.vertices.push(m.transform_point3(x.0));
            out.normals.push((lin * x.1).normalize_or(x.1));
        }
        let point = m.transform_point3(scene.verts(i)[0]);
        out.polygons.push(Polygon {
            start,
            len: a.len() as u32,
            plane: Plane::new((lin * p.plane.n).normalize(), point),
            ..*p
        });
    }
    // Clipping by the mirror's plane opens solids, and the polygons are renumbered.
    out.polygons_changed();
    if reflect_lights {
        for l in &mut out.lights {
            l.kind = match l.kind {
                LightKind::Point { position } => LightKind::Point { position: m.transform_point3(position) },
                LightKind::Directional { direction } => LightKind::Directional { direction: lin * direction },
                LightKind::Spot { position, direction, cutoff, exponent } => LightKind::Spot {
                    position: m.transform_point3(position),
                    direction: lin * direction,
                    cutoff,
                    exponent,
                },
                LightKind::Area { corner, edge_u, edge_v, samples } => LightKind::Area {
                    corner: m.transform_point3(corner),
                    edge_u: lin * edge_u,
                    edge_v: lin * edge_v,
                    samples,
                },
            };
        }
    }
    out
}

/// Reflected camera of method 1.
fn reflected_camera(camera: &Camera, m: DMat4) -> Camera {
    Camera {
        eye: m.transform_point3(camera.eye),
        target: m.transform_point3(camera.target),
        up: m.transform_vector3(camera.up),
        ..camera.clone()
    }
}

/// Adds the reflections of every mirror seen from the front to `frame` (whose visible runs
/// are `runs`), and fills `frame.mirror_id` (in a buffer from `ids`). `mirror_pass`
/// renders what a mirror shows: the frame pass over the mirrored scene; each such frame is
/// handed to `done` once blended in. Returns whether a mirror was seen.
pub(crate) fn add_reflections(
    scene: &Scene,
    method: ReflectionMethod,
    frame: &mut Frame,
    runs: &crate::visibility::FrameRuns,
    (ids, mut mirror_pass, mut done): (&Pool<u32>, impl FnMut(&Scene) -> Result<Frame>, impl FnMut(Frame)),
) -> Result<bool> {
    if method == ReflectionMethod::Off {
        return Ok(false);
    }
    // No mirror material, no mirror: the runs (a million on a large scene) are not read.
    if scene.materials.iter().all(|m| m.mirror <= 0.0) {
        return Ok(false);
    }
    let eye = scene.camera.eye;
    let mut mirrors: Vec<u32> = runs
        .lines
        .par_iter()
        .flat_map_iter(|line| {
            line.iter().map(|r| r.poly).filter(|&p| {
                scene.material(p as usize).mirror > 0.0 && scene.polygons[p as usize].plane.distance(eye) > 0.0
            })
        })
        .collect();
    mirrors.sort_unstable();
    mirrors.dedup();
    if mirrors.is_empty() {
        return Ok(false);
    }
    let w = frame.width as usize;
    let mut mirror_id = ids.filled(frame.id.len(), BACKGROUND);
    for m_poly in mirrors {
        let plane = scene.polygons[m_poly as usize].plane;
        let rho = scene.material(m_poly as usize).mirror;
        let m = reflection_matrix(&plane);
        let (reflected, flip) = match method {
            ReflectionMethod::ReflectScene => (mirrored_scene(scene, &plane, m, true), false),
            _ => {
                let mut s = mirrored_scene(scene, &plane, DMat4::IDENTITY, false);
                s.camera = reflected_camera(&scene.camera, m);
                (s, true)
            }
        };
        let seen = mirror_pass(&reflected)?;
        for (y, line) in runs.lines.iter().enumerate() {
            for r in line.iter().filter(|r| r.poly == m_poly) {
                for x in r.x0 as usize..r.x1 as usize {
                    let src = y * w + if flip { w - 1 - x } else { x };
                    let k = y * w + x;
                    frame.color[k] = frame.color[k] * (1.0 - rho) + seen.color[src] * rho;
                    mirror_id[k] = seen.id[src];
                }
            }
        }
        done(seen);
    }
    frame.mirror_id = Some(mirror_id);
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec4;

    #[test]
    fn seed_matrix_equals_householder() {
        for (n, p) in [
            (DVec3::Y, DVec3::ZERO),
            (DVec3::new(0.3, -0.2, 0.9).normalize(), DVec3::new(1.0, 2.0, -3.0)),
            (DVec3::new(-1.0, 0.0, 0.0), DVec3::new(5.0, 0.0, 0.0)),
        ] {
            let plane = Plane::new(n, p);
            let (a, b) = (reflection_matrix(&plane), householder(&plane));
            for (x, y) in a.to_cols_array().iter().zip(b.to_cols_array()) {
                assert!((x - y).abs() < 1e-12, "{a} vs {b}");
            }
            // A point on the plane stays; the eye side maps to the other side.
            assert!((a.transform_point3(p) - p).length() < 1e-12);
            let q = p + n;
            assert!((a.transform_point3(q) - (p - n)).length() < 1e-12);
            assert_eq!(a * DVec4::new(0.0, 0.0, 0.0, 1.0), a.w_axis);
        }
    }
}
