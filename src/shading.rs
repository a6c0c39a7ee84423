//! Shading: the colour of each pixel of a visible run from the ambient term and, per light
//! sample, the light that reaches it (the lit value from the shadow stage).
//!
//! `I = Ia ka Od + Σ_l Σ_s S_s (I_l / n_l) kd Od max(0, N.L)` with flat shading: one normal
//! per polygon (its plane normal, turned toward the eye: polygons are two-sided) and `L`
//! taken at the polygon's centroid, as seed 001 describes flat shading. The lit value `S`
//! applies per pixel, so a shadow edge crosses a flat polygon sharply.

use crate::geometry::centroid;
use crate::scene::{LightSample, Scene};
use crate::view::View;
use glam::{DVec3, Vec3};

/// Shades runs of a scene seen from a view.
pub struct Shader<'a> {
    scene: &'a Scene,
    view: &'a View,
    samples: &'a [Vec<LightSample>],
}

impl<'a> Shader<'a> {
    /// A shader for `scene` from `view`, with each light's samples.
    pub fn new(scene: &'a Scene, view: &'a View, samples: &'a [Vec<LightSample>]) -> Self {
        Shader { scene, view, samples }
    }

    /// The ambient term `Ia ka Od` of polygon `poly`.
    pub fn ambient(&self, poly: usize) -> Vec3 {
        let m = self.scene.material(poly);
        self.scene.render.ambient * m.ka * m.color
    }

    /// The plane normal of `poly` turned toward the eye.
    fn seen_normal(&self, poly: usize) -> DVec3 {
        let plane = &self.scene.polygons[poly].plane;
        if plane.distance(self.view.eye) >= 0.0 {
            plane.n
        } else {
            -plane.n
        }
    }

    /// Adds the light of sample `sample` of light `light` to `out`, pixel `i` weighted by
    /// `lit[i]`, for a run on polygon `poly`.
    pub fn add_light(&self, poly: usize, light: usize, sample: usize, lit: &[f32], out: &mut [Vec3]) {
        let l = &self.scene.lights[light];
        let m = self.scene.material(poly);
        let n = self.seen_normal(poly);
        let c = centroid(self.scene.verts(poly));
        let (to_light, _) = self.samples[light][sample].toward(c);
        let cos = n.dot(to_light).max(0.0) as f32;
        let weight = l.intensity / self.samples[light].len() as f32;
        let colour = l.color * weight * m.kd * m.color * cos;
        for (o, &s) in out.iter_mut().zip(lit) {
            *o += colour * s;
        }
    }
}
