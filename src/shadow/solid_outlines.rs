//! Bouknight-Kelley's shadow polygons of a closed solid counted as the outline of their union
//! (ours; the switch `solid_outlines`, `--no-solid-outlines`; see
//! `docs/algorithms/bouknight-kelley.md`).
//!
//! A receiver under a whole closed solid (s3's floor under its spheres) takes one shadow
//! polygon from each of the solid's polygons that face the light: 490,000 on s3's floor,
//! 1.5 million edges to project, sort and walk, nearly all of them shared by two shadow
//! polygons. What the walk needs at a pixel is only whether any of them covers it.
//!
//! 1. **Counted.** Projected from the light onto the receiver's plane and then by the camera,
//!    every caster's shadow polygon winds the same way on screen: its way round about the
//!    receiver's normal is the caster's side of the light times the receiver's (a central or
//!    parallel projection looks the same from the light), and [`far_outline::facing`] turns
//!    that into the screen's. So the number of shadow polygons over a pixel centre is the sum
//!    of the weights of their edges' crossings at or left of it ([`far_outline`]), and the
//!    pixel is in shadow where that number is above zero. The receiver's polygons go into a
//!    counted table ([`super::overlay`]) whose walker gives the intervals of their union.
//! 2. **Outlined.** The solid's casters that face the light are a patch of its surface,
//!    wound alike; summed, their edges cancel wherever two of them meet, and what is left is
//!    the patch's boundary, the edges between such a caster and a polygon that is not one:
//!    the solid's silhouette from the light. (Casters facing away, which cast only with the
//!    solid cull off, wind the other way: they keep their own shadow polygons, counted
//!    with the rest.) Each corner is projected on its own (onto
//!    the receiver's plane, then by the camera), so the two shadow polygons on a shared edge
//!    would give its image the same bits, and the boundary's crossings sum to what every
//!    caster's would: the count at every pixel is the same. A solid is outlined on a
//!    receiver only when its bounding box lies strictly between the light and the
//!    receiver's plane (then no caster is clipped, and each projects to a finite point) and
//!    the box's shadow lies where the camera puts every point on screen without a cut; and
//!    only when it gives the receiver many candidates ([`PER_SOLID`]), where one pass over
//!    its polygons costs less than projecting them.
//!
//! The outline counts the casters the prefilter, the behind test and the wedge would have
//! dropped too: their shadows miss the receiver, so they count nowhere on it. Shadow
//! polygons with no area, which the projection drops, count on no pixel centre but on
//! their edges (a tie). Traces (which keep each shadow polygon) and the paper path do
//! without it, and so does the stage without its prefilter, where every caster is a
//! candidate of every receiver.

use super::far_outline::{self, FarEdge};
use super::projection::Target;
use crate::pool::Stash;
use crate::scene::{LightSample, Scene};
use crate::view::View;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};

/// The fewest candidates a receiver must have before its solids are looked at.
pub(crate) const RECEIVER_MIN: usize = 256;

/// The fewest of a receiver's candidates a solid must give it to be outlined.
pub(crate) const PER_SOLID: u32 = 64;

/// One light sample's solid outlines: which polygons cast, and each solid's boundary edges,
/// found the first time a receiver asks.
pub(crate) struct SolidOutlines {
    /// `outlined[i]`: polygon `i` casts shadows for this sample and faces the light from its
    /// closed solid's outside (one its solid's outline counts).
    outlined: Vec<bool>,
    /// Each solid's polygons.
    members: Arc<Vec<Vec<u32>>>,
    /// Each solid's boundary edges between a caster and a polygon that is not one, each
    /// run as the caster runs it.
    edges: Vec<OnceLock<Vec<[DVec3; 2]>>>,
}

/// Each solid's polygons, kept by a renderer for which polygons ([`Scene::polygons_id`]).
type KeptMembers = (u64, Arc<Vec<Vec<u32>>>);

impl SolidOutlines {
    /// The outlines of `scene`'s solids for light sample `sample`, whose casters are
    /// `casters`.
    pub(crate) fn new(scene: &Scene, casters: &[u32], sample: LightSample, kept: &Stash) -> Self {
        let id = scene.polygons_id;
        let members = kept.find_or_make::<KeptMembers>(|k| k.0 == id, || (id, Arc::new(scene.solid_members())), 4).1;
        let edges = (0..scene.solids.len()).map(|_| OnceLock::new()).collect();
        let facing = |i: u32| {
            let solid = scene.solids.get(scene.solid_of[i as usize] as usize);
            solid.is_some_and(|solid| solid.sign * sample.side_of(&scene.polygons[i as usize].plane) > 0.0)
        };
        let outlined = crate::pieces::marked(
            scene.polygons.len(),
            casters.par_iter().filter(|&&i| facing(i)).map(|&i| i as usize),
        );
        SolidOutlines { outlined, members, edges }
    }

    /// Whether polygon `i` casts and faces the light from its closed solid's outside: one
    /// its solid's outline counts.
    pub(crate) fn outlined(&self, i: u32) -> bool {
        self.outlined.get(i as usize).copied().unwrap_or(false)
    }

    /// Solid `s`'s boundary edges (step 2).
    pub(crate) fn edges(&self, scene: &Scene, s: u32) -> &[[DVec3; 2]] {
        self.edges[s as usize].get_or_init(|| {
            let mut out = Vec::new();
            for &i in &self.members[s as usize] {
                if !self.outlined(i) {
                    continue;
                }
                let verts = scene.verts(i as usize);
                for (k, &g) in scene.across(i as usize).iter().enumerate() {
                    if !self.outlined(g) {
                        out.push([verts[k], verts[(k + 1) % verts.len()]]);
                    }
                }
            }
            out
        })
    }

    /// Whether solid `s` may be outlined on the receiver `target` names (step 2's box
    /// test): its bounding box strictly between the light and the plane, by a margin of
    /// `margin`, and the box's shadow on the plane whole on screen.
    pub(crate) fn fits(&self, scene: &Scene, s: u32, target: &Target, view: &View, margin: f64) -> bool {
        let solid = &scene.solids[s as usize];
        let corners = crate::geometry::box_corners(solid.lo, solid.hi);
        let (plane, side) = (&target.plane, target.side);
        let between = corners.iter().all(|&c| {
            let before = plane.distance(c) * side > margin;
            match target.sample {
                LightSample::Point(l) => before && (plane.distance(l) - plane.distance(c)) * side > margin,
                LightSample::Directional(_) => before,
            }
        });
        between && view.whole_on_screen(corners.iter().map(|&c| target.onto(c).extend(1.0)))
    }
}

/// Step 2's edges on screen: each of `edges` (a solid's boundary) projected onto `target`'s
/// plane and by the camera, run `winding` times, onto `out`.
pub(crate) fn push_outline(view: &View, target: &Target, edges: &[[DVec3; 2]], winding: i32, out: &mut Vec<FarEdge>) {
    out.extend(
        edges.iter().map(|&[p, q]| FarEdge::run(view.image(target.onto(p)), view.image(target.onto(q)), winding)),
    );
}

/// Step 1: how a shadow polygon of a caster on `caster_side` of the light (the sign of the
/// light's side of its plane) winds on screen on the receiver `target` names, seen through
/// `view` (0 when the eye lies in the receiver's plane).
pub(crate) fn winding(view: &View, target: &Target, caster_side: f64) -> i32 {
    let facing = far_outline::facing(view, &target.plane);
    (caster_side.signum() * target.side) as i32 * facing
}
