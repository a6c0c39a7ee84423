//! Soft-edged shadows after A. Shastry, "Soft-Edged Shadows" (GameDev.net, 2005; the seed
//! article summarised in `docs/sources.md`), on any shadow stage.
//!
//! 1. **The shadow term in a screen buffer.** The stage's lit fraction of every visible pixel
//!    is written into a screen-sized buffer, one per light sample (1 where nothing is seen,
//!    0 where the sample is behind the seen side). The article renders a shadow map's term;
//!    it names shadow volumes as working the same way, and so does every stage here.
//! 2. **The blur.** The buffer is blurred: by the article's separable Gaussian of 15 taps
//!    (as published: offsets 0, ±1, ±3, …, ±13, the two sides weighted unequally, clamped
//!    to [0, 1] as its 8-bit target is), or by the Poisson-disk filter it offers instead
//!    (16 taps in a disk as wide as the Gaussian's reach, equal weights).
//! 3. **The tap spacing** sets the blur's width: the article's offsets are in units of one
//!    texel of the buffer; `spacing` multiplies them (rounded to whole pixels).
//! 4. **Read back** when shading, in place of the stage's own answer.
//!
//! **The buffers.** The article keeps one 8-bit screen buffer (and the blur's render
//! targets) for all lights: it renders one light's term into it, blurs it, shades that
//! light's pass and adds the pass to the frame, then reuses the buffer for the next light
//! ([`Buffers::Shared`]). Ours, the default ([`Buffers::PerSample`]): every light sample keeps
//! its own buffer, in f32, so that all lights are shaded in one pass (8 bytes a pixel per
//! sample, checked against the budget before any is made).

use super::{Decision, Detail, ShadowWalker};
use crate::error::Result;
use crate::visibility::Run;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

/// Which blur softens the shadow term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum Blur {
    /// The article's separable Gaussian, 15 taps.
    #[default]
    Gaussian,
    /// A Poisson-disk filter of 16 taps.
    Poisson,
}

impl Blur {
    /// Every blur.
    pub const ALL: [Blur; 2] = [Blur::Gaussian, Blur::Poisson];

    /// The blur's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Blur::Gaussian => "gaussian",
            Blur::Poisson => "poisson",
        }
    }
}

crate::error::named!(Blur, "blur");

/// Where the screen buffers of soft edges are kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum Buffers {
    /// Ours: one f32 buffer per light sample, all lights shaded in one pass.
    #[default]
    PerSample,
    /// The article's: one 8-bit screen buffer shared by every light sample, a shading pass
    /// per sample added to the frame.
    Shared,
}

impl Buffers {
    /// Every choice.
    pub const ALL: [Buffers; 2] = [Buffers::PerSample, Buffers::Shared];

    /// The choice's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Buffers::PerSample => "per-sample",
            Buffers::Shared => "shared",
        }
    }
}

crate::error::named!(Buffers, "soft-edge buffers");

/// Shastry's soft edges: which blur, how far apart its taps are, where its buffers are kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SoftEdges {
    /// The blur.
    pub blur: Blur,
    /// The taps' spacing in pixels (the article's: 1). Larger spacing, wider blur.
    pub spacing: f64,
    /// The screen buffers: one per light sample (ours) or one shared (the article's).
    pub buffers: Buffers,
}

impl Default for SoftEdges {
    fn default() -> Self {
        SoftEdges { blur: Blur::Gaussian, spacing: 1.0, buffers: Buffers::PerSample }
    }
}

impl SoftEdges {
    /// Refuses a spacing that is not a finite number from 0.25 to 64.
    pub(crate) fn check(&self) -> Result<()> {
        if !(0.25..=64.0).contains(&self.spacing) {
            return Err(crate::Error::out_of_range("soft edges: tap spacing", self.spacing, "from 0.25 to 64 pixels"));
        }
        Ok(())
    }

    /// Step 2 and 3 on one `w×h` buffer: blurred, clamped to [0, 1].
    pub(crate) fn blurred(&self, term: &[f32], w: usize, h: usize) -> Vec<f32> {
        let out = match self.blur {
            Blur::Gaussian => {
                let taps: Vec<(i64, f32)> =
                    gaussian_taps().into_iter().map(|(o, wt)| (self.at(o as f64), wt)).collect();
                let rows = separable(term, w, h, &taps, true);
                separable(&rows, w, h, &taps, false)
            }
            Blur::Poisson => {
                let taps: Vec<(i64, i64)> =
                    poisson_disk().iter().map(|&(x, y)| (self.at(x * REACH), self.at(y * REACH))).collect();
                disk(term, w, h, &taps)
            }
        };
        out.into_iter().map(|v| v.clamp(0.0, 1.0)).collect()
    }

