//! Williams' two-pass z-buffer shadows (L. Williams, "Casting curved shadows on curved
//! surfaces", SIGGRAPH 1978; the "Rendering 6: Shadow", "Special Effect" and "Árnyékolás" notes and Shastry's "Soft-Edged Shadows"), with percentage-closer filtering
//! over a regular box of texels, Reeves, Salesin & Cook's stochastic percentage-closer
//! filtering (SIGGRAPH 1987), and the soft-edged screen-space blur of Shastry's "Soft-Edged Shadows".
//!
//! **Pass 1** renders the depth of the shadow casters from each light sample with the same
//! z-buffer loop as visibility (`raster::rasterize`): a perspective map aimed at
//! the scene when the scene lies within 80° of one direction from the sample (spot and point
//! lights outside the scene, area-light samples), a cube of six 90° maps when it surrounds
//! the sample, and an orthographic map fitted to the scene for a directional light. The map
//! covers the scene, not only a spot's cone, because the lit fraction is defined outside the
//! cone too. Optionally the polygons facing the light are culled (the "Special Effect" notes).
//!
//! **Pass 2** takes each visible point into the light's map and compares: `Z_map + bias <
//! Z_pixel` means shadow. Three remedies against acne combine (`docs/algorithms/williams.md`,
//! "The bias"): a constant; a **normal offset** (Holbert 2011), the lookup point moved along
//! the receiver's normal by a number of the map's texels at its depth (the default, 1); and a
//! **slope term** that follows the receiver polygon's depth slope in the map's own texel
//! space, as `glPolygonOffset` does: a planar polygon's nearness is affine in the texel
//! coordinates, `a·x + b·y + c`, so `slope_bias × (|a| + |b|) × (r + 1)` (r the filter
//! kernel's radius in texels) is exact everywhere on the polygon, with no cap (off by
//! default: at grazing angles it detaches shadows). Filters: `nearest` (one texel), `pcf`
//! (compare each of N×N texels,
//! then average the answers — never the depths), and `soft-edge` (Shastry's "Soft-Edged Shadows": the PCF term of
//! every pixel written to a screen-sized buffer, blurred by Shastry's separable 15-tap
//! Gaussian, and used when shading).

use super::{Decision, ShadowContext, ShadowStage, ShadowWalker, Texel};
use crate::error::{Error, Result};
use crate::geometry::Plane;
use crate::pool::Pool;
use crate::raster::rasterize;
use crate::scene::{Camera, LightSample};
use crate::stats::Counters;
use crate::view::{DepthPlane, Screen, View};
use crate::visibility::Run;
use glam::{DVec2, DVec3, DVec4};
use rayon::prelude::*;
use wide::f32x4;

/// How the shadow-map comparison is filtered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ShadowFilter {
    /// One texel, one comparison.
    Nearest,
    /// Percentage-closer filtering over a regular box of N×N texels (N odd): every texel of
    /// the box compared once, the form GPUs give.
    Pcf(u32),
    /// Reeves, Salesin & Cook's percentage-closer filtering as published (1987): N×N samples
    /// jittered over the same N-texel box (one at a random place in each of its N×N cells),
    /// each compared with the point's depth, the answers averaged. The random places follow
    /// from the point's position in the map, so a frame is the same at every thread count.
    Stochastic(u32),
    /// Shastry's "Soft-Edged Shadows": N×N PCF into a screen buffer, then the 15-tap separable Gaussian blur.
    SoftEdge(u32),
}

/// Options of Williams' shadow maps.
#[derive(Debug, Clone, PartialEq)]
pub struct WilliamsOptions {
    /// Texels along each side of a map.
    pub map_size: u32,
    /// Constant bias in world units along the light's axis; `None`: one texel of depth at
    /// the point (a texel's width there: it follows the map's resolution and the depth).
    pub bias: Option<f64>,
    /// Slope-scaled bias: this times the receiver's nearness change over the texels a
    /// lookup reaches, in each map's texel space (the `factor` of `glPolygonOffset`).
    pub slope_bias: f64,
    /// Normal offset (Holbert 2011): each lookup point is moved along the receiver's normal,
    /// toward the light's side, by this many of the map's texels at its depth (0: off).
    pub normal_offset: f64,
    /// Receiver-plane depth bias (Isidoro 2006): compare each texel of the filter's kernel
    /// with the receiver's plane extrapolated to it, not with the point's own depth.
    pub receiver_plane: bool,
    /// Filter.
    pub filter: ShadowFilter,
    /// Leave out polygons facing the light in pass 1 (the "Special Effect" notes).
    pub cull_front: bool,
    /// Fit each orthographic map, and each single perspective map, to the points the camera
    /// sees rather than to the whole scene (what production engines do; cube maps are not
    /// fitted).
    pub fit_to_view: bool,
}

impl Default for WilliamsOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl WilliamsOptions {
    /// The defaults: a 2048² map, a bias of one texel, a normal offset of one texel, one texel
    /// per lookup (no filter), maps fitted to the view; chosen by measurement over a family of
    /// scenes (`docs/algorithms/williams.md`, "The defaults").
    pub const DEFAULT: WilliamsOptions = WilliamsOptions {
        map_size: 2048,
        bias: None,
        slope_bias: 0.0,
        normal_offset: 1.0,
        receiver_plane: false,
        filter: ShadowFilter::Nearest,
        cull_front: false,
        fit_to_view: true,
    };
}

impl WilliamsOptions {
    /// The command-line flags that set these options apart from the defaults.
    pub(crate) fn flags(&self) -> Vec<String> {
        let d = WilliamsOptions::DEFAULT;
        let mut f = Vec::new();
        if self.map_size != d.map_size {
            f.push(format!("--map-size {}", self.map_size));
        }
        if let Some(b) = self.bias {
            f.push(format!("--bias {b}"));
        }
        if self.slope_bias != d.slope_bias {
            f.push(format!("--slope-bias {}", self.slope_bias));
        }
        if self.normal_offset != d.normal_offset {
            f.push(format!("--normal-offset {}", self.normal_offset));
        }
        if self.receiver_plane {
            f.push("--receiver-plane".into());
        }
        match self.filter {
            ShadowFilter::Nearest => {}
            ShadowFilter::Pcf(n) => f.push(format!("--shadow-filter pcf --pcf-size {n}")),
            ShadowFilter::Stochastic(n) => f.push(format!("--shadow-filter stochastic --pcf-size {n}")),
            ShadowFilter::SoftEdge(n) => f.push(format!("--shadow-filter soft-edge --pcf-size {n}")),
        }
        if self.cull_front {
            f.push("--cull-front".into());
        }
        if !self.fit_to_view {
            f.push("--no-fit".into());
        }
        f
    }

