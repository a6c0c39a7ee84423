//! A bounding-volume hierarchy over scene polygons for the ray-cast reference: median splits
//! on the widest axis, exact ray-polygon tests (plane hit, then even-odd point in polygon).

use crate::geometry::{dominant_axis, even_odd_edges};
use crate::scene::Scene;
use glam::{DVec2, DVec3};

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Interior: index of the left child (right is `first + 1`); leaf: first item.
    first: u32,
    /// Items in a leaf; 0 for an interior node.
    count: u32,
}

/// A BVH over a chosen set of a scene's polygons.
#[derive(Debug, Clone, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    items: Vec<u32>,
}

const LEAF: usize = 4;

fn bounds(scene: &Scene, i: u32) -> (DVec3, DVec3) {
    let v = scene.verts(i as usize);
    v.iter().fold((v[0], v[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)))
}

impl Bvh {
    /// The bytes it holds.
    pub fn bytes(&self) -> usize {
        crate::pool::held(&self.nodes) + crate::pool::held(&self.items)
    }

    /// Builds the hierarchy over polygons `items` of `scene`.
    pub fn new(scene: &Scene, items: Vec<u32>) -> Bvh {
        let boxes: Vec<(DVec3, DVec3)> = (0..scene.polygons.len() as u32).map(|i| bounds(scene, i)).collect();
        let mut bvh = Bvh { nodes: Vec::with_capacity(2 * items.len() / LEAF + 1), items };
        if !bvh.items.is_empty() {
            bvh.nodes.push(Node { lo: DVec3::ZERO, hi: DVec3::ZERO, first: 0, count: 0 });
            let n = bvh.items.len();
            bvh.build(&boxes, 0, 0, n);
        }
        bvh
    }

