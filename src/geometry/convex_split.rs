//! Splitting one convex polygon by another's edges (ours, beside Weiler-Atherton clipping).
//!
//! Weiler & Atherton's clipper ([`super::weiler_atherton`]) takes any two regions and traces
//! the inside and outside parts of the subject as rings. When both polygons are convex, as a
//! mesh's triangles and their pieces are, the same two parts come from a much shorter walk:
//!
//! 1. **Apart?** Two convex polygons overlap unless the line through an edge of one has the
//!    other wholly on its far side. If such a line exists, nothing of the subject is inside.
//! 2. **Cut by each clip edge in turn.** What is left of the subject is split by the line
//!    through the clip's next edge: the part beyond the line is outside the clip and is kept
//!    as one piece of the outside part; the part on the clip's side goes on to the next edge.
//!    This is Sutherland & Hodgman's reentrant clipping ("Reentrant polygon clipping", 1974)
//!    keeping both sides of every cut, as beam tracing splits polygons by a beam's edges.
//! 3. **What is left** after the last edge is the inside part.
//!
//! Every piece is convex. The outside part is at most one piece per clip edge, pieces that
//! touch along the cut lines and never overlap: the same region as Weiler-Atherton's outside
//! ring (with its notch or hole), cut into convex parts. Tolerance, as the clipper's: points
//! within `1e-9 ×` the inputs' bounding-box diagonal of a cut line lie on it, go to both
//! sides, and are never moved.

use super::weiler_atherton::{ring_bounds, signed_area, Ring};
use glam::DVec2;
use smallvec::SmallVec;
use std::borrow::Cow;

/// The two parts of a convex subject split by a convex clip polygon.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Split {
    /// The part inside the clip polygon.
    pub inside: Ring,
    /// The part outside it, as convex pieces that touch but do not overlap.
    pub outside: SmallVec<[Ring; 4]>,
}

/// Whether `ring` is convex: every corner turns the same way (straight corners allowed).
pub fn is_convex(ring: &[DVec2]) -> bool {
    let n = ring.len();
    if n < 3 {
        return false;
    }
    let (mut left, mut right) = (false, false);
    for i in 0..n {
        let (a, b, c) = (ring[i], ring[(i + 1) % n], ring[(i + 2) % n]);
        let turn = (b - a).perp_dot(c - b);
        left |= turn > 0.0;
        right |= turn < 0.0;
    }
    left != right
}

/// Splits convex `subject` by convex `clip` (steps 1-3); `None` when the clip does not
/// overlap it (the subject is all outside).
pub fn split(subject: &[DVec2], clip: &[DVec2]) -> Option<Split> {
    let (sb, cb) = (ring_bounds(subject)?, ring_bounds(clip)?);
    let eps = super::tolerance(sb.0.min(cb.0), sb.1.max(cb.1));
    let (s_turn, c_turn) = (turn(subject), turn(clip));
    if s_turn == 0.0 || c_turn == 0.0 || apart(subject, s_turn, clip, eps) || apart(clip, c_turn, subject, eps) {
        return None;
    }
    // What is left is the subject itself until a line cuts it (ours: a line that leaves it
    // whole makes no copy).
    let mut rest = Cow::Borrowed(subject);
    let mut outside = SmallVec::new();
    let n = clip.len();
    for i in 0..n {
        let (a, b) = (clip[i], clip[(i + 1) % n]);
        if a == b {
            continue; // a repeated corner bounds nothing
        }
        let line = Line::through(a, b, c_turn);
        match sides(&rest, |p| line.distance(p), eps) {
            Sides::Positive => {}
            // Touching within the tolerance only: nothing of the subject is inside.
            Sides::Negative | Sides::On => return None,
            Sides::Both(inner, outer) => {
                outside.push(outer);
                rest = Cow::Owned(inner);
            }
        }
    }
    Some(Split { inside: rest.into_owned(), outside })
}

/// The part of `ring` on the positive side of the line whose signed distance is `dist`:
/// `None` when nothing of the ring lies more than `eps` on that side, the ring itself when
/// nothing lies more than `eps` on the other.
pub fn positive_part(ring: &[DVec2], dist: impl Fn(DVec2) -> f64, eps: f64) -> Option<Ring> {
    match sides(ring, dist, eps) {
        Sides::Positive => Some(ring.to_vec()),
        Sides::Both(inner, _) => Some(inner),
        Sides::Negative | Sides::On => None,
    }
}

