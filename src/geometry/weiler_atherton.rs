//! Weiler-Atherton polygon clipping (K. Weiler & P. Atherton, "Hidden surface removal using
//! polygon area sorting", SIGGRAPH 1977), in the graph form of Weiler's later work ("Polygon
//! comparison using a graph representation", SIGGRAPH 1980), which keeps the 1977 algorithm's
//! steps but survives its known failure modes.
//!
//! A subject region is clipped by a clip region into the part **inside** the clip and the
//! part **outside** it. Regions are sets of rings read by the even-odd rule: concave outlines
//! and holes both ways.
//!
//! 1. **Vertex lists with intersections inserted.** Both regions' edges are split wherever
//!    they meet: crossings, a vertex of one lying on an edge of the other, and the ends of
//!    collinear overlaps. Vertices closer than the tolerance are one vertex. A region's own
//!    edges are split against each other too, and pieces of one region running both ways
//!    over the same segment cancel: the zero-width "bridges" that clipping a concave polygon
//!    by a plane leaves behind bound nothing.
//! 2. **Entering and exiting.** Each piece of a subject edge is classified by its midpoint as
//!    inside or outside the clip region (and each clip piece against the subject); a piece
//!    lying on a piece of the other region is *shared*, running the same way or opposite.
//!    Rings are first oriented so each region's interior lies to the left of its edges.
//! 3. **Tracing.** The inside part is bounded by the subject pieces inside the clip, the clip
//!    pieces inside the subject, and shared pieces running the same way; the outside part by
//!    the subject pieces outside the clip, the clip pieces inside the subject (reversed), and
//!    shared pieces running opposite ways. Walking these edges from vertex to vertex, turning
//!    as far left as possible where several leave a vertex — the 1977 algorithm's switch
//!    from one vertex list to the other at an intersection — closes the output rings.
//!
//! Identical polygons come out as all-inside; polygons sharing an edge as touching, not
//! overlapping. Tolerance: points within `1e-9 ×` the inputs' bounding-box diagonal are the
//! same point. Every loop is bounded by the number of edges; a vertex where the edges do not
//! balance (which only badly inconsistent input can cause) is an error, never a panic or a
//! hang. There is no limit on vertex counts. Inputs should be simple: rings may touch each
//! other at vertices or run back along themselves (bridges), but an edge should not cross
//! another edge of its own region.

use super::inside_even_odd;
use glam::DVec2;
use rustc_hash::FxHashMap as HashMap;

/// A closed polygon outline.
pub type Ring = Vec<DVec2>;

/// A planar region: rings by the even-odd rule.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Region {
    /// The outlines (outer boundaries and holes, any orientation).
    pub rings: Vec<Ring>,
}

/// The two parts of a clipped subject.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Clipped {
    /// The part of the subject inside the clip region.
    pub inside: Region,
    /// The part of the subject outside the clip region.
    pub outside: Region,
}

/// Why a clip failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClipError {
    /// A coordinate is NaN or infinite.
    #[error("polygon clipping: non-finite coordinate")]
    NonFinite,
    /// The traced edges do not balance at a vertex: the traversal cannot close its rings.
    #[error("polygon clipping: the boundary does not close at ({x}, {y}) ({inbound} edges in, {outbound} out)")]
    Unbalanced {
        /// Where.
        x: f64,
        /// Where.
        y: f64,
        /// Edges arriving.
        inbound: usize,
        /// Edges leaving.
        outbound: usize,
    },
}

impl Region {
    /// A region of one ring.
    pub fn from_ring(ring: Ring) -> Region {
        Region { rings: vec![ring] }
    }

    /// Whether it has no rings.
    pub fn is_empty(&self) -> bool {
        self.rings.is_empty()
    }

    /// Its area (even-odd: holes subtract).
    pub fn area(&self) -> f64 {
        oriented(self).iter().map(|r| signed_area(r)).sum::<f64>()
    }

    /// Its bounding box `(min, max)`, or `None` when empty.
    pub fn bounds(&self) -> Option<(DVec2, DVec2)> {
        let first = *self.rings.iter().flatten().next()?;
        Some(self.rings.iter().flatten().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))))
    }

    /// Whether `p` is inside by the even-odd rule.
    pub fn contains(&self, p: DVec2) -> bool {
        self.rings.iter().filter(|r| inside_even_odd(r, p)).count() % 2 == 1
    }
}

/// The signed area of a ring (positive counter-clockwise).
pub fn signed_area(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    (0..n).map(|i| ring[i].perp_dot(ring[(i + 1) % n])).sum::<f64>() * 0.5
}

