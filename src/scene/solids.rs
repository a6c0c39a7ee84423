//! Closed solids: the parts of an object whose polygons close up into a watertight,
//! consistently wound surface. Found once, when a scene compiles, so that shadow stages can
//! drop the polygons of a solid that face away from a light (see
//! `docs/algorithms/bouknight-kelley.md`, "Speed-ups that are ours").
//!
//! A *solid* is a connected set of an object's polygons in which every edge (between welded
//! vertex positions) is used by exactly two polygons, once in each direction. Its *sign* is
//! the sign of the volume it encloses: +1 when its polygons' front sides face out, −1 when
//! they face in. A segment from a point outside the solid's bounds to any point crosses the
//! surface first from the side its normals point to when the sign is +1 (from the other side
//! when −1), so the first polygon of the solid that such a segment meets always has the
//! outside point on the side the sign names. This needs the surface not to pass through
//! itself with parts turned inside out (a self-intersecting mesh whose winding goes
//! negative), which a scanned or modelled closed mesh does not do.
//!
//! A solid may have *holes*: loops of edges used by one polygon only (a scanned mesh's
//! unscanned patches). The argument then needs a cap over each hole that turns its back to
//! the viewpoint, so that the surface crossed first is never a cap. Such a cap exists when
//! the hole's loop, projected from the viewpoint, is a simple polygon wound the way a
//! polygon turned away is (a triangulation of that polygon, lifted onto the loop's
//! corners, is the cap); [`crate::scene::Scene::closed_from`] checks it per viewpoint, and
//! assumes, as above, that the capped surface does not pass through itself.

use super::LightSample;
use crate::geometry::weiler_atherton::signed_area;
use crate::geometry::{edge_loops, simple, unit};
use glam::{DVec2, DVec3};

/// No solid: the polygon is on an open or non-manifold part of its mesh.
pub(crate) const NO_SOLID: u32 = u32::MAX;

/// One closed, consistently wound surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Solid {
    /// +1 when the polygons' front sides face out of the enclosed volume, −1 when in.
    pub sign: f64,
    /// Its bounding box.
    pub lo: DVec3,
    pub hi: DVec3,
}

impl Solid {
    /// Whether `p` lies outside the solid's bounding box (so outside the solid).
    pub fn outside(&self, p: DVec3) -> bool {
        p.cmplt(self.lo).any() || p.cmpgt(self.hi).any()
    }
}

/// Whether `solid`, with holes `holes`, is closed as seen from `from`: `from` lies outside
/// its bounds (a directional light always does), and each hole, projected from `from`, is
/// a simple polygon wound as a polygon turned away from `from` is (see the module's notes).
pub(crate) fn closed_from(solid: &Solid, holes: &[Vec<DVec3>], from: LightSample) -> bool {
    let outside = match from {
        LightSample::Point(p) => solid.outside(p),
        LightSample::Directional(_) => true,
    };
    outside
        && holes
            .iter()
            .all(|ring| seen_from(from, ring).is_some_and(|r| signed_area(&r) * solid.sign > 0.0 && simple(&r)))
}

/// `ring` projected from `from` onto a plane across the line of sight to its centre, on
/// axes `e1`, `e2` with `e1 × e2` pointing away from `from`: a polygon turned away from
/// `from` comes out counter-clockwise. `None` when a corner is not in front of `from`.
fn seen_from(from: LightSample, ring: &[DVec3]) -> Option<Vec<DVec2>> {
    let centre = ring.iter().copied().sum::<DVec3>() / ring.len() as f64;
    let axis = unit(match from {
        LightSample::Point(p) => centre - p,
        LightSample::Directional(d) => d,
    })?;
    let e1 = axis.any_orthonormal_vector();
    let e2 = axis.cross(e1);
    ring.iter()
        .map(|&v| match from {
            LightSample::Point(p) => {
                let q = v - p;
                let depth = q.dot(axis);
                (depth > 0.0).then(|| DVec2::new(q.dot(e1), q.dot(e2)) / depth)
            }
            LightSample::Directional(_) => Some(DVec2::new(v.dot(e1), v.dot(e2))),
        })
        .collect()
}

/// One polygon's corners: `keys[start..start+len]` (welded vertex ids) and the same range of
/// `verts`.
pub(crate) struct Corners<'a> {
    pub ranges: &'a [(u32, u32)],
    pub keys: &'a [u32],
    pub verts: &'a [DVec3],
}

