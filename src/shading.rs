//! Shading: the local illumination model of the "Lighting and Shading" and "Árnyékolás" notes
//! (docs/sources.md) and the three shading modes.
//!
//! Per R, G, B, summed over lights `l` and their samples `s`:
//!
//! ```text
//! I = Ia ka Od + Σ_l Σ_s S_s f_att(d_s) spot(L_s) (I_l / n_l) [kd Od (N.L_s) + ks Os spec]
//! ```
//!
//! - `spec` is Phong's `(R.V)^n`, Blinn's `(N.H)^n`, or Cook-Torrance's
//!   `π D F G / (4 N.V)`: the microfacet BRDF `D F G / (4 (N.L)(N.V))` times `π (N.L)`, so
//!   that, like `kd Od (N.L)` for a Lambertian BRDF `kd Od / π`, it is radiance per unit
//!   irradiance. D is Beckmann's distribution with the material's roughness `m`
//!   (`exp(-tan²α/m²) / (π m² cos⁴α)`, normalised), F Schlick's Fresnel with the material's
//!   `fresnel` F0 (default 0.04), G the Torrance-Sparrow geometry term
//!   `min(1, 2(N.H)(N.V)/(V.H), 2(N.H)(N.L)/(V.H))`. Specular is zero where `N.L <= 0`.
//! - `f_att = min(1, 1/(a + b d + c d²))` for point, spot and area samples; 1 for directional.
//! - `spot = cos^exponent` of the angle to the spot axis inside the cone, 0 outside (shading
//!   only: the contract's lit fraction ignores the cone).
//! - `S_s`, the lit value from the shadow stage, applies per pixel in every mode, so a shadow
//!   edge crosses a Gouraud-shaded polygon sharply instead of being smeared by interpolation.
//!
//! Shading modes, per material:
//! - **flat**: one colour per polygon and sample, lit at the polygon's centroid with its
//!   plane normal (the "Lighting and Shading" notes).
//! - **Gouraud**: colours lit at the vertices (vertex normals from OBJ `vn`, or averaged over
//!   the faces sharing the vertex), interpolated along the polygon's edges to the scanline and
//!   along the span between them.
//! - **Phong**: vertex normals interpolated the same way and renormalised, lit per pixel.
//!
//! Interpolation is perspective-correct: the scanline's crossings with the polygon's edges
//! are taken in the *scan plane* (the plane through the eye and the scanline) in world space,
//! and each pixel's point is placed between its two crossings in world space, so values vary
//! linearly over the surface, not over the screen. Polygons are two-sided: normals are turned
//! toward the viewer.

use crate::geometry::centroid;
use crate::scene::{Light, LightKind, LightSample, Material, Scene, ShadingMode, SpecularModel};
use crate::view::View;
use crate::visibility::Run;
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// The light a sample sends toward a point: unit direction to the light, and the radiance
/// factor `f_att spot I_l / n_l` times the light's colour.
pub fn incident(light: &Light, sample: &LightSample, samples: usize, p: DVec3) -> (DVec3, Vec3) {
    let (l, d) = sample.toward(p);
    let base = light.color * (light.intensity / samples as f32);
    let att = match light.kind {
        LightKind::Directional { .. } => 1.0,
        _ => {
            let [a, b, c] = light.attenuation;
            (1.0 / (a + b * d + c * d * d)).min(1.0)
        }
    };
    let spot = match light.kind {
        LightKind::Spot { direction, cutoff, exponent, .. } => {
            let cos = (-l).dot(direction);
            if cos >= cutoff.to_radians().cos() {
                cos.max(0.0).powf(exponent)
            } else {
                0.0
            }
        }
        _ => 1.0,
    };
    (l, base * (att * spot) as f32)
}

/// `kd Od (N.L) + ks Os spec` for unit vectors `n` (turned toward the viewer), `v` (to the
/// eye) and `l` (to the light); zero where `N.L <= 0`.
pub fn reflect(m: &Material, n: DVec3, v: DVec3, l: DVec3) -> Vec3 {
    let nl = n.dot(l);
    if nl <= 0.0 {
        return Vec3::ZERO;
    }
    m.kd * m.color * nl as f32 + m.ks * m.specular_color * specular(m, n, v, l, nl) as f32
}