/// The rings of `r` oriented with the interior on the left: outer boundaries counter-
/// clockwise, holes clockwise. A ring's depth is the number of the region's other rings that
/// hold the midpoint of its longest edge (rings touch at most at vertices, so that midpoint
/// is strictly inside or outside each).
fn oriented(r: &Region) -> Vec<Ring> {
    let rings: Vec<&Ring> = r.rings.iter().filter(|x| x.len() >= 3).collect();
    rings
        .iter()
        .enumerate()
        .map(|(i, ring)| {
            let n = ring.len();
            let k = (0..n).max_by(|&a, &b| {
                let la = ring[a].distance_squared(ring[(a + 1) % n]);
                let lb = ring[b].distance_squared(ring[(b + 1) % n]);
                la.total_cmp(&lb)
            });
            let mid = k.map_or(ring[0], |k| (ring[k] + ring[(k + 1) % n]) * 0.5);
            let depth = rings.iter().enumerate().filter(|&(j, other)| j != i && inside_even_odd(other, mid)).count();
            let ccw = signed_area(ring) > 0.0;
            let mut out = (*ring).clone();
            if ccw != (depth % 2 == 0) {
                out.reverse();
            }
            out
        })
        .collect()
}

/// Vertices, merged within the tolerance (a grid of cells one tolerance wide).
struct Vertices {
    pts: Vec<DVec2>,
    grid: HashMap<(i64, i64), Vec<u32>>,
    eps: f64,
}

impl Vertices {
    fn id(&mut self, p: DVec2) -> u32 {
        let cell = ((p.x / self.eps).floor() as i64, (p.y / self.eps).floor() as i64);
        for dx in -1..=1 {
            for dy in -1..=1 {
                // Saturating: far-off points share the edge cells, and the distance test
                // below still decides.
                if let Some(ids) = self.grid.get(&(cell.0.saturating_add(dx), cell.1.saturating_add(dy))) {
                    if let Some(&i) = ids.iter().find(|&&i| self.pts[i as usize].distance(p) <= self.eps) {
                        return i;
                    }
                }
            }
        }
        let i = self.pts.len() as u32;
        self.pts.push(p);
        self.grid.entry(cell).or_default().push(i);
        i
    }
}

/// An edge of one region with the points where it must be split, as (parameter, vertex).
struct Edge {
    a: u32,
    b: u32,
    splits: Vec<(f64, u32)>,
}

