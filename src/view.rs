//! The view: the camera basis and pixel-centre rule of `docs/scene-format.md` section 3, clipping
//! of world polygons to the near (and far) plane, and perspective projection to screen space.
//!
//! Screen space is continuous pixel coordinates: x to the right, y down, pixel `(px, py)`
//! sampled at `(px + 0.5, py + 0.5)`. A planar polygon's inverse camera depth `1/z` is an
//! affine function of screen position; each screen polygon carries it, derived straight from
//! the world plane, so depth at a pixel centre is the exact ray-plane hit of section 3.

use crate::geometry::{clip_in_place, Plane};
use crate::scan::boundary;
use crate::scene::{Camera, Scene};
use glam::{DVec2, DVec3, DVec4};
use rayon::prelude::*;

/// Camera basis and projection.
#[derive(Debug, Clone, Copy)]
pub struct View {
    /// Eye position.
    pub eye: DVec3,
    /// Forward `f = normalize(target - eye)`.
    pub f: DVec3,
    /// Right `r = normalize(f x up)`.
    pub r: DVec3,
    /// Up `u = r x f`.
    pub u: DVec3,
    /// `tan(fov_y / 2)`.
    pub t: f64,
    /// Aspect `width / height`.
    pub aspect: f64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Near plane depth.
    pub near: f64,
    /// Far plane depth, if any.
    pub far: Option<f64>,
}

/// `1/z = a x + b y + c` over screen position `(x, y)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DepthPlane {
    /// d(1/z)/dx.
    pub a: f64,
    /// d(1/z)/dy.
    pub b: f64,
    /// 1/z at the screen origin.
    pub c: f64,
}

impl DepthPlane {
    /// Inverse depth at screen position `(x, y)`; larger is nearer.
    #[inline]
    pub fn inv_z(&self, x: f64, y: f64) -> f64 {
        self.a * x + self.b * y + self.c
    }
}

/// A polygon in screen space, ready to scan-convert; its ring is kept in its [`Screen`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScreenPolygon {
    /// Index of the scene polygon it came from.
    pub poly: u32,
    /// Its vertices in screen space (one ring; near/far clipping keeps a single ring):
    /// `points[start..start + len]` of its part of the [`Screen`].
    len: u32,
    start: usize,
    /// Its inverse depth over the screen.
    pub depth: DepthPlane,
}

/// How many bits of a screen polygon's number give its place in its part: a part holds at
/// most `1 << PART_BITS` polygons (those of one chunk of scene polygons). 1,024: s2's
/// 100,000 polygons make 98 chunks, six or more for each of sixteen threads (at 4,096 they
/// made 25, and half the threads clipped two while the rest waited).
const PART_BITS: u32 = 10;

/// The screen polygons of a view, in parts of at most `1 << PART_BITS`, each part's rings
/// stored one after another in one buffer (a million triangles are a million rings: one
/// allocation each would cost more than clipping them). The parts are clipped in parallel
/// and kept as they are, not joined into one list (a second copy of the screen, 43 MB on s3):
/// a polygon's number is its part's number, then its place in the part ([`PART_BITS`]), so
/// numbers increase in the order of the scene's polygons but are not all used. A frame lets
/// the camera's screen go once its visible runs are found, keeping only each part's size
/// ([`ScreenSizes`]), so that the next frame makes each part in one allocation.
#[derive(Debug, Clone, Default)]
pub(crate) struct Screen {
    parts: Vec<Part>,
    /// The parts in use (the rest are kept memory).
    used: usize,
    /// Each part's polygons and points in a screen let go before ([`Screen::sized`]).
    sizes: Vec<(usize, usize)>,
}

/// The size of each part of a screen let go ([`Screen::let_go`]): polygons and points.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct ScreenSizes(Vec<(usize, usize)>);

/// One part of a [`Screen`].
#[derive(Debug, Clone, Default)]
struct Part {
    polygons: Vec<ScreenPolygon>,
    points: Vec<DVec2>,
}

