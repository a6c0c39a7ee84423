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
//!
//! Two paths compute this. The formulas below, [`incident`] and [`reflect`], are the
//! reference, in f64, point by point. The frame's runs go, wherever they can, through
//! the `lanes` module: a line at a time, eight pixels at a time in f32, each pixel's point
//! and interpolation parameter found from its place along its run (one division each),
//! the Phong pixels of all the line's runs lit together in full lanes, and powers through
//! `fast_pow`, whose error bound is stated and tested there. A run stays on the f64 path
//! when its line crosses the polygon's outline more than twice (a concave polygon), when
//! its points are too far from the eye for single precision (`LANE_REACH`), or, in Phong
//! mode, when a light sample is too close to the polygon's plane for its direction to be
//! found in single precision (`LANE_RATIO`). A test holds the two paths to each other on
//! every pixel of random scenes.

use crate::geometry::centroid;
use crate::scene::{Light, LightKind, LightSample, Material, Scene, ShadingMode, SpecularModel};
use crate::view::View;
use crate::visibility::Run;
use glam::{DVec3, Vec3};
use lanes::{LaneLight, LaneMaterial, LineLanes, RunGeometry, Toward};

mod fast_pow;
mod lanes;
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

/// `ks Os spec` alone: [`reflect`] without its diffuse term.
pub fn specular_term(m: &Material, n: DVec3, v: DVec3, l: DVec3) -> Vec3 {
    let nl = n.dot(l);
    if nl <= 0.0 {
        return Vec3::ZERO;
    }
    m.ks * m.specular_color * specular(m, n, v, l, nl) as f32
}

/// An area light's centre (`None` for other lights).
fn area_centre(light: &Light) -> Option<DVec3> {
    match light.kind {
        LightKind::Area { corner, edge_u, edge_v, .. } => Some(corner + 0.5 * (edge_u + edge_v)),
        _ => None,
    }
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

/// Shades the runs of a scene seen from a view, a line at a time.
pub(crate) struct Shader<'a> {
    scene: &'a Scene,
    view: &'a View,
    /// The terms the shading sums.
    terms: Vec<Term>,
    /// Every term as the lane kernels see it, with its position for point samples (checked
    /// against the polygon's plane, [`LANE_RATIO`]).
    lane_lights: Vec<LaneLight>,
    positions: Vec<Option<PointAt>>,
    /// Each material as the lane kernels see it.
    lane_materials: Vec<LaneMaterial>,
}

/// One term of the shading's sum: a light sample (its intensity the light's over `share`),
/// weighted by the lit values in row `row`; with `vector`, the centre of an area light,
/// whose diffuse term comes from the irradiance vectors in the three rows from `vector`.
#[derive(Debug, Clone, Copy)]
struct Term {
    light: usize,
    at: LightSample,
    share: usize,
    row: usize,
    vector: Option<usize>,
}

/// Scratch for shading lines, kept from line to line (one per band of lines).
#[derive(Debug, Default)]
pub(crate) struct LineShading {
    lanes: LineLanes,
    run: RunShading,
    /// Each run's [`Shader::triangle`] (zero for other polygons), made for the whole line
    /// before its first run is shaded (ours): the runs' reads, independent of one another,
    /// then wait on memory together, not one run after another (a line of s3 meets some
    /// five hundred triangles, most of them for the first time).
    triangles: Vec<[DVec3; 6]>,
    /// Whether each run is dark ([`Shader::dark`]), made with `triangles` (a dark run's
    /// triangle is not made).
    dark: Vec<bool>,
    /// Every run on the f64 path (the tests compare the two paths with it).
    f64_only: bool,
    /// Dark runs lit like the others (the tests compare the two with it).
    light_dark_runs: bool,
    /// Gouraud and Phong runs shaded in lanes and in f64, and dark runs left at their
    /// ambient term.
    runs_in_lanes: u64,
    runs_in_f64: u64,
    runs_dark: u64,
}

impl LineShading {
    /// The runs shaded so far that no light reached ([`Shader::dark`]).
    pub(crate) fn dark_runs(&self) -> u64 {
        self.runs_dark
    }
}

/// Per-run scratch: what one run needs whatever the light (reused from run to run).
#[derive(Debug, Default)]
struct RunShading {
    poly: usize,
    /// +1 or -1: turns the polygon's normals toward the viewer.
    flip: f64,
    /// The run's first pixel and its length, its line's centre, the normal of the line's
    /// scan plane, the ray through the line's first pixel centre, and its change from one
    /// pixel to the next.
    x0: u32,
    len: u32,
    yc: f64,
    scan_normal: DVec3,
    ray_row: DVec3,
    step: DVec3,
    /// The scan plane's crossings with the polygon's edges, sorted along `along`, the line
    /// where the polygon meets the scan plane.
    crossings: Vec<ScanCrossing>,
    along: DVec3,
    /// The signed distance of the eye from the run's plane.
    eye_distance: f64,
    /// The larger `|p - eye|` of the run's ends (for runs in lanes), the ray through its
    /// first pixel, and its plane's `depth` and `den` (see [`lanes`]).
    reach: f64,
    ray: DVec3,
    depth: f64,
    den: [f64; 2],
    /// The f64 path: world point seen at each pixel, its value as weights of up to four of
    /// the polygon's vertices, the interpolated unit normal (Phong mode), and the light.
    points: Vec<DVec3>,
    weights: Vec<[(u32, f64); 4]>,
    normals: Vec<DVec3>,
    light: Vec<Vec3>,
    /// Scratch: one value per polygon vertex (Gouraud mode).
    vertex_colors: Vec<Vec3>,
    /// What the lanes take of the run, written here in place (ours: a copy of a struct just
    /// made and returned waits on the stores that made it).
    geometry: RunGeometry,
}

