//! The per-pixel part of shading in eight f32 lanes, a whole scanline at a time.
//!
//! A line is shaded in two steps. First each run writes what its pixels need into the
//! line's arrays, one value per pixel, struct-of-arrays: its ambient term, the light of
//! flat and Gouraud shading, and, for Phong shading, each pixel's point `q = p − eye`, its
//! unit normal and its material. Then one pass over the line lights the Phong pixels
//! eight at a time, whichever runs they belong to, so a line of short runs (a mesh of small
//! triangles) fills its lanes as well as one long run does, and each pixel's geometry is
//! loaded once for all light samples.
//!
//! Along a scanline, the ray through pixel `x0 + i` is `ray + i·step`, and the polygon's
//! plane is met at `q = (ray + i·step) · depth / (den₀ + i·den₁)` (`den` is the plane
//! normal's dot product with the ray, so both are linear in `i`). The parameter `s`
//! between the run's two edge crossings, by which [`super`] interpolates normals and
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

/// One line's pixels, struct-of-arrays, padded to whole lane groups.
#[derive(Debug, Default)]
pub(super) struct LineLanes {
    /// Pixels in the line, and rounded up to whole groups.
    width: usize,
    padded: usize,
    /// Phong pixels: `p − eye` and the unit normal turned toward the viewer.
    q: [Vec<f32x8>; 3],
    normal: [Vec<f32x8>; 3],
    /// The line's Phong pixels as stretches of one material, in increasing x.
    stretches: Vec<Stretch>,
    /// The light gathered so far, starting from the ambient term.
    acc: [Vec<f32x8>; 3],
    /// Scratch: a Gouraud run's `s`, one value per pixel.
    s: Vec<f32x8>,
    /// The Phong pass's constants for one material, one per light sample.
    constants: Vec<PhongConstants>,
    constants_for: u32,
    /// The background colour, and the end of the last run started.
    background: Vec3,
    claimed: usize,
}

/// What a run's lanes are filled from: the f64 coefficients above, rounded to f32.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct RunGeometry {
    /// The ray through the first pixel's centre and its change per pixel.
    pub ray: [f32; 3],
    pub step: [f32; 3],
    /// `−plane(eye)`, and the plane normal's dot product with `ray` and with `step`.
    pub depth: f32,
    pub den: [f32; 2],
    /// Gouraud: `s = (num₀ + i num₁) / (div₀ + i div₁)`, as `[num, div]`.
    pub s: [[f32; 2]; 2],
    /// Phong: the normal at pixel `i` is along `normal₀ + i normal₁`, turned toward the
    /// viewer, or the plane's `plane` where that is zero.
    pub normal: [[f32; 3]; 2],
    pub plane: [f32; 3],
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
    /// The diffuse term's weight (1, or 0 where it comes from `vector`).
    pub diffuse: f32,
    /// The row of lit values that weights it.
    pub row: usize,
    /// An area light's centre whose diffuse term comes from irradiance vectors: the first
    /// of the three lit rows of their components.
    pub vector: Option<usize>,
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

/// Eight values of `v` from `at` (zero past its end).
#[inline(always)]
fn load(v: &[f32], at: usize) -> f32x8 {
    match v.get(at..at + W) {
        Some(a) => f32x8::from(<[f32; W]>::try_from(a).unwrap_or_default()),
        None => {
            let mut a = [0.0; W];
            let from = v.get(at..).unwrap_or_default();
            a[..from.len()].copy_from_slice(from);
            f32x8::from(a)
        }
    }
}

/// Eight pixels' values of a three-channel array, group `g`.
#[inline(always)]
fn load3(v: &[Vec<f32x8>; 3], g: usize) -> V3 {
    [v[0][g], v[1][g], v[2][g]]
}

/// Groups of eight values as the values.
fn flat(v: &[f32x8]) -> &[f32] {
    wide::bytemuck::cast_slice(v)
}

fn flat_mut(v: &mut [f32x8]) -> &mut [f32] {
    wide::bytemuck::cast_slice_mut(v)
}

/// Writes the eight values of `x` to `v` from `at`: the values past the pixels meant are
/// scratch, written again by what follows them along the line (ours: one store, not a
/// loop over the pixels meant; the line's arrays have a group to spare at the end).
#[inline(always)]
fn store_wide(v: &mut [f32], at: usize, x: f32x8) {
    v[at..at + W].copy_from_slice(&x.to_array());
}

