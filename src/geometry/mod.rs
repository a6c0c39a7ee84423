//! Planar polygons in f64: Newell normals, planes, the planarity and degeneracy rules of
//! `docs/scene-format.md` section 2, clipping by a plane, point-in-polygon by the even-odd rule,
//! Weiler-Atherton polygon clipping ([`weiler_atherton`]), its shortcut for two convex
//! polygons ([`convex_split`]), and Lambert's contour formula (`lambert`).

pub mod convex_split;
pub mod even_odd;
pub(crate) mod lambert;
pub(crate) mod lone_sheets;
mod rings;
pub mod weiler_atherton;

pub(crate) use rings::{RingList, RingPieces, Rings};

use glam::{DVec2, DVec3};

/// A plane `n . x + d = 0` with unit normal `n`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// Unit normal (the polygon's front side, by the right-hand rule).
    pub n: DVec3,
    /// Offset: `n . x + d = 0` on the plane.
    pub d: f64,
}

impl Plane {
    /// The plane through `point` with unit normal `n`.
    pub fn new(n: DVec3, point: DVec3) -> Self {
        Plane { n, d: -n.dot(point) }
    }

    /// Signed distance of `p` from the plane (positive on the front side).
    #[inline]
    pub fn distance(&self, p: DVec3) -> f64 {
        self.n.dot(p) + self.d
    }
}

/// Newell's normal of a polygon: twice its area times its unit normal (zero when degenerate).
pub fn newell_normal(verts: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for (i, a) in verts.iter().enumerate() {
        let b = verts[(i + 1) % verts.len()];
        n.x += (a.y - b.y) * (a.z + b.z);
        n.y += (a.z - b.z) * (a.x + b.x);
        n.z += (a.x - b.x) * (a.y + b.y);
    }
    n
}

/// `v` scaled to unit length, safely for any finite `v`: it is first divided by its largest
/// component, so a huge vector does not overflow and a tiny one does not underflow. `None`
/// for the zero vector (or a non-finite one).
pub fn unit(v: DVec3) -> Option<DVec3> {
    let m = v.abs().max_element();
    if !(m > 0.0 && m.is_finite()) {
        return None;
    }
    Some((v / m).normalize())
}

/// The average of a polygon's vertices.
pub fn centroid(verts: &[DVec3]) -> DVec3 {
    verts.iter().copied().sum::<DVec3>() / verts.len() as f64
}

/// Faces with more vertices than this measure their size by their bounding box.
pub const EXACT_DIAMETER_VERTICES: usize = 256;

/// The length scale of a face's planarity and degeneracy rules: the largest distance between
/// two vertices, for faces of up to [`EXACT_DIAMETER_VERTICES`] vertices; for larger faces the
/// diagonal of their bounding box (between 1 and √3 times the diameter), which keeps a
/// face of 200,000 vertices linear instead of quadratic.
pub fn diameter(verts: &[DVec3]) -> f64 {
    if verts.len() > EXACT_DIAMETER_VERTICES {
        let Some(&first) = verts.first() else { return 0.0 };
        let (lo, hi) = verts.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        return (hi - lo).length();
    }
    let mut d2: f64 = 0.0;
    for (i, a) in verts.iter().enumerate() {
        for b in &verts[i + 1..] {
            d2 = d2.max(a.distance_squared(*b));
        }
    }
    d2.sqrt()
}

/// What the rules of section 2 make of one face, as indices into the face's vertex list.
#[derive(Debug, Clone, PartialEq)]
pub enum FaceShape {
    /// Fewer than 3 distinct vertices, or zero area: keeps its id, draws nothing.
    Degenerate,
    /// A planar polygon (consecutive duplicate vertices removed) and its plane.
    Planar(Vec<usize>, Plane),
    /// A non-planar face: the fan of triangles from its first vertex, each with its plane
    /// (degenerate triangles of the fan are left out).
    Fan(Vec<([usize; 3], Plane)>),
}

