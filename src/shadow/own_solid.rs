//! Bouknight-Kelley's behind test answered for a receiver's own closed solid at once (ours;
//! the switch `own_solid`, `--no-own-solid`; see `docs/algorithms/bouknight-kelley.md`).
//!
//! The pair loop drops, unprojected, a caster whose every corner lies on or behind the
//! receiver's plane as the light sees it, or is a corner of the receiver (`drop_behind`). On
//! closed meshes most of the casters the sphere prefilter offers a receiver are of this kind:
//! the polygons of the receiver's own solid around it as the light sees them (on s3, 92% of
//! what the grid's cells offer). Each was gathered from the grid, its cone compared and its
//! corners measured, one pair at a time.
//!
//! 1. **The front set, once per polygon B of a closed solid**, the first time B is a
//!    receiver (kept for later frames of the same polygons, as Crow's edge adjacency is):
//!    the polygons of B's solid with a corner that lies strictly in front of B's plane on
//!    the solid's outer side and is not a corner of B. The test is the pair loop's own
//!    arithmetic (`Plane::distance` times the side, the side being the solid's sign), put to
//!    the solid's vertices in a box tree. A box is not opened when it holds no vertex in
//!    front, for one of two reasons:
//!    - its corner furthest along the normal measures at most zero, by the same dot product
//!      (rounding is monotone, so no vertex of the box measures more than that corner);
//!    - it misses the box round the *cap*: the part of the ball round the solid's centre
//!      that holds its vertices which lies in front of B's plane, taken a billionth of the
//!      solid's size larger than it is, so that rounding cannot put a vertex in front outside
//!      it. On a rounded solid the cap is a sliver the size of B, and a query opens a few
//!      boxes beside B (on s3, 29 boxes a query, where the first test alone opened 136).
//! 2. **For each receiver** whose light lies on its solid's outer side of its plane (the
//!    side the pair loop then measures from is the solid's sign), the pair loop takes, of
//!    its own solid's polygons, only the front set: the behind test drops every other. In
//!    the grid's cells the solid's polygons are one stretch (a cell lists its casters in
//!    increasing order, and a solid's polygons are one range of indices), passed over
//!    unread but for the front set's.
//!
//! The casters left are the ones the pair loop would keep, in the same order, so the images
//! are the same with the step on or off; only the counters move (the skipped pairs are
//! neither kept by the prefilter nor dropped as behind). A convex solid has empty front
//! sets, but the step asks no convexity: s3's spheres, made of quadrilaterals cut in two
//! whose corners lie off one plane by up to a billionth, give a triangle whose neighbour
//! across the cut rises above its plane that neighbour as its front set.

use crate::pool::Stash;
use crate::scene::{LightSample, Scene};
use glam::DVec3;
use rustc_hash::FxHashMap;
use std::sync::{Arc, OnceLock};

/// For a scene's closed solids, their vertices in box trees, and each polygon's front set
/// once it is asked for (step 1).
pub(crate) struct OwnSolid {
    /// Each solid's polygons, in increasing order.
    members: Vec<Vec<u32>>,
    trees: Vec<OnceLock<SolidTree>>,
    /// `front[i]`: the front set of polygon `i` (on a closed solid), in increasing order.
    front: Vec<OnceLock<Box<[u32]>>>,
}

/// What step 2 leaves of receiver `b`'s own solid: the solid, its polygons' range of
/// indices where they are one, and `b`'s front set.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Own<'a> {
    solid: u32,
    range: Option<(u32, u32)>,
    pub front: &'a [u32],
}

impl Own<'_> {
    /// Whether the pair loop passes over polygon `a`, on solid `solid_of`.
    #[inline]
    pub fn skips(&self, a: u32, solid_of: u32) -> bool {
        let own = match self.range {
            Some((lo, hi)) => (lo..=hi).contains(&a),
            None => solid_of == self.solid,
        };
        own && self.front.binary_search(&a).is_err()
    }

    /// The polygons of a cell's list (in increasing order) that the pair loop passes over,
    /// as the stretch `start..end` of it, when the solid's polygons are one range; the front
    /// set's among them are to be taken on their own.
    #[inline]
    pub fn stretch(&self, cell: &[u32]) -> Option<(usize, usize)> {
        let (lo, hi) = self.range?;
        Some((cell.partition_point(|&a| a < lo), cell.partition_point(|&a| a <= hi)))
    }
}