    /// The largest map side accepted (a 16,384² map takes a gigabyte).
    pub const MAX_MAP_SIZE: u32 = 16_384;

    /// The largest kernel side accepted for PCF and the soft-edged filter.
    pub const MAX_KERNEL: u32 = 63;

    /// Checks that the options can be carried out: a map side of 1 to
    /// [`Self::MAX_MAP_SIZE`] texels, an odd kernel side of 1 to [`Self::MAX_KERNEL`] and no
    /// wider than the map, and biases that are finite and not negative.
    pub fn check(&self) -> Result<()> {
        let fail = |setting: &str, value: &dyn std::fmt::Display, allowed: String| {
            Err(Error::out_of_range(format!("williams: {setting}"), value, allowed))
        };
        if !(1..=Self::MAX_MAP_SIZE).contains(&self.map_size) {
            return fail("map size", &self.map_size, format!("in 1..={}", Self::MAX_MAP_SIZE));
        }
        if let ShadowFilter::Pcf(n) | ShadowFilter::SoftEdge(n) | ShadowFilter::Stochastic(n) = self.filter {
            if n.is_multiple_of(2) || n > Self::MAX_KERNEL {
                return fail("kernel size", &n, format!("odd and in 1..={}", Self::MAX_KERNEL));
            }
            if n > self.map_size {
                return fail("kernel size", &n, format!("within the {0}x{0} map", self.map_size));
            }
        }
        for (name, v) in
            [("bias", self.bias.unwrap_or(0.0)), ("slope bias", self.slope_bias), ("normal offset", self.normal_offset)]
        {
            if !(v.is_finite() && v >= 0.0) {
                return fail(name, &v, "a finite number ≥ 0".into());
            }
        }
        Ok(())
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
    /// The rows taking a homogeneous world point `h = (w·p, w)` (`w > 0`) to `(X, Y, Z)`:
    /// texel coordinates `(X, Y) / q` with `q = Z` for a perspective map and `q = w` for an
    /// orthographic one, and depth `Z / w`. Along a run `h` is linear in x, so these are too.
    fn rows(&self) -> [DVec4; 3] {
        match self {
            Projection::Perspective(view) => {
                // Camera-space rows, then View::project with the division by depth left out.
                let row = |a: DVec3| a.extend(-a.dot(view.eye));
                let (r, u, f) = (row(view.r), row(view.u), row(view.f));
                let (half_w, half_h) = (0.5 * view.width as f64, 0.5 * view.height as f64);
                [r * (half_w / (view.t * view.aspect)) + f * half_w, f * half_h - u * (half_h / view.t), f]
            }
            Projection::Ortho { u, v, d, u0, v0, s0, texel } => {
                [(*u).extend(-u0) / *texel, (-*v).extend(*v0) / *texel, (*d).extend(-s0)]
            }
        }
    }

    /// A plane's nearness (what the map holds: `1/z`, or `−depth` for an orthographic map)
    /// as an affine function of the texel coordinates; `None` when the plane is edge-on to
    /// the light.
    fn depth_plane(&self, plane: &Plane) -> Option<DepthPlane> {
        match self {
            Projection::Perspective(view) => view.depth_plane(plane),
            Projection::Ortho { u, v, d, u0, v0, s0, texel } => {
                let nd = plane.n.dot(*d);
                if nd == 0.0 {
                    return None;
                }
                let o = *u * *u0 + *v * *v0 + *d * *s0;
                Some(DepthPlane {
                    a: texel * plane.n.dot(*u) / nd,
                    b: -texel * plane.n.dot(*v) / nd,
                    c: plane.distance(o) / nd,
                })
            }
        }
    }
}

/// The world points at the first and last pixel centre of every visible run, into `pts`
/// (a kept list; two a run, not finite where the run's plane passes through the eye): each
/// run is a segment of a planar polygon, so these bound every point the camera sees. Each
/// line fills its own stretch, by all threads.
fn visible_points(ctx: &ShadowContext, mut pts: Vec<DVec3>) -> Vec<DVec3> {
    let counts = || ctx.runs.lines.iter().map(|runs| 2 * runs.len());
    pts.clear();
    pts.par_extend(rayon::iter::repeat_n(DVec3::NAN, counts().sum()));
    let stretches = crate::pieces::stretches(&mut pts, counts());
    stretches.into_par_iter().zip(&ctx.runs.lines).enumerate().for_each(|(y, (out, runs))| {
        let yc = y as f64 + 0.5;
        for (out, r) in out.chunks_exact_mut(2).zip(runs) {
            let plane = &ctx.scene.polygons[r.poly as usize].plane;
            for (o, x) in out.iter_mut().zip([r.x0, r.x1.saturating_sub(1).max(r.x0)]) {
                *o = ctx.view.point_on(plane, x as f64 + 0.5, yc);
            }
        }
    });
    pts
}

/// The least and greatest of `f` over the finite points of `pts`, by all threads.
fn extent_of(pts: &[DVec3], f: impl Fn(DVec3) -> f64 + Sync) -> (f64, f64) {
    pts.par_iter()
        .filter(|p| p.is_finite())
        .fold(|| (f64::INFINITY, f64::NEG_INFINITY), |(l, h), &c| (l.min(f(c)), h.max(f(c))))
        .reduce(|| (f64::INFINITY, f64::NEG_INFINITY), |a, b| (a.0.min(b.0), a.1.max(b.1)))
}

/// The bias of one receiver polygon: `constant` in world units along the light's axis, and
/// `slope` times the receiver plane's nearness change over the texels a lookup reaches,
/// taken in each map's own texel space (the polygon offset of `glPolygonOffset`).
struct Bias {
    constant: f64,
    /// A constant in texels of depth: a perspective map's texel is `2·t/size` times the
    /// depth wide, an orthographic map's one `texel`.
    texels: f64,
    slope: f64,
    plane: Plane,
    /// The normal offset in texels, and the receiver's normal turned to the light's side.
    offset: f64,
    normal: DVec3,
    /// Compare each kernel texel with the receiver's plane extrapolated to it.
    receiver_plane: bool,
    /// Reeves et al.'s jittered samples instead of the regular box.
    stochastic: bool,
}

/// Texels added to each row of a map: rows a power of two apart would otherwise share
/// cache sets, and a kernel walking down the map would evict its own rows. The extra
/// columns hold what lies just beyond the map's edge, and are never read.
const PAD: u32 = 16;

/// A 64-bit mix (splitmix64's finaliser): the random places of
/// [`DepthMap::filter_stochastic`]'s samples, from a point's position and a cell.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// One depth map: the nearness of the nearest caster per texel (as rasterised: `1/z` for a
/// perspective map, `−depth` for an orthographic one; `−∞` where none was drawn).
struct DepthMap {
    proj: Projection,
    rows: [DVec4; 3],
    size: u32,
    nearness: Vec<f32>,
    /// Where the texels' memory goes back to (the renderer's pool: a real-time renderer
    /// keeps its shadow-map textures between frames too).
    storage: Pool<f32>,
}

impl Drop for DepthMap {
    fn drop(&mut self) {
        self.storage.give(std::mem::take(&mut self.nearness));
    }
}

impl DepthMap {
    /// Pass 1 for one projection.
    fn render(ctx: &ShadowContext, proj: Projection, sample: LightSample, o: &WilliamsOptions) -> DepthMap {
        let size = o.map_size;
        let scene = ctx.scene;
        let casts = |i: usize| {
            let plane = &scene.polygons[i].plane;
            scene.casts_shadows(i) && !(o.cull_front && sample.side_of(plane) > 0.0)
        };
        let screen = match &proj {
            Projection::Perspective(view) => view.screen_polygons_in(scene, casts, ctx.pools.stash.take()),
            Projection::Ortho { u, v, u0, v0, texel, .. } => {
                let (mut screen, mut ring) = (Screen::default(), Vec::new());
                for i in (0..scene.polygons.len()).filter(|&i| casts(i)) {
                    let Some(depth) = proj.depth_plane(&scene.polygons[i].plane) else { continue };
                    ring.clear();
                    ring.extend(
                        scene.verts(i).iter().map(|&p| DVec2::new((p.dot(*u) - u0) / texel, (v0 - p.dot(*v)) / texel)),
                    );
                    screen.push(i as u32, &ring, depth);
                }
                screen
            }
        };
        let storage = ctx.pools.f32.clone();
        let nearness = rasterize::<f32>(&screen, size + PAD, size, None, storage.take()).depth;
        ctx.pools.stash.put(screen);
        DepthMap { rows: proj.rows(), proj, size, nearness, storage }
    }