/// Clips `subject` by `clip` into its parts inside and outside `clip`.
pub fn clip(subject: &Region, clip: &Region) -> Result<Clipped, ClipError> {
    let finite = |r: &Region| r.rings.iter().flatten().all(|p| p.is_finite());
    if !finite(subject) || !finite(clip) {
        return Err(ClipError::NonFinite);
    }
    let (Some(sb), Some(cb)) = (subject.bounds(), clip.bounds()) else {
        return Ok(Clipped { inside: Region::default(), outside: subject.clone() });
    };
    let eps = 1e-9 * (sb.1.max(cb.1) - sb.0.min(cb.0)).length().max(1e-300);
    let ring_box =
        |r: &Ring| r.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let meets = |r: &Ring, b: (DVec2, DVec2)| {
        let (lo, hi) = ring_box(r);
        lo.x <= b.1.x + eps && b.0.x <= hi.x + eps && lo.y <= b.1.y + eps && b.0.y <= hi.y + eps
    };
    // A ring whose box misses the other region's box cannot change anything inside that box
    // (by the even-odd rule): subject rings there pass to the outside part untouched, clip
    // rings there are dropped. Rings with no area (slivers, lines walked there and back)
    // bound nothing and are dropped too.
    let solid = |r: &Ring| signed_area(r).abs() > eps * eps;
    let (near, far): (Vec<Ring>, Vec<Ring>) =
        subject.rings.iter().filter(|r| solid(r)).cloned().partition(|r| meets(r, cb));
    let c_near: Vec<Ring> = clip.rings.iter().filter(|r| solid(r) && meets(r, sb)).cloned().collect();
    let (s_rings, c_rings) = (oriented(&Region { rings: near }), oriented(&Region { rings: c_near }));
    if s_rings.is_empty() || c_rings.is_empty() {
        return Ok(Clipped {
            inside: Region::default(),
            outside: Region { rings: s_rings.into_iter().chain(far).collect() },
        });
    }
    let mut verts = Vertices { pts: Vec::new(), grid: HashMap::default(), eps };
    let edges_of = |rings: &[Ring], verts: &mut Vertices| -> Vec<Edge> {
        let mut out = Vec::new();
        for ring in rings {
            let ids: Vec<u32> = ring.iter().map(|&p| verts.id(p)).collect();
            for k in 0..ids.len() {
                let (a, b) = (ids[k], ids[(k + 1) % ids.len()]);
                if a != b {
                    out.push(Edge { a, b, splits: Vec::new() });
                }
            }
        }
        out
    };
    let se = edges_of(&s_rings, &mut verts);
    let ce = edges_of(&c_rings, &mut verts);

    // Step 1: split both regions' edges wherever they meet, each other's and their own (a
    // ring cut by Sutherland-Hodgman can run back along itself: a zero-width bridge). Only
    // edges whose boxes overlap can meet: a sweep along x finds them.
    let n_s = se.len();
    let mut all: Vec<Edge> = se.into_iter().chain(ce).collect();
    for (i, j) in overlapping_pairs(&all, &verts.pts, eps) {
        let (head, tail) = all.split_at_mut(j);
        split_pair(&mut head[i], &mut tail[0], &mut verts);
    }
    let ce = all.split_off(n_s);
    let se = all;
    // Sub-edges, with pieces that run both ways within one region (bridges) cancelled.
    let pieces = |edges: &[Edge]| -> Vec<(u32, u32)> {
        let mut count: HashMap<(u32, u32), i32> = HashMap::default();
        let mut order = Vec::new();
        for e in edges {
            let mut s = e.splits.clone();
            s.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut prev = e.a;
            for (_, v) in s.into_iter().chain([(1.0, e.b)]) {
                if v != prev {
                    let key = (prev.min(v), prev.max(v));
                    let c = count.entry(key).or_insert_with(|| {
                        order.push(key);
                        0
                    });
                    *c += if prev < v { 1 } else { -1 };
                    prev = v;
                }
            }
        }
        let mut out = Vec::new();
        for key in order {
            let c = count[&key];
            let e = if c > 0 { key } else { (key.1, key.0) };
            out.extend(std::iter::repeat_n(e, c.unsigned_abs() as usize));
        }
        out
    };
    let (sp, cp) = (pieces(&se), pieces(&ce));

    // Step 2: classify.
    let pts = &verts.pts;
    let mid = |&(a, b): &(u32, u32)| (pts[a as usize] + pts[b as usize]) * 0.5;
    // Point-in-region by the even-odd rule over a region's pieces (bridges cancelled).
    let contains = |edges: &[(u32, u32)], p: DVec2| {
        let mut inside = false;
        for &(a, b) in edges {
            let (a, b) = (pts[a as usize], pts[b as usize]);
            let (top, bot) = if a.y <= b.y { (a, b) } else { (b, a) };
            if top.y <= p.y && p.y < bot.y && top.x + (p.y - top.y) * ((bot.x - top.x) / (bot.y - top.y)) <= p.x {
                inside = !inside;
            }
        }
        inside
    };
    let c_dir: HashMap<(u32, u32), ()> = cp.iter().map(|&e| (e, ())).collect();
    let s_dir: HashMap<(u32, u32), ()> = sp.iter().map(|&e| (e, ())).collect();
    let (mut inside, mut outside) = (Vec::new(), Vec::new());
    for e in &sp {
        if c_dir.contains_key(e) {
            inside.push(*e); // shared, same way
        } else if c_dir.contains_key(&(e.1, e.0)) {
            outside.push(*e); // shared, opposite ways
        } else if contains(&cp, mid(e)) {
            inside.push(*e);
        } else {
            outside.push(*e);
        }
    }
    for e in &cp {
        if s_dir.contains_key(e) || s_dir.contains_key(&(e.1, e.0)) {
            continue; // shared: taken from the subject above
        }
        if contains(&sp, mid(e)) {
            inside.push(*e);
            outside.push((e.1, e.0));
        }
    }

    // Step 3: trace.
    let mut outside = trace(pts, &outside, eps)?;
    outside.rings.extend(far);
    Ok(Clipped { inside: trace(pts, &inside, eps)?, outside })
}