/// Classifies a face by the planarity and degeneracy rules of `docs/scene-format.md` section 2.
pub fn classify_face(verts: &[DVec3]) -> FaceShape {
    let mut idx: Vec<usize> = Vec::with_capacity(verts.len());
    for (i, &p) in verts.iter().enumerate() {
        if idx.last().map(|&j| verts[j]) != Some(p) {
            idx.push(i);
        }
    }
    while idx.len() > 1 && verts[idx[0]] == verts[*idx.last().unwrap_or(&0)] {
        idx.pop();
    }
    let v: Vec<DVec3> = idx.iter().map(|&i| verts[i]).collect();
    let mut distinct = v.clone();
    distinct.sort_by(|a, b| a.to_array().partial_cmp(&b.to_array()).unwrap_or(std::cmp::Ordering::Equal));
    distinct.dedup();
    if distinct.len() < 3 {
        return FaceShape::Degenerate;
    }
    let diam = diameter(&v);
    let n = newell_normal(&v);
    if n.length() <= 1e-12 * diam * diam {
        return FaceShape::Degenerate;
    }
    let plane = Plane::new(n.normalize(), centroid(&v));
    if v.iter().all(|&p| plane.distance(p).abs() <= 1e-6 * diam) {
        return FaceShape::Planar(idx, plane);
    }
    let fan = (1..idx.len() - 1)
        .filter_map(|i| {
            let tri = [idx[0], idx[i], idx[i + 1]];
            let pts = tri.map(|j| verts[j]);
            let d = diameter(&pts);
            let n = newell_normal(&pts);
            (n.length() > 1e-12 * d * d).then(|| (tri, Plane::new(n.normalize(), centroid(&pts))))
        })
        .collect();
    FaceShape::Fan(fan)
}

/// Keeps the part of polygon `a` where `dist >= 0`, in place (`b` is scratch): the
/// Sutherland-Hodgman step every clip by a half-space takes, skipped when no vertex is
/// outside. Whether it cut anything.
pub(crate) fn clip_in_place<T>(a: &mut Vec<T>, b: &mut Vec<T>, dist: impl Fn(T) -> f64) -> bool
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Sub<Output = T> + std::ops::Mul<f64, Output = T>,
{
    let cut = a.iter().any(|&x| dist(x) < 0.0);
    if cut {
        clip_polygon(a, dist, b);
        std::mem::swap(a, b);
    }
    cut
}
/// Clips a polygon (convex or not) to the half-space `dist(p) >= 0` (Sutherland-Hodgman),
/// in 3D or, with `DVec4`, in homogeneous coordinates. A concave polygon may come back with
/// coincident "bridge" edges along the plane; the even-odd rule cancels them. Fewer than
/// three vertices means nothing is left.
pub fn clip_polygon<T>(poly: &[T], dist: impl Fn(T) -> f64, out: &mut Vec<T>)
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Sub<Output = T> + std::ops::Mul<f64, Output = T>,
{
    out.clear();
    let Some(&last) = poly.last() else { return };
    let mut prev = last;
    let mut dprev = dist(prev);
    for &cur in poly {
        let dcur = dist(cur);
        if (dprev >= 0.0) != (dcur >= 0.0) {
            let t = dprev / (dprev - dcur);
            let mut p = prev + (cur - prev) * t;
            // Snap the crossing exactly onto the plane along the edge's dominant change.
            if dcur >= 0.0 && t >= 1.0 {
                p = cur;
            } else if dprev >= 0.0 && t <= 0.0 {
                p = prev;
            }
            out.push(p);
        }
        if dcur >= 0.0 {
            out.push(cur);
        }
        prev = cur;
        dprev = dcur;
    }
    if out.len() < 3 {
        out.clear();
    }
}

/// The tolerance of the 2D clippers for inputs with bounding box `lo`..`hi`: `1e-9` of its
/// diagonal, but never finer than 64 times the spacing of doubles at the largest coordinate
/// (tiny pieces far from the origin, 1e-5 across at coordinates in the thousands, would
/// otherwise get a tolerance finer than their coordinates can resolve, and the predicates
/// built on it disagree).
pub(crate) fn tolerance(lo: glam::DVec2, hi: glam::DVec2) -> f64 {
    let size = 1e-9 * (hi - lo).length();
    let magnitude = lo.abs().max(hi.abs()).max_element();
    size.max(64.0 * f64::EPSILON * magnitude).max(1e-300)
}

/// Whether `p` lies inside the 2D polygon `ring` by the even-odd rule, with the scan
/// converter's half-open convention: an edge is crossed for `y_top <= p.y < y_bottom`, and a
/// point is inside a span `[x_left, x_right)` that the crossings bound.
pub fn inside_even_odd(ring: &[DVec2], p: DVec2) -> bool {
    let Some(&last) = ring.last() else {
        return false;
    };
    let edges = std::iter::once(last).chain(ring.iter().copied()).zip(ring.iter().copied());
    even_odd_edges(edges, p)
}

