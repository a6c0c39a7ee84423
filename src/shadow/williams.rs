//! Williams' two-pass z-buffer shadows (L. Williams, "Casting curved shadows on curved
//! surfaces", SIGGRAPH 1978; seeds 000, 002, 003, 004), with percentage-closer filtering
//! (Reeves, Salesin & Cook 1987) and the soft-edged screen-space blur of seed 002.
//!
//! **Pass 1** renders the depth of the shadow casters from each light sample with the same
//! z-buffer loop as visibility ([`crate::visibility::rasterize`]): a perspective map aimed at
//! the scene when the scene lies within 80° of one direction from the sample (spot and point
//! lights outside the scene, area-light samples), a cube of six 90° maps when it surrounds
//! the sample, and an orthographic map fitted to the scene for a directional light. The map
//! covers the scene, not only a spot's cone, because the lit fraction is defined outside the
//! cone too. Optionally the polygons facing the light are culled (seed 003).
//!
//! **Pass 2** takes each visible point into the light's map and compares: `Z_map + bias <
//! Z_pixel` means shadow, with `bias = constant + slope × texel size × tan θ × (r + 1)` (θ
//! between the normal and the light at the polygon's centroid, r the filter kernel's radius
//! in texels, since a wider kernel reaches texels farther down the slope). Filters: `nearest` (one texel), `pcf` (compare each of N×N texels,
//! then average the answers — never the depths), and `soft-edge` (seed 002: the PCF term of
//! every pixel written to a screen-sized buffer, blurred by the seed's separable 15-tap
//! Gaussian, and used when shading).

use super::{Decision, ShadowContext, ShadowStage, ShadowWalker};
use crate::scene::{Camera, LightSample};
use crate::stats::Counters;
use crate::view::{DepthPlane, ScreenPolygon, View};
use crate::visibility::{rasterize, Run};
use glam::{DVec2, DVec3, DVec4};
use rayon::prelude::*;

/// How the shadow-map comparison is filtered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShadowFilter {
    /// One texel, one comparison.
    Nearest,
    /// Percentage-closer filtering over N×N texels (N odd).
    Pcf(u32),
    /// Seed 002: N×N PCF into a screen buffer, then the 15-tap separable Gaussian blur.
    SoftEdge(u32),
}

/// Options of Williams' shadow maps.
#[derive(Debug, Clone, PartialEq)]
pub struct WilliamsOptions {
    /// Texels along each side of a map.
    pub map_size: u32,
    /// Constant bias in world units along the light's axis; `None`: 0.1% of the scene's size.
    pub bias: Option<f64>,
    /// Slope-scaled bias, in texels times the tangent of the angle of incidence.
    pub slope_bias: f64,
    /// Filter.
    pub filter: ShadowFilter,
    /// Leave out polygons facing the light in pass 1 (seed 003).
    pub cull_front: bool,
}

impl Default for WilliamsOptions {
    fn default() -> Self {
        WilliamsOptions { map_size: 2048, bias: None, slope_bias: 1.5, filter: ShadowFilter::Pcf(3), cull_front: false }
    }
}

/// How world points map into a shadow map.
#[derive(Debug, Clone)]
enum Projection {
    /// A pinhole at the light (texel coordinates are the view's pixel coordinates; depth is
    /// the camera-space depth).
    Perspective(View),
    /// Parallel to the light: `x = (p·u − u0) / texel`, `y = (v0 − p·v) / texel`,
    /// depth `p·d − s0`.
    Ortho { u: DVec3, v: DVec3, d: DVec3, u0: f64, v0: f64, s0: f64, texel: f64 },
}

impl Projection {
    /// Texel coordinates and depth of the point `h.xyz / h.w` (homogeneous, `w > 0`), or
    /// `None` behind a perspective map.
    #[inline]
    fn locate(&self, h: DVec4) -> Option<(f64, f64, f64)> {
        match self {
            Projection::Perspective(view) => {
                let v = h.truncate() - view.eye * h.w;
                let c = DVec3::new(v.dot(view.r), v.dot(view.u), v.dot(view.f));
                (c.z > 0.0).then(|| {
                    let s = view.project(c);
                    (s.x, s.y, c.z / h.w)
                })
            }
            Projection::Ortho { u, v, d, u0, v0, s0, texel } => {
                let (p, w) = (h.truncate(), h.w);
                Some(((p.dot(*u) - u0 * w) / (texel * w), (v0 * w - p.dot(*v)) / (texel * w), (p.dot(*d) - s0 * w) / w))
            }
        }
    }