/// The pairs `(i, j)`, `i < j`, of edges whose bounding boxes (grown by `eps`) overlap: a
/// sweep over the boxes sorted by their left side.
fn overlapping_pairs(edges: &[Edge], pts: &[DVec2], eps: f64) -> Vec<(usize, usize)> {
    let boxes: Vec<(DVec2, DVec2)> = edges
        .iter()
        .map(|e| {
            let (a, b) = (pts[e.a as usize], pts[e.b as usize]);
            (a.min(b) - DVec2::splat(eps), a.max(b) + DVec2::splat(eps))
        })
        .collect();
    let mut order: Vec<usize> = (0..edges.len()).collect();
    order.sort_unstable_by(|&i, &j| boxes[i].0.x.total_cmp(&boxes[j].0.x));
    let mut active: Vec<usize> = Vec::new();
    let mut pairs = Vec::new();
    for &i in &order {
        let (lo, hi) = boxes[i];
        active.retain(|&k| boxes[k].1.x >= lo.x);
        for &k in &active {
            if boxes[k].0.y <= hi.y && lo.y <= boxes[k].1.y {
                pairs.push((i.min(k), i.max(k)));
            }
        }
        active.push(i);
    }
    pairs
}

/// Splits edges `e` and `f` where they meet. One set of predicates decides everything: the
/// signed distance of each endpoint from the other edge's line. An endpoint within the
/// tolerance of the other edge (and between its ends) splits it there; otherwise the edges
/// cross only when both pairs of endpoints lie strictly on opposite sides, and the crossing is
/// interpolated from those distances, well conditioned even for nearly parallel edges.
fn split_pair(e: &mut Edge, f: &mut Edge, verts: &mut Vertices) {
    let (a, b) = (verts.pts[e.a as usize], verts.pts[e.b as usize]);
    let (c, d) = (verts.pts[f.a as usize], verts.pts[f.b as usize]);
    let eps = verts.eps;
    let (r, s) = (b - a, d - c);
    let (lr, ls) = (r.length(), s.length());
    let side = |p: DVec2, o: DVec2, dir: DVec2, len: f64| dir.perp_dot(p - o) / len;
    let (dc, dd) = (side(c, a, r, lr), side(d, a, r, lr));
    let (da, db) = (side(a, c, s, ls), side(b, c, s, ls));
    // An endpoint on the other edge.
    let on = |p: DVec2, id: u32, dist: f64, e: &mut Edge, o: DVec2, dir: DVec2| {
        if dist.abs() > eps || id == e.a || id == e.b {
            return;
        }
        let t = (p - o).dot(dir) / dir.length_squared();
        if t > 0.0 && t < 1.0 && !e.splits.iter().any(|x| x.1 == id) {
            e.splits.push((t, id));
        }
    };
    on(c, f.a, dc, e, a, r);
    on(d, f.b, dd, e, a, r);
    on(a, e.a, da, f, c, s);
    on(b, e.b, db, f, c, s);
    // A proper crossing.
    let strictly = |x: f64, y: f64| x.abs() > eps && y.abs() > eps && (x > 0.0) != (y > 0.0);
    if !(strictly(dc, dd) && strictly(da, db)) {
        return;
    }
    let t = da / (da - db);
    let u = dc / (dc - dd);
    let id = verts.id(a + r * t);
    for (edge, param) in [(e, t), (f, u)] {
        if id != edge.a && id != edge.b && !edge.splits.iter().any(|x| x.1 == id) {
            edge.splits.push((param, id));
        }
    }
}