    /// The homogeneous point `h = (w·p, w)` moved along the receiver's normal by
    /// `bias.offset` texels of this map at its depth. A perspective map's texel at depth `z`
    /// (`z = rz·h / w`) is `2·t/size · z` wide, so the moved point `h + (n·k·rz·h, 0)` is
    /// linear in `h`, and a run's start and step can be moved alike.
    fn offset_point(&self, h: DVec4, bias: &Bias) -> DVec4 {
        if bias.offset == 0.0 {
            return h;
        }
        let shift = match &self.proj {
            Projection::Perspective(view) => 2.0 * view.t / view.height as f64 * self.rows[2].dot(h),
            Projection::Ortho { texel, .. } => texel * h.w,
        };
        h + (bias.normal * (bias.offset * shift)).extend(0.0)
    }

    /// Pass 2 along a run on the receiver plane `bias.plane`: the lit value at each point
    /// `h0 + i·step` (homogeneous, `w > 0`) under a `(2r+1)²` kernel. The run is taken in
    /// batches: first every point of a batch is located in the map, four at a time in vector
    /// registers, then every kernel is compared.
    fn lit_run(&self, h0: DVec4, step: DVec4, bias: &Bias, r: usize, batch: &mut Located, out: &mut [f32]) {
        let lookup = self.lookup(h0, step, bias, r);
        for (b, out) in out.chunks_mut(BATCH).enumerate() {
            self.locate(&lookup, b * BATCH, out.len(), r, batch);
            match lookup.receiver_plane {
                Some(gradient) => self.filter_receiver_plane(batch, r, gradient, out),
                None if bias.stochastic => self.filter_stochastic(batch, r, out),
                None => self.filter(batch, r, out),
            }
        }
    }

    /// What every point of a run shares: its start and step in light space, in single
    /// precision, and the bias terms.
    fn lookup(&self, h0: DVec4, step: DVec4, bias: &Bias, r: usize) -> Lookup {
        let [rx, ry, rz] = self.rows;
        let (h0, step) = (self.offset_point(h0, bias), self.offset_point(step, bias));
        // In single precision from here: its rounding (a few parts in 10⁷ of the depth) is
        // far below any bias, and the map holds single-precision nearness anyway.
        let at = |h: DVec4| DVec4::new(rx.dot(h), ry.dot(h), rz.dot(h), h.w).as_vec4().to_array();
        let (l0, dl) = (at(h0), at(step));
        // The slope-scaled term, in nearness: how much the receiver's own nearness changes
        // over the texels the kernel reaches (r + ½ each way, rounded up to r + 1).
        let plane = self.proj.depth_plane(&bias.plane);
        let slope = plane.map_or(0.0, |d| d.a.abs() + d.b.abs());
        let (b0, bs) = (bias.constant as f32, (bias.slope * slope * (r + 1) as f64) as f32);
        let receiver_plane = bias.receiver_plane.then(|| plane.map_or((0.0, 0.0), |d| (d.a as f32, d.b as f32)));
        // The constant in texels of depth: relative to the depth for a perspective map
        // (`b1`), absolute for an orthographic one (folded into `b0`).
        let (b0, b1) = match &self.proj {
            Projection::Perspective(view) => (b0, (bias.texels * 2.0 * view.t / view.height as f64) as f32),
            Projection::Ortho { texel, .. } => (b0 + (bias.texels * texel) as f32, 0.0),
        };
        Lookup { l0, dl, b0, b1, bs, receiver_plane }
    }