impl Part {
    fn push(&mut self, poly: u32, ring: &[DVec2], depth: DepthPlane) {
        let start = self.points.len();
        self.points.extend_from_slice(ring);
        self.polygons.push(ScreenPolygon { poly, len: ring.len() as u32, start, depth });
    }

    fn clear(&mut self) {
        self.polygons.clear();
        self.points.clear();
    }
}

impl Screen {
    /// Lets the screen's memory go, keeping the size of each part: what a frame keeps for
    /// the next, so that the screen (62 MB on s3) does not sit through the shadow
    /// preparation, and the next frame still grows no list ([`Screen::sized`]).
    pub fn let_go(self) -> ScreenSizes {
        ScreenSizes(self.parts[..self.used].iter().map(|p| (p.polygons.len(), p.points.len())).collect())
    }

    /// An empty screen whose parts [`View::screen_polygons_in`] makes at `sizes`.
    pub fn sized(sizes: ScreenSizes) -> Screen {
        Screen { sizes: sizes.0, ..Screen::default() }
    }

    /// Adds scene polygon `poly` with its screen `ring` and inverse depth.
    pub fn push(&mut self, poly: u32, ring: &[DVec2], depth: DepthPlane) {
        if self.used == 0 || self.parts[self.used - 1].polygons.len() >> PART_BITS != 0 {
            if self.parts.len() == self.used {
                self.parts.push(Part::default());
            }
            self.parts[self.used].clear();
            self.used += 1;
        }
        self.parts[self.used - 1].push(poly, ring, depth);
    }

    /// Polygon number `i` and its ring.
    #[inline]
    pub fn get(&self, i: u32) -> (&ScreenPolygon, &[DVec2]) {
        let part = &self.parts[(i >> PART_BITS) as usize];
        let p = &part.polygons[(i & ((1 << PART_BITS) - 1)) as usize];
        (p, &part.points[p.start..p.start + p.len as usize])
    }

    /// Every polygon with its number and its ring, in increasing number.
    pub fn iter(&self) -> impl Iterator<Item = (u32, &ScreenPolygon, &[DVec2])> {
        self.parts[..self.used].iter().enumerate().flat_map(|(k, part)| {
            part.polygons.iter().enumerate().map(move |(j, p)| {
                ((k as u32) << PART_BITS | j as u32, p, &part.points[p.start..p.start + p.len as usize])
            })
        })
    }

    /// Number of polygons.
    pub fn len(&self) -> usize {
        self.parts[..self.used].iter().map(|p| p.polygons.len()).sum()
    }

    /// For each band of `band` lines of an image `height` lines high, the polygons (numbers,
    /// increasing) that reach one of its lines' centres; polygons that reach none are in no
    /// band. Found in parallel, a few parts at a time.
    pub fn band_members(&self, height: u32, band: u32) -> Vec<Vec<u32>> {
        const PARTS: usize = 4;
        let bands = height.div_ceil(band) as usize;
        let parts: Vec<Vec<Vec<u32>>> = self.parts[..self.used]
            .par_chunks(PARTS)
            .enumerate()
            .map(|(c, parts)| {
                let mut lists = vec![Vec::new(); bands];
                for (k, part) in (c * PARTS..).zip(parts) {
                    for (j, p) in part.polygons.iter().enumerate() {
                        let ring = &part.points[p.start..p.start + p.len as usize];
                        let (lo, hi) = ring
                            .iter()
                            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| (lo.min(q.y), hi.max(q.y)));
                        let (first, end) = (boundary(lo, height), boundary(hi, height));
                        if first >= end {
                            continue;
                        }
                        let i = (k as u32) << PART_BITS | j as u32;
                        for list in &mut lists[(first / band) as usize..end.div_ceil(band) as usize] {
                            list.push(i);
                        }
                    }
                }
                lists
            })
            .collect();
        (0..bands)
            .into_par_iter()
            .map(|b| {
                let mut list = Vec::with_capacity(parts.iter().map(|p| p[b].len()).sum());
                for part in &parts {
                    list.extend_from_slice(&part[b]);
                }
                list
            })
            .collect()
    }
}

impl std::ops::Index<u32> for Screen {
    type Output = ScreenPolygon;
    fn index(&self, i: u32) -> &ScreenPolygon {
        self.get(i).0
    }
}

