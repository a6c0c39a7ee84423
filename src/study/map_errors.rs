//! Why a shadow map is wrong: each wrong pixel of Williams' stage, against the exact answer,
//! put down to one of four causes, so that a user sees why the map is wrong, not only how
//! much (`umbra compare` reports them; `docs/algorithms/williams.md` has the definitions and
//! what to expect where).
//!
//! Only *interior* pixels are judged (those whose 3×3 neighbourhood is uniform in the
//! reference, as `compare` counts errors), and only those that see the reference's face: a
//! pixel that sees another face is a visibility error, not a shadow's. For each such pixel,
//! the first light whose lit fraction differs decides:
//!
//! - **acne**: the map is darker than the exact answer, and no shadow edge of the exact image
//!   lies within [`EDGE_RADIUS`] pixels: a lit surface shadows itself.
//! - **detached**: the map is lighter, and a map with no bias at all (no constant, no normal
//!   offset, no slope term) gets the pixel as dark as the exact answer: the caster is in the
//!   map there, and only the bias let the receiver pass it (the shadow parts from its caster,
//!   "peter-panning").
//! - **aliasing**: otherwise, a shadow edge of the exact image lies within [`EDGE_RADIUS`]
//!   pixels: the edge is drawn in the map's texels, not where it lies.
//! - **resolution**: the rest, lighter than the exact answer with no edge near: the map lacks
//!   the caster at that texel (a caster smaller than a texel, lost between texel centres).

use crate::error::Result;
use crate::frame::Frame;
use crate::render::{render, RenderOptions};
use crate::scene::Scene;
use crate::shadow::{ShadowMethod, WilliamsOptions};
use serde::Serialize;

/// How far (in pixels, the Chebyshev distance) a shadow edge of the exact image may lie for a
/// wrong pixel to count as on that edge.
pub const EDGE_RADIUS: u32 = 3;

/// A shadow map's wrong interior pixels by cause (see the module's definitions).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct MapErrors {
    /// Darker than exact, away from every shadow edge.
    pub acne: usize,
    /// Lighter than exact where a map without bias is right.
    pub detached: usize,
    /// Wrong within [`EDGE_RADIUS`] pixels of a shadow edge.
    pub aliasing: usize,
    /// Lighter than exact, away from every edge, and wrong without bias too.
    pub resolution: usize,
}

impl MapErrors {
    /// All four together.
    pub fn total(&self) -> usize {
        self.acne + self.detached + self.aliasing + self.resolution
    }
}

/// The same shadow-map method with every bias off (the counterfactual that tells detached
/// shadows apart); `None` for a method that is not Williams'.
pub fn without_bias(method: &ShadowMethod) -> Option<ShadowMethod> {
    match method {
        ShadowMethod::Williams(o) => Some(ShadowMethod::Williams(WilliamsOptions {
            bias: Some(0.0),
            normal_offset: 0.0,
            slope_bias: 0.0,
            receiver_plane: false,
            ..o.clone()
        })),
        _ => None,
    }
}

/// The wrong interior pixels of `got` by cause, where `got` is the frame `opts` rendered of
/// `scene` with a shadow map and `reference` the exact frame: renders the same map once more
/// without bias ([`without_bias`]) and [`classify`]s. `None` for other shadow methods.
pub fn measure(scene: &Scene, opts: &RenderOptions, got: &Frame, reference: &Frame) -> Result<Option<MapErrors>> {
    let Some(unbiased) = without_bias(&opts.shadows) else { return Ok(None) };
    let unbiased = render(scene, &RenderOptions { shadows: unbiased, ..opts.clone() })?;
    Ok(Some(classify(reference, got, &unbiased.frame)))
}

/// Classifies the wrong interior pixels of `got` (a shadow map's frame) against `reference`
/// (the exact frame), with `unbiased` the same map rendered by [`without_bias`].
pub fn classify(reference: &Frame, got: &Frame, unbiased: &Frame) -> MapErrors {
    let mut out = MapErrors::default();
    let (w, h) = (reference.width, reference.height);
    for y in 0..h {
        for x in 0..w {
            let k = (y * w + x) as usize;
            if !reference.is_interior(x, y) || reference.id[k] != got.id[k] {
                continue;
            }
            let Some(l) = (0..reference.light.len()).find(|&l| reference.light[l][k] != got.light[l][k]) else {
                continue;
            };
            let (exact, map) = (reference.light[l][k], got.light[l][k]);
            let edge = near_edge(reference, l, x, y);
            let cause = if map < exact {
                if edge {
                    &mut out.aliasing
                } else {
                    &mut out.acne
                }
            } else if unbiased.id[k] == reference.id[k] && unbiased.light[l][k] <= exact {
                &mut out.detached
            } else if edge {
                &mut out.aliasing
            } else {
                &mut out.resolution
            };
            *cause += 1;
        }
    }
    out
}

/// Whether the exact image's lit fraction of light `l`, or its face, changes within
/// [`EDGE_RADIUS`] pixels of `(x, y)`.
fn near_edge(reference: &Frame, l: usize, x: u32, y: u32) -> bool {
    let (w, h) = (reference.width, reference.height);
    let k = (y * w + x) as usize;
    let (lit, id) = (reference.light[l][k], reference.id[k]);
    (y.saturating_sub(EDGE_RADIUS)..=(y + EDGE_RADIUS).min(h - 1)).any(|yy| {
        (x.saturating_sub(EDGE_RADIUS)..=(x + EDGE_RADIUS).min(w - 1)).any(|xx| {
            let j = (yy * w + xx) as usize;
            reference.light[l][j] != lit || reference.id[j] != id
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A 16×16 frame of one face, lit but for the columns `shadow` (light 0).
    fn frame(shadow: std::ops::Range<u32>) -> Frame {
        let mut f = Frame::new(16, 16, 1, Vec3::ZERO);
        for k in 0..256 {
            f.id[k] = 1;
            f.light[0][k] = if shadow.contains(&(k as u32 % 16)) { 0.0 } else { 1.0 };
        }
        f
    }

    /// Each cause from a frame built to show it: a dark speck far from the shadow (acne), a
    /// shadow missing that the unbiased map has (detached), a shadow missing that the
    /// unbiased map lacks too (aliasing near its edge, resolution away from it), the edge
    /// moved by two columns (aliasing).
    #[test]
    fn each_cause_from_a_frame_that_shows_it() {
        let exact = frame(8..16);
        let mut acne = exact.clone();
        acne.light[0][3 * 16 + 2] = 0.0;
        assert_eq!(classify(&exact, &acne, &exact), MapErrors { acne: 1, ..Default::default() });

        let missing = frame(0..0);
        // The reference's interior shadow columns are 9..=14 (8 borders the edge, 15 the
        // frame), on rows 1..=14.
        let rows = 14;
        assert_eq!(classify(&exact, &missing, &exact), MapErrors { detached: 6 * rows, ..Default::default() });
        // Columns 9 and 10 lie within three pixels of column 7, which the shadow does not
        // reach; 11..=14 do not.
        assert_eq!(
            classify(&exact, &missing, &missing),
            MapErrors { aliasing: 2 * rows, resolution: 4 * rows, ..Default::default() }
        );
        let moved = frame(10..16);
        assert_eq!(classify(&exact, &moved, &moved), MapErrors { aliasing: rows, ..Default::default() });
    }
}