/// Where an edge `k -> k+1` of the polygon meets the scan plane, at parameter `t` on the edge
/// and `u` along the line where the polygon meets the scan plane.
#[derive(Debug, Clone, Copy)]
struct ScanCrossing {
    u: f64,
    k: u32,
    t: f64,
}

/// A point light sample's position, and its distance from the eye.
type PointAt = (DVec3, f64);

/// Lanes take runs whose points lie within this distance of the eye, so that squared
/// lengths stay far inside single precision.
const LANE_REACH: f64 = 1e15;

/// ... and, in Phong mode, only where every point light sample is at least
/// 1/`LANE_RATIO` as far from the polygon's plane as it and the run's points are from the
/// eye: the vector from a pixel to the light is then found to a relative error below about
/// `LANE_RATIO · 2⁻²³`, 1.2·10⁻⁴.
const LANE_RATIO: f64 = 1000.0;

impl<'a> Shader<'a> {
    /// A shader for `scene` from `view`, with each light's samples (the tests': every light
    /// lit by its samples alone).
    #[cfg(test)]
    pub fn new(scene: &'a Scene, view: &'a View, samples: &'a [Vec<LightSample>]) -> Self {
        Self::with_irradiance(scene, view, samples, vec![None; scene.lights.len()])
    }

    /// The same, with each light `l` whose `vector_rows[l]` is given (an area light whose
    /// shadow stage gives each pixel its irradiance vector, in the three lit rows from it:
    /// `ShadowContext::vector_row`) shaded as one term at its centre: its diffuse term
    /// `kd Od I f_att(d) max(0, N · vector)` from the vector, its specular term that of a
    /// point light of the whole intensity at its centre, weighted by the light's lit value
    /// (its sample 0's row).
    pub fn with_irradiance(
        scene: &'a Scene,
        view: &'a View,
        samples: &'a [Vec<LightSample>],
        vector_rows: Vec<Option<usize>>,
    ) -> Self {
        let mut terms = Vec::new();
        let mut row = 0;
        for (l, (light, samples)) in scene.lights.iter().zip(samples).enumerate() {
            match area_centre(light).zip(vector_rows[l]) {
                Some((centre, vector_row)) => {
                    let vector = Some(vector_row);
                    terms.push(Term { light: l, at: LightSample::Point(centre), share: 1, row, vector });
                }
                None => terms.extend(samples.iter().enumerate().map(|(s, &at)| Term {
                    light: l,
                    at,
                    share: samples.len(),
                    row: row + s,
                    vector: None,
                })),
            }
            row += samples.len();
        }
        let (lane_lights, positions) = terms
            .iter()
            .map(|t| {
                let (lane, at) = lane_light(&scene.lights[t.light], &t.at, t.share, view.eye);
                let diffuse = if t.vector.is_some() { 0.0 } else { 1.0 };
                (LaneLight { diffuse, row: t.row, vector: t.vector, ..lane }, at.filter(|_| t.vector.is_none()))
            })
            .unzip();
        let lane_materials = scene.materials.iter().map(lane_material).collect();
        Shader { scene, view, terms, lane_lights, positions, lane_materials }
    }

    /// The ambient term `Ia ka Od` of polygon `poly`.
    pub fn ambient(&self, poly: usize) -> Vec3 {
        let m = self.scene.material(poly);
        self.scene.render.ambient * m.ka * m.color
    }