fn specular(m: &Material, n: DVec3, v: DVec3, l: DVec3, nl: f64) -> f64 {
    if m.ks == 0.0 {
        return 0.0;
    }
    let shininess = m.shininess as f64;
    match m.model {
        SpecularModel::Phong => {
            let r = 2.0 * nl * n - l;
            r.dot(v).max(0.0).powf(shininess)
        }
        SpecularModel::Blinn => {
            let h = (l + v).normalize_or_zero();
            n.dot(h).max(0.0).powf(shininess)
        }
        SpecularModel::CookTorrance => {
            let nv = n.dot(v);
            let h = (l + v).normalize_or_zero();
            let (nh, vh) = (n.dot(h), v.dot(h));
            if nv <= 0.0 || nh <= 0.0 || vh <= 0.0 {
                return 0.0;
            }
            let m2 = (m.roughness as f64).powi(2);
            let cos2 = nh * nh;
            let tan2 = (1.0 - cos2) / cos2;
            let d = (-tan2 / m2).exp() / (PI * m2 * cos2 * cos2);
            let f0 = m.fresnel as f64;
            let f = f0 + (1.0 - f0) * (1.0 - vh).powi(5);
            let g = (2.0 * nh * nv / vh).min(2.0 * nh * nl / vh).min(1.0);
            PI * d * f * g / (4.0 * nv)
        }
    }
}

/// Shades runs of a scene seen from a view.
pub(crate) struct Shader<'a> {
    scene: &'a Scene,
    view: &'a View,
    samples: &'a [Vec<LightSample>],
}

/// Per-run scratch: what one run needs whatever the light (reused from run to run).
#[derive(Debug, Default)]
pub(crate) struct RunShading {
    poly: usize,
    mode: ShadingMode,
    /// +1 or -1: turns the polygon's normals toward the viewer.
    flip: f64,
    centroid: DVec3,
    /// World point seen at each pixel (Gouraud and Phong modes).
    points: Vec<DVec3>,
    /// Each pixel's value as weights of up to four of the polygon's vertices.
    weights: Vec<[(u32, f64); 4]>,
    /// Interpolated unit normal at each pixel (Phong mode).
    normals: Vec<DVec3>,
    /// Scratch: one value per polygon vertex (Gouraud mode).
    vertex_colors: Vec<Vec3>,
    crossings: Vec<ScanCrossing>,
}

/// Where an edge `k -> k+1` of the polygon meets the scan plane, at parameter `t` on the edge
/// and `u` along the line where the polygon meets the scan plane.
#[derive(Debug, Clone, Copy)]
struct ScanCrossing {
    u: f64,
    k: u32,
    t: f64,
}

impl<'a> Shader<'a> {
    /// A shader for `scene` from `view`, with each light's samples.
    pub fn new(scene: &'a Scene, view: &'a View, samples: &'a [Vec<LightSample>]) -> Self {
        Shader { scene, view, samples }
    }

    /// The ambient term `Ia ka Od` of polygon `poly`.
    pub fn ambient(&self, poly: usize) -> Vec3 {
        let m = self.scene.material(poly);
        self.scene.render.ambient * m.ka * m.color
    }

    /// Prepares `rs` for `run` on line `line`: the points seen and, for Gouraud and Phong
    /// shading, each pixel's interpolation weights (and normals).
    pub fn begin_run(&self, run: &Run, line: u32, rs: &mut RunShading) {
        let poly = run.poly as usize;
        let plane = &self.scene.polygons[poly].plane;
        rs.poly = poly;
        rs.mode = self.scene.material(poly).shading;
        rs.flip = if plane.distance(self.view.eye) >= 0.0 { 1.0 } else { -1.0 };
        if rs.mode == ShadingMode::Flat {
            rs.centroid = centroid(self.scene.verts(poly));
            return;
        }
        let yc = line as f64 + 0.5;
        rs.points.clear();
        rs.points.extend((run.x0..run.x1).map(|x| self.view.point_on(plane, x as f64 + 0.5, yc)));
        self.interpolation_weights(yc, rs);
        if rs.mode == ShadingMode::Phong {
            let vn = self.scene.vertex_normals(poly);
            rs.normals.clear();
            rs.normals.extend(rs.weights.iter().map(|w| {
                let n: DVec3 = w.iter().map(|&(k, a)| vn[k as usize] * a).sum();
                (n * rs.flip).normalize_or(plane.n * rs.flip)
            }));
        }
    }

