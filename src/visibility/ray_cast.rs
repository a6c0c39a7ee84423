//! Visibility by casting one ray per pixel centre (section 3 of the contract, directly): the
//! reference the other stages are checked against.

use super::{runs_of_row, Run, Visibility};
use crate::bvh::Bvh;
use crate::scene::Scene;
use crate::stats::Counters;
use crate::view::View;
use std::ops::Range;

/// The prepared ray-cast stage: a BVH over every polygon.
pub struct RayCastVisibility<'a> {
    scene: &'a Scene,
    view: &'a View,
    bvh: Bvh,
}

impl<'a> RayCastVisibility<'a> {
    /// Builds the BVH.
    pub fn new(scene: &'a Scene, view: &'a View) -> Self {
        let bvh = Bvh::new(scene, (0..scene.polygons.len() as u32).collect());
        RayCastVisibility { scene, view, bvh }
    }

    /// The polygon seen through the centre of pixel `(x, y)`, if any.
    pub fn pixel(&self, x: u32, y: u32) -> Option<u32> {
        let d = self.view.ray(x as f64 + 0.5, y as f64 + 0.5);
        let far = self.view.far.unwrap_or(f64::INFINITY);
        // With d scaled to unit depth, the ray parameter is the camera-space depth.
        self.bvh.closest(self.scene, self.view.eye, d, self.view.near, far).map(|(i, _)| i)
    }
}

impl Visibility for RayCastVisibility<'_> {
    fn walk(&self, lines: Range<u32>, counters: &mut Counters, f: &mut dyn FnMut(u32, &[Run])) {
        let mut row = vec![u32::MAX; self.view.width as usize];
        let mut runs = Vec::new();
        counters.add(crate::stats::Counter::Rays, lines.len() as u64 * row.len() as u64);
        for y in lines {
            for (x, id) in row.iter_mut().enumerate() {
                *id = self.pixel(x as u32, y).unwrap_or(u32::MAX);
            }
            runs_of_row(&row, &mut runs);
            f(y, &runs);
        }
    }
}
