//! The per-pixel part of Gouraud and Phong shading in eight f32 lanes: one run of pixels at a
//! time, each value found from the pixel's position along the run rather than from the
//! pixel's world point.
//!
//! Along a scanline, the ray through pixel `x0 + i` is `ray + i·step`, and the polygon's
//! plane is met at `q = (ray + i·step) · depth / (den₀ + i·den₁)` (`q = p − eye`; `den` is
//! the plane normal's dot product with the ray, so both are linear in `i`). The parameter
//! `s` between the run's two edge crossings, by which [`super`] interpolates normals and
//! colours, is the ratio of two such linear functions as well. So a pixel costs a handful
//! of multiply-adds and one division for its geometry, whatever the polygon, and then
//! Phong, Blinn or Cook-Torrance in lanes, with [`super::fast_pow`] for the powers.
//!
//! The coefficients are computed in f64 by [`super::Shader`] and rounded once; the lanes
//! then work in f32. [`super::Shader`] only sends runs here whose coordinates fit single
//! precision with room to square them, and whose line crosses the polygon's outline just
//! twice (every run of a convex polygon); other runs take the f64 path, which is also what
//! the tests hold these kernels to.

use super::fast_pow::{exp2, pow};
use crate::scene::SpecularModel;
use glam::Vec3;
use wide::f32x8;

/// Pixels to a lane group.
const W: usize = 8;

type V3 = [f32x8; 3];

/// A run's pixels, eight to a lane group, struct-of-arrays.
#[derive(Debug, Default)]
pub(super) struct RunLanes {
    len: usize,
    /// `s` between the two edge crossings, in `[0, 1]` (Gouraud mode).
    s: Vec<f32x8>,
    /// `p − eye`, the unit normal turned toward the viewer, and the unit vector to the eye
    /// (Phong mode only).
    q: Vec<V3>,
    normal: Vec<V3>,
    view: Vec<V3>,
    /// The light gathered so far.
    acc: Vec<V3>,
}

/// What a run's lanes are filled from: the f64 coefficients above, rounded to f32.
#[derive(Debug, Clone, Copy)]
pub(super) struct RunGeometry {
    /// The ray through the first pixel's centre and its change per pixel.
    pub ray: [f32; 3],
    pub step: [f32; 3],
    /// `−plane(eye)`, and the plane normal's dot product with `ray` and with `step`.
    pub depth: f32,
    pub den: [f32; 2],
    /// `s = (num₀ + i num₁) / (div₀ + i div₁)`.
    pub s_num: [f32; 2],
    pub s_div: [f32; 2],
    /// For Phong shading: the normals at the two crossings, and the plane's (for a blend
    /// that cancels to zero), all turned toward the viewer.
    pub normals: Option<[[f32; 3]; 3]>,
}

/// A light sample as the lanes see it.
#[derive(Debug, Clone, Copy)]
pub(super) struct LaneLight {
    pub toward: Toward,
    /// `I_l / n_l` times the light's colour.
    pub radiance: [f32; 3],
    /// `[a, b, c]` of `f_att`; unused for directional lights.
    pub attenuation: [f32; 3],
    /// Axis, `cos(cutoff)` and exponent of a spot light's cone.
    pub spot: Option<([f32; 3], f32, f32)>,
}

/// Where a sample's light comes from.
#[derive(Debug, Clone, Copy)]
pub(super) enum Toward {
    /// A point at `position − eye`.
    Point([f32; 3]),
    /// A direction (unit, toward the light).
    Direction([f32; 3]),
}

/// A material's reflectance as the lanes see it.
#[derive(Debug, Clone, Copy)]
pub(super) struct LaneMaterial {
    /// `kd Od` and `ks Os`.
    pub diffuse: [f32; 3],
    pub specular: [f32; 3],
    pub model: SpecularModel,
    pub shininess: f32,
    /// Beckmann's `m²` and Schlick's `F0`.
    pub m2: f32,
    pub f0: f32,
}

fn splat(v: [f32; 3]) -> V3 {
    v.map(f32x8::splat)
}

fn dot(a: &V3, b: &V3) -> f32x8 {
    a[0].mul_add(b[0], a[1].mul_add(b[1], a[2] * b[2]))
}

/// `v / |v|`, and `fallback` where `|v| = 0`.
fn normalize(v: V3, fallback: &V3) -> V3 {
    let len2 = dot(&v, &v);
    let nonzero = len2.simd_gt(f32x8::ZERO);
    let inv = nonzero.select(f32x8::ONE / len2.sqrt(), f32x8::ZERO);
    [0, 1, 2].map(|c| nonzero.select(v[c] * inv, fallback[c]))
}

