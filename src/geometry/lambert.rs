//! Lambert's contour formula: the irradiance a point receives from a uniformly bright
//! polygon, in closed form (J. H. Lambert, *Photometria*, 1760; the form Nishita and Nakamae
//! integrate over the visible part of a light, `docs/algorithms/nishita-nakamae.md`).
//!
//! For a point P and a polygon with corners `V_1..V_k`, with `r_i = V_i − P`, each edge
//! contributes the angle `θ_i` it subtends at P along the unit normal `g_i` of the plane
//! through P and the edge:
//!
//! ```text
//! Φ = ½ Σ_i θ_i g_i,   θ_i = atan2(|r_i × r_{i+1}|, r_i · r_{i+1}),   g_i = (r_i × r_{i+1}) / |r_i × r_{i+1}|
//! ```
//!
//! `Φ` is the polygon's *irradiance vector*: for a surface at P with unit normal N, `N · Φ`
//! is `∫ (N · ω) dω` over the solid angle the polygon subtends (up to the sign its winding
//! gives), so a polygon of uniform radiance L gives the irradiance `L N · Φ` where all of it
//! lies above the surface. It is linear in N (a shader dots it with any normal), and
//! additive over polygons: regions that tile a polygon, wound alike, sum to its vector, and
//! a hole subtracts.

use glam::DVec3;

/// `Φ` of the polygon `ring` (in order round it) seen from `p`, with the sign its winding
/// gives: for a ring wound counter-clockwise as seen from `p`, `Φ` points away from it.
/// Zero for a ring of fewer than three corners, or one seen edge-on from `p`.
pub(crate) fn irradiance_vector(p: DVec3, ring: impl IntoIterator<Item = DVec3>) -> DVec3 {
    let mut ring = ring.into_iter();
    let Some(first) = ring.next() else { return DVec3::ZERO };
    let first = first - p;
    let (mut sum, mut a) = (DVec3::ZERO, first);
    for v in ring.chain(std::iter::once(first + p)) {
        let b = v - p;
        sum += edge_term(a, b);
        a = b;
    }
    0.5 * sum
}

/// [`irradiance_vector`] of the quadrilateral `ring` from each of `points`, into `out`
/// (as long), four points at a time in f64 lanes (ours, for speed: a frame asks for it at
/// every pixel that sees all of a light). The angles are `wide`'s `atan2`, within a few
/// units in the last place.
pub(crate) fn irradiance_vectors(ring: &[DVec3; 4], points: &[DVec3], out: &mut [DVec3]) {
    use wide::f64x4;
    for (points, out) in points.chunks(4).zip(out.chunks_mut(4)) {
        // A short last chunk repeats its last point.
        let p = |c: usize| std::array::from_fn::<f64, 4, _>(|j| points[j.min(points.len() - 1)][c]);
        let [px, py, pz] = [p(0), p(1), p(2)].map(f64x4::from);
        let r = ring.map(|v| [f64x4::splat(v.x) - px, f64x4::splat(v.y) - py, f64x4::splat(v.z) - pz]);
        let mut sum = [f64x4::ZERO; 3];
        for k in 0..4 {
            let (a, b) = (&r[k], &r[(k + 1) % 4]);
            let c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
            let s = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            let d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            let none = s.simd_eq(f64x4::ZERO);
            let w = none.select(f64x4::ZERO, s.atan2(d) / s);
            for (sum, c) in sum.iter_mut().zip(c) {
                *sum += c * w;
            }
        }
        let [x, y, z] = sum.map(|v| v.to_array());
        for (j, o) in out.iter_mut().enumerate() {
            *o = 0.5 * DVec3::new(x[j], y[j], z[j]);
        }
    }
}

/// One edge's `θ g`, from the corners less P.
#[inline]
fn edge_term(a: DVec3, b: DVec3) -> DVec3 {
    let c = a.cross(b);
    let s = c.length();
    if s == 0.0 {
        return DVec3::ZERO;
    }
    c * (angle(s, a.dot(b)) / s)
}

