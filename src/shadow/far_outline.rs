//! Z-fail's far caps counted as the outline of their union (ours; `--no-far-outline` turns
//! it off).
//!
//! Z-fail closed at a far plane ([`super::volumes`], `FarPlane`) starts every count from the
//! far caps: each volume's cross-section with a plane beyond the scene, all in that one
//! plane, behind every visible point, each adding +1. What they add at a pixel therefore
//! depends on the pixel alone: it is the number of far caps whose screen outlines hold its
//! centre. Summed as indicator functions, that number is the winding number of the caps'
//! outlines taken together, each wound the same way; and where two casters share an edge,
//! their caps share its image, run once each way, and the two cancel. What is left is the
//! outline of the caps' union: on a closed mesh lit from outside, the far ends of the
//! silhouette's sides (on s3, the far caps of 490,095 triangles).
//!
//! 1. **Wound alike.** Each far cap is put on screen as before, and its edges are kept wound
//!    so that its inside has winding number +1 ([`wound`], from its normal in the
//!    world, never from its screen area, which rounding can turn for a sliver).
//! 2. **Cancelled.** A cap *whole* on screen (nothing of it cut, by the projection's clips
//!    or the camera's) is its corners' images, each worked out from the corner alone
//!    (`Target::onto`, then the camera), so the caps on one edge of the scene give its
//!    image the same bits. Such a cap leaves only the way it winds, and a pass over the
//!    merged edges (`volumes::Adjacency`) sums, on each, the ways its whole caps run it:
//!    an edge run as often each way is left out, any other is kept with its count (on a
//!    closed mesh, the far end of a side). A cap that was cut leaves its own edges. Last,
//!    edges with the same end points' bits are summed and those that come to zero dropped
//!    ([`cancel`]); an edge that finds no partner stays and still counts right.
//! 3. **Walked.** The edges left go into an edge table of their own, each tagged with the
//!    weight its crossing adds ([`FarEdge::crossing_weight`]); the count at a pixel adds the
//!    weights of the crossings at or left of its centre. A cap edge's crossings are those
//!    it made in the caps' table (the same edge from the same end points, walked by the
//!    same rule), and a cancelled pair's crossings fall on the same pixel, once +1 and
//!    once −1: the count is the one the caps gave, pixel by pixel.
//!
//! The caps of volumes kept apart (fan pieces, self-intersecting polygons) stay shadow
//! polygons of their own: a kept-apart volume never counts on its own face.

use crate::geometry::Plane;
use crate::scan::EdgeTable;
use crate::view::View;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// A screen edge between `lo` and `hi` (ordered by their bits, [`key`]), run `w` times from
/// `lo` to `hi` (negative: from `hi` to `lo`) by caps wound counter-clockwise (positive
/// shoelace area in screen coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FarEdge {
    pub(crate) lo: DVec2,
    pub(crate) hi: DVec2,
    pub(crate) w: i32,
}

impl FarEdge {
    /// The edge `a → b` run once.
    fn new(a: DVec2, b: DVec2) -> FarEdge {
        if key(a) <= key(b) {
            FarEdge { lo: a, hi: b, w: 1 }
        } else {
            FarEdge { lo: b, hi: a, w: -1 }
        }
    }

    /// The edge `a → b` run `n` times (negative: the other way).
    pub(crate) fn run(a: DVec2, b: DVec2, n: i32) -> FarEdge {
        let e = FarEdge::new(a, b);
        FarEdge { w: e.w * n, ..e }
    }

    /// What crossing it adds to the winding number of a point right of the crossing: an
    /// edge of a cap wound counter-clockwise (positive shoelace area) runs toward lesser `y`
    /// on the cap's left side, where a line from the left enters it.
    pub(crate) fn crossing_weight(&self) -> i32 {
        if self.hi.y < self.lo.y {
            self.w
        } else {
            -self.w
        }
    }
}

/// Step 3's edge table of `edges`, for an image `height` lines high: each edge tagged with
/// its crossing's weight (an `i32`'s bits).
pub(crate) fn table(height: u32, edges: &[FarEdge]) -> EdgeTable {
    let mut table = EdgeTable::new(height);
    for e in edges {
        table.add_edge(e.crossing_weight() as u32, e.lo, e.hi);
    }
    table.finish();
    table
}

/// A point's key: its bits, `x` first.
fn key(p: DVec2) -> (u64, u64) {
    (p.x.to_bits(), p.y.to_bits())
}

/// The edges of the closed `ring` wound `winding` (+1: as listed, −1: reversed), onto `out`.
pub(crate) fn push_ring(ring: &[DVec2], winding: i32, out: &mut Vec<FarEdge>) {
    let from = ring.last().into_iter().chain(ring);
    out.extend(from.zip(ring).map(|(&a, &b)| if winding > 0 { FarEdge::new(a, b) } else { FarEdge::new(b, a) }));
}