    /// Steps 1 to 3 as the article's 8-bit render targets hold them: `term` quantised to
    /// 1/255, blurred, quantised again.
    pub(crate) fn blurred_8bit(&self, term: &[f32], w: usize, h: usize) -> Vec<u8> {
        let to_8bit = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
        let screen: Vec<f32> = term.iter().map(|&v| f32::from(to_8bit(v)) / 255.0).collect();
        self.blurred(&screen, w, h).into_iter().map(to_8bit).collect()
    }

    /// An offset of `o` texels at this spacing, in whole pixels.
    fn at(&self, o: f64) -> i64 {
        (o * self.spacing).round() as i64
    }
}

/// How far the Poisson disk reaches, in taps of spacing 1: as far as the Gaussian's
/// 15 taps carry most of their weight (about two of its widths, ρ = 3).
const REACH: f64 = 7.0;

/// Shastry's 15 taps (offset in texels, weight): the centre weighted `G(0, ρ = 2)`, then for
/// i = 1, 3, …, 13 the offsets `+i` and `−i` weighted `2 G(i, 3)` and `2 G(i + 1, 3)`, with
/// `G(x, ρ) = exp(−x²/2ρ²)/√(2πρ²)`. Reproduced as published: the taps skip even offsets,
/// the two sides are weighted unequally, and the weights sum to about 1.07 (the blurred term
/// is clamped to [0, 1], as the article's 8-bit render target does).
pub(crate) fn gaussian_taps() -> Vec<(i64, f32)> {
    let g = |x: f64, rho: f64| (-(x * x) / (2.0 * rho * rho)).exp() / (2.0 * std::f64::consts::PI * rho * rho).sqrt();
    let mut taps = vec![(0i64, g(0.0, 2.0) as f32)];
    for i in (1..15).step_by(2) {
        taps.push((i, (2.0 * g(i as f64, 3.0)) as f32));
        taps.push((-i, (2.0 * g(i as f64 + 1.0, 3.0)) as f32));
    }
    taps
}

/// 16 points in the unit disk, no two closer than 0.35 (dart throwing from a fixed seed, so
/// every frame uses the same pattern), the first at the centre.
fn poisson_disk() -> Vec<(f64, f64)> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2005);
    let mut points = vec![(0.0, 0.0)];
    while points.len() < 16 {
        let (x, y): (f64, f64) = (rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        let apart = points.iter().all(|&(px, py)| (px - x).hypot(py - y) >= 0.35);
        if x.hypot(y) <= 1.0 && apart {
            points.push((x, y));
        }
    }
    points
}

/// One pass of a separable blur along rows or columns, with clamped addressing at the
/// borders (as a texture sampler clamps).
fn separable(src: &[f32], w: usize, h: usize, taps: &[(i64, f32)], along_rows: bool) -> Vec<f32> {
    let mut out = vec![0.0f32; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            *o = taps
                .iter()
                .map(|&(off, wt)| {
                    let (sx, sy) = if along_rows {
                        ((x as i64 + off).clamp(0, w as i64 - 1) as usize, y)
                    } else {
                        (x, (y as i64 + off).clamp(0, h as i64 - 1) as usize)
                    };
                    src[sy * w + sx] * wt
                })
                .sum();
        }
    });
    out
}

/// A 2D blur with equal weights at `taps` (pixel offsets), clamped at the borders.
fn disk(src: &[f32], w: usize, h: usize, taps: &[(i64, i64)]) -> Vec<f32> {
    let weight = 1.0 / taps.len() as f32;
    let mut out = vec![0.0f32; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            *o = taps
                .iter()
                .map(|&(dx, dy)| {
                    let sx = (x as i64 + dx).clamp(0, w as i64 - 1) as usize;
                    let sy = (y as i64 + dy).clamp(0, h as i64 - 1) as usize;
                    src[sy * w + sx]
                })
                .sum::<f32>()
                * weight;
        }
    });
    out
}

/// A stage whose answers are read from blurred screen buffers (step 4).
pub(crate) struct SoftEdged {
    width: usize,
    held: Held,
    /// The flat index of each light's first sample.
    first: Vec<usize>,
}