/// An [`OwnSolid`] kept by a renderer, for which polygons ([`Scene::polygons_id`]).
type Kept = (u64, Arc<OwnSolid>);

impl OwnSolid {
    /// Step 1's structure for `scene`, from `kept` when an earlier frame of the same
    /// polygons made it (it depends on the polygons alone).
    pub(crate) fn kept(scene: &Scene, kept: &Stash) -> Arc<OwnSolid> {
        let id = scene.polygons_id;
        kept.find_or_make::<Kept>(|k| k.0 == id, || (id, Arc::new(OwnSolid::new(scene))), 4).1
    }

    /// No tree and no front set yet: each is made the first time it is asked for.
    fn new(scene: &Scene) -> Self {
        let trees = (0..scene.solids.len()).map(|_| OnceLock::new()).collect();
        let polygons = if scene.solids.is_empty() { 0 } else { scene.polygons.len() };
        let front = (0..polygons).map(|_| OnceLock::new()).collect();
        OwnSolid { members: scene.solid_members(), trees, front }
    }

    /// The bytes it holds (for `--stats`): the front sets and the trees made so far.
    pub(crate) fn bytes(&self) -> usize {
        let sets: usize = self.front.iter().filter_map(|f| f.get()).map(|f| f.len() * 4).sum();
        let members: usize = self.members.iter().map(|m| m.capacity() * 4).sum();
        let trees: usize = self.trees.iter().filter_map(|t| t.get()).map(SolidTree::bytes).sum();
        self.front.len() * std::mem::size_of::<OnceLock<Box<[u32]>>>() + sets + members + trees
    }

    /// Step 2: what receiver `b` takes of its own solid for light sample `sample`, when the
    /// light lies on the solid's outer side of its plane.
    pub(crate) fn of(&self, scene: &Scene, b: u32, sample: LightSample) -> Option<Own<'_>> {
        let solid = scene.solid_of[b as usize];
        let on = scene.solids.get(solid as usize)?;
        if super::projection::light_side(&scene.polygons[b as usize].plane, sample) != on.sign {
            return None;
        }
        let tree =
            self.trees[solid as usize].get_or_init(|| SolidTree::new(scene, solid, &self.members[solid as usize]));
        let front = self.front[b as usize].get_or_init(|| tree.front_of(scene, b, on.sign));
        Some(Own { solid, range: tree.range, front })
    }
}

/// One solid's vertices (each position once) in a tree of boxes, halved along their longest
/// side down to [`LEAF`] vertices, and the solid's polygons at each.
struct SolidTree {
    /// The solid's polygons as one range of indices, where they are.
    range: Option<(u32, u32)>,
    /// The centre of the solid's bounding box, and the ball round it that holds its
    /// vertices: its radius.
    centre: DVec3,
    reach: f64,
    /// The vertices, in the tree's order.
    verts: Vec<DVec3>,
    /// `at[k]`: the polygons with a corner at `verts[k]` are `polygons[start[at[k]]..start[at[k] + 1]]`.
    at: Vec<u32>,
    start: Vec<u32>,
    polygons: Vec<u32>,
    nodes: Vec<Node>,
}

/// A box of the tree: its bounds, its vertices `start..end`, and its two halves (none for a
/// leaf).
struct Node {
    lo: DVec3,
    hi: DVec3,
    start: u32,
    end: u32,
    halves: Option<[u32; 2]>,
}

/// The most vertices a leaf holds.
const LEAF: usize = 8;