    /// Shades line `line`: its `runs` (in increasing x) from the lit values the shadow
    /// stage left, sample `k`'s at `lit[k * width + x]`, and the background between them,
    /// into `out`, the line's pixels.
    pub fn shade_line(&self, ls: &mut LineShading, line: u32, runs: &[Run], lit: &[f32], out: &mut [Vec3]) {
        let width = self.view.width as usize;
        ls.lanes.start(width, self.scene.render.background);
        let rs = &mut ls.run;
        rs.yc = line as f64 + 0.5;
        // The scan plane holds the eye and every ray of this scanline.
        rs.scan_normal = self.view.ray(0.0, rs.yc).cross(self.view.r);
        rs.ray_row = self.view.ray(0.5, rs.yc);
        rs.step = self.view.ray_step();
        ls.triangles.clear();
        ls.dark.clear();
        for run in runs {
            let dark = !ls.light_dark_runs && self.dark(run, lit, width);
            ls.dark.push(dark);
            ls.triangles.push(if dark { [DVec3::ZERO; 6] } else { self.triangle(run.poly as usize) });
        }
        for ((run, triangle), &dark) in runs.iter().zip(&ls.triangles).zip(&ls.dark) {
            let (x0, x1) = (run.x0 as usize, run.x1 as usize);
            let lit = |k: usize| &lit[k * width + x0..k * width + x1];
            ls.lanes.start_run(x0, x1, self.ambient(run.poly as usize));
            if dark {
                ls.runs_dark += 1;
                continue;
            }
            self.begin_run(run, rs);
            let in_lanes = match self.scene.material(rs.poly).shading {
                ShadingMode::Flat => {
                    self.flat_run(rs, &mut ls.lanes, lit);
                    continue;
                }
                ShadingMode::Gouraud => self.gouraud_run(rs, &mut ls.lanes, ls.f64_only, lit),
                ShadingMode::Phong => self.phong_run(rs, triangle, &mut ls.lanes, ls.f64_only, lit),
            };
            *(if in_lanes { &mut ls.runs_in_lanes } else { &mut ls.runs_in_f64 }) += 1;
        }
        ls.lanes.shade_phong(&self.lane_lights, &self.lane_materials, lit);
        ls.lanes.finish(out);
    }

    /// Whether no light reaches any pixel of `run` (ours): every term's lit values there,
    /// and an area light's irradiance vectors, are zero. Each term's light is weighted by
    /// them, and a zero weight adds nothing (both paths pass over it), so the run is its
    /// ambient term alone, and is not lit at all: a run in shadow, or turned from every
    /// light, costs its ambient term.
    fn dark(&self, run: &Run, lit: &[f32], width: usize) -> bool {
        let zero =
            |row: usize| lit[row * width + run.x0 as usize..row * width + run.x1 as usize].iter().all(|&v| v == 0.0);
        self.terms.iter().all(|t| zero(t.row) && t.vector.is_none_or(|v| (v..v + 3).all(zero)))
    }

    /// Readies `rs` for `run`, on the line `rs` was readied for.
    fn begin_run(&self, run: &Run, rs: &mut RunShading) {
        let poly = run.poly as usize;
        let plane = &self.scene.polygons[poly].plane;
        rs.poly = poly;
        rs.eye_distance = plane.distance(self.view.eye);
        rs.flip = if rs.eye_distance >= 0.0 { 1.0 } else { -1.0 };
        (rs.x0, rs.len) = (run.x0, run.x1 - run.x0);
    }

    /// The light of term `t` at a world point `p` with unit normal `n` (turned toward the
    /// viewer), in f64: its specular term alone for an area light's centre, whose diffuse
    /// term comes from irradiance vectors ([`Shader::lambert`]).
    fn shade(&self, poly: usize, t: &Term, p: DVec3, n: DVec3) -> Vec3 {
        let (to_light, radiance) = incident(&self.scene.lights[t.light], &t.at, t.share, p);
        let m = self.scene.material(poly);
        let v = (self.view.eye - p).normalize();
        if t.vector.is_some() {
            return radiance * specular_term(m, n, v, to_light);
        }
        radiance * reflect(m, n, v, to_light)
    }

    /// An area light's diffuse term (term `t`, its centre) from its irradiance vector
    /// `vector` at a point `p` with unit normal `n`: `kd Od I f_att(d) max(0, N · vector)`.
    fn lambert(&self, poly: usize, t: &Term, p: DVec3, n: DVec3, vector: DVec3) -> Vec3 {
        let (_, radiance) = incident(&self.scene.lights[t.light], &t.at, t.share, p);
        let m = self.scene.material(poly);
        radiance * m.kd * m.color * n.dot(vector).max(0.0) as f32
    }