/// Closes directed edges into rings: at each vertex the next edge is the unused one that
/// turns furthest left. An error when edges do not balance at some vertex.
pub(crate) fn trace(pts: &[DVec2], edges: &[(u32, u32)], eps: f64) -> Result<Region, ClipError> {
    let mut out_of: HashMap<u32, Vec<usize>> = HashMap::default();
    let mut into: HashMap<u32, usize> = HashMap::default();
    for (i, &(a, b)) in edges.iter().enumerate() {
        out_of.entry(a).or_default().push(i);
        *into.entry(b).or_default() += 1;
    }
    for (&v, outs) in &out_of {
        let inbound = into.get(&v).copied().unwrap_or(0);
        if inbound != outs.len() {
            let p = pts[v as usize];
            return Err(ClipError::Unbalanced { x: p.x, y: p.y, inbound, outbound: outs.len() });
        }
    }
    if let Some((&v, &inbound)) = into.iter().find(|(v, _)| !out_of.contains_key(v)) {
        let p = pts[v as usize];
        return Err(ClipError::Unbalanced { x: p.x, y: p.y, inbound, outbound: 0 });
    }
    let mut used = vec![false; edges.len()];
    let mut region = Region::default();
    for start in 0..edges.len() {
        if used[start] {
            continue;
        }
        let mut ring = Vec::new();
        let mut e = start;
        // Each step uses up one edge, so the walk ends within `edges.len()` steps.
        for _ in 0..edges.len() {
            used[e] = true;
            let (a, b) = edges[e];
            ring.push(pts[a as usize]);
            let dir_in = pts[b as usize] - pts[a as usize];
            let next = out_of[&b].iter().copied().filter(|&k| !used[k]).max_by(|&x, &y| {
                let turn = |k: usize| {
                    let d = pts[edges[k].1 as usize] - pts[b as usize];
                    dir_in.perp_dot(d).atan2(dir_in.dot(d))
                };
                turn(x).total_cmp(&turn(y))
            });
            match next {
                Some(k) => e = k,
                None => break,
            }
        }
        if ring.len() >= 3 && signed_area(&ring).abs() > eps * eps {
            region.rings.push(ring);
        }
    }
    Ok(region)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x: f64, y: f64, s: f64) -> Region {
        Region::from_ring(vec![DVec2::new(x, y), DVec2::new(x + s, y), DVec2::new(x + s, y + s), DVec2::new(x, y + s)])
    }

    fn check(subject: &Region, clip_region: &Region, inside_area: f64) -> Clipped {
        let c = clip(subject, clip_region).unwrap();
        assert!((c.inside.area() - inside_area).abs() < 1e-9, "inside {} want {inside_area}", c.inside.area());
        assert!((c.inside.area() + c.outside.area() - subject.area()).abs() < 1e-9);
        c
    }

    #[test]
    fn overlapping_squares() {
        check(&square(0.0, 0.0, 2.0), &square(1.0, 1.0, 2.0), 1.0);
    }

    #[test]
    fn identical_polygons() {
        let c = check(&square(0.0, 0.0, 1.0), &square(0.0, 0.0, 1.0), 1.0);
        assert!(c.outside.is_empty());
    }

    #[test]
    fn shared_edge_touches_only() {
        let c = check(&square(0.0, 0.0, 1.0), &square(1.0, 0.0, 1.0), 0.0);
        assert!(c.inside.is_empty());
    }

    #[test]
    fn collinear_partial_overlap_and_vertex_on_edge() {
        check(&square(0.0, 0.0, 2.0), &square(1.0, 0.0, 2.0), 2.0);
        // A triangle whose apex lies on the square's edge.
        let tri = Region::from_ring(vec![DVec2::new(1.0, 2.0), DVec2::new(0.5, 3.0), DVec2::new(1.5, 3.0)]);
        check(&tri, &square(0.0, 0.0, 2.0), 0.0);
    }

    #[test]
    fn holes_in_and_out() {
        // Subject: a 4x4 square with a 2x2 hole; clip: a square over the hole and the ring.
        let mut subject = square(0.0, 0.0, 4.0);
        subject.rings.push(square(1.0, 1.0, 2.0).rings.remove(0));
        let c = check(&subject, &square(2.0, 2.0, 4.0), 4.0 - 1.0);
        // Clip with a hole: the outside part keeps the subject inside the clip's hole.
        let mut clip_region = square(-1.0, -1.0, 6.0);
        clip_region.rings.push(square(0.5, 0.5, 3.0).rings.remove(0));
        let d = check(&subject, &clip_region, 16.0 - 4.0 - (9.0 - 4.0));
        assert!((d.outside.area() - 5.0).abs() < 1e-9);
        assert!(!c.outside.is_empty());
    }

    #[test]
    fn concave_subject() {
        // A U shape clipped by a bar across its arms: two pieces inside.
        let u = Region::from_ring(vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(3.0, 0.0),
            DVec2::new(3.0, 3.0),
            DVec2::new(2.0, 3.0),
            DVec2::new(2.0, 1.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(1.0, 3.0),
            DVec2::new(0.0, 3.0),
        ]);
        let bar = Region::from_ring(vec![
            DVec2::new(-1.0, 2.0),
            DVec2::new(4.0, 2.0),
            DVec2::new(4.0, 2.5),
            DVec2::new(-1.0, 2.5),
        ]);
        let c = check(&u, &bar, 1.0);
        assert_eq!(c.inside.rings.len(), 2);
    }

    #[test]
    fn unbalanced_edges_are_an_error_not_a_hang() {
        let pts = [DVec2::ZERO, DVec2::X, DVec2::Y];
        let err = trace(&pts, &[(0, 1), (1, 2)], 1e-9).unwrap_err();
        assert!(matches!(err, ClipError::Unbalanced { .. }), "{err}");
        assert_eq!(
            clip(&Region::from_ring(vec![DVec2::new(f64::NAN, 0.0), DVec2::X, DVec2::Y]), &square(0.0, 0.0, 1.0)),
            Err(ClipError::NonFinite)
        );
    }
}