impl SolidTree {
    fn new(scene: &Scene, solid: u32, members: &[u32]) -> Self {
        let range = match (members.first(), members.last()) {
            (Some(&lo), Some(&hi)) if (hi - lo) as usize + 1 == members.len() => Some((lo, hi)),
            _ => None,
        };
        // Each position once (`items`, with its number), and every corner's position.
        let mut number: FxHashMap<[u64; 3], u32> = FxHashMap::default();
        let mut items: Vec<(DVec3, u32)> = Vec::new();
        let at: Vec<u32> = members
            .iter()
            .flat_map(|&i| scene.verts(i as usize))
            .map(|v| {
                *number.entry(v.to_array().map(f64::to_bits)).or_insert_with(|| {
                    items.push((*v, items.len() as u32));
                    items.len() as u32 - 1
                })
            })
            .collect();
        drop(number);
        // The polygons at each position, in increasing order (a count, then a fill).
        let mut start = vec![0u32; items.len() + 1];
        at.iter().for_each(|&g| start[g as usize + 1] += 1);
        (1..start.len()).for_each(|g| start[g] += start[g - 1]);
        let mut polygons = vec![0u32; at.len()];
        let mut next = start.clone();
        let corners = members.iter().flat_map(|&i| std::iter::repeat_n(i, scene.polygons[i as usize].len as usize));
        for (&g, i) in at.iter().zip(corners) {
            polygons[next[g as usize] as usize] = i;
            next[g as usize] += 1;
        }
        let bounds = &scene.solids[solid as usize];
        let centre = (bounds.lo + bounds.hi) / 2.0;
        let reach = items.iter().map(|(v, _)| v.distance(centre)).fold(0.0, f64::max);
        let mut tree = SolidTree {
            range,
            centre,
            reach,
            verts: Vec::new(),
            at: Vec::new(),
            start,
            polygons,
            nodes: Vec::with_capacity(2 * items.len() / LEAF + 1),
        };
        tree.split(&mut items, 0);
        (tree.verts, tree.at) = items.into_iter().unzip();
        tree
    }

    fn bytes(&self) -> usize {
        self.verts.capacity() * 24
            + (self.at.capacity() + self.start.capacity() + self.polygons.capacity()) * 4
            + self.nodes.capacity() * std::mem::size_of::<Node>()
    }

    /// Adds the box of `items` (which start at `start` in the whole list) and its halves;
    /// returns its index.
    fn split(&mut self, items: &mut [(DVec3, u32)], start: usize) -> u32 {
        let lo = items.iter().fold(DVec3::INFINITY, |b, &(v, _)| b.min(v));
        let hi = items.iter().fold(DVec3::NEG_INFINITY, |b, &(v, _)| b.max(v));
        let k = self.nodes.len();
        let (start32, end) = (start as u32, (start + items.len()) as u32);
        self.nodes.push(Node { lo, hi, start: start32, end, halves: None });
        if items.len() > LEAF {
            let size = hi - lo;
            let axis = if size.x >= size.y && size.x >= size.z {
                0
            } else if size.y >= size.z {
                1
            } else {
                2
            };
            let mid = items.len() / 2;
            items.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
            let (left, right) = items.split_at_mut(mid);
            let l = self.split(left, start);
            let r = self.split(right, start + mid);
            self.nodes[k].halves = Some([l, r]);
        }
        k as u32
    }

    /// Step 1 for polygon `b`, the solid's sign `sign`: the polygons at a vertex that is not
    /// a corner of `b` and measures more than zero, `(n · v + d) · sign` computed as
    /// `Plane::distance` times the side computes it, in increasing order.
    fn front_of(&self, scene: &Scene, b: u32, sign: f64) -> Box<[u32]> {
        let plane = &scene.polygons[b as usize].plane;
        // Negating both terms negates the rounded sum exactly.
        let (n, d, corners) = (plane.n * sign, plane.d * sign, scene.verts(b as usize));
        let (cap_lo, cap_hi) = self.cap(n, d);
        let mut front: smallvec::SmallVec<[u32; 16]> = smallvec::SmallVec::new();
        let mut stack: smallvec::SmallVec<[u32; 64]> = smallvec::smallvec![0];
        while let Some(k) = stack.pop() {
            let Some(node) = self.nodes.get(k as usize) else { continue };
            // The corner furthest along `n`: each product and each sum rounds no lower than
            // a vertex's of the box.
            let far = DVec3::select(n.cmpge(DVec3::ZERO), node.hi, node.lo);
            if n.dot(far) + d <= 0.0 || node.hi.cmplt(cap_lo).any() || node.lo.cmpgt(cap_hi).any() {
                continue;
            }
            match node.halves {
                Some(halves) => stack.extend(halves),
                None => {
                    for k in node.start as usize..node.end as usize {
                        let v = self.verts[k];
                        if n.dot(v) + d > 0.0 && !corners.contains(&v) {
                            let g = self.at[k] as usize;
                            front.extend_from_slice(&self.polygons[self.start[g] as usize..self.start[g + 1] as usize]);
                        }
                    }
                }
            }
        }
        front.sort_unstable();
        front.dedup();
        front.into_iter().collect()
    }