    fn build(&mut self, boxes: &[(DVec3, DVec3)], node: usize, start: usize, end: usize) {
        let items = &mut self.items[start..end];
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        let (mut clo, mut chi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &i in items.iter() {
            let (a, b) = boxes[i as usize];
            lo = lo.min(a);
            hi = hi.max(b);
            let c = (a + b) * 0.5;
            clo = clo.min(c);
            chi = chi.max(c);
        }
        self.nodes[node].lo = lo;
        self.nodes[node].hi = hi;
        let ext = chi - clo;
        if items.len() <= LEAF || ext.max_element() == 0.0 {
            self.nodes[node].first = start as u32;
            self.nodes[node].count = items.len() as u32;
            return;
        }
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = items.len() / 2;
        let key = |i: &u32| {
            let (a, b) = boxes[*i as usize];
            (a[axis] + b[axis]) * 0.5
        };
        items.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
        let left = self.nodes.len();
        let empty = Node { lo: DVec3::ZERO, hi: DVec3::ZERO, first: 0, count: 0 };
        self.nodes.push(empty);
        self.nodes.push(empty);
        self.nodes[node].first = left as u32;
        self.nodes[node].count = 0;
        self.build(boxes, left, start, start + mid);
        self.build(boxes, left + 1, start + mid, end);
    }

    /// Walks the leaves whose boxes the ray `o + t d`, `t in (tmin, tmax)` meets; `f` gets each
    /// polygon and returns a new `tmax` (or `None` to stop the walk).
    fn walk(&self, o: DVec3, d: DVec3, tmin: f64, mut tmax: f64, mut f: impl FnMut(u32, f64) -> Option<f64>) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = d.recip();
        let mut stack = [0u32; 64];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let n = self.nodes[stack[sp] as usize];
            let t0 = (n.lo - o) * inv;
            let t1 = (n.hi - o) * inv;
            let near = t0.min(t1).max_element().max(tmin);
            let far = t0.max(t1).min_element().min(tmax);
            // NaN (0 * inf on a slab edge) compares false: treat as a hit to stay conservative.
            if near > far {
                continue;
            }
            if n.count == 0 {
                if sp + 2 > stack.len() {
                    // Deeper than any balanced tree of 2^32 items; cannot happen with median splits.
                    continue;
                }
                stack[sp] = n.first;
                stack[sp + 1] = n.first + 1;
                sp += 2;
            } else {
                for &i in &self.items[n.first as usize..(n.first + n.count) as usize] {
                    match f(i, tmax) {
                        Some(t) => tmax = t,
                        None => return,
                    }
                }
            }
        }
    }

    /// Calls `f` with every item in a leaf whose box meets the box `lo..hi` (a superset of
    /// the items whose own boxes meet it).
    pub(crate) fn overlapping(&self, lo: DVec3, hi: DVec3, mut f: impl FnMut(u32)) {
        let mut stack = if self.nodes.is_empty() { Vec::new() } else { vec![0u32] };
        while let Some(n) = stack.pop() {
            let node = self.nodes[n as usize];
            if node.lo.cmpgt(hi).any() || node.hi.cmplt(lo).any() {
                continue;
            }
            if node.count == 0 {
                stack.extend([node.first, node.first + 1]);
            } else {
                self.items[node.first as usize..(node.first + node.count) as usize].iter().for_each(|&i| f(i));
            }
        }
    }

    /// Calls `f` with every item in a leaf whose box is not wholly outside one of `planes`
    /// (`(n, d)`: outside where `n·x > d`).
    pub(crate) fn within(&self, planes: &[(DVec3, f64)], mut f: impl FnMut(u32)) {
        let mut stack = if self.nodes.is_empty() { Vec::new() } else { vec![0u32] };
        while let Some(n) = stack.pop() {
            let node = self.nodes[n as usize];
            // The box's corner least far along each plane's normal.
            let outside = planes.iter().any(|&(n, d)| {
                let near = DVec3::select(n.cmpge(DVec3::ZERO), node.lo, node.hi);
                n.dot(near) > d
            });
            if outside {
                continue;
            }
            if node.count == 0 {
                stack.extend([node.first, node.first + 1]);
            } else {
                self.items[node.first as usize..(node.first + node.count) as usize].iter().for_each(|&i| f(i));
            }
        }
    }

    /// Calls `f` with every item.
    pub(crate) fn each(&self, f: impl FnMut(u32)) {
        self.items.iter().copied().for_each(f);
    }

    /// The nearest polygon hit by `o + t d` with `t in [tmin, tmax]`, and its `t`.
    pub fn closest(&self, scene: &Scene, o: DVec3, d: DVec3, tmin: f64, tmax: f64) -> Option<(u32, f64)> {
        let mut best: Option<(u32, f64)> = None;
        self.walk(o, d, tmin, tmax, |i, tmax| {
            match hit(scene, i as usize, o, d) {
                Some(t) if t >= tmin && t <= tmax => {
                    // Equal distances: the lower polygon index wins, whatever the walk order.
                    if best.is_none_or(|(j, bt)| t < bt || (t == bt && i < j)) {
                        best = Some((i, t));
                    }
                    Some(t)
                }
                _ => Some(tmax),
            }
        });
        best
    }

    /// Whether any polygon other than those of face `skip_face` meets `o + t d` with
    /// `t in (tmin, tmax)`.
    pub fn occluded(&self, scene: &Scene, o: DVec3, d: DVec3, tmin: f64, tmax: f64, skip_face: u32) -> bool {
        let mut found = false;
        self.walk(o, d, tmin, tmax, |i, tmax| {
            if scene.polygons[i as usize].face == skip_face {
                return Some(tmax);
            }
            match hit(scene, i as usize, o, d) {
                Some(t) if t > tmin && t < tmax => {
                    found = true;
                    None
                }
                _ => Some(tmax),
            }
        });
        found
    }
}

/// The ray parameter where `o + t d` meets polygon `i` (inside by the even-odd rule).
pub fn hit(scene: &Scene, i: usize, o: DVec3, d: DVec3) -> Option<f64> {
    let plane = &scene.polygons[i].plane;
    let nd = plane.n.dot(d);
    if nd == 0.0 {
        return None;
    }
    let t = -plane.distance(o) / nd;
    if !t.is_finite() {
        return None;
    }
    let p = o + t * d;
    inside(scene.verts(i), dominant_axis(plane.n), p).then_some(t)
}

/// Even-odd test of a point on a polygon's plane, in the plane's projection that drops `axis`
/// (each projection its own monomorphic loop: this is the ray caster's innermost test).
fn inside(verts: &[DVec3], axis: usize, p: DVec3) -> bool {
    match axis {
        0 => inside_flat(verts, p, |q| DVec2::new(q.y, q.z)),
        1 => inside_flat(verts, p, |q| DVec2::new(q.z, q.x)),
        _ => inside_flat(verts, p, |q| DVec2::new(q.x, q.y)),
    }
}

#[inline]
fn inside_flat(verts: &[DVec3], p: DVec3, flat: impl Fn(DVec3) -> DVec2) -> bool {
    let Some(&last) = verts.last() else { return false };
    let mut a = flat(last);
    let edges = verts.iter().map(|&v| {
        let b = flat(v);
        (std::mem::replace(&mut a, b), b)
    });
    even_odd_edges(edges, flat(p))
}