/// What [`find`] finds among one object's polygons.
pub(crate) struct Found {
    /// For each polygon, its solid's index in the scene's list, or [`NO_SOLID`].
    pub solid_of: Vec<u32>,
    /// The solids, in the order of their first polygons.
    pub solids: Vec<Solid>,
    /// For each corner (parallel to `keys`), the polygon (an index among the object's) across
    /// the edge from that corner to the next, where exactly one other polygon runs that edge
    /// the other way; [`NO_SOLID`] otherwise.
    pub across: Vec<u32>,
    /// Per solid, its holes: each loop of edges used once, as the ring a cap over it runs
    /// (the other way round from the polygons on it).
    pub holes: Vec<Vec<Vec<DVec3>>>,
}

/// The solids among one object's polygons (their indices in the scene's list offset by
/// `first`), and which polygon lies across each edge.
pub(crate) fn find(corners: &Corners, first: u32) -> Found {
    let n = corners.ranges.len();
    let mut sets = DisjointSets::new(n);
    let mut bad = vec![false; n];
    let mut across = vec![NO_SOLID; corners.keys.len()];
    let once = pair_edges(corners, &mut sets, &mut bad, &mut across);
    for p in 0..n {
        if bad[p] {
            let r = sets.root(p);
            bad[r] = true;
        }
    }
    // Each component's holes, from its edges used once; a component whose edges used once
    // do not make loops has none to speak of.
    let mut loose: Vec<Vec<Edge>> = vec![Vec::new(); n];
    for e in once {
        let r = sets.root(e.poly as usize);
        loose[r].push(e);
    }
    let mut holes_of: Vec<Vec<Vec<DVec3>>> = vec![Vec::new(); n];
    for r in 0..n {
        if !bad[r] && !loose[r].is_empty() {
            match loops(&loose[r]) {
                Some(h) => holes_of[r] = h,
                None => bad[r] = true,
            }
        }
    }
    // One solid per component, in the order of its first polygon.
    let mut index = vec![NO_SOLID; n];
    let mut volume: Vec<(f64, DVec3, DVec3, DVec3, usize)> = Vec::new();
    let mut of = vec![NO_SOLID; n];
    for (p, &(start, len)) in corners.ranges.iter().enumerate() {
        let r = sets.root(p);
        if bad[r] {
            continue;
        }
        let v = &corners.verts[start as usize..(start + len) as usize];
        if index[r] == NO_SOLID {
            index[r] = volume.len() as u32;
            volume.push((0.0, v[0], v[0], v[0], r));
        }
        let s = &mut volume[index[r] as usize];
        // Six times the signed volume of the cone from the component's first corner.
        let o = s.1;
        for k in 1..v.len() - 1 {
            s.0 += (v[0] - o).dot((v[k] - o).cross(v[k + 1] - o));
        }
        for &q in v {
            s.2 = s.2.min(q);
            s.3 = s.3.max(q);
        }
        of[p] = index[r];
    }
    // The holes closed by fans from their centres count toward the volume.
    for s in &mut volume {
        let o = s.1;
        for ring in &holes_of[s.4] {
            let c = ring.iter().copied().sum::<DVec3>() / ring.len() as f64;
            for k in 0..ring.len() {
                s.0 += (c - o).dot((ring[k] - o).cross(ring[(k + 1) % ring.len()] - o));
            }
        }
    }
    // A component that encloses (next to) no volume has no inside to speak of.
    let sign: Vec<f64> = volume
        .iter()
        .map(|&(vol, _, lo, hi, _)| {
            let size = (hi - lo).length();
            if vol.abs() > 1e-9 * size * size * size {
                vol.signum()
            } else {
                0.0
            }
        })
        .collect();
    let mut renumber = vec![NO_SOLID; volume.len()];
    let (mut solids, mut holes) = (Vec::new(), Vec::new());
    for (i, &(_, _, lo, hi, r)) in volume.iter().enumerate() {
        if sign[i] != 0.0 {
            renumber[i] = first + solids.len() as u32;
            solids.push(Solid { sign: sign[i], lo, hi });
            holes.push(std::mem::take(&mut holes_of[r]));
        }
    }
    for s in &mut of {
        if *s != NO_SOLID {
            *s = renumber[*s as usize];
        }
    }
    Found { solid_of: of, solids, across, holes }
}

/// An edge used by one polygon only: its polygon, and its ends as welded keys and points.
#[derive(Debug, Clone, Copy)]
struct Edge {
    poly: u32,
    keys: (u32, u32),
    ends: (DVec3, DVec3),
}

