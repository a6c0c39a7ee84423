//! Closed solids: the parts of an object whose polygons close up into a watertight,
//! consistently wound surface. Found once, when a scene compiles, so that the hidden-surface
//! stages can leave out a solid's polygons turned away from the eye and the shadow stages
//! those turned away from a light (ours, not the papers'; see
//! `docs/algorithms/bouknight-kelley.md`, "Speed-ups that are ours").
//!
//! A *solid* is a connected set of an object's polygons in which every edge (between welded
//! vertex positions) is used by exactly two polygons, once in each direction, and which
//! encloses a volume. Its *sign* is the sign of that volume: +1 when its polygons' front sides
//! face out, −1 when they face in. A segment from a point outside the solid's bounds to any
//! point crosses the surface first from the side its normals point to when the sign is +1
//! (from the other side when −1): the winding number of the surface is 0 outside its bounds,
//! and the first crossing takes it to the sign, never to its opposite. So the first polygon
//! of the solid that such a segment meets always has the outside point on the side the sign
//! names. This needs the surface to have no region of winding opposite to its sign (no part
//! turned inside out through the rest), which a modelled or scanned closed mesh does not
//! have; a surface that passes through itself without turning inside out (a pushed-through
//! lobe, winding 2) keeps the argument.
//!
//! A mesh with an edge used by one polygon only (an open sheet, a fan, a grid, a scanned mesh
//! with unscanned patches) is never a solid. Closing its holes with caps would need each cap
//! to meet the surface nowhere but on its hole, and a cap across an open sheet lies across the
//! sheet itself: taking such a mesh for a solid with a hole hid seen faces on random scenes
//! (`tests/data/solids/`).

