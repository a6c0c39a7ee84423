//! Blinn's planar projected shadows (J. Blinn, "Me and my (fake) shadow", IEEE CG&A 1988;
//! the "Rendering 6: Shadow", "Special Effect" and "Árnyékolás" notes): every caster is flattened onto each *receiver* plane (polygons of
//! objects marked `receiver = true`) by a projection matrix, and the flattened polygon, kept
//! to the receiver polygon, is drawn with ambient light only.
//!
//! - A point light at L, plane `A x + B y + C z + D = 0` written with the light at the origin
//!   (the "Rendering 6: Shadow" notes): `M = [[−D,0,0,0],[0,−D,0,0],[0,0,−D,0],[A,B,C,0]]`, applied as
//!   `T(L) · M · T(−L)`. (The "Árnyékolás" notes' `M_per`, for the plane `z = 0` and the centre of
//!   projection at `(0, 0, −d)`, is the same matrix up to scale.)
//! - A directional light along `(x_l, y_l, z_l)` and the plane `z = 0` (the "Árnyékolás" notes):
//!   `M_par = [[1,0,−x_l/z_l,0],[0,1,−y_l/z_l,0],[0,0,0,0],[0,0,0,1]]`, applied in a frame
//!   whose `z` axis is the receiver's normal.
//! - The stencil step (the "Special Effect" notes) that keeps the shadow on the receiver polygon is, on a
//!   scanline, the overlay walk: a flattened polygon only darkens runs whose visible polygon
//!   is its receiver.
//!
//! What it cannot do, by design: shadows on anything but the marked planar receivers (no
//! shadows between objects, none on curved surfaces); it has no idea of "between", so a
//! caster behind the receiver still darkens it (an anti-shadow). Points beyond the plane
//! through the light parallel to the receiver would project through infinity to the wrong
//! side; those parts of a caster are clipped away first (w > 0 in the projection).

use super::overlay::{CoverWalker, Overlay};
use super::{ShadowContext, ShadowStage, ShadowWalker};
use crate::error::{Error, Result};
use crate::geometry::{clip_polygon, Plane};
use crate::scene::LightSample;
use crate::stats::Counters;
use glam::{DMat4, DVec3, DVec4};

/// Blinn's projection onto `plane` from a light sample, as a 4×4 matrix on homogeneous
/// points (divide by `w` after).
pub fn projection_matrix(plane: &Plane, sample: LightSample) -> DMat4 {
    match sample {
        LightSample::Point(l) => {
            // The plane seen from the light: n · x' + D = 0 with x' = x − L.
            let d = plane.distance(l);
            let n = plane.n;
            let m = DMat4::from_cols(
                DVec4::new(-d, 0.0, 0.0, n.x),
                DVec4::new(0.0, -d, 0.0, n.y),
                DVec4::new(0.0, 0.0, -d, n.z),
                DVec4::new(0.0, 0.0, 0.0, 0.0),
            );
            DMat4::from_translation(l) * m * DMat4::from_translation(-l)
        }
        LightSample::Directional(dir) => {
            // A frame with the plane as z = 0: columns e1, e2, n, origin on the plane.
            let n = plane.n;
            let e1 = n.any_orthonormal_vector();
            let e2 = n.cross(e1);
            let frame = DMat4::from_cols(e1.extend(0.0), e2.extend(0.0), n.extend(0.0), (-plane.d * n).extend(1.0));
            let l = frame.inverse().transform_vector3(dir);
            let m_par = DMat4::from_cols(
                DVec4::new(1.0, 0.0, 0.0, 0.0),
                DVec4::new(0.0, 1.0, 0.0, 0.0),
                DVec4::new(-l.x / l.z, -l.y / l.z, 0.0, 0.0),
                DVec4::new(0.0, 0.0, 0.0, 1.0),
            );
            frame * m_par * frame.inverse()
        }
    }
}

/// The prepared stage: per light sample, the flattened casters on their receivers.
pub struct Planar<'a> {
    ctx: &'a ShadowContext<'a>,
    shadows: Vec<Overlay>,
}