/// `atan2(s, d)` for `s > 0`, within 5·10⁻¹⁰ radians (ours, for speed: a frame asks for it
/// four times at every lit pixel): the angle is reduced to `|u| ≤ tan(π/8)` and
/// `atan u` summed by its series to `u¹⁹` (the next term is below 4.4·10⁻¹⁰).
#[inline]
fn angle(s: f64, d: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let (lo, hi) = if s <= d.abs() { (s, d.abs()) } else { (d.abs(), s) };
    let t = lo / hi;
    // atan t = π/4 + atan((t − 1)/(t + 1)) brings t in [0, 1] to |u| ≤ tan(π/8).
    let (u, base) = if t > 0.414_213_562_373_095 { ((t - 1.0) / (t + 1.0), FRAC_PI_4) } else { (t, 0.0) };
    let u2 = u * u;
    let series = [
        -1.0 / 19.0,
        1.0 / 17.0,
        -1.0 / 15.0,
        1.0 / 13.0,
        -1.0 / 11.0,
        1.0 / 9.0,
        -1.0 / 7.0,
        1.0 / 5.0,
        -1.0 / 3.0,
        1.0,
    ];
    let atan_t = base + u * series.iter().fold(0.0, |acc, &k| acc * u2 + k);
    let first = if s <= d.abs() { atan_t } else { FRAC_PI_2 - atan_t };
    if d < 0.0 {
        PI - first
    } else {
        first
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ (N·ω) dω` over a parallelogram, by the midpoint rule on an n×n grid of it:
    /// `dω = |n_L · r̂| dA / r²`.
    fn integrated(p: DVec3, n: DVec3, corner: DVec3, u: DVec3, v: DVec3, grid: usize) -> f64 {
        let nl = u.cross(v);
        let da = nl.length() / (grid * grid) as f64;
        let nl = nl.normalize();
        let mut sum = 0.0;
        for i in 0..grid {
            for j in 0..grid {
                let q = corner + u * ((i as f64 + 0.5) / grid as f64) + v * ((j as f64 + 0.5) / grid as f64);
                let r = q - p;
                let d2 = r.length_squared();
                let w = r / d2.sqrt();
                sum += n.dot(w) * nl.dot(w).abs() * da / d2;
            }
        }
        sum
    }

    #[test]
    fn equals_the_integral_of_the_cosine_over_the_solid_angle() {
        let cases = [
            // A square straight above, a tilted light off to the side, a long thin one.
            (DVec3::ZERO, DVec3::Y, DVec3::new(-1.0, 3.0, -1.0), DVec3::X * 2.0, DVec3::Z * 2.0),
            (
                DVec3::new(0.3, 0.0, -0.2),
                DVec3::new(0.2, 1.0, 0.1).normalize(),
                DVec3::new(1.0, 2.0, 0.5),
                DVec3::new(1.0, 0.5, 0.0),
                DVec3::new(0.0, 0.3, 1.5),
            ),
            (DVec3::ZERO, DVec3::Y, DVec3::new(-4.0, 0.5, 0.2), DVec3::X * 8.0, DVec3::Z * 0.3),
        ];
        for (p, n, corner, u, v) in cases {
            let ring = [corner, corner + u, corner + u + v, corner + v];
            let phi = irradiance_vector(p, ring);
            // Wound one way or the other: the magnitude is the integral's.
            let exact = n.dot(phi).abs();
            let numeric = integrated(p, n, corner, u, v, 600);
            assert!((exact - numeric).abs() < 1e-5 * numeric.max(1e-3), "{exact} against {numeric}");
            // Reversing the ring reverses the vector.
            let back = irradiance_vector(p, ring.into_iter().rev());
            assert!((phi + back).length() < 1e-12);
        }
    }

    #[test]
    fn a_tiling_sums_to_the_whole_and_a_hole_subtracts() {
        let p = DVec3::new(0.2, -1.0, 0.1);
        let at = |x: f64, z: f64| DVec3::new(x, 1.0, z);
        let whole = irradiance_vector(p, [at(0.0, 0.0), at(2.0, 0.0), at(2.0, 1.0), at(0.0, 1.0)]);
        let left = irradiance_vector(p, [at(0.0, 0.0), at(1.0, 0.0), at(1.0, 1.0), at(0.0, 1.0)]);
        let right = irradiance_vector(p, [at(1.0, 0.0), at(2.0, 0.0), at(2.0, 1.0), at(1.0, 1.0)]);
        // To the angles' bound (5·10⁻¹⁰ radians) over the twelve edges.
        assert!((whole - left - right).length() < 12.0 * 5e-10);
        // A unit square's quarter seen head-on from a point far below: about its solid angle.
        let far = DVec3::new(0.5, -1000.0, 0.5);
        let square = irradiance_vector(far, [at(0.0, 0.0), at(1.0, 0.0), at(1.0, 1.0), at(0.0, 1.0)]);
        assert!((square.length() - 1.0 / (1001.0f64).powi(2)).abs() < 1e-9);
        // Wound counter-clockwise as seen from below (from `far`): it points away, down.
        assert!(square.y < 0.0 && square.y.abs() > 1e3 * square.x.abs().max(square.z.abs()));
    }

    #[test]
    fn the_angle_is_atan2_within_its_bound() {
        let mut worst = 0.0f64;
        for i in 1..20_000 {
            let a = std::f64::consts::PI * i as f64 / 20_000.0;
            for r in [1e-3, 1.0, 7e4] {
                let (s, d) = (r * a.sin(), r * a.cos());
                worst = worst.max((angle(s, d) - s.atan2(d)).abs());
            }
        }
        assert!(worst < 5e-10, "{worst:e}");
    }

    #[test]
    fn in_lanes_as_one_by_one() {
        let ring = [
            DVec3::new(-1.0, 3.0, -1.0),
            DVec3::new(1.0, 3.2, -1.0),
            DVec3::new(1.0, 3.0, 1.0),
            DVec3::new(-1.0, 2.9, 1.0),
        ];
        let points: Vec<DVec3> =
            (0..11).map(|i| DVec3::new(i as f64 * 0.7 - 3.0, (i % 3) as f64 * 0.4, 0.1 * i as f64)).collect();
        let mut out = vec![DVec3::NAN; points.len()];
        irradiance_vectors(&ring, &points, &mut out);
        for (&p, got) in points.iter().zip(&out) {
            let want = irradiance_vector(p, ring);
            // Within the one-by-one angles' bound (5·10⁻¹⁰ radians) over four edges.
            assert!((*got - want).length() < 4.0 * 5e-10, "{p}: {got} against {want}");
        }
    }

    #[test]
    fn a_degenerate_ring_gives_nothing() {
        assert_eq!(irradiance_vector(DVec3::ZERO, []), DVec3::ZERO);
        let edge_on = [DVec3::X, DVec3::X * 2.0, DVec3::X * 3.0];
        assert_eq!(irradiance_vector(DVec3::ZERO, edge_on), DVec3::ZERO);
    }
}