    /// Fills `rs.weights`: each pixel's point as a blend of the two edge crossings of the scan
    /// plane that bracket it, each a blend of its edge's two vertices.
    fn interpolation_weights(&self, yc: f64, rs: &mut RunShading) {
        let verts = self.scene.verts(rs.poly);
        let plane = &self.scene.polygons[rs.poly].plane;
        let eye = self.view.eye;
        // The scan plane holds the eye and every ray of this scanline.
        let ns = self.view.ray(0.0, yc).cross(self.view.r);
        let along = plane.n.cross(ns);
        rs.crossings.clear();
        let n = verts.len();
        for k in 0..n {
            let (a, b) = (verts[k], verts[(k + 1) % n]);
            let (da, db) = (ns.dot(a - eye), ns.dot(b - eye));
            if (da >= 0.0) != (db >= 0.0) {
                let t = da / (da - db);
                let c = a + (b - a) * t;
                rs.crossings.push(ScanCrossing { u: (c - eye).dot(along), k: k as u32, t });
            }
        }
        rs.crossings.sort_unstable_by(|a, b| a.u.total_cmp(&b.u));
        rs.weights.clear();
        let pairs = rs.crossings.len() / 2;
        for p in &rs.points {
            let w = if pairs == 0 {
                // The scanline only grazes the polygon: fall back to its first vertex.
                [(0, 1.0), (0, 0.0), (0, 0.0), (0, 0.0)]
            } else {
                let u = (*p - eye).dot(along);
                // The pair whose interval holds u (or, through rounding at an end, the nearest).
                let j = (0..pairs)
                    .min_by(|&i, &j| {
                        let gap = |i: usize| {
                            let (l, r) = (rs.crossings[2 * i].u, rs.crossings[2 * i + 1].u);
                            (l - u).max(u - r).max(0.0)
                        };
                        gap(i).total_cmp(&gap(j))
                    })
                    .unwrap_or(0);
                let (l, r) = (rs.crossings[2 * j], rs.crossings[2 * j + 1]);
                let s = if r.u > l.u { ((u - l.u) / (r.u - l.u)).clamp(0.0, 1.0) } else { 0.5 };
                let next = |k: u32| (k + 1) % n as u32;
                [
                    (l.k, (1.0 - l.t) * (1.0 - s)),
                    (next(l.k), l.t * (1.0 - s)),
                    (r.k, (1.0 - r.t) * s),
                    (next(r.k), r.t * s),
                ]
            };
            rs.weights.push(w);
        }
    }