/// The lit values of lane group `g` (zero past the run's end).
fn load(lit: &[f32], g: usize) -> f32x8 {
    let mut a = [0.0; W];
    let from = &lit[W * g..lit.len().min(W * g + W)];
    a[..from.len()].copy_from_slice(from);
    f32x8::from(a)
}

/// A channel that overflowed, to infinity or to not-a-number (infinity times zero, or less
/// infinity), becomes the largest finite value: no NaN or infinity reaches a pixel.
fn finite(c: f32x8) -> f32x8 {
    let max = f32x8::splat(f32::MAX);
    c.is_nan().select(max, c.max(-max).min(max))
}

impl RunLanes {
    /// Starts a run of `len` pixels with no light yet.
    pub fn start(&mut self, len: usize) {
        self.len = len;
        self.acc.clear();
        self.acc.resize(len.div_ceil(W), splat([0.0; 3]));
    }

    /// Writes `ambient` plus the light gathered to `out`, the run's pixels in the frame.
    pub fn finish(&self, ambient: Vec3, out: &mut [Vec3]) {
        let ambient = splat(ambient.to_array());
        for (acc, out) in self.acc.iter().zip(out.chunks_mut(W)) {
            let [r, g, b] = [0, 1, 2].map(|c| finite(acc[c] + ambient[c]).to_array());
            for (j, o) in out.iter_mut().enumerate() {
                *o = Vec3::new(r[j], g[j], b[j]);
            }
        }
    }

    /// Flat: adds one colour, weighted by `lit`.
    pub fn add_flat(&mut self, color: Vec3, lit: &[f32]) {
        let c = splat(color.to_array());
        for (g, acc) in self.acc.iter_mut().enumerate() {
            let v = load(lit, g);
            for k in 0..3 {
                acc[k] = c[k].mul_add(v, acc[k]);
            }
        }
    }