/// Writes colour `x` to the three channels `v` in `from..to`, and as scratch up to seven
/// values past it ([`store_wide`]).
#[inline(always)]
fn fill_wide(v: &mut [Vec<f32x8>; 3], from: usize, to: usize, x: Vec3) {
    let [r, g, b] = v;
    let (r, g, b) = (flat_mut(r), flat_mut(g), flat_mut(b));
    let x = splat(x.to_array());
    for at in (from..to).step_by(W) {
        store_wide(r, at, x[0]);
        store_wide(g, at, x[1]);
        store_wide(b, at, x[2]);
    }
}

/// Writes the first `n` of the eight values of `x` to `v` from `at`.
#[inline(always)]
fn store(v: &mut [f32], at: usize, n: usize, x: f32x8) {
    let x = x.to_array();
    if n == W {
        v[at..at + W].copy_from_slice(&x);
    } else {
        for (v, x) in v[at..at + n].iter_mut().zip(x) {
            *v = x;
        }
    }
}

/// The index `i` of each lane of group `g` along a run.
fn index(g: usize) -> f32x8 {
    f32x8::from([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]) + (W * g) as f32
}

/// `s` of the lanes at `i`, in `[0, 1]`.
fn s_at(g: &RunGeometry, i: f32x8) -> f32x8 {
    let [num, div] = g.s;
    let s =
        i.mul_add(f32x8::splat(num[1]), f32x8::splat(num[0])) / i.mul_add(f32x8::splat(div[1]), f32x8::splat(div[0]));
    // Not-a-number (a zero divisor) fails the first test and becomes 0.
    s.simd_ge(f32x8::ZERO).select(s, f32x8::ZERO).min(f32x8::ONE)
}

/// A channel that overflowed, to infinity or to not-a-number (infinity times zero, or less
/// infinity), becomes the largest finite value: no NaN or infinity reaches a pixel.
fn finite(c: f32x8) -> f32x8 {
    let max = f32x8::splat(f32::MAX);
    c.is_nan().select(max, c.max(-max).min(max))
}

impl LineLanes {
    /// Starts a line of `width` pixels, every one the background until a run claims it.
    pub fn start(&mut self, width: usize, background: Vec3) {
        self.width = width;
        self.padded = width.div_ceil(W) * W;
        for v in self.acc.iter_mut().chain(&mut self.q).chain(&mut self.normal) {
            // A group to spare for the scratch of [`store_wide`].
            v.resize(self.padded / W + 1, f32x8::ZERO);
        }
        self.stretches.clear();
        (self.background, self.claimed) = (background, 0);
    }

    /// Starts the run of pixels `x0..x1` (runs come in increasing x) with its ambient term;
    /// the pixels since the last run are background.
    pub fn start_run(&mut self, x0: usize, x1: usize, ambient: Vec3) {
        self.background_to(x0);
        fill_wide(&mut self.acc, x0, x1, ambient);
        self.claimed = x1;
    }

    /// Makes the pixels from the last run's end to `x` background.
    fn background_to(&mut self, x: usize) {
        fill_wide(&mut self.acc, self.claimed.min(x), x, self.background);
    }

    /// Flat: adds one colour to the run at `x0`, weighted by `lit` (one value per pixel).
    pub fn add_flat(&mut self, x0: usize, color: Vec3, lit: &[f32]) {
        for (c, v) in self.acc.iter_mut().enumerate() {
            for (a, &l) in flat_mut(v)[x0..x0 + lit.len()].iter_mut().zip(lit) {
                *a = color[c].mul_add(l, *a);
            }
        }
    }

    /// Gouraud: readies the run of `len` pixels for [`LineLanes::add_gouraud`].
    pub fn gouraud_run(&mut self, g: &RunGeometry, len: usize) {
        self.s.clear();
        self.s.extend((0..len.div_ceil(W)).map(|group| s_at(g, index(group))));
    }

    /// Gouraud: adds the colour interpolated between `left` and `right`, the colours at the
    /// run's two edge crossings, to the run at `x0`, weighted by `lit`.
    pub fn add_gouraud(&mut self, x0: usize, left: Vec3, right: Vec3, lit: &[f32]) {
        let (l, d) = (splat(left.to_array()), splat((right - left).to_array()));
        for (group, &s) in self.s.iter().enumerate() {
            let (at, n) = (x0 + W * group, (lit.len() - W * group).min(W));
            let v = load(lit, W * group);
            for c in 0..3 {
                let sum = s.mul_add(d[c], l[c]).mul_add(v, load(flat(&self.acc[c]), at));
                store(flat_mut(&mut self.acc[c]), at, n, sum);
            }
        }
    }