    /// World size of a texel at depth `z`.
    fn texel_size(&self, z: f64) -> f64 {
        match self {
            Projection::Perspective(view) => 2.0 * z * view.t / view.height as f64,
            Projection::Ortho { texel, .. } => *texel,
        }
    }
}

/// One depth map: the nearness of the nearest caster per texel (as rasterised: `1/z` for a
/// perspective map, `−depth` for an orthographic one; `−∞` where none was drawn).
struct DepthMap {
    proj: Projection,
    size: u32,
    nearness: Vec<f32>,
}

impl DepthMap {
    /// Pass 1 for one projection.
    fn render(ctx: &ShadowContext, proj: Projection, size: u32, sample: LightSample, cull_front: bool) -> DepthMap {
        let scene = ctx.scene;
        let casters = (0..scene.polygons.len()).filter(|&i| {
            let plane = &scene.polygons[i].plane;
            let facing = match sample {
                LightSample::Point(s) => plane.distance(s) > 0.0,
                LightSample::Directional(d) => plane.n.dot(d) < 0.0,
            };
            scene.casts_shadows(i) && !(cull_front && facing)
        });
        let screen: Vec<ScreenPolygon> = match &proj {
            Projection::Perspective(view) => {
                let mut scratch = [Vec::new(), Vec::new()];
                let mut ring = Vec::new();
                casters
                    .filter_map(|i| {
                        let depth = view.depth_plane(&scene.polygons[i].plane)?;
                        view.clip_project(scene.verts(i), &mut scratch, &mut ring).then(|| ScreenPolygon {
                            poly: i as u32,
                            ring: ring.clone(),
                            depth,
                        })
                    })
                    .collect()
            }
            Projection::Ortho { u, v, d, u0, v0, s0, texel } => casters
                .filter_map(|i| {
                    let plane = &scene.polygons[i].plane;
                    let nd = plane.n.dot(*d);
                    if nd == 0.0 {
                        return None;
                    }
                    // Nearness −s as an affine function of the texel coordinates.
                    let o = *u * *u0 + *v * *v0 + *d * *s0;
                    let depth = DepthPlane {
                        a: texel * plane.n.dot(*u) / nd,
                        b: -texel * plane.n.dot(*v) / nd,
                        c: (plane.distance(o)) / nd,
                    };
                    let ring = scene
                        .verts(i)
                        .iter()
                        .map(|&p| DVec2::new((p.dot(*u) - u0) / texel, (v0 - p.dot(*v)) / texel))
                        .collect();
                    Some(ScreenPolygon { poly: i as u32, ring, depth })
                })
                .collect(),
        };
        let nearness = rasterize::<f32>(&screen, size, size, false).depth;
        DepthMap { proj, size, nearness }
    }

    /// The nearness above which a texel hides a point at depth `z`: `Z_map + bias < z` means
    /// shadow, that is `1/Z_map > 1/(z − bias)` (perspective) or `−Z_map > bias − z` (ortho).
    fn threshold(&self, z: f64, bias: f64) -> f32 {
        match self.proj {
            Projection::Perspective(_) if z - bias <= 0.0 => f32::INFINITY,
            Projection::Perspective(_) => (1.0 / (z - bias)) as f32,
            Projection::Ortho { .. } => (bias - z) as f32,
        }
    }

    /// The fraction of the `k×k` texels around `(x, y)` that do not hide depth `z`: compare
    /// each texel first, then average (1 outside the map: nothing was recorded there).
    fn lit(&self, x: f64, y: f64, z: f64, bias: f64, k: u32) -> f32 {
        // floor, with anything left of or above the map at −1.
        let cell = |v: f64| if v < 0.0 { -1 } else { v as i64 };
        let (i, j) = (cell(x), cell(y));
        let r = (k / 2) as i64;
        let n = self.size as i64;
        let threshold = self.threshold(z, bias);
        let mut lit = 0u32;
        if i >= r && j >= r && i + r < n && j + r < n {
            // The whole kernel lies inside the map.
            for tj in j - r..=j + r {
                let row = &self.nearness[(tj * n + i - r) as usize..=(tj * n + i + r) as usize];
                lit += row.iter().filter(|&&d| d <= threshold).count() as u32;
            }
        } else {
            for tj in j - r..=j + r {
                for ti in i - r..=i + r {
                    let inside = ti >= 0 && tj >= 0 && ti < n && tj < n;
                    lit += (!inside || self.nearness[(tj * n + ti) as usize] <= threshold) as u32;
                }
            }
        }
        lit as f32 / (k * k) as f32
    }
}