/// Where a ring lies against a line, cut by it where it has parts on both sides.
enum Sides {
    /// Nothing more than `eps` on the negative side, something on the positive side.
    Positive,
    /// The other way round.
    Negative,
    /// Every corner within `eps` of the line.
    On,
    /// Cut: the parts on the positive and on the negative side.
    Both(Ring, Ring),
}

/// Where `ring` lies against the line whose signed distance is `dist` (positive on the kept
/// side), corners within `eps` of it on it: a ring the line does not cut is named, not
/// copied.
fn sides(ring: &[DVec2], dist: impl Fn(DVec2) -> f64, eps: f64) -> Sides {
    let snap = |d: f64| if d.abs() <= eps { 0.0 } else { d };
    let d: SmallVec<[f64; 16]> = ring.iter().map(|&p| snap(dist(p))).collect();
    let (pos, neg) = (d.iter().any(|&x| x > 0.0), d.iter().any(|&x| x < 0.0));
    match (pos, neg) {
        (true, false) => return Sides::Positive,
        (false, true) => return Sides::Negative,
        (false, false) => return Sides::On,
        (true, true) => {}
    }
    let (mut inner, mut outer) = (Vec::with_capacity(ring.len() + 1), Vec::with_capacity(ring.len() + 1));
    let n = ring.len();
    for i in 0..n {
        let (a, da, b, db) = (ring[i], d[i], ring[(i + 1) % n], d[(i + 1) % n]);
        if da >= 0.0 {
            inner.push(a);
        }
        if da <= 0.0 {
            outer.push(a);
        }
        if (da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0) {
            let x = a + (b - a) * (da / (da - db));
            inner.push(x);
            outer.push(x);
        }
    }
    Sides::Both(inner, outer)
}

/// A directed line's signed distance, positive on the side a polygon turning `turn` (+1
/// counter-clockwise, -1 clockwise) keeps its inside.
struct Line {
    a: DVec2,
    normal: DVec2,
}

impl Line {
    fn through(a: DVec2, b: DVec2, turn: f64) -> Line {
        let dir = b - a;
        let normal = DVec2::new(-dir.y, dir.x) * (turn / dir.length().max(f64::MIN_POSITIVE));
        Line { a, normal }
    }

    fn distance(&self, p: DVec2) -> f64 {
        (p - self.a).dot(self.normal)
    }
}

/// Whether the line through some edge of convex `ring` (turning `turn`) has all of `other`
/// on its outer side, within `eps`.
fn apart(ring: &[DVec2], turn: f64, other: &[DVec2], eps: f64) -> bool {
    let n = ring.len();
    (0..n).any(|i| {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        a != b && {
            let line = Line::through(a, b, turn);
            other.iter().all(|&p| line.distance(p) <= eps)
        }
    })
}

/// Whether every point of `points` lies inside convex `ring` or on its outline (never, for
/// a ring without area).
pub fn holds(ring: &[DVec2], mut points: impl Iterator<Item = DVec2>) -> bool {
    let t = turn(ring);
    let n = ring.len();
    t != 0.0 && points.all(|p| (0..n).all(|i| (ring[(i + 1) % n] - ring[i]).perp_dot(p - ring[i]) * t >= 0.0))
}

/// Whether convex `ring` holds the whole box `(lo, hi)` with room to spare, so that
/// [`holds`] is true for any points in the box (ours): every corner lies inside the line
/// of every edge `e` from `a` by more than `1e-9 |e|₁ r`, where `r` is the farthest any
/// corner is from `a` along an axis. [`holds`]' product for a point `p` of the box errs by
/// some `1e-15 |e|₁ r` at most, and its exact value is at least the least of the corners'
/// (it is affine in `p`).
pub fn holds_box(ring: &[DVec2], (lo, hi): (DVec2, DVec2)) -> bool {
    let t = turn(ring);
    let n = ring.len();
    let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
    t != 0.0
        && (0..n).all(|i| {
            let (a, e) = (ring[i], ring[(i + 1) % n] - ring[i]);
            let reach = corners.iter().map(|&c| (c - a).abs().max_element()).fold(0.0, f64::max);
            let margin = 1e-9 * (e.x.abs() + e.y.abs()) * reach;
            corners.iter().all(|&c| e.perp_dot(c - a) * t > margin)
        })
}