    /// Locates points `from..from + len` of a run (at most [`BATCH`]) in the map, four at a
    /// time in vector registers: their texel coordinates and the nearness above which a
    /// texel hides them.
    #[inline]
    fn locate(&self, lk: &Lookup, from: usize, len: usize, r: usize, batch: &mut Located) {
        let Lookup { l0, dl, b0, b1, bs, .. } = *lk;
        for g in 0..len.div_ceil(4) {
            let t = f32x4::splat((from + 4 * g) as f32) + f32x4::new([0.0, 1.0, 2.0, 3.0]);
            // The four points in light space.
            let [x, y, z, w] = [0, 1, 2, 3].map(|c| f32x4::splat(l0[c]) + f32x4::splat(dl[c]) * t);
            let (px, py, threshold) = match self.proj {
                // `Z_map + b0 + b1·z < z` means shadow, that is `1/Z_map > 1/(z(1 − b1)
                // − b0)` with `z = Z/w`; the slope term is added in nearness: the
                // threshold is `w / (Z(1 − b1) − b0·w) + bs`. A point behind the light, or within the bias of
                // it, is lit: it goes far outside the map.
                Projection::Perspective(_) => {
                    let denom = z * (1.0 - b1) - w * b0;
                    let ahead = z.simd_gt(0.0) & denom.simd_gt(0.0);
                    let q = f32x4::ONE / z;
                    let far = f32x4::splat(f32::NEG_INFINITY);
                    let threshold = w / denom + f32x4::splat(bs);
                    (ahead.select(x * q, far), ahead.select(y * q, far), ahead.select(threshold, -far))
                }
                // The map holds `−Z_map`: shadow when `−Z_map > b0 − z + bs`.
                Projection::Ortho { .. } => {
                    let q = f32x4::ONE / w;
                    (x * q, y * q, f32x4::splat(b0 + bs) - z * q)
                }
            };
            batch.put(g, px, py, threshold, r, self.size);
        }
    }

    /// The map as a picture at most `side` texels wide: nearer is brighter, black where
    /// nothing was drawn.
    fn picture(&self, side: u32) -> image::GrayImage {
        let (n, stride) = (self.size, (self.size + PAD) as usize);
        let step = n.div_ceil(side.max(1)).max(1);
        let at = |x: u32, y: u32| self.nearness[(y * step) as usize * stride + (x * step) as usize];
        let out = n.div_ceil(step);
        let finite =
            (0..out).flat_map(|y| (0..out).map(move |x| (x, y))).map(|(x, y)| at(x, y)).filter(|v| v.is_finite());
        let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        let span = (hi - lo).max(f32::MIN_POSITIVE);
        image::GrayImage::from_fn(out, out, |x, y| {
            let v = at(x, y);
            image::Luma([if v.is_finite() { (40.0 + 215.0 * (v - lo) / span) as u8 } else { 0 }])
        })
    }

    /// Point `i` of a run as [`Self::lit_run`] looks it up: where it falls in the map, the
    /// nearness recorded there and the point's threshold (for traces).
    fn texel(&self, lookup: &Lookup, i: usize, r: usize, batch: &mut Located) -> (f32, f32, Option<f32>, f32) {
        self.locate(lookup, i, 1, r, batch);
        let (u, v, threshold) = (batch.x[0][0], batch.y[0][0], batch.threshold[0][0]);
        let n = self.size as f32;
        let inside = (0.0..n).contains(&u) && (0.0..n).contains(&v);
        let stride = (self.size + PAD) as usize;
        let map = inside.then(|| self.nearness[v as usize * stride + u as usize]).filter(|m| m.is_finite());
        (u, v, map, threshold)
    }

    /// Receiver-plane depth bias (Isidoro 2006): each texel of the kernel is compared with
    /// the receiver's plane extrapolated to that texel's centre, `threshold + a·dx + b·dy`
    /// (`(a, b)` the receiver's nearness gradient in texels, `(dx, dy)` from the point to the
    /// texel's centre), so a wide kernel needs no slope allowance. Texels outside the map
    /// count as lit.
    fn filter_receiver_plane(&self, batch: &Located, r: usize, (a, b): (f32, f32), out: &mut [f32]) {
        let r = r as i64;
        let share = 1.0 / ((2 * r + 1) * (2 * r + 1)) as f32;
        Self::per_point(batch, out, |x, y, t| {
            let (cx, cy) = (x.floor() as i64, y.floor() as i64);
            let mut lit = 0u32;
            for ty in cy - r..=cy + r {
                for tx in cx - r..=cx + r {
                    let receiver = t + a * (tx as f32 + 0.5 - x) + b * (ty as f32 + 0.5 - y);
                    lit += u32::from(self.passes(tx, ty, receiver));
                }
            }
            lit as f32 * share
        });
    }