/// A light sample's maps: one, or a cube of six.
enum LightMaps {
    Single(DepthMap),
    Cube(Box<[DepthMap; 6]>),
}

/// The cube faces' axes and up vectors.
const CUBE: [(DVec3, DVec3); 6] = [
    (DVec3::X, DVec3::Y),
    (DVec3::NEG_X, DVec3::Y),
    (DVec3::Y, DVec3::Z),
    (DVec3::NEG_Y, DVec3::Z),
    (DVec3::Z, DVec3::Y),
    (DVec3::NEG_Z, DVec3::Y),
];

impl LightMaps {
    fn new(ctx: &ShadowContext, sample: LightSample, o: &WilliamsOptions, counters: &mut Counters) -> LightMaps {
        let (lo, hi) = ctx.scene.bounds().unwrap_or((DVec3::ZERO, DVec3::ONE));
        let corners: Vec<DVec3> = (0..8)
            .map(|i| {
                DVec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let near = 1e-6 * ctx.extent;
        let pinhole = |eye: DVec3, axis: DVec3, up: DVec3, fov: f64| {
            let up = if axis.cross(up).length() < 1e-6 { axis.any_orthonormal_vector() } else { up };
            let cam = Camera {
                eye,
                target: eye + axis,
                up,
                fov_y: fov,
                width: o.map_size,
                height: o.map_size,
                near,
                far: None,
            };
            Projection::Perspective(View::new(&cam))
        };
        match sample {
            LightSample::Directional(d) => {
                counters.add("maps_ortho", 1);
                let u = d.any_orthonormal_vector();
                let v = d.cross(u);
                let range = |a: DVec3| {
                    corners
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), c| (l.min(c.dot(a)), h.max(c.dot(a))))
                };
                let ((u0, u1), (v0, v1), (s0, _)) = (range(u), range(v), range(d));
                let side = (u1 - u0).max(v1 - v0) * 1.01 + 1e-12;
                let proj = Projection::Ortho {
                    u,
                    v,
                    d,
                    u0: u0 - 0.005 * side,
                    v0: v1 + 0.005 * side,
                    s0: s0 - 0.01 * side,
                    texel: side / o.map_size as f64,
                };
                LightMaps::Single(DepthMap::render(ctx, proj, o.map_size, sample, o.cull_front))
            }
            LightSample::Point(s) => {
                let center = (lo + hi) * 0.5;
                let axis = (center - s).normalize_or(DVec3::NEG_Y);
                let half = corners
                    .iter()
                    .map(|c| (*c - s).normalize_or(axis).dot(axis).clamp(-1.0, 1.0).acos())
                    .fold(0.0, f64::max);
                if half < 80f64.to_radians() {
                    counters.add("maps_perspective", 1);
                    let proj = pinhole(s, axis, DVec3::Y, (2.0 * half).to_degrees() * 1.02 + 0.1);
                    LightMaps::Single(DepthMap::render(ctx, proj, o.map_size, sample, o.cull_front))
                } else {
                    counters.add("maps_cube_faces", 6);
                    let faces = CUBE.map(|(axis, up)| {
                        DepthMap::render(ctx, pinhole(s, axis, up, 90.0), o.map_size, sample, o.cull_front)
                    });
                    LightMaps::Cube(Box::new(faces))
                }
            }
        }
    }