use super::LightSample;
use glam::DVec3;
use rayon::slice::ParallelSliceMut;

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

    /// Whether the solid is closed as seen from `from`: `from` lies outside its bounds (a
    /// directional light always does), so every segment from `from` starts at winding 0.
    pub fn closed_from(&self, from: LightSample) -> bool {
        match from {
            LightSample::Point(p) => self.outside(p),
            LightSample::Directional(_) => true,
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
}

/// The solids among one object's polygons (their indices in the scene's list offset by
/// `first`), and which polygon lies across each edge.
pub(crate) fn find(corners: &Corners, first: u32) -> Found {
    let n = corners.ranges.len();
    let mut sets = DisjointSets::new(n);
    let mut open = vec![false; n];
    let mut across = vec![NO_SOLID; corners.keys.len()];
    pair_edges(corners, &mut sets, &mut open, &mut across);
    for p in 0..n {
        if open[p] {
            let r = sets.root(p);
            open[r] = true;
        }
    }
    // One candidate per closed component, in the order of its first polygon: six times the
    // signed volume of the cones from its first corner, and its bounds.
    let mut index = vec![NO_SOLID; n];
    let mut volume: Vec<(f64, DVec3, DVec3, DVec3)> = Vec::new();
    let mut of = vec![NO_SOLID; n];
    for (p, &(start, len)) in corners.ranges.iter().enumerate() {
        let r = sets.root(p);
        if open[r] {
            continue;
        }
        let v = &corners.verts[start as usize..(start + len) as usize];
        if index[r] == NO_SOLID {
            index[r] = volume.len() as u32;
            volume.push((0.0, v[0], v[0], v[0]));
        }
        let s = &mut volume[index[r] as usize];
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
    // A component that encloses no volume (two faces back to back) has no inside to speak of.
    let mut renumber = vec![NO_SOLID; volume.len()];
    let mut solids = Vec::new();
    for (i, &(vol, _, lo, hi)) in volume.iter().enumerate() {
        let size = (hi - lo).length();
        if vol.abs() > 1e-9 * size * size * size {
            renumber[i] = first + solids.len() as u32;
            solids.push(Solid { sign: vol.signum(), lo, hi });
        }
    }
    for s in &mut of {
        if *s != NO_SOLID {
            *s = renumber[*s as usize];
        }
    }
    Found { solid_of: of, solids, across }
}

/// Joins the polygons that share an edge, marks `open` those with an edge used other than by
/// exactly two polygons running it opposite ways (an edge used once, an edge used three
/// times or more, an edge from a corner to itself), and notes in `across` (per corner) the
/// polygon across each edge that is.
fn pair_edges(corners: &Corners, sets: &mut DisjointSets, open: &mut [bool], across: &mut [u32]) {
    // Each edge as (lesser key, greater key, runs from the greater, polygon, its corner).
    let mut edges = Vec::new();
    for (p, &(start, len)) in corners.ranges.iter().enumerate() {
        let keys = &corners.keys[start as usize..(start + len) as usize];
        for k in 0..keys.len() {
            let (a, b) = (keys[k], keys[(k + 1) % keys.len()]);
            if a == b {
                open[p] = true;
                continue;
            }
            edges.push((a.min(b), a.max(b), a > b, p as u32, start + k as u32));
        }
    }
    // Every edge is distinct (its corner is its own), so any sort gives this order.
    edges.par_sort_unstable();
    for group in edges.chunk_by(|e, f| (e.0, e.1) == (f.0, f.1)) {
        if let [e, f] = group {
            if e.2 != f.2 {
                sets.join(e.3 as usize, f.3 as usize);
                across[e.4 as usize] = f.3;
                across[f.4 as usize] = e.3;
                continue;
            }
        }
        for e in group {
            open[e.3 as usize] = true;
        }
    }
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

    /// A cube missing a face is open: no solid, whatever its volume with the hole capped.
    /// So is a bumpy open sheet, whose capped volume is not zero either (the cap would lie
    /// across the sheet; `tests/data/solids/` holds random scenes where taking such sheets for
    /// solids with a hole hid faces the eye sees).
    #[test]
    fn a_mesh_with_an_edge_used_once_is_no_solid() {
        let mut open = cube(false, DVec3::ZERO);
        open.pop();
        let s = scene(&[open]);
        assert!(s.solids.is_empty() && s.solid_of.iter().all(|&i| i == NO_SOLID));

        let h = |x: usize, z: usize| 0.3 * ((x * 7 + z * 3) % 5) as f64;
        let p = |x: usize, z: usize| DVec3::new(x as f64, h(x, z), z as f64);
        let sheet: Vec<Vec<DVec3>> = (0..3)
            .flat_map(|x| (0..3).map(move |z| (x, z)))
            .flat_map(|(x, z)| {
                [vec![p(x, z), p(x, z + 1), p(x + 1, z)], vec![p(x + 1, z), p(x, z + 1), p(x + 1, z + 1)]]
            })
            .collect();
        let s = scene(&[sheet]);
        assert_eq!(s.polygons.len(), 18);
        assert!(s.solids.is_empty(), "an open sheet is not closed");
    }

    /// A solid is closed from a viewpoint outside its bounds, and from every directional
    /// light; from inside its bounds its turned-away polygons may be seen, so none is left out.
    #[test]
    fn a_solid_is_closed_only_from_outside_its_bounds() {
        use crate::scene::LightSample;
        let s = scene(&[cube(false, DVec3::ZERO)]);
        let outside = LightSample::Point(DVec3::new(-5.0, 0.3, -3.0));
        let closed = s.closed_from(outside);
        assert_eq!(closed, vec![true]);
        // From x = -5, z = -3 the face at x = 0 (the fifth) faces the viewpoint, the one at
        // z = 1 (the second) turns away: it is left out.
        assert!(!s.turned_away_on_solid(4, outside, &closed) && s.turned_away_on_solid(1, outside, &closed));
        let inside = LightSample::Point(DVec3::new(0.5, 0.5, 0.5));
        let closed = s.closed_from(inside);
        assert_eq!(closed, vec![false]);
        assert!((0..6).all(|i| !s.turned_away_on_solid(i, inside, &closed)));
        assert_eq!(s.closed_from(LightSample::Directional(DVec3::X)), vec![true]);
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