/// The even-odd test over a region's edges `(a, b)`, in any order (the test of
/// [`inside_even_odd`], for rings given other ways: projected from 3D, or as a clipper's
/// pieces).
#[inline]
pub(crate) fn even_odd_edges(edges: impl IntoIterator<Item = (DVec2, DVec2)>, p: DVec2) -> bool {
    let mut inside = false;
    for (a, b) in edges {
        // An edge is crossed when its ends lie on either side of the line `y = p.y`
        // (half-open: `y_top <= p.y < y_bottom`); most are not, and cost one comparison.
        if (a.y <= p.y) != (b.y <= p.y) {
            let (top, bot) = if a.y <= b.y { (a, b) } else { (b, a) };
            let x = top.x + (p.y - top.y) * ((bot.x - top.x) / (bot.y - top.y));
            if x <= p.x {
                inside = !inside;
            }
        }
    }
    inside
}

/// The cells of a grid of `gx` columns and `gy` rows over the box at `lo` of `size` that the
/// box `(a, b)` meets, as (column, row), clamped to the grid.
pub(crate) fn grid_cells(
    lo: DVec2,
    size: DVec2,
    g: (usize, usize),
    ab: (DVec2, DVec2),
) -> impl Iterator<Item = (usize, usize)> {
    let (c0, c1, r0, r1) = grid_rectangle(lo, size, g, ab);
    (c0..=c1).flat_map(move |c| (r0..=r1).map(move |r| (c, r)))
}

/// The cells [`grid_cells`] lists, as their first and last column and first and last row.
pub(crate) fn grid_rectangle(
    lo: DVec2,
    size: DVec2,
    (gx, gy): (usize, usize),
    (a, b): (DVec2, DVec2),
) -> (usize, usize, usize, usize) {
    // Cells per unit, found once: a multiplication for each coordinate (a coordinate's cell
    // only has to grow with it, for boxes that meet to share a cell).
    let per = DVec2::new(gx as f64, gy as f64) / size;
    let cell = |v: f64, lo: f64, per: f64, g: usize| (((v - lo) * per).floor().max(0.0) as usize).min(g - 1);
    let (c0, c1) = (cell(a.x, lo.x, per.x, gx), cell(b.x, lo.x, per.x, gx));
    let (r0, r1) = (cell(a.y, lo.y, per.y, gy), cell(b.y, lo.y, per.y, gy));
    (c0, c1, r0, r1)
}

/// The eight corners of the box `lo..hi`: corner `k` takes `hi` in x, y and z where bits 0,
/// 1 and 2 of `k` are set.
pub(crate) fn box_corners(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|k| DVec3::new([lo.x, hi.x][k & 1], [lo.y, hi.y][(k >> 1) & 1], [lo.z, hi.z][k >> 2]))
}

/// Directed edges, given by the keys of their ends, chained into closed loops (each a list
/// of edge indices in order); `None` when a key starts two edges or an edge leads nowhere.
pub(crate) fn edge_loops<K: Eq + std::hash::Hash + Copy>(ends: &[(K, K)]) -> Option<Vec<Vec<usize>>> {
    let mut from: rustc_hash::FxHashMap<K, usize> = rustc_hash::FxHashMap::default();
    for (e, &(a, _)) in ends.iter().enumerate() {
        if from.insert(a, e).is_some() {
            return None;
        }
    }
    let mut used = vec![false; ends.len()];
    let mut loops = Vec::new();
    for start in 0..ends.len() {
        let mut chain = Vec::new();
        let mut e = start;
        while !used[e] {
            used[e] = true;
            chain.push(e);
            e = *from.get(&ends[e].1)?;
        }
        if !chain.is_empty() {
            if e != start {
                return None;
            }
            loops.push(chain);
        }
    }
    Some(loops)
}