/// +1 for a ring wound counter-clockwise, −1 clockwise, 0 without area (where `f64::signum`
/// would give 1).
fn turn(ring: &[DVec2]) -> f64 {
    let a = signed_area(ring);
    if a > 0.0 {
        1.0
    } else if a < 0.0 {
        -1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::inside_even_odd;
    use crate::geometry::weiler_atherton::{clip, Region};
    use proptest::prelude::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn area(r: &[DVec2]) -> f64 {
        signed_area(r).abs()
    }

    #[test]
    fn a_corner_overlap_leaves_two_outside_pieces() {
        let square = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        let other = [v(1.0, 1.0), v(3.0, 1.0), v(3.0, 3.0), v(1.0, 3.0)];
        let s = split(&square, &other).unwrap();
        assert!((area(&s.inside) - 1.0).abs() < 1e-12);
        assert_eq!(s.outside.len(), 2);
        assert!((s.outside.iter().map(|r| area(r)).sum::<f64>() - 3.0).abs() < 1e-12);
        assert!(s.outside.iter().chain([&s.inside]).all(|r| is_convex(r)));
    }

    #[test]
    fn neighbours_sharing_an_edge_are_apart() {
        let a = [v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)];
        let b = [v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)];
        assert_eq!(split(&a, &b), None);
    }

    #[test]
    fn inside_and_containing() {
        let big = [v(0.0, 0.0), v(4.0, 0.0), v(4.0, 4.0), v(0.0, 4.0)];
        let small = [v(1.0, 1.0), v(2.0, 1.0), v(1.0, 2.0)];
        let s = split(&small, &big).unwrap();
        assert_eq!(s.inside, small.to_vec());
        assert!(s.outside.is_empty());
        // Clockwise, and holding the clip: the outside is the square less the triangle.
        let cw: Vec<DVec2> = big.iter().rev().copied().collect();
        let t = split(&cw, &small).unwrap();
        assert!((area(&t.inside) - 0.5).abs() < 1e-12);
        assert!((t.outside.iter().map(|r| area(r)).sum::<f64>() - 15.5).abs() < 1e-12);
    }

    /// A clip polygon with a corner given twice (a mesh's pole triangle, a quad with two
    /// corners in one place) still clips: the repeated corner's empty edge is no cut line.
    #[test]
    fn a_repeated_corner_still_clips() {
        let square = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        let tri = [v(1.0, 1.0), v(1.0, 1.0), v(3.0, 1.0), v(1.0, 2.0)];
        let s = split(&square, &tri).unwrap();
        // Inside: the square [1, 2]² below the line x + 2y = 5.
        assert!((area(&s.inside) - 0.75).abs() < 1e-12);
        assert!((s.outside.iter().map(|r| area(r)).sum::<f64>() - 3.25).abs() < 1e-12);
    }

    /// A polygon without area neither clips nor is clipped.
    #[test]
    fn no_area_no_split() {
        let square = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        let flat = [v(0.5, 1.0), v(1.0, 1.0), v(1.5, 1.0)];
        assert_eq!(split(&flat, &square), None);
        assert_eq!(split(&square, &flat), None);
    }

    /// Points inside a convex ring or on its outline are held, either way round; a point
    /// outside is not, and a ring without area holds nothing.
    #[test]
    fn a_convex_ring_holds_its_inside_and_outline() {
        let square = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        let cw: Vec<DVec2> = square.iter().rev().copied().collect();
        for ring in [&square[..], &cw[..]] {
            assert!(holds(ring, [v(1.0, 1.0), v(0.0, 1.0), v(2.0, 2.0)].into_iter()));
            assert!(!holds(ring, [v(1.0, 1.0), v(2.5, 1.0)].into_iter()));
        }
        assert!(!holds(&[v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0)], [v(1.0, 0.0)].into_iter()));
    }

    /// A box that a convex ring is found to hold with room to spare holds only points the
    /// ring holds: 3,000 random rings (either way round) and boxes, some nearly touching an
    /// edge, 40 points in each held box (its corners and edges among them). At least a
    /// tenth of the boxes are found held, and a box over the outline never is.
    #[test]
    fn a_box_held_holds_only_points_held() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut found = 0;
        for case in 0..3000 {
            let k = rng.gen_range(3..8);
            let c = v(rng.gen_range(-1e3..1e3), rng.gen_range(-1e3..1e3));
            let r = 10f64.powi(rng.gen_range(-3..4));
            let mut ring: Vec<DVec2> = (0..k)
                .map(|j| {
                    let a = std::f64::consts::TAU * (j as f64 + rng.gen_range(0.0..0.9)) / k as f64;
                    c + v(a.cos(), a.sin()) * r
                })
                .collect();
            if case % 2 == 1 {
                ring.reverse();
            }
            // A box around a point near the centre, or one reaching the outline's corner.
            let m = c + v(rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5)) * r;
            let half = r * 10f64.powi(rng.gen_range(-9..0));
            let bx = if case % 5 == 0 { (m.min(ring[0]), m.max(ring[0])) } else { (m - half, m + half) };
            if !holds_box(&ring, bx) {
                continue;
            }
            found += 1;
            assert!(case % 5 != 0, "a box reaching a corner of the outline is held");
            let (lo, hi) = bx;
            let mut points = vec![lo, hi, v(lo.x, hi.y), v(hi.x, lo.y)];
            points.extend((0..36).map(|_| {
                let (s, u) = (rng.gen_range(0.0..=1.0), rng.gen_range(0.0..=1.0));
                v(lo.x + (hi.x - lo.x) * s, lo.y + (hi.y - lo.y) * u)
            }));
            for p in points {
                assert!(holds(&ring, std::iter::once(p)), "case {case}: {p} in {bx:?}");
            }
        }
        assert!(found > 300, "{found} boxes held");
    }

    #[test]
    fn convexity() {
        assert!(is_convex(&[v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0), v(1.0, 1.0)]));
        assert!(!is_convex(&[v(0.0, 0.0), v(2.0, 0.0), v(1.0, 0.5), v(2.0, 2.0), v(0.0, 2.0)]));
        assert!(!is_convex(&[v(0.0, 0.0), v(1.0, 0.0)]));
    }

    fn convex_polygon() -> impl Strategy<Value = Vec<DVec2>> {
        // Points on a circle at sorted angles: convex, either way round.
        (
            -1.0..1.0f64,
            -1.0..1.0f64,
            0.1..1.0f64,
            prop::collection::vec(0.0..std::f64::consts::TAU, 3..7),
            any::<bool>(),
        )
            .prop_map(|(cx, cy, r, mut angles, ccw)| {
                angles.sort_by(f64::total_cmp);
                angles.dedup_by(|a, b| (*a - *b).abs() < 1e-3);
                let mut ring: Vec<DVec2> = angles.iter().map(|t| v(cx + r * t.cos(), cy + r * t.sin())).collect();
                if !ccw {
                    ring.reverse();
                }
                ring
            })
            .prop_filter("a polygon with area", |r| r.len() >= 3 && area(r) > 1e-3)
    }

    proptest! {
        /// The split gives Weiler-Atherton's two parts: at every sample point, inside the
        /// subject and the clip exactly when inside the inside part, and inside the subject
        /// but not the clip exactly when inside one outside piece (never two); no split
        /// (`None`) when nothing is inside.
        #[test]
        fn the_parts_are_weiler_athertons(s in convex_polygon(), c in convex_polygon()) {
            let parts = split(&s, &c)
                .unwrap_or_else(|| Split { inside: Vec::new(), outside: SmallVec::from_elem(s.clone(), 1) });
            let wa = clip(&Region::from_ring(s.clone()), &Region::from_ring(c.clone())).unwrap();
            prop_assert!(parts.outside.iter().all(|r| is_convex(r)));
            prop_assert!(parts.inside.is_empty() || is_convex(&parts.inside));
            let inside_area = area(&parts.inside);
            prop_assert!((inside_area - wa.inside.area()).abs() < 1e-9);
            let outside_area: f64 = parts.outside.iter().map(|r| area(r)).sum();
            prop_assert!((outside_area - wa.outside.area()).abs() < 1e-9);
            for i in 0..40 {
                for j in 0..40 {
                    let p = v(-2.0 + 4.0 * (i as f64 + 0.5) / 40.0, -2.0 + 4.0 * (j as f64 + 0.5) / 40.0);
                    let (in_s, in_c) = (inside_even_odd(&s, p), inside_even_odd(&c, p));
                    let inside = inside_even_odd(&parts.inside, p);
                    let outside = parts.outside.iter().filter(|r| inside_even_odd(r, p)).count();
                    prop_assert_eq!(inside, in_s && in_c, "at {:?}", p);
                    prop_assert_eq!(outside, usize::from(in_s && !in_c), "at {:?}", p);
                }
            }
        }
    }
}