    /// Fills the lanes for a run of `len` pixels.
    pub fn fill(&mut self, g: &RunGeometry, len: usize) {
        self.start(len);
        self.s.clear();
        self.q.clear();
        self.normal.clear();
        self.view.clear();
        let first = f32x8::from([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        for group in 0..len.div_ceil(W) {
            let i = first + (W * group) as f32;
            let s = i.mul_add(f32x8::splat(g.s_num[1]), f32x8::splat(g.s_num[0]))
                / i.mul_add(f32x8::splat(g.s_div[1]), f32x8::splat(g.s_div[0]));
            // Not-a-number (a zero divisor) fails the first test and becomes 0.
            let s = s.simd_ge(f32x8::ZERO).select(s, f32x8::ZERO).min(f32x8::ONE);
            // Gouraud keeps `s`; Phong keeps what it interpolates with it.
            let Some([left, right, plane]) = g.normals else {
                self.s.push(s);
                continue;
            };
            let t = f32x8::splat(g.depth) / i.mul_add(f32x8::splat(g.den[1]), f32x8::splat(g.den[0]));
            let q = [0, 1, 2].map(|c| i.mul_add(f32x8::splat(g.step[c]), f32x8::splat(g.ray[c])) * t);
            let n = [0, 1, 2].map(|c| s.mul_add(f32x8::splat(right[c] - left[c]), f32x8::splat(left[c])));
            self.view.push(normalize(q.map(|v| -v), &splat([0.0; 3])));
            self.normal.push(normalize(n, &splat(plane)));
            self.q.push(q);
        }
    }

    /// Gouraud: adds the colour interpolated between `left` and `right`, the colours at the
    /// run's two edge crossings, weighted by `lit`.
    pub fn add_gouraud(&mut self, left: Vec3, right: Vec3, lit: &[f32]) {
        let (l, d) = (splat(left.to_array()), splat((right - left).to_array()));
        for (g, (&s, acc)) in self.s.iter().zip(&mut self.acc).enumerate() {
            let v = load(lit, g);
            for c in 0..3 {
                acc[c] = s.mul_add(d[c], l[c]).mul_add(v, acc[c]);
            }
        }
    }

    /// Phong: adds one light sample's light at every pixel, weighted by `lit`; the same
    /// formulas as [`super::incident`] and [`super::reflect`].
    pub fn add_phong(&mut self, light: &LaneLight, m: &LaneMaterial, lit: &[f32]) {
        // Every constant in lanes once, before the loop.
        let k = PhongConstants::new(light, m);
        for g in 0..self.q.len() {
            let v = load(lit, g);
            if v == f32x8::ZERO {
                continue;
            }
            let (n, eye) = (&self.normal[g], &self.view[g]);
            let (l, att) = incident(&k, &self.q[g]);
            let nl = dot(n, &l);
            let spec = specular(m, &k, n, eye, &l, nl);
            let weight = nl.simd_gt(f32x8::ZERO).select(att * spot(&k, &l) * v, f32x8::ZERO);
            for ((acc, ks), kd) in self.acc[g].iter_mut().zip(&k.specular).zip(&k.diffuse) {
                *acc = ks.mul_add(spec, *kd * nl).mul_add(weight, *acc);
            }
        }
        debug_assert!(self.q.len() * W >= self.len);
    }
}

/// A light sample and a material's numbers in lanes; the light's radiance is folded into
/// the material's `kd Od` and `ks Os`.
struct PhongConstants {
    point: Option<V3>,
    direction: V3,
    attenuation: [f32x8; 3],
    spot: Option<(V3, f32x8, f32)>,
    diffuse: V3,
    specular: V3,
    shininess: f32,
}

impl PhongConstants {
    fn new(light: &LaneLight, m: &LaneMaterial) -> Self {
        let (point, direction) = match light.toward {
            Toward::Point(p) => (Some(splat(p)), splat([0.0; 3])),
            Toward::Direction(d) => (None, splat(d)),
        };
        let times = |a: [f32; 3]| splat([0, 1, 2].map(|c| a[c] * light.radiance[c]));
        PhongConstants {
            point,
            direction,
            attenuation: light.attenuation.map(f32x8::splat),
            spot: light.spot.map(|(axis, cos, exponent)| (splat(axis), f32x8::splat(cos), exponent)),
            diffuse: times(m.diffuse),
            specular: times(m.specular),
            shininess: m.shininess,
        }
    }
}

/// The unit vector to the light, and `f_att`.
#[inline(always)]
fn incident(k: &PhongConstants, q: &V3) -> (V3, f32x8) {
    let Some(p) = &k.point else { return (k.direction, f32x8::ONE) };
    let d = [0, 1, 2].map(|c| p[c] - q[c]);
    let len2 = dot(&d, &d);
    let inv = f32x8::ONE / len2.sqrt();
    let dist = len2 * inv;
    let [a, b, c] = k.attenuation;
    let att = f32x8::ONE / dist.mul_add(dist.mul_add(c, b), a);
    (d.map(|v| v * inv), att.min(f32x8::ONE))
}

/// The spot cone's `cos^exponent` inside, 0 outside; 1 for other lights.
#[inline(always)]
fn spot(k: &PhongConstants, l: &V3) -> f32x8 {
    let Some((axis, cos_cutoff, exponent)) = &k.spot else { return f32x8::ONE };
    let cos = -dot(l, axis);
    cos.simd_ge(*cos_cutoff).select(pow(cos, *exponent), f32x8::ZERO)
}

/// `spec` of each model (zero where `N.L <= 0` is left to the caller's weight).
#[inline(always)]
fn specular(m: &LaneMaterial, k: &PhongConstants, n: &V3, v: &V3, l: &V3, nl: f32x8) -> f32x8 {
    if m.specular == [0.0; 3] {
        return f32x8::ZERO;
    }
    match m.model {
        SpecularModel::Phong => {
            let r = [0, 1, 2].map(|c| (nl + nl).mul_sub(n[c], l[c]));
            pow(dot(&r, v), k.shininess)
        }
        SpecularModel::Blinn => {
            let h = normalize([0, 1, 2].map(|c| l[c] + v[c]), &splat([0.0; 3]));
            pow(dot(n, &h), k.shininess)
        }
        SpecularModel::CookTorrance => cook_torrance(m, n, v, l, nl),
    }
}

/// `π D F G / (4 N.V)` with Beckmann's D, Schlick's F and Torrance-Sparrow's G.
#[inline(always)]
fn cook_torrance(m: &LaneMaterial, n: &V3, v: &V3, l: &V3, nl: f32x8) -> f32x8 {
    use std::f32::consts::{LOG2_E, PI};
    let h = normalize([0, 1, 2].map(|c| l[c] + v[c]), &splat([0.0; 3]));
    let (nv, nh, vh) = (dot(n, v), dot(n, &h), dot(v, &h));
    let valid = nv.simd_gt(f32x8::ZERO) & nh.simd_gt(f32x8::ZERO) & vh.simd_gt(f32x8::ZERO);
    let one = f32x8::ONE;
    let cos2 = valid.select(nh * nh, one);
    let tan2 = (one - cos2) / cos2;
    let d = exp2(tan2 * (-LOG2_E / m.m2)) / (cos2 * cos2 * (PI * m.m2));
    let grazing = one - vh;
    let grazing2 = grazing * grazing;
    let f = (grazing2 * grazing2 * grazing).mul_add(f32x8::splat(1.0 - m.f0), f32x8::splat(m.f0));
    let (nv, vh) = (valid.select(nv, one), valid.select(vh, one));
    let g = ((nh + nh) * nv / vh).min((nh + nh) * nl / vh).min(one);
    valid.select(d * f * g * PI / (nv * 4.0), f32x8::ZERO)
}