/// Step 2: the edges with the same end points summed, those that come to zero dropped, in
/// the order of their keys (sorted by all threads when there are many).
pub(crate) fn cancel(mut edges: Vec<FarEdge>) -> Vec<FarEdge> {
    let by_ends = |e: &FarEdge| (key(e.lo), key(e.hi));
    if edges.len() >= 1 << 16 {
        edges.par_sort_unstable_by_key(by_ends);
    } else {
        edges.sort_unstable_by_key(by_ends);
    }
    edges.dedup_by(|e, kept| {
        let same = by_ends(e) == by_ends(kept);
        if same {
            kept.w += e.w;
        }
        same
    });
    edges.retain(|e| e.w != 0);
    edges.shrink_to_fit();
    edges
}

/// What every patch of `plane` with positive area about its normal winds on screen: `view`'s
/// side of the plane times the handedness of the camera's axes (0 when the eye lies in the
/// plane). The perspective projection gives a small patch at camera point `c` with normal
/// `N` the orientation of `N · c` in `(x/z, y/z)`, and the screen's `y` runs down; `N · c`
/// has the sign of the area about the normal times minus the eye's side, for every point of
/// the plane. One number for the whole plane, worked out once for all its caps.
pub(crate) fn facing(view: &View, plane: &Plane) -> i32 {
    let eye_side = plane.distance(view.eye);
    if eye_side == 0.0 {
        return 0;
    }
    let handedness = view.r.dot(view.u.cross(view.f));
    (eye_side.signum() * handedness.signum()) as i32
}

/// Step 1: which way a far cap winds on screen, +1 counter-clockwise (positive shoelace
/// area), from its Newell normal in the world (`newell`) on `plane`, whose [`facing`] is
/// `facing`: the sign of its area about the plane's normal times the facing. Zero for a cap
/// with no area about the normal, or on a plane the eye sees edge-on.
pub(crate) fn wound(newell: DVec3, plane: &Plane, facing: i32) -> i32 {
    let area = newell.dot(plane.n);
    if area == 0.0 {
        return 0;
    }
    area.signum() as i32 * facing
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Twice the shoelace area of a ring.
    fn shoelace(ring: &[DVec2]) -> f64 {
        let from = ring.last().into_iter().chain(ring);
        from.zip(ring).map(|(a, b)| a.x * b.y - b.x * a.y).sum()
    }

    #[test]
    fn the_winding_from_the_world_is_the_winding_on_screen() {
        // Triangles on planes of every tilt, seen from eyes on both sides, by cameras of
        // both handednesses: the world's answer matches the screen's area.
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut checked = 0;
        for _ in 0..2000 {
            let eye = DVec3::new(next(), next(), next()) * 5.0;
            let target = DVec3::new(next(), next(), next());
            let camera = crate::scene::Camera {
                eye,
                target,
                up: DVec3::Y,
                fov_y: 50.0,
                width: 640,
                height: 480,
                near: 0.01,
                far: None,
            };
            let mut view = View::new(&camera);
            if next() > 0.0 {
                view.r = -view.r; // the other handedness
            }
            let n = DVec3::new(next(), next(), next()).normalize();
            let centre = target + DVec3::new(next(), next(), next()) * 0.5;
            let (u, v) = (n.any_orthonormal_vector(), n.cross(n.any_orthonormal_vector()));
            let tri: Vec<DVec3> = (0..3).map(|_| centre + u * next() * 0.3 + v * next() * 0.3).collect();
            let screen: Vec<DVec2> =
                tri.iter().map(|&p| view.to_camera(p)).filter(|c| c.z > 0.05).map(|c| view.project(c)).collect();
            if screen.len() < 3 {
                continue;
            }
            let area = shoelace(&screen);
            if area.abs() < 1e-3 {
                continue;
            }
            let plane = Plane::new(n, centre);
            let w = wound(crate::geometry::newell_normal(&tri), &plane, facing(&view, &plane));
            assert_eq!(w, area.signum() as i32, "eye {eye} target {target} n {n}");
            checked += 1;
        }
        assert!(checked > 500, "{checked}");
    }

    #[test]
    fn shared_edges_cancel_and_the_rest_wind_once() {
        // Two triangles sharing an edge, one listed clockwise (wound -1), make a square:
        // four edges are left, each run once, and they wind +1 inside.
        let (a, b, c, d) = (DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0));
        let mut edges = Vec::new();
        push_ring(&[a, b, c], 1, &mut edges);
        push_ring(&[a, d, c], -1, &mut edges);
        let left = cancel(edges);
        assert_eq!(left.len(), 4);
        assert!(left.iter().all(|e| e.w.abs() == 1));
        // A line through the middle crosses the left edge (+1) and the right edge (−1).
        let crossing = |x: f64| left.iter().find(|e| e.lo.x == x && e.hi.x == x).unwrap().crossing_weight();
        assert_eq!((crossing(0.0), crossing(1.0)), (1, -1));
        // The same cap twice stays, run twice.
        let mut twice = Vec::new();
        push_ring(&[a, b, c], 1, &mut twice);
        push_ring(&[a, b, c], 1, &mut twice);
        assert!(cancel(twice).iter().all(|e| e.w.abs() == 2));
    }
}