/// Whether a closed ring is simple: no two of its edges meet but neighbours at their shared
/// corner, and no corner turns straight back. Edges that come within rounding of meeting
/// count as meeting.
pub(crate) fn simple(ring: &[DVec2]) -> bool {
    let m = ring.len();
    if m < 3 {
        return false;
    }
    let (lo, hi) = ring.iter().fold((ring[0], ring[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let tol = 1e-12 * (hi - lo).length_squared();
    let side = |a: DVec2, b: DVec2, c: DVec2| {
        let d = (b - a).perp_dot(c - a);
        if d.abs() <= tol {
            0.0
        } else {
            d.signum()
        }
    };
    let seg = |k: usize| (ring[k], ring[(k + 1) % m]);
    // Neighbours: the corner between them must not turn straight back.
    for k in 0..m {
        let ((a, b), (_, c)) = (seg(k), seg((k + 1) % m));
        if side(a, b, c) == 0.0 && (b - a).dot(c - b) <= 0.0 {
            return false;
        }
    }
    // Others, by a sweep over the edges' x extents.
    let mut order: Vec<usize> = (0..m).collect();
    let x0 = |k: usize| seg(k).0.x.min(seg(k).1.x);
    order.sort_unstable_by(|&a, &b| x0(a).total_cmp(&x0(b)));
    let mut active: Vec<usize> = Vec::new();
    for &k in &order {
        let (a, b) = seg(k);
        active.retain(|&j| seg(j).0.x.max(seg(j).1.x) >= x0(k));
        for &j in &active {
            if j == (k + 1) % m || k == (j + 1) % m {
                continue;
            }
            let (c, d) = seg(j);
            let boxes = a.min(b).cmple(c.max(d)).all() && c.min(d).cmple(a.max(b)).all();
            if boxes && side(a, b, c) * side(a, b, d) <= 0.0 && side(c, d, a) * side(c, d, b) <= 0.0 {
                return false;
            }
        }
        active.push(k);
    }
    true
}

/// The 2D projection of a 3D point that drops the normal's dominant axis, for point-in-polygon
/// tests on a plane.
#[inline]
pub fn drop_axis(p: DVec3, axis: usize) -> DVec2 {
    match axis {
        0 => DVec2::new(p.y, p.z),
        1 => DVec2::new(p.z, p.x),
        _ => DVec2::new(p.x, p.y),
    }
}

/// The index of the largest component of `|n|`.
#[inline]
pub fn dominant_axis(n: DVec3) -> usize {
    let a = n.abs();
    if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newell_normal_of_unit_square_is_twice_its_area() {
        let sq = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        assert_eq!(newell_normal(&sq), DVec3::new(0.0, 0.0, 2.0));
    }

    #[test]
    fn classify_rules() {
        let sq = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        assert!(matches!(classify_face(&sq), FaceShape::Planar(v, _) if v == vec![0, 1, 2, 3]));
        assert_eq!(classify_face(&sq[..2]), FaceShape::Degenerate);
        let line = [DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)];
        assert_eq!(classify_face(&line), FaceShape::Degenerate);
        let dup = [DVec3::ZERO, DVec3::X, DVec3::X, DVec3::ZERO];
        assert_eq!(classify_face(&dup), FaceShape::Degenerate);
        let bent = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.1), DVec3::Y];
        match classify_face(&bent) {
            FaceShape::Fan(tris) => {
                let idx: Vec<[usize; 3]> = tris.iter().map(|t| t.0).collect();
                assert_eq!(idx, vec![[0, 1, 2], [0, 2, 3]]);
            }
            other => panic!("expected a fan, got {other:?}"),
        }
    }

    #[test]
    fn clip_keeps_the_positive_side() {
        let sq = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let mut out = Vec::new();
        clip_polygon(&sq, |p| p.x - 0.25, &mut out);
        assert_eq!(out.len(), 4);
        assert!(out.iter().all(|p| p.x >= 0.25));
        let area = newell_normal(&out).length() / 2.0;
        assert!((area - 0.75).abs() < 1e-12);
        clip_polygon(&sq, |p| p.x - 2.0, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn even_odd_inside() {
        let ring = [DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(4.0, 4.0), DVec2::new(0.0, 4.0)];
        assert!(inside_even_odd(&ring, DVec2::new(2.0, 2.0)));
        assert!(!inside_even_odd(&ring, DVec2::new(5.0, 2.0)));
        assert!(inside_even_odd(&ring, DVec2::new(0.0, 0.0)));
        assert!(!inside_even_odd(&ring, DVec2::new(4.0, 2.0)));
    }

    #[test]
    fn huge_faces_classify_in_linear_time() {
        // 200,000 vertices on a circle: the diameter of the planarity rule is linear here.
        let n = 200_000;
        let ring: Vec<DVec3> = (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                DVec3::new(a.cos(), 0.5, a.sin())
            })
            .collect();
        assert!(matches!(classify_face(&ring), FaceShape::Planar(..)));
    }

    #[test]
    fn simple_rings_and_crossing_ones() {
        let square = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
        assert!(simple(&square));
        let bow = [DVec2::ZERO, DVec2::ONE, DVec2::X, DVec2::Y];
        assert!(!simple(&bow));
        // A corner that turns straight back, and one passed twice.
        assert!(!simple(&[DVec2::ZERO, DVec2::X, DVec2::new(0.5, 0.0), DVec2::Y]));
        assert!(!simple(&[
            DVec2::ZERO,
            DVec2::new(2.0, 0.0),
            DVec2::ONE,
            DVec2::new(2.0, 2.0),
            DVec2::new(0.0, 2.0),
            DVec2::ONE
        ]));
    }
}