    /// Reeves, Salesin & Cook (1987): the `(2r+1)`-texel box around each located point cut
    /// into `(2r+1)²` cells, one sample at a random place in each (jittered sampling), each
    /// sample's texel compared with the point's threshold, the answers averaged. Texels outside
    /// the map count as lit. The paper's box is the pixel's footprint in the map; this stage
    /// uses the fixed box of the regular filter (ours), so the two differ only in where the
    /// samples fall.
    fn filter_stochastic(&self, batch: &Located, r: usize, out: &mut [f32]) {
        let width = 2 * r + 1;
        let share = 1.0 / (width * width) as f32;
        Self::per_point(batch, out, |x, y, t| {
            let seed = (u64::from(x.to_bits()) << 32) | u64::from(y.to_bits());
            let (x0, y0) = (x - width as f32 / 2.0, y - width as f32 / 2.0);
            let mut lit = 0u32;
            for cell in 0..width * width {
                let jitter = mix(seed ^ (cell as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
                let (jx, jy) =
                    ((jitter >> 40) as f32 / (1u64 << 24) as f32, (jitter & 0xff_ffff) as f32 / (1u64 << 24) as f32);
                let (sx, sy) = (x0 + (cell % width) as f32 + jx, y0 + (cell / width) as f32 + jy);
                lit += u32::from(self.passes(sx.floor() as i64, sy.floor() as i64, t));
            }
            lit as f32 * share
        });
    }

    /// Each located point's answer from `answer(x, y, threshold)` into `out`; 1 for a point
    /// with no place in the map (behind the light, or within the bias of it).
    fn per_point(batch: &Located, out: &mut [f32], mut answer: impl FnMut(f32, f32, f32) -> f32) {
        let len = out.len();
        let (xs, ys) = (&batch.x.as_flattened()[..len], &batch.y.as_flattened()[..len]);
        let thresholds = &batch.threshold.as_flattened()[..len];
        for (k, o) in out.iter_mut().enumerate() {
            let (x, y) = (xs[k], ys[k]);
            *o = if x.is_finite() && y.is_finite() { answer(x, y, thresholds[k]) } else { 1.0 };
        }
    }

    /// Whether texel `(tx, ty)` lets a point of threshold `t` through: it lies outside the
    /// map (nothing was recorded there) or holds nothing nearer than `t`.
    fn passes(&self, tx: i64, ty: i64, t: f32) -> bool {
        let (n, stride) = (self.size as i64, (self.size + PAD) as usize);
        let inside = (0..n).contains(&tx) && (0..n).contains(&ty);
        !inside || self.nearness[ty as usize * stride + tx as usize] <= t
    }

    /// Compares each texel of the `(2r+1)²` kernel around each located point with the
    /// point's threshold, then averages the answers — never the depths. Texels outside the
    /// map count as lit: nothing was recorded there.
    fn filter(&self, batch: &Located, r: usize, out: &mut [f32]) {
        let (n, stride) = (self.size as usize, (self.size + PAD) as usize);
        let width = 2 * r + 1;
        let share = 1.0 / (width * width) as f32;
        let len = out.len();
        let thresholds = &batch.threshold.as_flattened()[..len];
        let corners = batch.row.as_flattened().iter().zip(batch.col.as_flattened());
        let corners = corners.map(|(&row, &col)| row as usize * stride + col as usize);
        let kernels = out.iter_mut().zip(corners).zip(thresholds).map(|((o, c), &t)| (o, c, t));
        // Kernels wholly inside the map (the others, which start at 0, are redone below).
        match r {
            0 => {
                for (o, c, t) in kernels {
                    *o = f32::from(u8::from(self.nearness[c] <= t));
                }
            }
            // 3×3: each row's three texels and the one after them (which the row's padding
            // guarantees is there), compared four at a time, the fourth answer dropped.
            1 => {
                let keep = f32x4::new([1.0, 1.0, 1.0, 0.0]);
                for (o, c, t) in kernels {
                    let block = &self.nearness[c..c + 2 * stride + 4];
                    let row = |k: usize| {
                        let texels: [f32; 4] = block[k * stride..][..4].try_into().unwrap_or_default();
                        f32x4::new(texels).simd_le(t) & keep
                    };
                    *o = (row(0) + row(1) + row(2)).reduce_add() * share;
                }
            }
            _ => {
                let span = (width - 1) * stride + width;
                for (o, c, t) in kernels {
                    let block = &self.nearness[c..c + span];
                    let lit: u32 = (0..width)
                        .map(|row| {
                            block[row * stride..][..width].iter().map(|&texel| u32::from(texel <= t)).sum::<u32>()
                        })
                        .sum();
                    *o = lit as f32 * share;
                }
            }
        }
        // Kernels reaching over the edge, texel by texel, with points far outside kept far
        // enough that their kernel misses the map.
        let cell = |v: f32| v.clamp(-(width as f32), (n + width) as f32).floor() as i64;
        let (xs, ys) = (batch.x.as_flattened(), batch.y.as_flattened());
        let mut outside = batch.outside & (u64::MAX >> (BATCH - len));
        while outside != 0 {
            let i = outside.trailing_zeros() as usize;
            outside &= outside - 1;
            let (cx, cy, r) = (cell(xs[i]), cell(ys[i]), r as i64);
            let mut lit = 0;
            for ty in cy - r..=cy + r {
                for tx in cx - r..=cx + r {
                    let inside = (0..n as i64).contains(&tx) && (0..n as i64).contains(&ty);
                    let texel = || self.nearness[ty as usize * stride + tx as usize];
                    lit += u32::from(!inside || texel() <= thresholds[i]);
                }
            }
            out[i] = lit as f32 * share;
        }
    }
}

/// Points located in a map per batch (at most 64: [`Located::outside`] is a bit set).
const BATCH: usize = 64;

/// A batch of points located in a shadow map, in groups of four: texel coordinates, the
/// nearness above which a texel hides the point, and the texel where its `(2r+1)²` kernel
/// starts, for points whose kernel lies wholly inside the map (0 for the others, which
/// are marked in `outside`).
struct Located {
    x: [[f32; 4]; BATCH / 4],
    y: [[f32; 4]; BATCH / 4],
    threshold: [[f32; 4]; BATCH / 4],
    row: [[i32; 4]; BATCH / 4],
    col: [[i32; 4]; BATCH / 4],
    outside: u64,
}

impl Default for Located {
    fn default() -> Self {
        let zero = [[0.0; 4]; BATCH / 4];
        Located { x: zero, y: zero, threshold: zero, row: [[0; 4]; BATCH / 4], col: [[0; 4]; BATCH / 4], outside: 0 }
    }
}

impl Located {
    /// Stores group `g`, four points at texel coordinates `(x, y)` in a map `size` texels
    /// wide, for a kernel of radius `r`.
    #[inline(always)]
    fn put(&mut self, g: usize, x: f32x4, y: f32x4, threshold: f32x4, r: usize, size: u32) {
        let (lo, hi) = (r as f32, (size as usize).saturating_sub(r) as f32);
        let inside = x.simd_ge(lo) & y.simd_ge(lo) & x.simd_lt(hi) & y.simd_lt(hi);
        // Truncation is the floor for the points inside, where these are not negative.
        let corner = |v: f32x4| inside.select(v - lo, f32x4::ZERO).fast_trunc_int().to_array();
        (self.x[g], self.y[g], self.threshold[g]) = (x.to_array(), y.to_array(), threshold.to_array());
        (self.row[g], self.col[g]) = (corner(y), corner(x));
        let outside = u64::from(!inside.to_bitmask() & 0xf) << (4 * g);
        self.outside = self.outside & !(0xf << (4 * g)) | outside;
    }
}

/// What the points of one run share when they are looked up in a map.
#[derive(Debug, Clone, Copy)]
struct Lookup {
    l0: [f32; 4],
    dl: [f32; 4],
    b0: f32,
    b1: f32,
    bs: f32,
    receiver_plane: Option<(f32, f32)>,
}

/// A light sample's maps: one, or a cube of six.
enum LightMaps {
    Single(Box<DepthMap>),
    /// The six faces of [`CUBE`] around the light at the point.
    Cube(Box<[DepthMap; 6]>, DVec3),
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
    /// Pass 1 for one light sample: one orthographic map for a directional light, one
    /// perspective map for a point light whose window is narrow enough, else a cube of six.
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
        // What a map's window must cover: the whole scene, or (fitted) only the points the
        // camera sees. A caster that shadows a seen point lies on that point's way to the
        // light, inside the same window (the same strip of an orthographic map, the same cone
        // from a point light), so the fitted map loses nothing and spends its texels on what
        // is seen. Depth still spans the whole scene.
        let seen = if o.fit_to_view { visible_points(ctx, ctx.pools.points.take()) } else { Vec::new() };
        let covered = if seen.par_iter().any(|p| p.is_finite()) { &seen } else { &corners };
        let maps = match sample {
            LightSample::Directional(d) => {
                counters.add(crate::stats::Counter::MapsOrtho, 1);
                let proj = orthographic(across(ctx.view, d), d, covered, &corners, o.map_size);
                LightMaps::Single(Box::new(DepthMap::render(ctx, proj, sample, o)))
            }
            LightSample::Point(s) => {
                let (clo, chi) = covered
                    .par_iter()
                    .filter(|p| p.is_finite())
                    .fold(|| (DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &p| (l.min(p), h.max(p)))
                    .reduce(|| (DVec3::INFINITY, DVec3::NEG_INFINITY), |a, b| (a.0.min(b.0), a.1.max(b.1)));
                let axis = ((clo + chi) * 0.5 - s).normalize_or(DVec3::NEG_Y);
                // The widest angle from the axis: the smallest cosine, one arccosine.
                let (least, _) = extent_of(covered, |c| (c - s).normalize_or(axis).dot(axis));
                let half = least.min(1.0).clamp(-1.0, 1.0).acos();
                let near = 1e-6 * ctx.extent;
                if half < 80f64.to_radians() {
                    counters.add(crate::stats::Counter::MapsPerspective, 1);
                    let fov = (2.0 * half).to_degrees() * 1.02 + 0.1;
                    let proj = pinhole(s, axis, across(ctx.view, axis).cross(axis), fov, o.map_size, near);
                    LightMaps::Single(Box::new(DepthMap::render(ctx, proj, sample, o)))
                } else {
                    counters.add(crate::stats::Counter::MapsCubeFaces, 6);
                    let face =
                        |(axis, up)| DepthMap::render(ctx, pinhole(s, axis, up, 90.0, o.map_size, near), sample, o);
                    LightMaps::Cube(Box::new(CUBE.map(face)), s)
                }
            }
        };
        ctx.pools.points.give(seen);
        maps
    }

    /// Pass 2 along a run (see [`DepthMap::lit_run`]).
    fn lit_run(&self, h0: DVec4, step: DVec4, bias: &Bias, r: usize, batch: &mut Located, out: &mut [f32]) {
        self.pieces(h0, step, out.len(), |map, _, start, a, b| {
            map.lit_run(start, step, bias, r, batch, &mut out[a..b])
        });
    }

    /// Where each of a run's `len` points falls in the maps, as [`Self::lit_run`] looks it up.
    fn texels(&self, h0: DVec4, step: DVec4, bias: &Bias, r: usize, len: usize) -> Vec<Texel> {
        let (mut texels, mut batch) = (Vec::with_capacity(len), Box::<Located>::default());
        self.pieces(h0, step, len, |map, face, start, a, b| {
            let lookup = map.lookup(start, step, bias, r);
            for i in a..b {
                let (u, v, map, threshold) = map.texel(&lookup, i - a, r, &mut batch);
                texels.push(Texel { x: i as u32, face: face as u8, u, v, map, threshold });
            }
        });
        texels
    }

    /// Calls `f(map, start, a, b)` for the pieces `a..b` of a run of `len` points starting at
    /// `h0`, each with the map its points fall in and its first point: one piece, or for a
    /// cube, a piece wherever the face holding the points changes.
    fn pieces(&self, h0: DVec4, step: DVec4, len: usize, mut f: impl FnMut(&DepthMap, usize, DVec4, usize, usize)) {
        match self {
            LightMaps::Single(map) => f(map, 0, h0, 0, len),
            LightMaps::Cube(faces, s) => {
                let face = |i: usize| {
                    let h = h0 + step * i as f64;
                    cube_face(h.truncate() / h.w - *s)
                };
                let mut a = 0;
                while a < len {
                    let k = face(a);
                    let b = (a + 1..len).find(|&i| face(i) != k).unwrap_or(len);
                    f(&faces[k], k, h0 + step * a as f64, a, b);
                    a = b;
                }
            }
        }
    }
}

/// The direction across a map whose axis is `axis`: the eye's right vector seen from the
/// light. The map's rows are turned to run along the screen's rows, so that pass 2, walking a
/// screen row, walks along map rows and reads texels that share cache lines.
fn across(view: &View, axis: DVec3) -> DVec3 {
    let r = view.r - axis * axis.dot(view.r);
    if r.length() < 1e-6 {
        axis.any_orthonormal_vector()
    } else {
        r.normalize()
    }
}

/// A square map of `size` texels looking from `eye` along `axis` with a field of `fov`
/// degrees.
fn pinhole(eye: DVec3, axis: DVec3, up: DVec3, fov: f64, size: u32, near: f64) -> Projection {
    let up = if axis.cross(up).length() < 1e-6 { axis.any_orthonormal_vector() } else { up };
    let cam = Camera { eye, target: eye + axis, up, fov_y: fov, width: size, height: size, near, far: None };
    Projection::Perspective(View::new(&cam))
}

/// The orthographic map along `d` (rows along `u`) whose window covers `covered` and whose
/// depth starts before every corner of the scene.
fn orthographic(u: DVec3, d: DVec3, covered: &[DVec3], corners: &[DVec3], size: u32) -> Projection {
    let v = d.cross(u);
    let range = |pts: &[DVec3], a: DVec3| extent_of(pts, |c| c.dot(a));
    let ((u0, u1), (v0, v1), (s0, _)) = (range(covered, u), range(covered, v), range(corners, d));
    let side = (u1 - u0).max(v1 - v0) * 1.01 + 1e-12;
    Projection::Ortho {
        u,
        v,
        d,
        u0: u0 - 0.005 * side,
        v0: v1 + 0.005 * side,
        s0: s0 - 0.01 * side,
        texel: side / size as f64,
    }
}

/// The cube face (index into [`CUBE`]) whose axis is nearest direction `v`.
fn cube_face(v: DVec3) -> usize {
    let a = v.abs();
    let (axis, positive) = if a.x >= a.y && a.x >= a.z {
        (0, v.x >= 0.0)
    } else if a.y >= a.z {
        (1, v.y >= 0.0)
    } else {
        (2, v.z >= 0.0)
    };
    2 * axis + usize::from(!positive)
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
    pub fn new(ctx: &'a ShadowContext<'a>, options: &WilliamsOptions, counters: &mut Counters) -> Result<Self> {
        let options = options.clone();
        options.check()?;
        Self::check_memory(ctx, &options)?;
        let bias = options.bias.unwrap_or(0.0);
        let samples: Vec<_> = ctx.all_samples().collect();
        let maps = samples.iter().map(|&(_, _, s)| LightMaps::new(ctx, s, &options, counters)).collect();
        counters.add(crate::stats::Counter::MapTexels, (options.map_size as u64).pow(2));
        let mut stage = Williams { ctx, options, bias, maps, blurred: Vec::new() };
        if let ShadowFilter::SoftEdge(_) = stage.options.filter {
            stage.blurred = samples.iter().map(|&(l, s, _)| stage.soft_edge_buffer(l, s)).collect();
        }
        Ok(stage)
    }

    /// Refuses options whose maps (every light sample's, up to six for a point light's cube)
    /// and soft-edge buffers would not fit [`crate::budget::MEMORY_BUDGET`].
    fn check_memory(ctx: &ShadowContext, o: &WilliamsOptions) -> Result<()> {
        use crate::budget::mul;
        let pad = o.map_size as u64 + PAD as u64;
        let per_map = mul(pad, pad + 2) * 4;
        let maps: u64 = ctx
            .all_samples()
            .map(|(_, _, s)| match s {
                LightSample::Point(_) => 6,
                LightSample::Directional(_) => 1,
            })
            .sum();
        let mut bytes = mul(maps, per_map);
        if let ShadowFilter::SoftEdge(_) = o.filter {
            let screen = ctx.view.width as u64 * ctx.view.height as u64 * 4;
            bytes = bytes.saturating_add(mul(ctx.all_samples().count() as u64, screen));
        }
        crate::budget::check(format_args!("williams: {maps} shadow map(s) of {0}x{0} texels", o.map_size), bytes)
    }

    /// The radius of the filter's kernel, in texels.
    fn kernel_radius(&self) -> usize {
        match self.options.filter {
            ShadowFilter::Nearest => 0,
            ShadowFilter::Pcf(n) | ShadowFilter::SoftEdge(n) | ShadowFilter::Stochastic(n) => {
                (n.max(1) | 1) as usize / 2
            }
        }
    }

    /// Pass 2 for the pixels of `run` on line `line` (written to `out`): the
    /// filtered lit value of sample `s` of light `light`. The visible point, in homogeneous
    /// form `(eye·D − dist·ray, D)` with `D = n·ray`, is linear in the ray, so it is stepped
    /// along the line rather than recomputed. The slope-scaled bias follows the receiver's
    /// depth slope in each map, as `glPolygonOffset` does.
    fn lookup_run(&self, light: usize, s: usize, line: u32, run: &Run, batch: &mut Located, out: &mut [f32]) {
        let (h0, step, bias) = self.run_start(line, run);
        let map = &self.maps[self.ctx.sample_index(light, s)];
        map.lit_run(h0, step, &bias, self.kernel_radius(), batch, out);
    }

    /// A run's first point and step on its polygon's plane (homogeneous, `w > 0`), and the
    /// bias at its points.
    fn run_start(&self, line: u32, run: &Run) -> (DVec4, DVec4, Bias) {
        let poly = run.poly as usize;
        let view = self.ctx.view;
        let plane = &self.ctx.scene.polygons[poly].plane;
        let dist = plane.distance(view.eye);
        let point_h = |ray: DVec3| {
            let d = plane.n.dot(ray);
            (view.eye * d - ray * dist).extend(d)
        };
        let h0 = point_h(view.ray(run.x0 as f64 + 0.5, line as f64 + 0.5));
        let step = point_h(view.ray_step());
        // Keep w > 0 so the maps' divisions read the right way round.
        let flip = if h0.w < 0.0 { -1.0 } else { 1.0 };
        // The normal turned to the light's side, which the same-side rule makes the seen side.
        let normal = if dist >= 0.0 { plane.n } else { -plane.n };
        let bias = Bias {
            constant: self.bias,
            // Without a constant in world units, one texel of depth at the point.
            texels: if self.options.bias.is_some() { 0.0 } else { 1.0 },
            slope: self.options.slope_bias,
            plane: *plane,
            offset: self.options.normal_offset,
            normal,
            receiver_plane: self.options.receiver_plane,
            stochastic: matches!(self.options.filter, ShadowFilter::Stochastic(_)),
        };
        (h0 * flip, step * flip, bias)
    }

    /// Shastry's "Soft-Edged Shadows": the N×N PCF term of every visible pixel in a screen-sized buffer (1 where
    /// nothing is seen, or the sample is on the polygon's unseen side), blurred horizontally
    /// then vertically with Shastry's 15 taps.
    fn soft_edge_buffer(&self, light: usize, s: usize) -> Vec<f32> {
        let view = self.ctx.view;
        let (w, h) = (view.width as usize, view.height as usize);
        let sample = self.ctx.samples[light][s];
        let mut term = vec![1.0f32; w * h];
        term.par_chunks_mut(w).zip(&self.ctx.runs.lines).enumerate().for_each(|(y, (row, runs))| {
            let mut batch = Located::default();
            for run in runs {
                let plane = &self.ctx.scene.polygons[run.poly as usize].plane;
                if !sample.on_seen_side(plane, view.eye) {
                    row[run.x0 as usize..run.x1 as usize].fill(0.0);
                    continue;
                }
                self.lookup_run(light, s, y as u32, run, &mut batch, &mut row[run.x0 as usize..run.x1 as usize]);
            }
        });
        super::soft_edges::SoftEdges::default().blurred(&term, w, h)
    }
}

impl ShadowStage for Williams<'_> {
    /// The depth maps, and the soft-edge filter's screen buffers.
    fn bytes(&self) -> usize {
        let map = |m: &DepthMap| crate::pool::held(&m.nearness);
        let maps = self.maps.iter().map(|m| match m {
            LightMaps::Single(m) => map(m),
            LightMaps::Cube(faces, _) => faces.iter().map(map).sum(),
        });
        maps.sum::<usize>() + self.blurred.iter().map(crate::pool::held).sum::<usize>()
    }

    fn pictures(&self) -> Vec<super::Picture> {
        let mut out = Vec::new();
        for (light, sample, _) in self.ctx.all_samples() {
            let maps = &self.maps[self.ctx.sample_index(light, sample)];
            let faces: Vec<&DepthMap> = match maps {
                LightMaps::Single(map) => vec![map],
                LightMaps::Cube(faces, _) => faces.iter().collect(),
            };
            for (face, map) in faces.into_iter().enumerate() {
                out.push(super::Picture { light, sample, face, size: map.size, image: map.picture(512) });
            }
        }
        out
    }

    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        Box::new(Walker {
            stage: self,
            batch: Box::default(),
            lookups: 0,
            last: (0, 0, 0),
            last_run: (0, 0, 0, Run { x0: 0, x1: 0, poly: 0 }),
        })
    }
}

struct Walker<'s> {
    stage: &'s Williams<'s>,
    /// Room for the points being looked up.
    batch: Box<Located>,
    lookups: u64,
    /// The last run and the texels compared per pixel.
    last: (u32, u32, u32),
    /// The last run's light, sample and line, and the run.
    last_run: (usize, usize, u32, Run),
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
        st.lookup_run(light, sample, line, run, &mut self.batch, lit);
        let width = 2 * st.kernel_radius() as u32 + 1;
        self.lookups += lit.len() as u64;
        self.last = (run.x0, run.x1, width * width);
        self.last_run = (light, sample, line, *run);
    }

    fn decision(&self) -> Decision {
        let (a, b, texels) = self.last;
        let st = self.stage;
        let (light, sample, line, run) = self.last_run;
        let (h0, step, bias) = st.run_start(line, &run);
        let r = st.kernel_radius();
        let map = &st.maps[st.ctx.sample_index(light, sample)];
        let mut points = map.texels(h0, step, &bias, r, (run.x1 - run.x0) as usize);
        for t in &mut points {
            t.x += run.x0;
        }
        Decision {
            tested: vec![(a, b, texels)],
            note: format!("{} map lookup(s) of {texels} texel(s) each", b - a),
            detail: super::Detail::Texels { size: st.options.map_size, kernel: 2 * r as u32 + 1, texels: points },
        }
    }

    fn finish(&mut self, counters: &mut Counters) {
        counters.add(crate::stats::Counter::MapLookups, self.lookups);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_gaussian_weights() {
        let taps = crate::shadow::soft_edges::gaussian_taps();
        assert_eq!(taps.len(), 15);
        let offsets: Vec<i64> = taps.iter().map(|t| t.0).collect();
        assert_eq!(offsets, vec![0, 1, -1, 3, -3, 5, -5, 7, -7, 9, -9, 11, -11, 13, -13]);
        let sum: f32 = taps.iter().map(|t| t.1).sum();
        assert!((sum - 1.0665).abs() < 1e-3, "{sum}");
    }

    /// Pass 2's vector code against the same arithmetic one point at a time: for random
    /// runs through a perspective and an orthographic map, every lane of every batch holds
    /// the texel coordinates, threshold, corner texel and outside flag that the scalar
    /// formulas give, bit for bit.
    #[test]
    fn vector_lookup_equals_the_scalar_formulas() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1978);
        let size = 64u32;
        let maps = [
            pinhole(DVec3::new(0.0, 5.0, 0.0), DVec3::NEG_Y, DVec3::Z, 60.0, size, 1e-3),
            orthographic(
                DVec3::X,
                DVec3::NEG_Y,
                &[DVec3::splat(-2.0), DVec3::splat(2.0)],
                &[DVec3::splat(-2.0), DVec3::splat(2.0)],
                size,
            ),
        ];
        for proj in maps {
            let perspective = matches!(proj, Projection::Perspective(_));
            let map = DepthMap { proj, rows: [DVec4::ZERO; 3], size, nearness: Vec::new(), storage: Pool::default() };
            for _ in 0..200 {
                let mut v4 = |lo: f32, hi: f32| [0; 4].map(|_| rng.gen_range(lo..hi));
                let (l0, dl) = (v4(-80.0, 80.0), v4(-3.0, 3.0));
                let (b0, b1, bs) =
                    (rng.gen_range(0.0..0.1f32), rng.gen_range(0.0..0.01f32), rng.gen_range(0.0..0.1f32));
                let lk = Lookup { l0, dl, b0, b1, bs, receiver_plane: None };
                let (r, from, len) = (rng.gen_range(0..3usize), rng.gen_range(0..500usize), rng.gen_range(1..=BATCH));
                let mut batch = Located::default();
                map.locate(&lk, from, len, r, &mut batch);
                for i in 0..len {
                    let t = (from + i) as f32;
                    let [x, y, z, w] = [0, 1, 2, 3].map(|c| l0[c] + dl[c] * t);
                    let (px, py, threshold) = if perspective {
                        let denom = z * (1.0 - b1) - w * b0;
                        if z > 0.0 && denom > 0.0 {
                            let q = 1.0 / z;
                            (x * q, y * q, w / denom + bs)
                        } else {
                            (f32::NEG_INFINITY, f32::NEG_INFINITY, f32::INFINITY)
                        }
                    } else {
                        let q = 1.0 / w;
                        (x * q, y * q, (b0 + bs) - z * q)
                    };
                    let (g, l) = (i / 4, i % 4);
                    let got = (batch.x[g][l], batch.y[g][l], batch.threshold[g][l]);
                    assert_eq!(
                        [got.0.to_bits(), got.1.to_bits(), got.2.to_bits()],
                        [px.to_bits(), py.to_bits(), threshold.to_bits()],
                        "point {i}: {got:?} against {:?}",
                        (px, py, threshold)
                    );
                    let (lo, hi) = (r as f32, (size as usize - r) as f32);
                    let inside = px >= lo && py >= lo && px < hi && py < hi;
                    assert_eq!(batch.outside >> i & 1 == 1, !inside, "point {i} at ({px}, {py})");
                    if inside {
                        assert_eq!((batch.col[g][l], batch.row[g][l]), ((px - lo) as i32, (py - lo) as i32));
                    }
                }
            }
        }
    }
}