/// Edges used once chained into loops, each as the ring a cap over it runs (against the
/// edges); `None` when a corner starts or ends more than one.
fn loops(edges: &[Edge]) -> Option<Vec<Vec<DVec3>>> {
    let keys: Vec<(u32, u32)> = edges.iter().map(|e| e.keys).collect();
    let loops = edge_loops(&keys)?;
    Some(loops.into_iter().map(|l| l.into_iter().rev().map(|e| edges[e].ends.0).collect()).collect())
}

/// Joins the polygons that share an edge, marks `bad` those with an edge shared other than
/// by exactly two polygons running it opposite ways (or no edge at all), and notes in
/// `across` (per corner) the polygon across each edge that is; returns the edges used once.
fn pair_edges(corners: &Corners, sets: &mut DisjointSets, bad: &mut [bool], across: &mut [u32]) -> Vec<Edge> {
    // Each edge as (lesser key, greater key, runs from the greater, polygon, its corner).
    let mut edges = Vec::new();
    for (p, &(start, len)) in corners.ranges.iter().enumerate() {
        let keys = &corners.keys[start as usize..(start + len) as usize];
        for k in 0..keys.len() {
            let (a, b) = (keys[k], keys[(k + 1) % keys.len()]);
            if a == b {
                bad[p] = true;
                continue;
            }
            edges.push((a.min(b), a.max(b), a > b, p as u32, start + k as u32));
        }
    }
    edges.sort_unstable();
    let mut once = Vec::new();
    let mut i = 0;
    while i < edges.len() {
        let (a, b) = (edges[i].0, edges[i].1);
        let mut j = i;
        while j < edges.len() && edges[j].0 == a && edges[j].1 == b {
            j += 1;
        }
        let group = &edges[i..j];
        if group.len() == 2 && group[0].2 != group[1].2 {
            sets.join(group[0].3 as usize, group[1].3 as usize);
            across[group[0].4 as usize] = group[1].3;
            across[group[1].4 as usize] = group[0].3;
        } else if let [(_, _, _, p, c)] = *group {
            let (start, len) = corners.ranges[p as usize];
            let k = c - start;
            let next = start + (k + 1) % len;
            once.push(Edge {
                poly: p,
                keys: (corners.keys[c as usize], corners.keys[next as usize]),
                ends: (corners.verts[c as usize], corners.verts[next as usize]),
            });
        } else {
            for e in group {
                bad[e.3 as usize] = true;
            }
        }
        i = j;
    }
    once
}

/// Union-find over polygon indices.
struct DisjointSets {
    parent: Vec<u32>,
}

impl DisjointSets {
    fn new(n: usize) -> Self {
        DisjointSets { parent: (0..n as u32).collect() }
    }

    fn root(&mut self, mut i: usize) -> usize {
        while self.parent[i] as usize != i {
            let up = self.parent[self.parent[i] as usize];
            self.parent[i] = up;
            i = up as usize;
        }
        i
    }

    fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.root(a), self.root(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb) as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::{Camera, Material, Mesh, Object, Scene, NO_SOLID};
    use glam::DVec3;

    fn cube(flip: bool, at: DVec3) -> Vec<Vec<DVec3>> {
        let c = |x: f64, y: f64, z: f64| at + DVec3::new(x, y, z);
        let mut faces = vec![
            vec![c(0., 0., 0.), c(0., 1., 0.), c(1., 1., 0.), c(1., 0., 0.)],
            vec![c(0., 0., 1.), c(1., 0., 1.), c(1., 1., 1.), c(0., 1., 1.)],
            vec![c(0., 0., 0.), c(1., 0., 0.), c(1., 0., 1.), c(0., 0., 1.)],
            vec![c(0., 1., 0.), c(0., 1., 1.), c(1., 1., 1.), c(1., 1., 0.)],
            vec![c(0., 0., 0.), c(0., 0., 1.), c(0., 1., 1.), c(0., 1., 0.)],
            vec![c(1., 0., 0.), c(1., 1., 0.), c(1., 1., 1.), c(1., 0., 1.)],
        ];
        if flip {
            faces.iter_mut().for_each(|f| f.reverse());
        }
        faces
    }

    fn scene(objects: &[Vec<Vec<DVec3>>]) -> Scene {
        let mut b = Scene::builder(Camera::new(DVec3::new(0.0, 0.0, 9.0), DVec3::ZERO)).material(Material::new("m"));
        for o in objects {
            b = b.object(Object::new(Mesh::from_polygons(o)), "m");
        }
        b.build().unwrap()
    }