impl<'a> Planar<'a> {
    /// Projects every caster onto every visible receiver polygon; an error when the scene
    /// marks no receiver.
    pub fn new(ctx: &'a ShadowContext<'a>, counters: &mut Counters) -> Result<Self> {
        let scene = ctx.scene;
        let receivers: Vec<usize> =
            (0..scene.polygons.len()).filter(|&i| scene.objects[scene.polygons[i].object as usize].receiver).collect();
        if receivers.is_empty() {
            return Err(Error::NotApplicable {
                stage: "planar".into(),
                why: "planar shadows need a receiver: mark the ground's object with receiver = true, or name it \
                      on the command line (--receiver NAME, or --receiver auto for every large flat object)"
                    .into(),
            });
        }
        counters.add(crate::stats::Counter::Receivers, receivers.len() as u64);
        let mut shadows = Vec::new();
        let (mut scratch, mut ring) = ([Vec::new(), Vec::new()], Vec::new());
        let (mut clipped, mut projected) = (Vec::new(), Vec::new());
        for (_, _, sample) in ctx.all_samples() {
            let mut overlay = Overlay::new(ctx.view.height, ctx.keep_outlines);
            for &r in receivers.iter().filter(|&&r| ctx.visible[r]) {
                let plane = scene.polygons[r].plane;
                let m = projection_matrix(&plane, sample);
                for a in (0..scene.polygons.len())
                    .filter(|&a| scene.casts_shadows(a) && scene.polygons[a].face != scene.polygons[r].face)
                {
                    let h: Vec<DVec4> = scene.verts(a).iter().map(|&v| m * v.extend(1.0)).collect();
                    // Keep w > 0 (for a directional light w is 1 throughout).
                    let sign = match sample {
                        LightSample::Point(l) => -plane.distance(l).signum(),
                        LightSample::Directional(_) => 1.0,
                    };
                    clip_polygon(&h, |p: DVec4| p.w * sign, &mut clipped);
                    if clipped.len() < 3 {
                        continue;
                    }
                    projected.clear();
                    projected.extend(clipped.iter().map(|p| p.truncate() / p.w));
                    if projected.iter().all(|p: &DVec3| p.is_finite())
                        && ctx.view.clip_project(&projected, &mut scratch, &mut ring)
                    {
                        overlay.add(r as u32, &ring);
                    }
                }
            }
            overlay.finish();
            counters.add(crate::stats::Counter::ShadowPolygons, overlay.len() as u64);
            shadows.push(overlay);
        }
        Ok(Planar { ctx, shadows })
    }
}

impl ShadowStage for Planar<'_> {
    fn bytes(&self) -> usize {
        self.shadows.iter().map(Overlay::bytes).sum()
    }

    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        Box::new(CoverWalker::new(self.ctx, &self.shadows, 0.0, 1.0, "flattened caster"))
    }

    fn outlines(&self) -> Vec<Vec<glam::DVec2>> {
        self.shadows.first().map_or_else(Vec::new, |o| o.rings().to_vec())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_matrix_projects_through_the_light_onto_the_plane() {
        let plane = Plane::new(DVec3::new(0.2, 1.0, -0.1).normalize(), DVec3::new(0.0, -1.0, 0.0));
        let l = DVec3::new(0.5, 4.0, 0.3);
        let m = projection_matrix(&plane, LightSample::Point(l));
        let p = DVec3::new(0.1, 1.0, 0.7);
        let h = m * p.extend(1.0);
        let q = h.truncate() / h.w;
        // The "Special Effect" notes' formula: Q = L − (P − L)(N·L + d)/(N·(P − L)).
        let want = l - (p - l) * (plane.distance(l) / plane.n.dot(p - l));
        assert!((q - want).length() < 1e-12, "{q} vs {want}");
        assert!(plane.distance(q).abs() < 1e-12);
    }

    #[test]
    fn seed_004_m_per_is_the_same_projection() {
        // M_per projects onto z = 0 from the centre (0, 0, −d).
        let d = 3.0;
        let m_per = DMat4::from_cols(
            DVec4::new(1.0, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.0, 0.0, 0.0),
            DVec4::new(0.0, 0.0, 0.0, 1.0 / d),
            DVec4::new(0.0, 0.0, 0.0, 1.0),
        );
        let ours = projection_matrix(&Plane::new(DVec3::Z, DVec3::ZERO), LightSample::Point(DVec3::new(0.0, 0.0, -d)));
        for p in [DVec3::new(1.0, 2.0, 1.0), DVec3::new(-0.5, 0.3, 2.5)] {
            let (a, b) = (m_per * p.extend(1.0), ours * p.extend(1.0));
            assert!((a.truncate() / a.w - b.truncate() / b.w).length() < 1e-12);
        }
    }

    #[test]
    fn parallel_matrix_moves_points_along_the_light() {
        let plane = Plane::new(DVec3::new(0.0, 1.0, 0.3).normalize(), DVec3::ZERO);
        let dir = DVec3::new(0.3, -1.0, 0.2).normalize();
        let m = projection_matrix(&plane, LightSample::Directional(dir));
        let p = DVec3::new(0.4, 2.0, -0.3);
        let h = m * p.extend(1.0);
        let q = h.truncate() / h.w;
        let want = p - dir * (plane.distance(p) / plane.n.dot(dir));
        assert!((q - want).length() < 1e-12, "{q} vs {want}");
    }
}
