//! The exact reference: for each pixel and light sample, one shadow ray from the visible
//! point toward the sample, tested against a BVH of the shadow-casting polygons (section 3 of
//! the contract, directly). Simple and obviously right; the oracle for the exact stages.

use super::{Decision, ShadowContext, ShadowStage, ShadowWalker};
use crate::bvh::Bvh;
use crate::scene::{LightSample, Scene};
use crate::stats::Counters;
use crate::visibility::Run;
use glam::DVec3;

/// Whether a casting polygon of `casters` other than face `face` crosses the open segment
/// from `p` to the light sample (section 3's lit rule, the same-side test aside): ends within
/// a relative 1e-9 of `p` or of the light do not count; for a directional light the ray
/// starts 1e-9 of the scene's size `extent` from `p`.
pub(crate) fn blocked(casters: &Bvh, scene: &Scene, p: DVec3, sample: LightSample, face: u32, extent: f64) -> bool {
    let eps = 1e-9;
    match sample {
        LightSample::Point(s) => casters.occluded(scene, p, s - p, eps, 1.0 - eps, face),
        LightSample::Directional(d) => casters.occluded(scene, p, -d, eps * extent, f64::INFINITY, face),
    }
}

/// The prepared reference stage.
pub struct RayCastShadows<'a> {
    ctx: &'a ShadowContext<'a>,
    bvh: Bvh,
}

impl<'a> RayCastShadows<'a> {
    /// Builds the BVH of the shadow casters.
    pub fn new(ctx: &'a ShadowContext<'a>, counters: &mut Counters) -> Self {
        let s = ctx.scene;
        let casters: Vec<u32> = (0..s.polygons.len() as u32).filter(|&i| s.casts_shadows(i as usize)).collect();
        counters.add(crate::stats::Counter::Casters, casters.len() as u64);
        RayCastShadows { ctx, bvh: Bvh::new(s, casters) }
    }
}

struct Walker<'s> {
    stage: &'s RayCastShadows<'s>,
    rays: u64,
    last: (u32, u32),
}

impl ShadowStage for RayCastShadows<'_> {
    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        Box::new(Walker { stage: self, rays: 0, last: (0, 0) })
    }

    fn bytes(&self) -> usize {
        self.bvh.bytes()
    }
}

impl ShadowWalker for Walker<'_> {
    fn lit(&mut self, light: usize, sample: usize, line: u32, run: &Run, lit: &mut [f32]) {
        let ctx = self.stage.ctx;
        let poly = &ctx.scene.polygons[run.poly as usize];
        let yc = line as f64 + 0.5;
        let s = ctx.samples[light][sample];
        for (i, out) in lit.iter_mut().enumerate() {
            let p = ctx.view.point_on(&poly.plane, (run.x0 + i as u32) as f64 + 0.5, yc);
            let shadowed = blocked(&self.stage.bvh, ctx.scene, p, s, poly.face, ctx.extent);
            *out = if shadowed { 0.0 } else { 1.0 };
        }
        self.rays += lit.len() as u64;
        self.last = (run.x0, run.x1);
    }

    fn decision(&self) -> Decision {
        Decision {
            tested: vec![(self.last.0, self.last.1, 1)],
            note: format!("{} shadow ray(s)", self.last.1 - self.last.0),
            detail: super::Detail::None,
        }
    }

    fn finish(&mut self, counters: &mut Counters) {
        counters.add(crate::stats::Counter::ShadowRays, self.rays);
    }
}
