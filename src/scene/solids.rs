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
//! assumes, as above, that the capped surface does not pass through itself. A hole no such
//! cap closes is a *window*: closed by the fan from its centre, which the viewpoint sees
//! within the box of the hole's corners, it hides only the polygons seen there.

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

/// How a solid looks from one viewpoint ([`closed_from`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) enum Closure {
    /// Its polygons turned away may be seen.
    #[default]
    Open,
    /// Closed but for these windows: a polygon turned away from the viewpoint is hidden by
    /// the solid's own polygons unless, seen from the viewpoint, it may lie behind one.
    Closed(Vec<Window>),
}

/// A hole that no cap turned away from the viewpoint can close. The cap taken for it is the
/// fan from its centre, which, seen from the viewpoint, lies within the box of its
/// corners.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Window {
    frame: Frame,
    lo: DVec2,
    hi: DVec2,
}

impl Window {
    /// Whether a polygon with corners `verts` may, seen from the viewpoint, lie behind the
    /// window (its box meets the window's, or a corner is not in front of the viewpoint).
    pub fn may_show(&self, verts: &[DVec3]) -> bool {
        let Some(seen) = verts.iter().map(|&v| self.frame.see(v)).collect::<Option<Vec<DVec2>>>() else { return true };
        let Some((lo, hi)) = crate::geometry::weiler_atherton::ring_bounds(&seen) else { return true };
        lo.cmple(self.hi).all() && self.lo.cmple(hi).all()
    }
}

/// How a solid with holes `holes` looks from `from`: open when `from` lies inside its
/// bounds (a directional light never does); otherwise closed, but for the holes that,
/// projected from `from`, are not simple polygons wound as a polygon turned away from
/// `from` is (those a cap turned away could close; see the module's notes).
pub(crate) fn closed_from(solid: &Solid, holes: &[Vec<DVec3>], from: LightSample) -> Closure {
    let outside = match from {
        LightSample::Point(p) => solid.outside(p),
        LightSample::Directional(_) => true,
    };
    if !outside {
        return Closure::Open;
    }
    let mut windows = Vec::new();
    for ring in holes {
        let Some(frame) = Frame::toward(from, ring) else { return Closure::Open };
        let Some(seen) = ring.iter().map(|&v| frame.see(v)).collect::<Option<Vec<DVec2>>>() else {
            return Closure::Open;
        };
        if signed_area(&seen) * solid.sign > 0.0 && simple(&seen) {
            continue;
        }
        let Some((lo, hi)) = crate::geometry::weiler_atherton::ring_bounds(&seen) else { return Closure::Open };
        windows.push(Window { frame, lo, hi });
    }
    Closure::Closed(windows)
}

/// A view from `from` across the line of sight to a hole's centre, on axes `e1`, `e2` with
/// `e1 × e2 = axis` pointing away from `from`: a polygon turned away from `from` comes out
/// counter-clockwise.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Frame {
    from: LightSample,
    axis: DVec3,
    e1: DVec3,
    e2: DVec3,
}

impl Frame {
    fn toward(from: LightSample, ring: &[DVec3]) -> Option<Frame> {
        let centre = ring.iter().copied().sum::<DVec3>() / ring.len() as f64;
        let axis = unit(match from {
            LightSample::Point(p) => centre - p,
            LightSample::Directional(d) => d,
        })?;
        let e1 = axis.any_orthonormal_vector();
        Some(Frame { from, axis, e1, e2: axis.cross(e1) })
    }

    /// Where `v` is seen, or `None` when it is not in front of the viewpoint.
    fn see(&self, v: DVec3) -> Option<DVec2> {
        match self.from {
            LightSample::Point(p) => {
                let q = v - p;
                let depth = q.dot(self.axis);
                (depth > 0.0).then(|| DVec2::new(q.dot(self.e1), q.dot(self.e2)) / depth)
            }
            LightSample::Directional(_) => Some(DVec2::new(v.dot(self.e1), v.dot(self.e2))),
        }
    }
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