    /// The map that holds `p`.
    fn map_for(&self, p: DVec3, sample: LightSample) -> &DepthMap {
        match self {
            LightMaps::Single(m) => m,
            LightMaps::Cube(faces) => {
                let LightSample::Point(s) = sample else { return &faces[0] };
                let v = p - s;
                let a = v.abs();
                let k = if a.x >= a.y && a.x >= a.z {
                    if v.x >= 0.0 {
                        0
                    } else {
                        1
                    }
                } else if a.y >= a.z {
                    if v.y >= 0.0 {
                        2
                    } else {
                        3
                    }
                } else if v.z >= 0.0 {
                    4
                } else {
                    5
                };
                &faces[k]
            }
        }
    }
}

/// The prepared stage.
pub struct Williams<'a> {
    ctx: &'a ShadowContext<'a>,
    options: WilliamsOptions,
    bias: f64,
    maps: Vec<LightMaps>,
    /// Soft-edge filter: each sample's blurred screen buffer.
    blurred: Vec<Vec<f32>>,
}

impl<'a> Williams<'a> {
    /// Pass 1 for every light sample (and, for the soft-edge filter, the screen buffers).
    pub fn new(ctx: &'a ShadowContext<'a>, counters: &mut Counters) -> Self {
        let options = ctx.options.williams.clone();
        let bias = options.bias.unwrap_or(1e-3 * ctx.extent);
        let samples: Vec<_> = ctx.all_samples().collect();
        let maps = samples.iter().map(|&(_, _, s)| LightMaps::new(ctx, s, &options, counters)).collect();
        counters.add("map_texels", (options.map_size as u64).pow(2));
        let mut stage = Williams { ctx, options, bias, maps, blurred: Vec::new() };
        if let ShadowFilter::SoftEdge(k) = stage.options.filter {
            stage.blurred =
                samples.iter().enumerate().map(|(i, &(l, s, _))| stage.soft_edge_buffer(i, l, s, k)).collect();
        }
        stage
    }

    /// Pass 2 for the pixels of `run` on line `line` (written to `out`): the
    /// filtered lit value of flat sample `k`. The visible point, in homogeneous form
    /// `(eye·D − dist·ray, D)` with `D = n·ray`, is linear in x along the line, so it is
    /// stepped rather than recomputed. The slope-scaled bias takes the polygon's angle to
    /// the light at its centroid, once per polygon, as `glPolygonOffset` does.
    fn lookup_run(&self, k: usize, sample: LightSample, line: u32, run: &Run, size: u32, out: &mut [f32]) {
        let (poly, x0) = (run.poly as usize, run.x0);
        let view = self.ctx.view;
        let plane = &self.ctx.scene.polygons[poly].plane;
        let yc = line as f64 + 0.5;
        let point_h = |xc: f64| {
            let ray = view.ray(xc, yc);
            let d = plane.n.dot(ray);
            (view.eye * d - ray * plane.distance(view.eye)).extend(d)
        };
        let mut h = point_h(x0 as f64 + 0.5);
        let step = point_h(x0 as f64 + 1.5) - h;
        // Keep w > 0 so the maps' divisions read the right way round.
        let flip = if h.w < 0.0 { -1.0 } else { 1.0 };
        let (h0, step) = (h * flip, step * flip);
        h = h0;
        let c = crate::geometry::centroid(self.ctx.scene.verts(poly));
        let (l, _) = sample.toward(c);
        let cos = plane.n.dot(l).abs().max(1e-3);
        let tan = ((1.0 - cos * cos).sqrt() / cos).min(10.0);
        for o in out.iter_mut() {
            let p = h.truncate() / h.w;
            let map = self.maps[k].map_for(p, sample);
            *o = match map.proj.locate(h) {
                Some((x, y, z)) => {
                    // A wider kernel reaches texels farther along the slope.
                    let reach = (size / 2 + 1) as f64;
                    let bias = self.bias + self.options.slope_bias * reach * map.proj.texel_size(z) * tan;
                    map.lit(x, y, z, bias, size)
                }
                None => 1.0,
            };
            h += step;
        }
    }