impl View {
    /// The view of `camera`.
    pub fn new(camera: &Camera) -> View {
        // Scaled before normalising, so that huge or tiny vectors neither overflow nor
        // underflow (the camera was validated: these are not zero).
        let f = crate::geometry::unit(camera.target - camera.eye).unwrap_or(DVec3::NEG_Z);
        let up = crate::geometry::unit(camera.up).unwrap_or(DVec3::Y);
        let r = f.cross(up).normalize();
        let u = r.cross(f);
        View {
            eye: camera.eye,
            f,
            r,
            u,
            t: (camera.fov_y.to_radians() / 2.0).tan(),
            aspect: camera.width as f64 / camera.height as f64,
            width: camera.width,
            height: camera.height,
            near: camera.near,
            far: camera.far,
        }
    }

    /// Camera coordinates `(x, y, z)` of a world point: along r, u and f.
    #[inline]
    pub fn to_camera(&self, p: DVec3) -> DVec3 {
        let v = p - self.eye;
        DVec3::new(v.dot(self.r), v.dot(self.u), v.dot(self.f))
    }

    /// Screen position of a camera-space point with `z > 0`.
    #[inline]
    pub fn project(&self, c: DVec3) -> DVec2 {
        let sx = c.x / c.z;
        let sy = c.y / c.z;
        DVec2::new(
            (sx / (self.t * self.aspect) + 1.0) * 0.5 * self.width as f64,
            (1.0 - sy / self.t) * 0.5 * self.height as f64,
        )
    }