    /// A cube is one solid, signed by its winding; two cubes in one object are two solids;
    /// a cube missing a face, or with one face wound the wrong way, is none.
    #[test]
    fn closed_consistently_wound_components_are_solids_with_their_winding_as_sign() {
        let s = scene(&[cube(false, DVec3::ZERO), cube(true, DVec3::X * 3.0)]);
        assert_eq!(s.solids.len(), 2);
        assert_eq!((s.solids[0].sign, s.solids[1].sign), (1.0, -1.0));
        assert!(s.solid_of[..6].iter().all(|&i| i == 0) && s.solid_of[6..].iter().all(|&i| i == 1));
        assert_eq!((s.solids[1].lo, s.solids[1].hi), (DVec3::X * 3.0, DVec3::new(4.0, 1.0, 1.0)));

        let mut two = cube(false, DVec3::ZERO);
        two.extend(cube(false, DVec3::Y * 2.0));
        let s = scene(&[two]);
        assert_eq!(s.solids.len(), 2);

        let mut wrong = cube(false, DVec3::ZERO);
        wrong[2].reverse();
        let s = scene(&[wrong]);
        assert!(s.solids.is_empty() && s.solid_of.iter().all(|&i| i == NO_SOLID));
    }

    /// A cube missing its face at x = 1 is a solid with one hole, closed as seen from the
    /// side away from the hole (a cap there would turn its back) and not from the hole's
    /// side, nor from inside its bounds; its polygons turned away are left out only where it
    /// is closed.
    #[test]
    fn a_solid_with_a_hole_is_closed_only_from_where_a_cap_would_turn_away() {
        use crate::scene::LightSample;
        let mut open = cube(false, DVec3::ZERO);
        open.pop();
        let s = scene(&[open]);
        assert_eq!(s.solids.len(), 1);
        assert_eq!(s.solid_holes[0].len(), 1);
        assert_eq!(s.solid_holes[0][0].len(), 4);
        let from = |p: DVec3| s.closed_from(LightSample::Point(p))[0];
        assert!(from(DVec3::new(-5.0, 0.3, 0.4)));
        assert!(!from(DVec3::new(5.0, 0.3, 0.4)));
        assert!(!from(DVec3::new(0.5, 0.5, 0.5)));
        assert!(s.closed_from(LightSample::Directional(DVec3::X))[0]);
        assert!(!s.closed_from(LightSample::Directional(DVec3::NEG_X))[0]);
        // Seen from x = -5, the face at x = 0 faces the viewpoint and the one at z = 1 (the
        // second) turns away from a viewpoint at z = -3.
        let p = LightSample::Point(DVec3::new(-5.0, 0.3, -3.0));
        let closed = s.closed_from(p);
        assert!(!s.turned_away_on_solid(4, p, &closed) && s.turned_away_on_solid(1, p, &closed));
        let q = LightSample::Point(DVec3::new(5.0, 0.3, -3.0));
        assert!(!s.turned_away_on_solid(1, q, &s.closed_from(q)));
    }

    /// Edges used once that pass a corner twice (a figure eight) make no hole to cap; a
    /// triangle's make one, run the other way round.
    #[test]
    fn holes_are_simple_chains_of_edges_used_once() {
        use super::{loops, Edge};
        let p = |k: u32| DVec3::new(k as f64, (k * k) as f64, 0.0);
        let edge = |a: u32, b: u32| Edge { poly: 0, keys: (a, b), ends: (p(a), p(b)) };
        let eight = [edge(0, 1), edge(1, 2), edge(2, 0), edge(0, 3), edge(3, 4), edge(4, 0)];
        assert!(loops(&eight).is_none());
        let triangle = [edge(0, 1), edge(1, 2), edge(2, 0)];
        assert_eq!(loops(&triangle), Some(vec![vec![p(2), p(1), p(0)]]));
        assert!(loops(&[edge(0, 1), edge(1, 2)]).is_none(), "a chain that does not close");
    }

    /// Two closed cubes that share a face (four polygons on one edge) are not solids.
    #[test]
    fn an_edge_used_more_than_twice_is_not_closed() {
        let mut two = cube(false, DVec3::ZERO);
        two.extend(cube(false, DVec3::X));
        let s = scene(&[two]);
        assert!(s.solids.is_empty());
    }
}