    /// Adds light computed elsewhere (the f64 path) to the run at `x0`.
    pub fn add(&mut self, x0: usize, light: &[Vec3]) {
        for (c, v) in self.acc.iter_mut().enumerate() {
            for (a, l) in flat_mut(v)[x0..x0 + light.len()].iter_mut().zip(light) {
                *a += l[c];
            }
        }
    }

    /// Phong: writes the point and normal of each of the run's `len` pixels from `x0`, for
    /// [`LineLanes::shade_phong`] to light with `material`.
    pub fn phong_run(&mut self, x0: usize, len: usize, g: &RunGeometry, material: u32) {
        let (ray, step) = (splat(g.ray), splat(g.step));
        let (depth, den) = (f32x8::splat(g.depth), g.den.map(f32x8::splat));
        let (n0, n1, plane) = (splat(g.normal[0]), splat(g.normal[1]), splat(g.plane));
        for group in 0..len.div_ceil(W) {
            let (i, at) = (index(group), x0 + W * group);
            let t = depth / i.mul_add(den[1], den[0]);
            let normal = normalize([0, 1, 2].map(|c| i.mul_add(n1[c], n0[c])), &plane);
            for c in 0..3 {
                store_wide(flat_mut(&mut self.q[c]), at, i.mul_add(step[c], ray[c]) * t);
                store_wide(flat_mut(&mut self.normal[c]), at, normal[c]);
            }
        }
        match self.stretches.last_mut() {
            Some(last) if last.material == material && last.x1 == x0 => last.x1 += len,
            _ => self.stretches.push(Stretch { material, x0, x1: x0 + len }),
        }
    }

    /// Phong: lights every Phong pixel of the line with every light sample, sample `k`'s
    /// lit values being `lit[k * width..][..width]`, a stretch of one material at a time,
    /// eight pixels at a time. Ends the line's runs.
    pub fn shade_phong(&mut self, lights: &[LaneLight], materials: &[LaneMaterial], lit: &[f32]) {
        self.background_to(self.padded);
        let LineLanes { width, q, normal, acc, stretches, constants, constants_for, .. } = self;
        let rows = Rows { lit, width: *width };
        for &Stretch { material: m, x0, x1 } in stretches.iter() {
            let k = constants_of(constants, constants_for, m, lights, materials);
            let material = &materials[m as usize];
            for at in (x0 / W * W..x1).step_by(W) {
                // A group the stretch does not fill is shared with its neighbours' pixels.
                let mask = (at < x0 || at + W > x1).then(|| {
                    let all = f32::from_bits(u32::MAX);
                    f32x8::from(std::array::from_fn(|j| if (x0..x1).contains(&(at + j)) { all } else { 0.0 }))
                });
                let g = at / W;
                let pixels = Pixels::new(load3(q, g), load3(normal, g), at);
                let mut sum = load3(acc, g);
                pixels.add(k, material, &rows, mask, &mut sum);
                (acc[0][g], acc[1][g], acc[2][g]) = (sum[0], sum[1], sum[2]);
            }
        }
    }

    /// Writes the line to `out`: the ambient term and the light gathered, kept finite.
    pub fn finish(&self, out: &mut [Vec3]) {
        let colors = |group: usize| {
            let [r, g, b] = load3(&self.acc, group);
            [finite(r).to_array(), finite(g).to_array(), finite(b).to_array()]
        };
        let mut whole = out.chunks_exact_mut(W);
        for (group, out) in whole.by_ref().enumerate() {
            let [r, g, b] = colors(group);
            for j in 0..W {
                out[j] = Vec3::new(r[j], g[j], b[j]);
            }
        }
        let rest = whole.into_remainder();
        if !rest.is_empty() {
            let [r, g, b] = colors(self.width / W);
            for (j, o) in rest.iter_mut().enumerate() {
                *o = Vec3::new(r[j], g[j], b[j]);
            }
        }
    }
}

/// Pixels `x0..x1` of a line, Phong-shaded with one material.
#[derive(Debug, Clone, Copy)]
struct Stretch {
    material: u32,
    x0: usize,
    x1: usize,
}

/// The lit rows of a line's light samples.
struct Rows<'a> {
    lit: &'a [f32],
    width: usize,
}

impl Rows<'_> {
    /// Sample `k`'s lit values at eight pixels from `at` (zero past the line's end).
    #[inline(always)]
    fn at(&self, k: usize, at: usize) -> f32x8 {
        load(&self.lit[k * self.width..(k + 1) * self.width], at)
    }
}