    /// The ray direction through screen position `(x, y)`, scaled so its component along `f`
    /// is 1: the hit at parameter `s` has camera depth `s`.
    #[inline]
    pub fn ray(&self, x: f64, y: f64) -> DVec3 {
        let sx = (2.0 * x / self.width as f64 - 1.0) * self.t * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height as f64) * self.t;
        self.f + sx * self.r + sy * self.u
    }

    /// How [`View::ray`] changes from one pixel to the next along a line.
    #[inline]
    pub(crate) fn ray_step(&self) -> DVec3 {
        self.r * (2.0 * self.t * self.aspect / self.width as f64)
    }

    /// The world point on `plane` seen at screen position `(x, y)`.
    #[inline]
    pub fn point_on(&self, plane: &Plane, x: f64, y: f64) -> DVec3 {
        let d = self.ray(x, y);
        let s = -plane.distance(self.eye) / plane.n.dot(d);
        self.eye + s * d
    }

    /// Whether the eye lies in `plane`: it sees the plane edge-on, and it has no
    /// [`View::depth_plane`].
    #[inline]
    pub(crate) fn edge_on(&self, plane: &Plane) -> bool {
        plane.distance(self.eye) == 0.0
    }

    /// The inverse-depth plane of a world plane; `None` when the eye lies in it (edge-on).
    pub(crate) fn depth_plane(&self, plane: &Plane) -> Option<DepthPlane> {
        // The eye's distance to the plane, read once: zero when the eye sees it edge-on
        // ([`View::edge_on`]).
        let e = plane.distance(self.eye);
        if e == 0.0 {
            return None;
        }
        // 1/z = -(n.f + sx n.r + sy n.u) / e, with sx, sy affine in x, y.
        let k = -1.0 / e;
        let (nr, nu) = (plane.n.dot(self.r) * self.t * self.aspect, plane.n.dot(self.u) * self.t);
        Some(DepthPlane {
            a: k * nr * 2.0 / self.width as f64,
            b: -k * nu * 2.0 / self.height as f64,
            c: k * (plane.n.dot(self.f) - nr + nu),
        })
    }

    /// Clips a world polygon to `near <= z (<= far)` in camera space and projects it.
    /// Returns `false` (and leaves `out` empty) when nothing is left.
    pub(crate) fn clip_project(&self, verts: &[DVec3], scratch: &mut [Vec<DVec3>; 2], out: &mut Vec<DVec2>) -> bool {
        self.clip_project_to(verts, self.far, scratch, out)
    }

    /// A world point's place on screen as [`Self::clip_project_homogeneous`] gives a corner
    /// of a polygon it finds whole: through the camera on its own, by the same steps, so with
    /// the same bits (a shared edge's image is the same from every polygon on it).
    pub(crate) fn image(&self, p: DVec3) -> DVec2 {
        self.project(self.homogeneous_in_camera(p.extend(1.0)).truncate())
    }

    /// Camera coordinates of a homogeneous world point (`w` kept).
    #[inline]
    pub(crate) fn homogeneous_in_camera(&self, h: DVec4) -> DVec4 {
        let v = h.truncate() - self.eye * h.w;
        DVec4::new(v.dot(self.r), v.dot(self.u), v.dot(self.f), h.w)
    }

    /// Clips a polygon given in homogeneous world coordinates (`w = 0` for points at infinity,
    /// as shadow volumes extruded to infinity have) to the near plane and to a guard band
    /// 10⁴ times wider than the view, then projects it. The guard band keeps every point in
    /// front of the eye, so vanishing points project to finite (far off-screen) positions.
    /// `None` when nothing is left; else whether the outline is the polygon's corners, each
    /// by [`Self::homogeneous_in_camera`] and [`Self::project`], uncut.
    pub(crate) fn clip_project_homogeneous(
        &self,
        verts: &[DVec4],
        scratch: &mut [Vec<DVec4>; 2],
        out: &mut Vec<DVec2>,
    ) -> Option<bool> {
        out.clear();
        let [a, b] = scratch;
        a.clear();
        a.extend(verts.iter().map(|&h| self.homogeneous_in_camera(h)));
        let mut whole = true;
        for keeps in self.homogeneous_clips() {
            whole &= !clip_in_place(a, b, keeps);
        }
        if a.len() < 3 {
            return None;
        }
        out.extend(a.iter().map(|c| self.project(c.truncate())));
        out.iter().all(|p| p.is_finite()).then_some(whole)
    }

    /// Whether [`Self::clip_project_homogeneous`] would find polygon `verts` whole on screen
    /// (`Some(true)`: no corner outside a clip, every image finite), found from the corners
    /// alone without making the outline. `false` whenever it would not, and for a corner it
    /// cannot place.
    pub(crate) fn whole_on_screen(&self, verts: impl ExactSizeIterator<Item = DVec4>) -> bool {
        let clips = self.homogeneous_clips();
        verts.len() >= 3
            && verts.into_iter().all(|h| {
                let c = self.homogeneous_in_camera(h);
                clips.iter().all(|keeps| keeps(c) >= 0.0) && self.project(c.truncate()).is_finite()
            })
    }

    /// The half-spaces [`Self::clip_project_homogeneous`] keeps, as distances of a point in
    /// camera coordinates (`>= 0`: kept): the near plane, then the guard band's four sides.
    fn homogeneous_clips(&self) -> [impl Fn(DVec4) -> f64; 5] {
        let g = 1e4 * (self.t * self.aspect).max(self.t);
        let near = self.near;
        std::array::from_fn(move |k| {
            move |c: DVec4| match k {
                0 => c.z - near * c.w,
                1 => g * c.z - c.x,
                2 => g * c.z + c.x,
                3 => g * c.z - c.y,
                _ => g * c.z + c.y,
            }
        })
    }

    /// The near plane (normal along the view direction) and the corners of the part of it
    /// the image sees, grown by 1% so pixel centres at the border are inside.
    pub(crate) fn near_rectangle(&self) -> (Plane, [DVec3; 4]) {
        let c = self.eye + self.f * self.near;
        let (hx, hy) = (self.near * self.t * self.aspect * 1.01, self.near * self.t * 1.01);
        let corner = |sx: f64, sy: f64| c + self.r * (sx * hx) + self.u * (sy * hy);
        (Plane::new(self.f, c), [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)])
    }

    fn clip_project_to(
        &self,
        verts: &[DVec3],
        far: Option<f64>,
        scratch: &mut [Vec<DVec3>; 2],
        out: &mut Vec<DVec2>,
    ) -> bool {
        out.clear();
        let [a, b] = scratch;
        a.clear();
        a.extend(verts.iter().map(|&p| self.to_camera(p)));
        // The guard band (10⁴ times the view's width): a polygon reaching beyond it is cut
        // there, far off screen, so that screen coordinates stay small enough for the scan
        // converter's arithmetic. Polygons within it (all but huge ones) are not touched.
        let g = 1e4 * (self.t * self.aspect).max(self.t);
        let near = |c: DVec3| c.z - self.near;
        let far = far.map(|far| move |c: DVec3| far - c.z);
        let band: [fn(f64, DVec3) -> f64; 4] =
            [|g, c| g * c.z - c.x, |g, c| g * c.z + c.x, |g, c| g * c.z - c.y, |g, c| g * c.z + c.y];
        // Most polygons are inside every plane: one pass finds that, and no plane cuts them.
        let cut =
            |c: DVec3| near(c) < 0.0 || far.is_some_and(|f| f(c) < 0.0) || band.iter().any(|plane| plane(g, c) < 0.0);
        if a.iter().any(|&c| cut(c)) {
            clip_in_place(a, b, near);
            if let Some(far) = far {
                clip_in_place(a, b, far);
            }
            for plane in band {
                clip_in_place(a, b, |c| plane(g, c));
            }
        }
        if a.len() < 3 {
            return false;
        }
        out.extend(a.iter().map(|&c| self.project(c)));
        if !out.iter().all(|p| p.is_finite()) {
            out.clear();
            return false;
        }
        true
    }

    /// Which of the scene's closed solids lie wholly beyond the near plane: no polygon of
    /// theirs is clipped, so each ray from the eye that reaches a polygon of theirs turned
    /// away from the eye has met one facing it first ([`Scene::turned_away_on_solid`]). (A
    /// far plane clips the farther of the two first.)
    pub(crate) fn solids_past_near_plane(&self, scene: &Scene) -> Vec<bool> {
        let depth = |p: DVec3| (p - self.eye).dot(self.f);
        let corners = |s: &crate::scene::Solid| crate::geometry::box_corners(s.lo, s.hi);
        scene.solids.iter().map(|s| corners(s).iter().all(|&c| depth(c) > self.near)).collect()
    }

    /// Every polygon of the scene that survives clipping, in screen space.
    pub(crate) fn screen_polygons(&self, scene: &Scene) -> Screen {
        self.screen_polygons_in(scene, |_| true, Screen::default())
    }

    /// The scene polygons `keep` picks that survive clipping, in screen space, in the memory
    /// of `kept` (a screen of an earlier frame): clipped and projected in parallel, a part of
    /// the screen from each chunk of polygons.
    pub(crate) fn screen_polygons_in(
        &self,
        scene: &Scene,
        keep: impl Fn(usize) -> bool + Sync,
        mut kept: Screen,
    ) -> Screen {
        const CHUNK: usize = 1 << PART_BITS;
        kept.used = scene.polygons.len().div_ceil(CHUNK);
        if kept.parts.len() < kept.used {
            kept.parts.resize_with(kept.used, Part::default);
        }
        let (parts, sizes) = (&mut kept.parts[..kept.used], &kept.sizes);
        scene.polygons.par_chunks(CHUNK).zip(parts.par_iter_mut()).enumerate().for_each(|(c, (polygons, part))| {
            let (mut scratch, mut ring) = ([Vec::new(), Vec::new()], Vec::new());
            part.clear();
            if let Some(&(n, points)) = sizes.get(c) {
                part.polygons.reserve(n);
                part.points.reserve(points);
            }
            for (i, p) in (c * CHUNK..).zip(polygons).filter(|&(i, _)| keep(i)) {
                let Some(depth) = self.depth_plane(&p.plane) else {
                    continue;
                };
                if self.clip_project(scene.verts(i), &mut scratch, &mut ring) {
                    part.push(i as u32, &ring, depth);
                }
            }
        });
        kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> View {
        let mut cam = Camera::new(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO);
        cam.width = 64;
        cam.height = 48;
        View::new(&cam)
    }

    /// `whole_on_screen` says "whole" exactly where the clipper would find the polygon
    /// whole: random triangles and quads in front of the eye, across the near plane, beyond
    /// the guard band, behind the eye, and with corners at infinity (`w = 0`).
    #[test]
    fn whole_on_screen_is_what_the_clipper_finds_whole() {
        use rand::{Rng, SeedableRng};
        let v = view();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(40);
        let (mut scratch, mut out) = ([Vec::new(), Vec::new()], Vec::new());
        let mut seen = [0; 2];
        for _ in 0..20_000 {
            let n = rng.gen_range(3..=4);
            let spread = [0.5, 5.0, 1e5][rng.gen_range(0..3)];
            let verts: Vec<DVec4> = (0..n)
                .map(|_| {
                    let p = DVec3::new(
                        rng.gen_range(-spread..spread),
                        rng.gen_range(-spread..spread),
                        rng.gen_range(-8.0..5.2),
                    );
                    p.extend(if rng.gen_bool(0.1) { 0.0 } else { 1.0 })
                })
                .collect();
            let whole = v.whole_on_screen(verts.iter().copied());
            let clipped = v.clip_project_homogeneous(&verts, &mut scratch, &mut out);
            assert_eq!(whole, clipped == Some(true), "{verts:?}");
            seen[usize::from(whole)] += 1;
        }
        assert!(seen[0] > 1000 && seen[1] > 1000, "both kinds: {seen:?}");
    }

    #[test]
    fn projection_and_ray_agree() {
        let v = view();
        let p = DVec3::new(0.3, -0.2, 0.7);
        let s = v.project(v.to_camera(p));
        let d = v.ray(s.x, s.y);
        let c = v.to_camera(p);
        assert!((v.eye + c.z * d - p).length() < 1e-12);
    }

    #[test]
    fn a_screen_let_go_keeps_its_sizes_and_the_next_is_the_same() {
        let scene = crate::generate::cubes(3, crate::generate::Faces::Quads, 64, 48).unwrap();
        let view = View::new(&scene.camera);
        let first = view.screen_polygons_in(&scene, |_| true, Screen::default());
        let listed = |s: &Screen| s.iter().map(|(i, p, r)| (i, p.poly, r.to_vec())).collect::<Vec<_>>();
        let before = listed(&first);
        assert!(!before.is_empty());
        let sizes: Vec<(usize, usize)> =
            first.parts[..first.used].iter().map(|p| (p.polygons.len(), p.points.len())).collect();
        let kept = first.let_go();
        assert_eq!(kept, ScreenSizes(sizes.clone()));
        let again = view.screen_polygons_in(&scene, |_| true, Screen::sized(kept));
        assert_eq!(listed(&again), before);
        for (part, &(n, points)) in again.parts.iter().zip(&sizes) {
            assert!(part.polygons.capacity() >= n && part.points.capacity() >= points, "made at its size");
        }
    }

    #[test]
    fn depth_plane_matches_ray_hit() {
        let v = view();
        let n = DVec3::new(0.2, 0.5, 1.0).normalize();
        let plane = Plane::new(n, DVec3::new(0.1, 0.0, -0.5));
        let dp = v.depth_plane(&plane).unwrap();
        for &(x, y) in &[(3.5, 7.5), (40.5, 30.5), (63.5, 0.5)] {
            let p = v.point_on(&plane, x, y);
            let z = v.to_camera(p).z;
            assert!((dp.inv_z(x, y) - 1.0 / z).abs() < 1e-12);
        }
    }

    #[test]
    fn near_clipping_keeps_the_visible_part() {
        let v = view();
        // A floor-like quad running from behind the eye to far in front.
        let quad = [
            DVec3::new(-1.0, -1.0, 10.0),
            DVec3::new(1.0, -1.0, 10.0),
            DVec3::new(1.0, -1.0, -10.0),
            DVec3::new(-1.0, -1.0, -10.0),
        ];
        let mut scratch = [Vec::new(), Vec::new()];
        let mut out = Vec::new();
        assert!(v.clip_project(&quad, &mut scratch, &mut out));
        assert_eq!(out.len(), 4);
        assert!(out.iter().all(|p| p.is_finite()));
    }
}
