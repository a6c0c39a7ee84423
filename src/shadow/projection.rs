//! Shadow projection: a polygon projected from a light sample onto a plane (the "Special Effect" notes'
//! `Q = L − (P − L)(N·L + d)/(N·(P − L))`; for a directional light the parallel projection of
//! the "Árnyékolás" notes' `M_par`), clipped so that only what lies between the light and the plane is
//! projected and the result stays within a rectangle of the plane. Bouknight-Kelley projects
//! onto each receiver; Crow projects onto the near plane for the eye's count.

use crate::geometry::{clip_polygon, newell_normal, Plane};
use crate::scene::{LightSample, Scene};
use glam::{DVec2, DVec3};

/// +1 or −1: the sign of `plane.distance` on the light's side of the plane.
pub fn light_side(plane: &Plane, sample: LightSample) -> f64 {
    if sample.side_of(plane) >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// Whether the light lies in polygon `i`'s plane (to a relative 1e-12): its shadow has no area.
pub fn edge_on(scene: &Scene, i: usize, sample: LightSample, extent: f64) -> bool {
    sample.side_of(&scene.polygons[i].plane).abs() <= edge_on_below(sample, extent)
}

/// The size of [`LightSample::side_of`] at or below which the light lies in a plane
/// ([`edge_on`]) in a scene `extent` across: a distance of `1e-12 * extent` from a point
/// light, a cosine of `1e-12` with a directional light's direction.
fn edge_on_below(sample: LightSample, extent: f64) -> f64 {
    match sample {
        LightSample::Point(_) => 1e-12 * extent,
        LightSample::Directional(_) => 1e-12,
    }
}

/// `unseen[i]`: whether light sample `sample` need not consider polygon `i`, found in
/// parallel: the light lies in its plane ([`edge_on`]: no lit area, no shadow), or, with
/// `cull`, it is a polygon of a closed solid that casts shadows, turned away from the light
/// ([`casters`]: unlit, and it hides nothing its solid's polygons turned to the light do
/// not; ours, not the papers').
pub fn unseen(scene: &Scene, sample: LightSample, extent: f64, cull: bool) -> Vec<bool> {
    use rayon::prelude::*;
    let closed = if cull { scene.closed_from(sample) } else { Vec::new() };
    let below = edge_on_below(sample, extent);
    // The light's side of each plane is found once for both tests.
    (0..scene.polygons.len())
        .into_par_iter()
        .map(|i| {
            let side = sample.side_of(&scene.polygons[i].plane);
            side.abs() <= below || (scene.casts_shadows(i) && scene.turned_away_at(i, side, &closed))
        })
        .collect()
}

/// The polygons that cast shadows for light sample `sample` and do not lie edge-on to it
/// ([`edge_on`]), in increasing order, split in two: where `cull` is set, those of a closed
/// solid turned away from the light, the sample outside the solid's bounds
/// ([`Scene::turned_away_on_solid`]); and the others. Returns `(kept, turned away)`.
///
/// A polygon turned away never needs to cast: a shadow ray that crosses it has crossed,
/// nearer the light, a polygon of the same solid that faces the light; and it is never lit,
/// for the same reason. A solid that casts no shadow hides nothing, so its polygons turned
/// away are lit through it (`tests/data/awg-area/wrong_120218.toml`, an inward-wound
/// icosahedron that casts none); they are not casters here. The light's side of each plane
/// is found once for both tests (ours).
pub(crate) fn casters(scene: &Scene, sample: LightSample, extent: f64, cull: bool) -> (Vec<u32>, Vec<u32>) {
    use rayon::iter::Either;
    use rayon::prelude::*;
    let closed = if cull { scene.closed_from(sample) } else { Vec::new() };
    let below = edge_on_below(sample, extent);
    (0..scene.polygons.len() as u32)
        .into_par_iter()
        .filter_map(|i| {
            let side = scene.casts_shadows(i as usize).then(|| sample.side_of(&scene.polygons[i as usize].plane))?;
            (side.abs() > below).then(|| (i, scene.turned_away_at(i as usize, side, &closed)))
        })
        .partition_map(|(i, away)| if away { Either::Right(i) } else { Either::Left(i) })
}

/// A bounded piece of a plane that polygons are projected onto from one light sample: the
/// plane, a rectangle of it, and the pyramid from the light over the rectangle (a prism for
/// a directional light), worked out once for all the polygons projected onto it.
#[derive(Debug, Clone)]
pub struct Target {
    /// The plane projected onto.
    pub plane: Plane,
    /// The rectangle of the plane that the shadows are kept within.
    pub rect: [DVec3; 4],
    pub(crate) sample: LightSample,
    /// [`light_side`] of the plane.
    pub(crate) side: f64,
    /// The faces of the pyramid from the light over `rect`, each as (a point on it, its
    /// inward normal).
    pyramid: [(DVec3, DVec3); 4],
}

impl Target {
    /// The rectangle `rect` of `plane`, lit by `sample`.
    pub fn new(plane: Plane, rect: [DVec3; 4], sample: LightSample) -> Self {
        let center = rect.iter().sum::<DVec3>() / 4.0;
        let pyramid = std::array::from_fn(|k| {
            let (q0, q1) = (rect[k], rect[(k + 1) % 4]);
            let (origin, m) = match sample {
                LightSample::Point(s) => (s, (q0 - s).cross(q1 - s)),
                LightSample::Directional(d) => (q0, (q1 - q0).cross(d)),
            };
            (origin, if m.dot(center - origin) >= 0.0 { m } else { -m })
        });
        Target { plane, rect, sample, side: light_side(&plane, sample), pyramid }
    }

    /// Point `x` projected from the light onto the plane (`x` between the light and the
    /// plane).
    #[inline]
    pub fn onto(&self, x: DVec3) -> DVec3 {
        let plane = &self.plane;
        match self.sample {
            LightSample::Point(s) => s + (x - s) * (-plane.distance(s) / plane.n.dot(x - s)),
            LightSample::Directional(d) => x - d * (plane.distance(x) / plane.n.dot(d)),
        }
    }

    /// Whether polygon `verts` lies wholly outside one face of the pyramid: then
    /// [`Projector::project`] would find nothing, and need not be asked.
    pub fn misses(&self, verts: &[DVec3]) -> bool {
        self.pyramid.iter().any(|&(origin, m)| verts.iter().all(|&x| m.dot(x - origin) < 0.0))
    }

    /// Whether the box `(lo, hi)` lies wholly outside one face of the pyramid, by a margin
    /// (a relative 1e-9) that rounding cannot cross: then [`Target::misses`] holds for every
    /// polygon whose corners lie in the box (ours: a whole piece of polygons is passed over).
    pub fn misses_box(&self, (lo, hi): (DVec3, DVec3)) -> bool {
        let corners = crate::geometry::box_corners(lo, hi);
        self.pyramid.iter().any(|&(origin, m)| {
            let reach = corners.iter().map(|&c| (c - origin).length()).fold(0.0, f64::max) + origin.length();
            let margin = 1e-9 * m.length() * reach;
            margin.is_finite() && corners.iter().all(|&c| m.dot(c - origin) < -margin)
        })
    }
}

/// Projects polygons from a light sample onto a [`Target`], keeping the scratch space
/// between calls.
#[derive(Debug, Default)]
pub struct Projector {
    /// The last shadow made, in world space.
    pub shadow: Vec<DVec3>,
    /// Whether the last shadow was cut by a clip: else it is the polygon's corners, each
    /// projected by [`Target::onto`].
    pub clipped: bool,
    scratch: Vec<DVec3>,
}

impl Projector {
    /// The shadow of polygon `verts` on `target`, into `self.shadow` (world space). Only the
    /// part of the polygon between the light and the plane can cast it: the polygon is
    /// clipped by the plane (keeping the light's side), for a point light by the plane
    /// through the light parallel to it, and by the target's pyramid, which keeps the
    /// projection finite; then projected from the light onto the plane. `false` when nothing
    /// is left or the shadow has no area.
    pub fn project(&mut self, verts: &[DVec3], target: &Target) -> bool {
        let (plane, side) = (&target.plane, target.side);
        self.clipped = false;
        self.shadow.clear();
        self.shadow.extend_from_slice(verts);
        self.clip(|x| plane.distance(x) * side);
        if let LightSample::Point(s) = target.sample {
            let ds = plane.distance(s);
            self.clip(|x| (ds - plane.distance(x)) * side);
        }
        for &(origin, m) in &target.pyramid {
            self.clip(|x| m.dot(x - origin));
        }
        if self.shadow.is_empty() {
            return false;
        }
        for x in &mut self.shadow {
            *x = target.onto(*x);
        }
        let area2 = newell_normal(&self.shadow).length();
        let size = target.rect[0].distance(target.rect[2]);
        area2 > 1e-12 * size * size && self.shadow.iter().all(|x| x.is_finite())
    }

    fn clip(&mut self, dist: impl Fn(DVec3) -> f64) {
        if !self.shadow.is_empty() && self.shadow.iter().any(|&x| dist(x) < 0.0) {
            clip_polygon(&self.shadow, dist, &mut self.scratch);
            std::mem::swap(&mut self.shadow, &mut self.scratch);
            self.clipped = true;
        }
    }
}

/// The corners of the smallest rectangle in `plane` around `verts` (axes: any pair of unit
/// vectors across the normal), grown by a relative 1e-9 so the polygon's own edges are inside.
pub fn bounding_rectangle(verts: &[DVec3], plane: &Plane) -> [DVec3; 4] {
    let u = plane.n.any_orthonormal_vector();
    let v = plane.n.cross(u);
    let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for p in verts {
        let q = DVec2::new(p.dot(u), p.dot(v));
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let grow = (hi - lo).max_element() * 1e-9;
    let (lo, hi) = (lo - grow, hi + grow);
    let o = -plane.d * plane.n;
    [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)].map(|c| o + c.x * u + c.y * v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A box the pyramid misses holds no polygon it meets: every polygon inside it is
    /// missed too, and most boxes well away from the pyramid are found to miss it.
    #[test]
    fn a_box_missed_holds_only_polygons_missed() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let plane = Plane::new(DVec3::Z, DVec3::ZERO);
        let rect = [
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(-1.0, 1.0, 0.0),
        ];
        let (mut missed, mut tried) = (0, 0);
        for _ in 0..2000 {
            let light = DVec3::new(rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0), rng.gen_range(2.0..8.0));
            let target = Target::new(plane, rect, LightSample::Point(light));
            let centre = DVec3::new(rng.gen_range(-6.0..6.0), rng.gen_range(-6.0..6.0), rng.gen_range(-1.0..9.0));
            let half = DVec3::new(rng.gen_range(0.0..1.5), rng.gen_range(0.0..1.5), rng.gen_range(0.0..1.5));
            let (lo, hi) = (centre - half, centre + half);
            tried += 1;
            if !target.misses_box((lo, hi)) {
                continue;
            }
            missed += 1;
            for _ in 0..20 {
                let point = |rng: &mut rand_chacha::ChaCha8Rng| {
                    // Corners and faces of the box too, where rounding is closest.
                    let t = DVec3::new(rng.gen_range(0.0..=1.0), rng.gen_range(0.0..=1.0), rng.gen_range(0.0..=1.0));
                    let t = if rng.gen_bool(0.3) { t.round() } else { t };
                    (lo + (hi - lo) * t).clamp(lo, hi)
                };
                let verts = [point(&mut rng), point(&mut rng), point(&mut rng)];
                assert!(target.misses(&verts), "{verts:?} in a box missed by the pyramid from {light}");
            }
        }
        assert!(missed * 4 > tried, "only {missed} of {tried} boxes missed");
        // A box around the light meets every face.
        let light = DVec3::new(0.0, 0.0, 4.0);
        let target = Target::new(plane, rect, LightSample::Point(light));
        assert!(!target.misses_box((light - DVec3::ONE, light + DVec3::ONE)));
    }
}