/// Eight pixels' geometry: `p − eye`, the unit normal, the unit vector to the eye.
struct Pixels {
    q: V3,
    n: V3,
    view: V3,
    at: usize,
}

impl Pixels {
    #[inline(always)]
    fn new(q: V3, n: V3, at: usize) -> Self {
        let view = normalize([-q[0], -q[1], -q[2]], &splat([0.0; 3]));
        Pixels { q, n, view, at }
    }

    /// Adds every light sample's light to `sum`, in the lanes of `mask` (all when `None`).
    #[inline(always)]
    fn add(&self, constants: &[PhongConstants], m: &LaneMaterial, rows: &Rows, mask: Option<f32x8>, sum: &mut V3) {
        for constants in constants {
            let v = rows.at(constants.row, self.at);
            if v == f32x8::ZERO {
                continue;
            }
            let mut light = phong(constants, m, &self.q, &self.n, &self.view, v);
            if let Some(row) = constants.vector {
                let vector = [0, 1, 2].map(|c| rows.at(row + c, self.at));
                let diffuse = lambert(constants, &self.q, &self.n, &vector);
                light = [0, 1, 2].map(|c| light[c] + diffuse[c]);
            }
            for c in 0..3 {
                sum[c] += mask.map_or(light[c], |mask| mask.select(light[c], f32x8::ZERO));
            }
        }
    }
}

/// The Phong pass's constants for material `m`, one per light sample: those kept in
/// `constants` if they are `m`'s (`kept_for`), else made anew.
fn constants_of<'c>(
    constants: &'c mut Vec<PhongConstants>,
    kept_for: &mut u32,
    m: u32,
    lights: &[LaneLight],
    materials: &[LaneMaterial],
) -> &'c [PhongConstants] {
    if *kept_for != m || constants.len() != lights.len() {
        constants.clear();
        constants.extend(lights.iter().map(|l| PhongConstants::new(l, &materials[m as usize])));
        *kept_for = m;
    }
    constants
}

/// One light sample's light at eight pixels weighted by `lit`; the same formulas as
/// [`super::incident`] and [`super::reflect`].
#[inline(always)]
fn phong(k: &PhongConstants, m: &LaneMaterial, q: &V3, n: &V3, view: &V3, lit: f32x8) -> V3 {
    let (l, att) = incident(k, q);
    let nl = dot(n, &l);
    let spec = specular(m, k, n, view, &l, nl);
    let weight = nl.simd_gt(f32x8::ZERO).select(att * spot(k, &l) * lit, f32x8::ZERO);
    [0, 1, 2].map(|c| k.specular[c].mul_add(spec, k.diffuse[c] * nl) * weight)
}

/// An area light's diffuse term from each pixel's irradiance vector: `kd Od I f_att(d)
/// max(0, N · vector)`, `d` to its centre; the same formula as `Shader::lambert`.
#[inline(always)]
fn lambert(k: &PhongConstants, q: &V3, n: &V3, vector: &V3) -> V3 {
    let (_, att) = incident(k, q);
    let weight = dot(n, vector).max(f32x8::ZERO) * att;
    [0, 1, 2].map(|c| k.lambert[c] * weight)
}

/// A light sample and a material's numbers in lanes; the light's radiance is folded into
/// the material's `kd Od` and `ks Os`.
#[derive(Debug)]
struct PhongConstants {
    point: Option<V3>,
    direction: V3,
    attenuation: [f32x8; 3],
    spot: Option<(V3, f32x8, f32)>,
    diffuse: V3,
    specular: V3,
    shininess: f32,
    row: usize,
    vector: Option<usize>,
    /// `kd Od` times the radiance, for the diffuse term from `vector`.
    lambert: V3,
}

impl PhongConstants {
    fn new(light: &LaneLight, m: &LaneMaterial) -> Self {
        let (point, direction) = match light.toward {
            Toward::Point(p) => (Some(splat(p)), splat([0.0; 3])),
            Toward::Direction(d) => (None, splat(d)),
        };
        let times = |a: [f32; 3], w: f32| splat([0, 1, 2].map(|c| a[c] * light.radiance[c] * w));
        PhongConstants {
            point,
            direction,
            attenuation: light.attenuation.map(f32x8::splat),
            spot: light.spot.map(|(axis, cos, exponent)| (splat(axis), f32x8::splat(cos), exponent)),
            diffuse: times(m.diffuse, light.diffuse),
            specular: times(m.specular, 1.0),
            shininess: m.shininess,
            row: light.row,
            vector: light.vector,
            lambert: times(m.diffuse, 1.0),
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