    /// Adds the light of sample `sample` of light `light` to the run prepared in `rs`,
    /// pixel `i` weighted by its lit value `lit[i]`.
    pub fn add_light(&self, rs: &mut RunShading, light: usize, sample: usize, lit: &[f32], out: &mut [Vec3]) {
        let l = &self.scene.lights[light];
        let s = &self.samples[light][sample];
        let ns = self.samples[light].len();
        let m = self.scene.material(rs.poly);
        let eye = self.view.eye;
        let shade = |p: DVec3, n: DVec3| {
            let (to_light, radiance) = incident(l, s, ns, p);
            radiance * reflect(m, n, (eye - p).normalize(), to_light)
        };
        match rs.mode {
            ShadingMode::Flat => {
                let n = self.scene.polygons[rs.poly].plane.n * rs.flip;
                let c = shade(rs.centroid, n);
                for (o, &v) in out.iter_mut().zip(lit) {
                    *o += c * v;
                }
            }
            ShadingMode::Gouraud => {
                let verts = self.scene.verts(rs.poly);
                let vn = self.scene.vertex_normals(rs.poly);
                rs.vertex_colors.clear();
                rs.vertex_colors.extend(verts.iter().zip(vn).map(|(&p, &n)| shade(p, n * rs.flip)));
                for ((o, &v), w) in out.iter_mut().zip(lit).zip(&rs.weights) {
                    if v != 0.0 {
                        let c: Vec3 = w.iter().map(|&(k, a)| rs.vertex_colors[k as usize] * a as f32).sum();
                        *o += c * v;
                    }
                }
            }
            ShadingMode::Phong => {
                for (((o, &v), &p), &n) in out.iter_mut().zip(lit).zip(&rs.points).zip(&rs.normals) {
                    if v != 0.0 {
                        *o += shade(p, n) * v;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mat(model: SpecularModel) -> Material {
        Material { model, ks: 1.0, kd: 0.0, ..Material::new("m") }
    }

    #[test]
    fn specular_is_zero_below_the_horizon() {
        let m = mat(SpecularModel::Phong);
        assert_eq!(reflect(&m, DVec3::Y, DVec3::Y, -DVec3::Y), Vec3::ZERO);
    }

    #[test]
    fn cook_torrance_by_hand() {
        // N = V = L = +Y: H = N, alpha = 0, D = 1/(π m²), F = F0, G = 1,
        // spec = π D F G / (4 N.V) = F0 / (4 m²).
        let m = Material { roughness: 0.5, fresnel: 0.04, ..mat(SpecularModel::CookTorrance) };
        let s = reflect(&m, DVec3::Y, DVec3::Y, DVec3::Y);
        assert!((s.x - 0.04 / (4.0 * 0.25)).abs() < 1e-6, "{s}");
        // L at 60° from N in the plane of V = N: H at 30°.
        let l = DVec3::new(60f64.to_radians().sin(), 60f64.to_radians().cos(), 0.0);
        let h = (l + DVec3::Y).normalize();
        let (nh, vh, nl, nv) = (h.y, h.y, l.y, 1.0);
        let tan2 = (1.0 - nh * nh) / (nh * nh);
        let d = (-tan2 / 0.25).exp() / (PI * 0.25 * nh.powi(4));
        let f = 0.04 + 0.96 * (1.0 - vh).powi(5);
        let g = (2.0 * nh * nv / vh).min(2.0 * nh * nl / vh).min(1.0);
        let want = PI * d * f * g / (4.0 * nv);
        let s = reflect(&m, DVec3::Y, DVec3::Y, l);
        assert!((s.x as f64 - want).abs() < 1e-6, "{s} vs {want}");
    }

    #[test]
    fn blinn_with_four_times_the_exponent_matches_phong_near_the_peak() {
        // Coplanar N, L, V: the angle between N and H is half that between R and V, so
        // (N.H)^(4n) ≈ (R.V)^n for small angles.
        let phong = Material { shininess: 20.0, ..mat(SpecularModel::Phong) };
        let blinn = Material { shininess: 80.0, ..mat(SpecularModel::Blinn) };
        let l = DVec3::new(-0.5, 1.0, 0.0).normalize();
        for deg in [0.0f64, 2.0, 5.0, 8.0] {
            let r = DVec3::new(0.5, 1.0, 0.0).normalize();
            let v = glam::DQuat::from_rotation_z(deg.to_radians()) * r;
            let (p, b) = (reflect(&phong, DVec3::Y, v, l).x, reflect(&blinn, DVec3::Y, v, l).x);
            assert!((p - b).abs() < 0.03, "{deg}°: phong {p} blinn {b}");
        }
    }

    #[test]
    fn attenuation_and_spot_cone() {
        let light = Light {
            kind: LightKind::Spot {
                position: DVec3::new(0.0, 2.0, 0.0),
                direction: -DVec3::Y,
                cutoff: 30.0,
                exponent: 2.0,
            },
            color: Vec3::ONE,
            intensity: 1.0,
            attenuation: [1.0, 0.5, 0.25],
        };
        let s = light.samples()[0];
        // Straight below at distance 2: f_att = 1/(1 + 1 + 1) = 1/3, spot = 1.
        let (_, r) = incident(&light, &s, 1, DVec3::ZERO);
        assert!((r.x - 1.0 / 3.0).abs() < 1e-6);
        // 20° off axis: inside; cos^2.
        let p = DVec3::new(2.0 * 20f64.to_radians().tan(), 0.0, 0.0);
        let d = (p - DVec3::new(0.0, 2.0, 0.0)).length();
        let (_, r) = incident(&light, &s, 1, p);
        let want = 20f64.to_radians().cos().powi(2) / (1.0 + 0.5 * d + 0.25 * d * d);
        assert!((r.x as f64 - want).abs() < 1e-6);
        // 31° off axis: outside the cone.
        let (_, r) = incident(&light, &s, 1, DVec3::new(2.0 * 31f64.to_radians().tan(), 0.0, 0.0));
        assert_eq!(r, Vec3::ZERO);
    }
}