    /// A box round the cap of the solid's ball in front of the plane `n · x + d = 0`, grown
    /// by a billionth of the solid's size and place. A vertex `v` that measures `n · v + d >
    /// 0` lies, but for rounding, in the ball and in front: at `t n̂ + w` from the centre, with
    /// `t` at least the centre's distance `h` behind the plane, at most the ball's radius
    /// `R`, and `|w| ≤ √(R² − h²)` across. Each axis's range follows.
    fn cap(&self, n: DVec3, d: f64) -> (DVec3, DVec3) {
        let (c, length) = (self.centre, n.length());
        let slack = 1e-9 * (self.reach + c.abs().max_element() + d.abs() / length.max(1e-300));
        let reach = self.reach + slack;
        let everywhere = (c - DVec3::splat(reach), c + DVec3::splat(reach));
        if length.is_nan() || length <= 0.0 {
            return everywhere;
        }
        let unit = n / length;
        let h = -(n.dot(c) + d) / length - slack;
        if h.is_nan() || h <= 0.0 {
            return everywhere;
        }
        let across = (reach * reach - h * h).max(0.0).sqrt() + slack;
        let (near, far) = (unit * h, unit * reach);
        (c + near.min(far) - DVec3::splat(across), c + near.max(far) + DVec3::splat(across))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Material, Mesh, Object};

    /// A UV sphere off the origin (its quadrilaterals cut in two, where rounding decides
    /// whether a neighbour rises above a triangle's plane), the same sphere dented (its upper
    /// cap pushed in: a closed solid that is not convex, with large front sets), and an
    /// icosahedron (convex, its corners far behind every other face's plane).
    fn solids() -> Scene {
        let sphere = Mesh::sphere(DVec3::new(0.37, 0.81, -0.73), 0.8, 800);
        let mut dented = Mesh::sphere(DVec3::ZERO, 1.0, 800);
        for p in &mut dented.positions {
            if p.y > 0.4 {
                p.y = 0.4 - 0.5 * (p.y - 0.4);
            }
            *p += DVec3::new(3.1, 0.2, 0.7);
        }
        let icosahedron = crate::generate::geodesic_sphere(DVec3::new(-2.9, 0.4, 0.3), 0.7, 0);
        let mut b = Scene::builder(Camera::new(DVec3::new(0.0, 2.0, 9.0), DVec3::ZERO)).material(Material::new("m"));
        for mesh in [sphere, dented, icosahedron] {
            b = b.object(Object::new(mesh), "m");
        }
        b.build().unwrap()
    }

    /// Every polygon's front set is the one every corner of its solid's polygons, measured
    /// one by one as the pair loop's behind test measures them, gives.
    #[test]
    fn front_sets_are_what_every_corner_measured_gives() {
        let scene = solids();
        assert_eq!(scene.solids.len(), 3);
        let own = OwnSolid::new(&scene);
        let mut sizes = vec![0usize; scene.solids.len()];
        for b in 0..scene.polygons.len() as u32 {
            let s = scene.solid_of[b as usize];
            let solid = scene.solids[s as usize];
            let plane = &scene.polygons[b as usize].plane;
            let corners = scene.verts(b as usize);
            let in_front = |v: &DVec3| plane.distance(*v) * solid.sign > 0.0 && !corners.contains(v);
            let every: Vec<u32> = (0..scene.polygons.len() as u32)
                .filter(|&a| scene.solid_of[a as usize] == s && scene.verts(a as usize).iter().any(in_front))
                .collect();
            let tree = own.trees[s as usize].get_or_init(|| SolidTree::new(&scene, s, &own.members[s as usize]));
            assert_eq!(&*tree.front_of(&scene, b, solid.sign), &every[..], "polygon {b}");
            sizes[s as usize] += every.len();
        }
        // The sphere has a few (its cut quadrilaterals), the dented one many, the icosahedron
        // none.
        assert!(sizes[0] > 0 && sizes[1] > 10 * sizes[0] && sizes[2] == 0, "{sizes:?}");
    }
}