    /// A cube missing its face at x = 1 is a solid with one hole. Seen from the side away
    /// from the hole it is closed (a cap there would turn its back); seen from the hole's
    /// side the hole is a window, through which the inside faces turned away are seen, so
    /// they stay; from inside its bounds it is open.
    #[test]
    fn a_solid_with_a_hole_is_closed_but_for_the_windows_it_shows() {
        use crate::scene::{Closure, LightSample};
        let mut open = cube(false, DVec3::ZERO);
        open.pop();
        let s = scene(&[open]);
        assert_eq!(s.solids.len(), 1);
        assert_eq!(s.solid_holes[0].len(), 1);
        assert_eq!(s.solid_holes[0][0].len(), 4);
        let windows = |from: LightSample| match &s.closed_from(from)[0] {
            Closure::Closed(w) => Some(w.len()),
            Closure::Open => None,
        };
        assert_eq!(windows(LightSample::Point(DVec3::new(-5.0, 0.3, 0.4))), Some(0));
        assert_eq!(windows(LightSample::Point(DVec3::new(5.0, 0.3, 0.4))), Some(1));
        assert_eq!(windows(LightSample::Point(DVec3::new(0.5, 0.5, 0.5))), None);
        assert_eq!(windows(LightSample::Directional(DVec3::X)), Some(0));
        assert_eq!(windows(LightSample::Directional(DVec3::NEG_X)), Some(1));
        // From x = -5 the face at x = 0 (the fifth) faces the viewpoint, and the one at
        // z = 1 (the second) turns away from a viewpoint at z = -3: it is left out.
        let p = LightSample::Point(DVec3::new(-5.0, 0.3, -3.0));
        let closed = s.closed_from(p);
        assert!(!s.turned_away_on_solid(4, p, &closed) && s.turned_away_on_solid(1, p, &closed));
        // From x = 5 every face but the missing one is seen from inside, through the hole.
        let q = LightSample::Point(DVec3::new(5.0, 0.3, 0.4));
        let closed = s.closed_from(q);
        assert!((0..5).all(|i| !s.turned_away_on_solid(i, q, &closed)));
    }

    /// A long box open at its end x = 10, seen from beyond that end and above: through the
    /// hole the viewpoint sees the inside of the far end (x = 0) only near the hole's line of
    /// sight, so the far end's face, turned away and seen well off the window, is left out,
    /// while the faces along the box, which reach the window, stay.
    #[test]
    fn a_window_keeps_only_what_may_be_seen_through_it() {
        use crate::scene::LightSample;
        let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let tube = vec![
            vec![c(0., 0., 0.), c(0., 1., 0.), c(10., 1., 0.), c(10., 0., 0.)],
            vec![c(0., 0., 1.), c(10., 0., 1.), c(10., 1., 1.), c(0., 1., 1.)],
            vec![c(0., 0., 0.), c(10., 0., 0.), c(10., 0., 1.), c(0., 0., 1.)],
            vec![c(0., 1., 0.), c(0., 1., 1.), c(10., 1., 1.), c(10., 1., 0.)],
            vec![c(0., 0., 0.), c(0., 0., 1.), c(0., 1., 1.), c(0., 1., 0.)],
        ];
        let s = scene(&[tube]);
        assert_eq!(s.solids.len(), 1);
        // From high above, just beyond the open end: the closed end at x = 0 faces out along
        // -x, away from the viewpoint at x = 11.
        let p = LightSample::Point(DVec3::new(11.0, 30.0, 0.5));
        let closed = s.closed_from(p);
        assert!(matches!(&closed[0], crate::scene::Closure::Closed(w) if w.len() == 1));
        assert!(s.turned_away_on_solid(4, p, &closed), "the far end lies well off the window");
        assert!(!s.turned_away_on_solid(2, p, &closed), "the floor of the box reaches the window");
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
