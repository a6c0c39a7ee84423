//! The even-odd region of a self-intersecting polygon as disjoint trapezoids.
//!
//! The scene format decides inside by the even-odd rule (`docs/scene-format.md` §2). Stages
//! that scan-convert a polygon get that rule for free from their crossing parity; stages that
//! build geometry from a polygon's edges (Crow's shadow volumes) would get the nonzero winding
//! rule instead, which differs where a polygon winds twice (the centre of a pentagram). For
//! those, a self-intersecting polygon is cut into trapezoids: its plane is cut into horizontal
//! slabs at every vertex and every crossing of two edges, so that within a slab no two edges
//! cross; the edges spanning a slab, in order of x, bound its inside intervals in pairs
//! (first to second, third to fourth, ...). The trapezoids cover the even-odd region once.

use glam::DVec2;

/// Whether two edges of the closed ring `ring` that are not neighbours meet (cross, touch or
/// overlap). Edges are swept in order of their lowest y, each tested against the edges whose
/// y-range it overlaps, so a ring whose edges rarely share a y-range costs `O(n log n)`.
pub fn self_intersects(ring: &[DVec2]) -> bool {
    let n = ring.len();
    if n < 4 {
        return false;
    }
    !crossings(ring, true).is_empty()
}

/// The y of every point where two non-neighbouring edges meet (all of them, or the first
/// when `first_only`).
fn crossings(ring: &[DVec2], first_only: bool) -> Vec<f64> {
    let n = ring.len();
    let edge = |i: usize| (ring[i], ring[(i + 1) % n]);
    let mut order: Vec<usize> = (0..n).collect();
    let ymin = |i: usize| edge(i).0.y.min(edge(i).1.y);
    let ymax = |i: usize| edge(i).0.y.max(edge(i).1.y);
    order.sort_by(|&a, &b| ymin(a).total_cmp(&ymin(b)));
    let mut active: Vec<usize> = Vec::new();
    let mut ys = Vec::new();
    for &i in &order {
        let y = ymin(i);
        active.retain(|&j| ymax(j) >= y);
        for &j in &active {
            let neighbours = (i + 1) % n == j || (j + 1) % n == i;
            if neighbours {
                continue;
            }
            if let Some(at) = meet(edge(i), edge(j)) {
                ys.extend(at);
                if first_only {
                    return ys;
                }
            }
        }
        active.push(i);
    }
    ys
}

fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Where segments `p` and `q` meet: the y of their crossing, or the y-range ends of their
/// overlap when they are collinear; `None` when they do not meet.
fn meet(p: (DVec2, DVec2), q: (DVec2, DVec2)) -> Option<Vec<f64>> {
    let (r, s) = (p.1 - p.0, q.1 - q.0);
    let d = cross(r, s);
    let w = q.0 - p.0;
    if d == 0.0 {
        if cross(w, r) != 0.0 {
            return None; // parallel, apart
        }
        // Collinear: overlapping when their projections on r (or s) overlap.
        let axis = if r.length_squared() > 0.0 { r } else { s };
        let t = |v: DVec2| (v - p.0).dot(axis);
        let (p0, p1) = (t(p.0).min(t(p.1)), t(p.0).max(t(p.1)));
        let (q0, q1) = (t(q.0).min(t(q.1)), t(q.0).max(t(q.1)));
        return (p0 <= q1 && q0 <= p1).then(|| vec![p.0.y, p.1.y, q.0.y, q.1.y]);
    }
    let (t, u) = (cross(w, s) / d, cross(w, r) / d);
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)).then(|| vec![p.0.y + t * r.y])
}

/// The even-odd region of `ring` as trapezoids `[bottom-left, bottom-right, top-right,
/// top-left]` (a triangle repeats a corner), disjoint but for shared boundaries.
pub fn trapezoids(ring: &[DVec2]) -> Vec<[DVec2; 4]> {
    let n = ring.len();
    let mut ys: Vec<f64> = ring.iter().map(|p| p.y).chain(crossings(ring, false)).collect();
    ys.sort_by(f64::total_cmp);
    ys.dedup();
    let mut out = Vec::new();
    let mut spanning: Vec<(f64, f64, f64)> = Vec::new();
    for w in ys.windows(2) {
        let (y0, y1) = (w[0], w[1]);
        if y0 >= y1 {
            continue;
        }
        let ym = 0.5 * (y0 + y1);
        spanning.clear();
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            let (lo, hi) = if a.y <= b.y { (a, b) } else { (b, a) };
            if lo.y <= y0 && hi.y >= y1 && lo.y < hi.y {
                let x_at = |y: f64| lo.x + (y - lo.y) * ((hi.x - lo.x) / (hi.y - lo.y));
                spanning.push((x_at(ym), x_at(y0), x_at(y1)));
            }
        }
        spanning.sort_by(|a, b| a.0.total_cmp(&b.0));
        for pair in spanning.chunks_exact(2) {
            let (l, r) = (pair[0], pair[1]);
            out.push([DVec2::new(l.1, y0), DVec2::new(r.1, y0), DVec2::new(r.2, y1), DVec2::new(l.2, y1)]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::inside_even_odd;
    use proptest::prelude::*;

    fn pentagram() -> Vec<DVec2> {
        (0..5)
            .map(|k| {
                let a = std::f64::consts::TAU * (2 * k) as f64 / 5.0;
                DVec2::new(a.cos(), a.sin())
            })
            .collect()
    }

    fn inside_trapezoids(traps: &[[DVec2; 4]], p: DVec2) -> usize {
        traps.iter().filter(|t| inside_even_odd(&t[..], p)).count()
    }

    #[test]
    fn simple_rings_do_not_self_intersect() {
        let square = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
        assert!(!self_intersects(&square));
        let concave =
            [DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(2.0, 1.0), DVec2::new(4.0, 4.0), DVec2::new(0.0, 4.0)];
        assert!(!self_intersects(&concave));
        assert!(self_intersects(&pentagram()));
        let bowtie = [DVec2::ZERO, DVec2::ONE, DVec2::X, DVec2::Y];
        assert!(self_intersects(&bowtie));
    }

    #[test]
    fn pentagram_centre_is_outside() {
        let traps = trapezoids(&pentagram());
        assert_eq!(inside_trapezoids(&traps, DVec2::new(0.01, 0.013)), 0);
        assert_eq!(inside_trapezoids(&traps, DVec2::new(0.8, 0.013)), 1);
    }

    proptest! {
        /// At random points, a random ring's trapezoids hold the point once exactly where the
        /// even-odd rule puts it inside the ring, and never twice.
        #[test]
        fn trapezoids_cover_the_even_odd_region(
            pts in prop::collection::vec((-4i32..=4, -4i32..=4), 4..9),
            probes in prop::collection::vec((-50i32..50, -50i32..50), 40),
        ) {
            let ring: Vec<DVec2> = pts.iter().map(|&(x, y)| DVec2::new(x as f64, y as f64)).collect();
            let traps = trapezoids(&ring);
            for (px, py) in probes {
                // Probes off the integer lattice, away from every vertex and crossing height.
                let p = DVec2::new(px as f64 / 10.0 + 0.0123, py as f64 / 10.0 + 0.0371);
                let want = inside_even_odd(&ring, p) as usize;
                prop_assert_eq!(inside_trapezoids(&traps, p), want, "at {:?}", p);
            }
        }
    }
}