    /// Adds the diffuse term of each area light lit from irradiance vectors to the run, at
    /// the points `point(i)` with normals `normal(i)`, the vectors read from `lit`'s rows.
    fn add_lambert<'l>(
        &self,
        rs: &mut RunShading,
        lanes: &mut LineLanes,
        lit: impl Fn(usize) -> &'l [f32],
        point: impl Fn(&RunShading, usize) -> DVec3,
        normal: impl Fn(&RunShading, usize) -> DVec3,
    ) {
        for t in &self.terms {
            let Some(row) = t.vector else { continue };
            let [x, y, z] = [lit(row), lit(row + 1), lit(row + 2)];
            let mut light = std::mem::take(&mut rs.light);
            light.clear();
            light.extend((0..rs.len as usize).map(|i| {
                let vector = DVec3::new(x[i] as f64, y[i] as f64, z[i] as f64);
                if vector == DVec3::ZERO {
                    return Vec3::ZERO;
                }
                self.lambert(rs.poly, t, point(rs, i), normal(rs, i), vector)
            }));
            lanes.add(rs.x0 as usize, &light);
            rs.light = light;
        }
    }

    /// Flat: one colour per sample, lit at the polygon's centroid with its plane normal.
    /// An area light's diffuse term from irradiance vectors: at the centroid too, with the
    /// plane normal, from each pixel's vector.
    fn flat_run<'l>(&self, rs: &mut RunShading, lanes: &mut LineLanes, lit: impl Fn(usize) -> &'l [f32] + Copy) {
        let centroid = centroid(self.scene.verts(rs.poly));
        let n = self.scene.polygons[rs.poly].plane.n * rs.flip;
        for t in &self.terms {
            lanes.add_flat(rs.x0 as usize, self.shade(rs.poly, t, centroid, n), lit(t.row));
        }
        self.add_lambert(rs, lanes, lit, |_, _| centroid, |_, _| n);
    }

    /// Gouraud: colours lit at the vertices, interpolated to the two crossings and along the
    /// run (in lanes when it can; else in f64). Returns whether it was in lanes.
    fn gouraud_run<'l>(
        &self,
        rs: &mut RunShading,
        lanes: &mut LineLanes,
        f64_only: bool,
        lit: impl Fn(usize) -> &'l [f32] + Copy,
    ) -> bool {
        self.scan_crossings(rs);
        let pair = if !f64_only && self.lane_geometry(rs) { self.crossing_pair(rs) } else { None };
        let in_lanes = pair.is_some();
        if let Some((l, r)) = pair {
            let (num, div) = self.s_between(rs, l, r);
            rs.geometry.s = [num, div].map(|v| v.map(|x| x as f32));
            lanes.gouraud_run(&rs.geometry, rs.len as usize);
        } else {
            self.prepare_f64(rs, false);
        }
        let verts = self.scene.verts(rs.poly);
        let vn = self.scene.vertex_normals(rs.poly);
        for t in &self.terms {
            let k = t.row;
            rs.vertex_colors.clear();
            rs.vertex_colors.extend(verts.iter().zip(vn).map(|(&p, &n)| self.shade(rs.poly, t, p, n * rs.flip)));
            if in_lanes {
                let at = |c: ScanCrossing| crossing_value(&rs.vertex_colors, c, |v| v.as_dvec3()).as_vec3();
                lanes.add_gouraud(rs.x0 as usize, at(rs.crossings[0]), at(rs.crossings[1]), lit(k));
                continue;
            }
            let (weights, colors) = (&rs.weights, &rs.vertex_colors);
            add_f64(&mut rs.light, lanes, rs.x0 as usize, lit(k), |i| {
                weights[i].iter().map(|&(k, a)| colors[k as usize] * a as f32).sum()
            });
        }
        // An area light's diffuse term from irradiance vectors has no value at the
        // vertices: at the centroid, with the plane normal, from each pixel's vector (as
        // flat).
        let (centroid, n) = (centroid(verts), self.scene.polygons[rs.poly].plane.n * rs.flip);
        self.add_lambert(rs, lanes, lit, |_, _| centroid, |_, _| n);
        in_lanes
    }

    /// Phong: normals interpolated and renormalised, lit per pixel: in lanes when the run
    /// and every light sample allow it (the lit pass of [`LineLanes::shade_phong`] then
    /// lights it with the rest of the line); else here, in f64. Returns whether it was in
    /// lanes.
    fn phong_run<'l>(
        &self,
        rs: &mut RunShading,
        barycentric: &[DVec3; 6],
        lanes: &mut LineLanes,
        f64_only: bool,
        lit: impl Fn(usize) -> &'l [f32] + Copy,
    ) -> bool {
        let triangle = self.scene.polygons[rs.poly].len == 3;
        if !triangle {
            self.scan_crossings(rs);
        }
        if !f64_only && self.lane_geometry(rs) && self.lights_fit_lanes(rs) {
            let normal = if triangle { self.triangle_normals(rs, barycentric) } else { self.crossing_normals(rs) };
            if let Some(normal) = normal {
                rs.geometry.normal = normal.map(|n| n.as_vec3().to_array());
                rs.geometry.plane = (self.scene.polygons[rs.poly].plane.n * rs.flip).as_vec3().to_array();
                let material = self.scene.material_index(rs.poly) as u32;
                lanes.phong_run(rs.x0 as usize, rs.len as usize, &rs.geometry, material);
                return true;
            }
        }
        if triangle {
            self.scan_crossings(rs);
        }
        self.prepare_f64(rs, true);
        for t in &self.terms {
            let (points, normals) = (&rs.points, &rs.normals);
            add_f64(&mut rs.light, lanes, rs.x0 as usize, lit(t.row), |i| {
                self.shade(rs.poly, t, points[i], normals[i])
            });
        }
        self.add_lambert(rs, lanes, lit, |rs, i| rs.points[i], |rs, i| rs.normals[i]);
        false
    }

    /// A triangle's interpolated normal at pixel `x0 + i` of the run, unnormalised:
    /// `N₀ + i N₁`, from its [`Shader::triangle`] `[e₀, e₁, e₂, n₀, n₁, n₂]`. The
    /// barycentric weight of vertex `k` seen along a ray `d` from the eye is
    /// `e_k·d / Σ e_j·d`, so the weighted sum of the vertex normals, times the denominator,
    /// is linear in `d` and so in `i`; the denominator's sign is the same over the
    /// triangle. Equal to the crossings' interpolation (linear along the edges, then along
    /// the scan plane), which for a triangle is barycentric.
    fn triangle_normals(&self, rs: &RunShading, t: &[DVec3; 6]) -> Option<[DVec3; 2]> {
        let [e0, e1, e2, n0, n1, n2] = *t;
        let sign = (e0 + e1 + e2).dot(rs.ray).signum() * rs.flip;
        let along = |d: DVec3| (n0 * e0.dot(d) + n1 * e1.dot(d) + n2 * e2.dot(d)) * sign;
        Some([along(rs.ray), along(rs.step)])
    }

    /// For triangle `poly`, `[e₀, e₁, e₂, n₀, n₁, n₂]`: `e_k` the cross product of its other
    /// two corners less the eye (`e₀ = b × c` and round), `n_k` its vertex normals; zero
    /// for other polygons.
    fn triangle(&self, poly: usize) -> [DVec3; 6] {
        match (self.scene.verts(poly), self.scene.vertex_normals(poly)) {
            (&[a, b, c], &[na, nb, nc]) => {
                let eye = self.view.eye;
                let [a, b, c] = [a - eye, b - eye, c - eye];
                [b.cross(c), c.cross(a), a.cross(b), na, nb, nc]
            }
            _ => [DVec3::ZERO; 6],
        }
    }

    /// A run's interpolated normal between its two crossings, unnormalised, as
    /// `N₀ + i N₁`: with `s = num/div`, `(1 − s) n_l + s n_r` times `div`.
    fn crossing_normals(&self, rs: &RunShading) -> Option<[DVec3; 2]> {
        let (l, r) = self.crossing_pair(rs)?;
        let (num, div) = self.s_between(rs, l, r);
        let vn = self.scene.vertex_normals(rs.poly);
        let at = |c: ScanCrossing| crossing_value(vn, c, |v| *v) * rs.flip;
        let (nl, nr) = (at(l), at(r));
        let sign = div[0].signum();
        Some([0, 1].map(|k| (nl * (div[k] - num[k]) + nr * num[k]) * sign))
    }

    /// Fills `rs.crossings` and `rs.along`.
    fn scan_crossings(&self, rs: &mut RunShading) {
        let verts = self.scene.verts(rs.poly);
        let plane = &self.scene.polygons[rs.poly].plane;
        let (eye, ns) = (self.view.eye, rs.scan_normal);
        rs.along = plane.n.cross(ns);
        rs.crossings.clear();
        // Each edge k -> k+1, the last one closing the ring (no division for the wrap).
        let mut a = verts[verts.len() - 1];
        let mut da = ns.dot(a - eye);
        for (k, &b) in verts.iter().enumerate() {
            let db = ns.dot(b - eye);
            if (da >= 0.0) != (db >= 0.0) {
                let t = da / (da - db);
                let c = a + (b - a) * t;
                let k = if k == 0 { verts.len() - 1 } else { k - 1 };
                rs.crossings.push(ScanCrossing { u: (c - eye).dot(rs.along), k: k as u32, t });
            }
            (a, da) = (b, db);
        }
        rs.crossings.sort_unstable_by(|a, b| a.u.total_cmp(&b.u));
    }

    /// Where the run's rays meet its polygon's plane, as the lanes take it (`rs.geometry`),
    /// if its points fit single precision ([`LANE_REACH`]); keeps the f64 values in `rs`
    /// for what follows. Returns whether they fit.
    fn lane_geometry(&self, rs: &mut RunShading) -> bool {
        let plane = &self.scene.polygons[rs.poly].plane;
        let step = rs.step;
        let ray = rs.ray_row + step * rs.x0 as f64;
        let depth = -rs.eye_distance;
        let den = [plane.n.dot(ray), plane.n.dot(step)];
        let reach2 = |i: f64| ((ray + step * i) * (depth / (den[0] + i * den[1]))).length_squared();
        rs.reach = reach2(0.0).max(reach2((rs.len - 1) as f64)).sqrt();
        if rs.reach.is_nan() || rs.reach >= LANE_REACH {
            return false;
        }
        (rs.ray, rs.depth, rs.den) = (ray, depth, den);
        let g = &mut rs.geometry;
        (g.ray, g.step) = (ray.as_vec3().to_array(), step.as_vec3().to_array());
        (g.depth, g.den) = (depth as f32, den.map(|x| x as f32));
        true
    }

    /// The run's two crossings, left to right, if its line crosses the outline just twice.
    fn crossing_pair(&self, rs: &RunShading) -> Option<(ScanCrossing, ScanCrossing)> {
        match rs.crossings[..] {
            [l, r] => Some((l, r)),
            _ => None,
        }
    }

    /// `s = (num₀ + i num₁) / (div₀ + i div₁)`, the place of pixel `x0 + i` between the
    /// crossings `l` and `r` (after [`Shader::lane_geometry`]): `s = (u − u_l) / (u_r − u_l)`
    /// with `u = depth (ray_i · along) / den_i`.
    fn s_between(&self, rs: &RunShading, l: ScanCrossing, r: ScanCrossing) -> ([f64; 2], [f64; 2]) {
        if r.u <= l.u {
            return ([0.5, 0.0], [1.0, 0.0]);
        }
        let (du, depth, den, step) = (r.u - l.u, rs.depth, rs.den, rs.step);
        let num = [depth * rs.ray.dot(rs.along) - l.u * den[0], depth * step.dot(rs.along) - l.u * den[1]];
        (num, [du * den[0], du * den[1]])
    }

    /// Whether every point light sample is far enough from the run's plane for the lanes
    /// ([`LANE_RATIO`]).
    fn lights_fit_lanes(&self, rs: &RunShading) -> bool {
        let plane = &self.scene.polygons[rs.poly].plane;
        self.positions.iter().flatten().all(|(p, from_eye)| {
            let far = from_eye + rs.reach;
            far < LANE_REACH && far < LANE_RATIO * plane.distance(*p).abs()
        })
    }

    /// The f64 path's points, weights and (Phong mode) normals.
    fn prepare_f64(&self, rs: &mut RunShading, phong: bool) {
        let plane = &self.scene.polygons[rs.poly].plane;
        rs.points.clear();
        let (x0, yc) = (rs.x0, rs.yc);
        rs.points.extend((x0..x0 + rs.len).map(|x| self.view.point_on(plane, x as f64 + 0.5, yc)));
        self.interpolation_weights(rs);
        if phong {
            let vn = self.scene.vertex_normals(rs.poly);
            rs.normals.clear();
            rs.normals.extend(rs.weights.iter().map(|w| {
                let n: DVec3 = w.iter().map(|&(k, a)| vn[k as usize] * a).sum();
                (n * rs.flip).normalize_or(plane.n * rs.flip)
            }));
        }
    }

    /// Fills `rs.weights`: each pixel's point as a blend of the two edge crossings of the scan
    /// plane that bracket it, each a blend of its edge's two vertices.
    fn interpolation_weights(&self, rs: &mut RunShading) {
        let n = self.scene.polygons[rs.poly].len;
        let eye = self.view.eye;
        rs.weights.clear();
        let pairs = rs.crossings.len() / 2;
        for p in &rs.points {
            let w = if pairs == 0 {
                // The scanline only grazes the polygon: fall back to its first vertex.
                [(0, 1.0), (0, 0.0), (0, 0.0), (0, 0.0)]
            } else {
                let u = (*p - eye).dot(rs.along);
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
                let next = |k: u32| (k + 1) % n;
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
}

/// The f64 path's light: adds `color(i)` times the lit value of every lit pixel `i` of the run
/// at `x0` (through `light`, scratch).
fn add_f64(light: &mut Vec<Vec3>, lanes: &mut LineLanes, x0: usize, lit: &[f32], color: impl Fn(usize) -> Vec3) {
    light.clear();
    light.extend(lit.iter().enumerate().map(|(i, &v)| if v == 0.0 { Vec3::ZERO } else { color(i) * v }));
    lanes.add(x0, light);
}

/// A channel that overflowed (to infinity, or to not-a-number through infinity times zero
/// or less infinity) becomes the largest finite value, as an overflow should look.
pub(crate) fn finite(c: Vec3) -> Vec3 {
    let f = |x: f32| if x.is_nan() { f32::MAX } else { x.clamp(-f32::MAX, f32::MAX) };
    Vec3::new(f(c.x), f(c.y), f(c.z))
}

/// The value at a scan crossing, between its edge's two vertices' values.
fn crossing_value<T>(values: &[T], c: ScanCrossing, get: impl Fn(&T) -> DVec3) -> DVec3 {
    let next = if c.k as usize + 1 == values.len() { 0 } else { c.k as usize + 1 };
    get(&values[c.k as usize]) * (1.0 - c.t) + get(&values[next]) * c.t
}

/// A light sample as the lanes see it, and, for a point, where it is and how far from the eye.
fn lane_light(light: &Light, sample: &LightSample, samples: usize, eye: DVec3) -> (LaneLight, Option<PointAt>) {
    let f32s = |v: DVec3| v.as_vec3().to_array();
    let (toward, position) = match *sample {
        LightSample::Point(p) => (Toward::Point(f32s(p - eye)), Some((p, (p - eye).length()))),
        LightSample::Directional(d) => (Toward::Direction(f32s(-d)), None),
    };
    let spot = match light.kind {
        LightKind::Spot { direction, cutoff, exponent, .. } => {
            Some((f32s(direction), cutoff.to_radians().cos() as f32, exponent as f32))
        }
        _ => None,
    };
    let radiance = (light.color * (light.intensity / samples as f32)).to_array();
    (
        LaneLight {
            toward,
            radiance,
            attenuation: light.attenuation.map(|a| a as f32),
            spot,
            diffuse: 1.0,
            row: 0,
            vector: None,
        },
        position,
    )
}

/// A material as the lanes see it.
fn lane_material(m: &Material) -> LaneMaterial {
    LaneMaterial {
        diffuse: (m.kd * m.color).to_array(),
        specular: (m.ks * m.specular_color).to_array(),
        model: m.model,
        shininess: m.shininess,
        m2: m.roughness * m.roughness,
        f0: m.fresnel,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every line of random scenes (convex and star-shaped polygons, point, spot,
    /// directional and area lights, every shading mode and specular model, area lights'
    /// diffuse terms from irradiance vectors on every other scene), shaded with the lanes
    /// and on the f64 path alone: every pixel agrees.
    #[test]
    fn lanes_agree_with_the_f64_path_on_random_scenes() {
        use crate::generate::{random, RandomOptions};
        use crate::visibility::{resolve_frame, VisibilityMethod};
        let (mut worst, mut in_lanes, mut in_f64, mut triangle_runs, mut lambert_lights) = (0.0f32, 0, 0, 0, 0);
        for seed in 0..40u64 {
            let mut scene = random(seed, RandomOptions { polygons: 8, width: 96, height: 72 }).unwrap();
            let mut materials = scene.materials().to_vec();
            for (i, m) in materials.iter_mut().enumerate() {
                let k = seed as usize + i;
                m.shading = [ShadingMode::Phong, ShadingMode::Gouraud, ShadingMode::Phong, ShadingMode::Flat][k % 4];
                m.model = [SpecularModel::Phong, SpecularModel::Blinn, SpecularModel::CookTorrance][k % 3];
                (m.ks, m.shininess, m.roughness) = (0.6, 5.0 + 20.0 * (k % 4) as f32, 0.3);
            }
            scene.set_materials(materials).unwrap();
            // Vertex normals that vary over each polygon, for the interpolation to show.
            for (n, v) in scene.normals.iter_mut().zip(&scene.vertices) {
                *n = (*n + 0.5 * DVec3::new((3.0 * v.x).sin(), (5.0 * v.y).cos(), (4.0 * v.z).sin())).normalize();
            }
            let view = View::new(&scene.camera);
            let samples: Vec<_> = scene.lights.iter().map(Light::samples).collect();
            // On every other scene, area lights' diffuse terms from irradiance vectors.
            let count: usize = samples.iter().map(Vec::len).sum();
            let lambert =
                |(l, light): (usize, &Light)| (seed % 2 == 0 && area_centre(light).is_some()).then_some(count + 3 * l);
            let rows: Vec<Option<usize>> = scene.lights.iter().enumerate().map(lambert).collect();
            lambert_lights += rows.iter().flatten().count();
            let shader = Shader::with_irradiance(&scene, &view, &samples, rows.clone());
            // A light lit by its vectors reads them from its rows, and its lit value from
            // its own sample 0's row.
            for t in shader.terms.iter().filter(|t| t.vector.is_some()) {
                assert_eq!(t.vector, rows[t.light]);
                assert_eq!(t.row, samples[..t.light].iter().map(Vec::len).sum::<usize>());
            }
            let (runs, _) = resolve_frame(&scene, VisibilityMethod::Scanline);
            triangle_runs += runs.lines.iter().flatten().filter(|r| scene.polygons[r.poly as usize].len == 3).count();
            let width = view.width as usize;
            let rows: usize = samples.iter().map(Vec::len).sum::<usize>() + 3 * samples.len();
            let (mut fast, mut slow) = (LineShading::default(), LineShading { f64_only: true, ..Default::default() });
            for (y, line) in runs.lines.iter().enumerate() {
                let lit: Vec<f32> = (0..rows * width).map(|i| [1.0, 0.0, 0.5, 1.0, -0.25][(i + y) % 5]).collect();
                let (mut a, mut b) = (vec![Vec3::ZERO; width], vec![Vec3::ZERO; width]);
                shader.shade_line(&mut fast, y as u32, line, &lit, &mut a);
                shader.shade_line(&mut slow, y as u32, line, &lit, &mut b);
                for (x, (a, b)) in a.iter().zip(&b).enumerate() {
                    let err = (*a - *b).abs().max_element() / b.abs().max_element().max(1.0);
                    assert!(err < 2e-5, "seed {seed}, pixel ({x}, {y}): lanes {a} f64 {b}");
                    worst = worst.max(err);
                }
            }
            (in_lanes, in_f64) = (in_lanes + fast.runs_in_lanes, in_f64 + fast.runs_in_f64);
            assert_eq!(slow.runs_in_lanes, 0);
        }
        assert!(in_lanes > 1000 && in_f64 > 50, "{in_lanes} runs in lanes, {in_f64} in f64");
        assert!(triangle_runs > 500, "{triangle_runs} runs on triangles");
        assert!(lambert_lights > 5, "{lambert_lights} area lights lit by irradiance vectors");
        eprintln!("worst difference {worst:e} over {in_lanes} runs in lanes, {triangle_runs} on triangles");
    }

    /// A dark run (no light reaches any of its pixels) comes out its ambient term alone,
    /// the same to the bit as when it is lit like the others: on random scenes in every
    /// shading mode and specular model, in lanes and in f64, with area lights' irradiance
    /// vectors on every other scene, and every other run dark.
    #[test]
    fn dark_runs_are_their_ambient_term_to_the_bit() {
        use crate::generate::{random, RandomOptions};
        use crate::visibility::{resolve_frame, VisibilityMethod};
        let (mut dark, mut lit_runs) = (0, 0);
        for seed in 0..24u64 {
            let mut scene = random(seed, RandomOptions { polygons: 8, width: 80, height: 60 }).unwrap();
            let mut materials = scene.materials().to_vec();
            for (i, m) in materials.iter_mut().enumerate() {
                let k = seed as usize + i;
                m.shading = [ShadingMode::Phong, ShadingMode::Gouraud, ShadingMode::Flat][k % 3];
                m.model = [SpecularModel::Phong, SpecularModel::Blinn, SpecularModel::CookTorrance][k % 3];
            }
            scene.set_materials(materials).unwrap();
            let view = View::new(&scene.camera);
            let samples: Vec<_> = scene.lights.iter().map(Light::samples).collect();
            let count: usize = samples.iter().map(Vec::len).sum();
            let vector =
                |(l, light): (usize, &Light)| (seed % 2 == 0 && area_centre(light).is_some()).then_some(count + 3 * l);
            let shader =
                Shader::with_irradiance(&scene, &view, &samples, scene.lights.iter().enumerate().map(vector).collect());
            let (runs, _) = resolve_frame(&scene, VisibilityMethod::Scanline);
            let (width, rows) = (view.width as usize, count + 3 * samples.len());
            for f64_only in [false, true] {
                let mut skipping = LineShading { f64_only, ..Default::default() };
                let mut lighting = LineShading { f64_only, light_dark_runs: true, ..Default::default() };
                for (y, line) in runs.lines.iter().enumerate() {
                    // Every other run dark in every row; the others lit in a pattern.
                    let mut lit = vec![0.0f32; rows * width];
                    for (k, run) in line.iter().enumerate().filter(|(k, _)| (k + y) % 2 == 0) {
                        for row in 0..rows {
                            for x in run.x0 as usize..run.x1 as usize {
                                lit[row * width + x] = [1.0, 0.5, 0.0, 0.25][(x + row + k) % 4];
                            }
                        }
                    }
                    let (mut a, mut b) = (vec![Vec3::ZERO; width], vec![Vec3::ZERO; width]);
                    shader.shade_line(&mut skipping, y as u32, line, &lit, &mut a);
                    shader.shade_line(&mut lighting, y as u32, line, &lit, &mut b);
                    assert_eq!(a, b, "seed {seed}, line {y}, f64 only: {f64_only}");
                }
                assert_eq!(lighting.runs_dark, 0);
                (dark, lit_runs) =
                    (dark + skipping.runs_dark, lit_runs + skipping.runs_in_lanes + skipping.runs_in_f64);
            }
        }
        assert!(dark > 1000 && lit_runs > 1000, "{dark} dark runs, {lit_runs} lit");
    }

    /// Background pixels between runs and after the last are the background colour, and a
    /// line shaded twice (scratch kept) comes out the same.
    #[test]
    fn a_line_is_background_outside_its_runs() {
        use crate::generate::{random, RandomOptions};
        use crate::visibility::{resolve_frame, VisibilityMethod};
        let mut scene = random(3, RandomOptions { polygons: 6, width: 61, height: 40 }).unwrap();
        scene.render.background = Vec3::new(0.25, 0.5, 0.75);
        let view = View::new(&scene.camera);
        let samples: Vec<_> = scene.lights.iter().map(Light::samples).collect();
        let shader = Shader::new(&scene, &view, &samples);
        let (runs, _) = resolve_frame(&scene, VisibilityMethod::Scanline);
        let count: usize = samples.iter().map(Vec::len).sum();
        let lit = vec![1.0; count * 61];
        let mut ls = LineShading::default();
        let mut gaps = 0;
        for (y, line) in runs.lines.iter().enumerate() {
            let mut out = vec![Vec3::splat(f32::NAN); 61];
            shader.shade_line(&mut ls, y as u32, line, &lit, &mut out);
            let mut again = vec![Vec3::ZERO; 61];
            shader.shade_line(&mut ls, y as u32, line, &lit, &mut again);
            assert_eq!(out, again);
            for (x, c) in out.iter().enumerate() {
                let covered = line.iter().any(|r| (r.x0..r.x1).contains(&(x as u32)));
                assert!(c.is_finite());
                if !covered {
                    assert_eq!(*c, scene.render.background, "pixel ({x}, {y})");
                    gaps += 1;
                }
            }
        }
        assert!(gaps > 100, "{gaps} background pixels");
    }

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