/// What the buffers hold.
enum Held {
    /// Ours: `blurred[flat sample index][pixel]`.
    PerSample(Vec<Vec<f32>>),
    /// The article's shared 8-bit buffer, holding one sample's blurred term (every other
    /// sample reads 0: its pass is not this one); `None`: the ambient pass, all read 0.
    Shared(Option<(usize, Vec<u8>)>),
}

impl SoftEdged {
    /// The stage serving `terms` (step 1's buffers, one per light sample, `w×h`), blurred
    /// by `options`. `first[l]`: the flat index of light `l`'s first sample.
    pub(crate) fn new(terms: Vec<Vec<f32>>, w: usize, h: usize, first: Vec<usize>, options: SoftEdges) -> Self {
        let blurred = terms.iter().map(|t| options.blurred(t, w, h)).collect();
        SoftEdged { width: w, held: Held::PerSample(blurred), first }
    }

    /// The stage of one pass over the article's shared buffer: flat sample `k`'s blurred
    /// term (from [`SoftEdges::blurred_8bit`]), or with `None` the ambient pass.
    pub(crate) fn shared(pass: Option<(usize, Vec<u8>)>, w: usize, first: Vec<usize>) -> Self {
        SoftEdged { width: w, held: Held::Shared(pass), first }
    }
}

impl super::ShadowStage for SoftEdged {
    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        Box::new(Reader { stage: self })
    }

    /// The blurred screen buffers (the stage they were walked from is let go).
    fn bytes(&self) -> usize {
        match &self.held {
            Held::PerSample(buffers) => buffers.iter().map(crate::pool::held).sum(),
            Held::Shared(buffer) => buffer.as_ref().map_or(0, |(_, b)| crate::pool::held(b)),
        }
    }
}

struct Reader<'s> {
    stage: &'s SoftEdged,
}

impl ShadowWalker for Reader<'_> {
    fn lit(&mut self, light: usize, sample: usize, line: u32, run: &Run, lit: &mut [f32]) {
        let k = self.stage.first[light] + sample;
        let row = line as usize * self.stage.width;
        let pixels = row + run.x0 as usize..row + run.x1 as usize;
        match &self.stage.held {
            Held::PerSample(blurred) => lit.copy_from_slice(&blurred[k][pixels]),
            Held::Shared(Some((pass, buffer))) if *pass == k => {
                for (l, &v) in lit.iter_mut().zip(&buffer[pixels]) {
                    *l = f32::from(v) / 255.0;
                }
            }
            Held::Shared(_) => lit.fill(0.0),
        }
    }

    fn decision(&self) -> Decision {
        Decision { tested: Vec::new(), note: "read from the blurred screen buffer".into(), detail: Detail::None }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sharp edge comes out soft and within [0, 1]; wider spacing, wider ramp; a flat
    /// buffer stays flat (away from the Gaussian's unequal sides, clamped at 1).
    #[test]
    fn a_sharp_edge_is_softened_the_wider_the_farther_apart_the_taps() {
        let (w, h) = (64, 8);
        let term: Vec<f32> = (0..w * h).map(|i| if i % w < 32 { 0.0 } else { 1.0 }).collect();
        for blur in Blur::ALL {
            let ramp = |spacing| {
                let out = SoftEdges { blur, spacing, ..Default::default() }.blurred(&term, w, h);
                assert!(out.iter().all(|v| (0.0..=1.0).contains(v)));
                out[4 * w..5 * w].iter().filter(|&&v| v > 0.02 && v < 0.98).count()
            };
            let (narrow, wide) = (ramp(1.0), ramp(2.0));
            assert!(narrow >= 4 && wide > narrow, "{blur:?}: ramps of {narrow} and {wide} pixels");
            let flat = SoftEdges { blur, ..Default::default() }.blurred(&vec![1.0; w * h], w, h);
            assert!(flat.iter().all(|&v| v == 1.0), "{blur:?}");
        }
    }

    #[test]
    fn the_poisson_disk_keeps_its_points_apart_in_the_disk() {
        let p = poisson_disk();
        assert_eq!(p.len(), 16);
        for (i, a) in p.iter().enumerate() {
            assert!(a.0.hypot(a.1) <= 1.0);
            for b in &p[i + 1..] {
                assert!((a.0 - b.0).hypot(a.1 - b.1) >= 0.35);
            }
        }
    }
}