    /// Seed 002: the N×N PCF term of every visible pixel in a screen-sized buffer (1 where
    /// nothing is seen, or the sample is on the polygon's unseen side), blurred horizontally
    /// then vertically with the seed's 15 taps.
    fn soft_edge_buffer(&self, k: usize, light: usize, s: usize, size: u32) -> Vec<f32> {
        let view = self.ctx.view;
        let (w, h) = (view.width as usize, view.height as usize);
        let sample = self.ctx.samples[light][s];
        let mut term = vec![1.0f32; w * h];
        term.par_chunks_mut(w).zip(&self.ctx.runs.lines).enumerate().for_each(|(y, (row, runs))| {
            for run in runs {
                let plane = &self.ctx.scene.polygons[run.poly as usize].plane;
                if !sample.on_seen_side(plane, view.eye) {
                    row[run.x0 as usize..run.x1 as usize].fill(0.0);
                    continue;
                }
                self.lookup_run(k, sample, y as u32, run, size, &mut row[run.x0 as usize..run.x1 as usize]);
            }
        });
        let taps = seed_gaussian_taps();
        let horizontal = blur(&term, w, h, &taps, true);
        blur(&horizontal, w, h, &taps, false).into_iter().map(|v| v.clamp(0.0, 1.0)).collect()
    }
}

/// One pass of a separable blur over a `w×h` buffer, along rows or columns, with clamped
/// addressing at the borders (as a texture sampler clamps).
fn blur(src: &[f32], w: usize, h: usize, taps: &[(i64, f32)], along_rows: bool) -> Vec<f32> {
    let mut out = vec![0.0f32; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            *o = taps
                .iter()
                .map(|&(off, wt)| {
                    let (sx, sy) = if along_rows {
                        ((x as i64 + off).clamp(0, w as i64 - 1) as usize, y)
                    } else {
                        (x, (y as i64 + off).clamp(0, h as i64 - 1) as usize)
                    };
                    src[sy * w + sx] * wt
                })
                .sum();
        }
    });
    out
}

/// Seed 002's 15 taps (offset in pixels, weight): the centre weighted `G(0, ρ = 2)`, then for
/// i = 1, 3, …, 13 the offsets `+i` and `−i` weighted `2 G(i, 3)` and `2 G(i + 1, 3)`, with
/// `G(x, ρ) = exp(−x²/2ρ²)/√(2πρ²)`. Reproduced as published: the taps skip even offsets,
/// the two sides are weighted unequally, and the weights sum to about 1.07 (the blurred term
/// is clamped to [0, 1], as the seed's 8-bit render target does).
pub fn seed_gaussian_taps() -> Vec<(i64, f32)> {
    let g = |x: f64, rho: f64| (-(x * x) / (2.0 * rho * rho)).exp() / (2.0 * std::f64::consts::PI * rho * rho).sqrt();
    let mut taps = vec![(0i64, g(0.0, 2.0) as f32)];
    for i in (1..15).step_by(2) {
        taps.push((i, (2.0 * g(i as f64, 3.0)) as f32));
        taps.push((-i, (2.0 * g(i as f64 + 1.0, 3.0)) as f32));
    }
    taps
}

impl ShadowStage for Williams<'_> {
    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        Box::new(Walker { stage: self, lookups: 0, last: (0, 0, 0) })
    }
}

struct Walker<'s> {
    stage: &'s Williams<'s>,
    lookups: u64,
    /// The last run and the texels compared per pixel.
    last: (u32, u32, u32),
}

impl ShadowWalker for Walker<'_> {
    fn lit(&mut self, light: usize, sample: usize, line: u32, run: &Run, lit: &mut [f32]) {
        let st = self.stage;
        let k = st.ctx.sample_index(light, sample);
        let view = st.ctx.view;
        if let ShadowFilter::SoftEdge(_) = st.options.filter {
            let row = line as usize * view.width as usize;
            lit.copy_from_slice(&st.blurred[k][row + run.x0 as usize..row + run.x1 as usize]);
            return;
        }
        let size = match st.options.filter {
            ShadowFilter::Pcf(n) => n.max(1) | 1,
            _ => 1,
        };
        st.lookup_run(k, st.ctx.samples[light][sample], line, run, size, lit);
        self.lookups += lit.len() as u64;
        self.last = (run.x0, run.x1, size * size);
    }

    fn decision(&self) -> Decision {
        let (a, b, texels) = self.last;
        Decision { tested: vec![(a, b, texels)], note: format!("{} map lookup(s) of {texels} texel(s) each", b - a) }
    }

    fn finish(&mut self, counters: &mut Counters) {
        counters.add("map_lookups", self.lookups);
    }
}
