//! The Weiler-Atherton clipper against an independent polygon-boolean crate (`i_overlay`,
//! a dev-dependency only) on thousands of random pairs: convex, concave, with holes, and
//! snapped to a coarse grid so that shared edges, collinear overlaps and vertices lying on
//! edges are common. Inside area + outside area = subject area; the inside area equals the
//! independent intersection's area. proptest shrinks any failure and records it in
//! `proptest-regressions/` so it is replayed first from then on.

use super::{clip, signed_area, Region};
use glam::DVec2;
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::single::SingleFloatOverlay;
use proptest::prelude::*;

fn independent_area(subject: &Region, clip_region: &Region, rule: OverlayRule) -> f64 {
    let conv = |r: &Region| -> Vec<Vec<[f64; 2]>> {
        r.rings.iter().map(|ring| ring.iter().map(|p| [p.x, p.y]).collect()).collect()
    };
    let shapes = conv(subject).overlay(&conv(clip_region), rule, FillRule::EvenOdd);
    shapes
        .iter()
        .map(|shape| {
            shape
                .iter()
                .enumerate()
                .map(|(i, c)| {
                    let ring: Vec<DVec2> = c.iter().map(|p| DVec2::new(p[0], p[1])).collect();
                    let a = signed_area(&ring).abs();
                    if i == 0 {
                        a
                    } else {
                        -a
                    }
                })
                .sum::<f64>()
        })
        .sum()
}

fn check(subject: &Region, clip_region: &Region) -> Result<(), TestCaseError> {
    let c = clip(subject, clip_region).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let scale = 100.0; // coordinates stay within ±10
    let (si, so, s) = (c.inside.area(), c.outside.area(), subject.area());
    prop_assert!((si + so - s).abs() < 1e-9 * scale, "inside {si} + outside {so} != subject {s}");
    let want = independent_area(subject, clip_region, OverlayRule::Intersect);
    // i_overlay snaps to an integer grid internally: allow for that.
    prop_assert!((si - want).abs() < 1e-5 * scale, "inside {si}, independent intersection {want}");
    let want_out = independent_area(subject, clip_region, OverlayRule::Difference);
    prop_assert!((so - want_out).abs() < 1e-5 * scale, "outside {so}, independent difference {want_out}");
    Ok(())
}

/// A star-shaped ring (convex when `dent` is 1) around `c`.
fn star(c: DVec2, r: f64, sides: usize, dent: f64, phase: f64) -> Vec<DVec2> {
    (0..sides)
        .map(|i| {
            let t = phase + std::f64::consts::TAU * i as f64 / sides as f64;
            let rr = if i % 2 == 1 { r * dent } else { r };
            c + DVec2::new(t.cos(), t.sin()) * rr
        })
        .collect()
}

fn polygon() -> impl Strategy<Value = Region> {
    (-3.0..3.0f64, -3.0..3.0f64, 0.5..5.0f64, 3usize..12, 0.2..1.0f64, 0.0..6.3f64, any::<bool>()).prop_map(
        |(x, y, r, sides, dent, phase, hole)| {
            let c = DVec2::new(x, y);
            let sides = if dent < 0.99 { sides * 2 } else { sides };
            let mut region = Region::from_ring(star(c, r, sides, dent, phase));
            if hole {
                region.rings.push(star(c, r * dent * 0.4, 5, 1.0, phase + 0.3));
            }
            region
        },
    )
}

/// Polygons with vertices on a coarse integer grid: rectangles, L shapes and triangles,
/// which share edges, overlap collinearly and put vertices on each other's edges.
fn grid_polygon() -> impl Strategy<Value = Region> {
    (0i32..3, -4i32..4, -4i32..4, 1i32..5, 1i32..5, 0i32..4).prop_map(|(kind, x, y, w, h, k)| {
        let p = |a: i32, b: i32| DVec2::new(a as f64, b as f64);
        let ring = match kind {
            0 => vec![p(x, y), p(x + w, y), p(x + w, y + h), p(x, y + h)],
            1 => {
                let k = k.min(w - 1).max(0);
                if k == 0 || h < 2 {
                    vec![p(x, y), p(x + w, y), p(x, y + h)]
                } else {
                    vec![p(x, y), p(x + w, y), p(x + w, y + 1), p(x + k, y + 1), p(x + k, y + h), p(x, y + h)]
                }
            }
            _ => vec![p(x, y), p(x + 2 * w, y), p(x + w, y + h)],
        };
        Region::from_ring(ring)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn random_pairs(subject in polygon(), clip_region in polygon()) {
        check(&subject, &clip_region)?;
    }

    #[test]
    fn grid_pairs_with_shared_and_collinear_edges(subject in grid_polygon(), clip_region in grid_polygon()) {
        check(&subject, &clip_region)?;
    }

    #[test]
    fn identical_and_nested(subject in polygon(), scale in 0.3..1.0f64) {
        check(&subject, &subject)?;
        // The same outline shrunk about its first vertex: nested, touching at that vertex.
        let o = subject.rings[0][0];
        let inner = Region::from_ring(subject.rings[0].iter().map(|&p| o + (p - o) * scale).collect());
        check(&subject, &inner)?;
        check(&inner, &subject)?;
    }
}
