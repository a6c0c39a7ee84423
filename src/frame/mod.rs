//! The frame: colour, and the analysis buffers of `docs/scene-format.md` section 4 (face id per
//! pixel, lit fraction per light), with their PNG encodings.

mod false_colour;

use crate::error::{Error, Result};
use glam::Vec3;
use std::path::Path;

/// Face id of background pixels.
pub const BACKGROUND: u32 = u32::MAX;

/// A rendered image and its analysis buffers, row-major from the top-left pixel.
///
/// ```
/// use umbra::{generate, render, RenderOptions, BACKGROUND};
///
/// let out = render(&generate::cubes(2, generate::Faces::Quads, 64, 48)?, &RenderOptions::default())?;
/// let f = &out.frame;
/// let k = (24 * f.width + 32) as usize; // the pixel at (32, 24)
/// assert_ne!(f.id[k], BACKGROUND); // the face seen there (the floor or a cube)
/// assert!((0.0..=1.0).contains(&f.light[0][k])); // how much of light 0 reaches it
/// f.save_png(&std::env::temp_dir().join("umbra-cubes.png"), Some(2.2))?;
/// # Ok::<(), umbra::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear colour.
    pub color: Vec<Vec3>,
    /// Global face id seen at each pixel centre, [`BACKGROUND`] for none.
    pub id: Vec<u32>,
    /// `light[k][pixel]`: lit fraction of light `k` at the visible point (0 on background).
    pub light: Vec<Vec<f32>>,
    /// Samples of each light (the lit fraction of an exact stage is a multiple of 1/n); 0
    /// where the stage gave an area light's exact fraction (`nishita-nakamae`), any number
    /// from 0 to 1.
    pub light_samples: Vec<u32>,
    /// Per-pixel counters, when the render was asked for them.
    pub counters: Option<PixelCounters>,
    /// Where a mirror is seen: the face id seen in it (same encoding as `id`); `None` when
    /// no mirror was seen from the front.
    pub mirror_id: Option<Vec<u32>>,
}

/// Per-pixel counters (`--aov` writes them as false-colour images).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PixelCounters {
    /// Screen polygons covering the pixel centre (before hidden-surface removal).
    pub depth_complexity: Vec<u32>,
    /// How many times Watkins' algorithm split the span holding the pixel.
    pub span_splits: Vec<u32>,
    /// Shadow-stage polygons (or texels, or rays) tested for the pixel, over all samples.
    pub shadow_tests: Vec<u32>,
}

/// Where a visible point stands against an area light (seed 000): the umbra, where no point
/// of the light is seen; the penumbra, where some are; or fully lit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShadeClass {
    /// No sample of the light reaches the point.
    Umbra,
    /// Some samples reach it, not all.
    Penumbra,
    /// Every sample reaches it.
    Lit,
}

impl Frame {
    /// A frame of background pixels.
    pub fn new(width: u32, height: u32, lights: usize, background: Vec3) -> Frame {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            color: crate::pieces::filled(n, background),
            id: crate::pieces::filled(n, BACKGROUND),
            // Each light's buffer its own zeroed allocation: `vec![v; lights]` would copy
            // the first into the others on one thread.
            light: (0..lights).map(|_| vec![0.0; n]).collect(),
            light_samples: vec![1; lights],
            counters: None,
            mirror_id: None,
        }
    }

    /// A frame in the memory of `old` (a frame rendered before), so that rendering again
    /// writes into pages the process already has. Its pixels are `old`'s where `old` had
    /// them, background beyond: the frame pass writes every pixel, line by line in its
    /// parallel bands, rather than clearing the frame on one thread first.
    pub(crate) fn recycle(old: Frame, width: u32, height: u32, lights: usize, background: Vec3) -> Frame {
        let n = width as usize * height as usize;
        let Frame { mut color, mut id, mut light, .. } = old;
        color.truncate(n);
        color.resize(n, background);
        id.truncate(n);
        id.resize(n, BACKGROUND);
        light.resize_with(lights, Vec::new);
        for l in &mut light {
            l.truncate(n);
            l.resize(n, 0.0);
        }
        Frame { width, height, color, id, light, light_samples: vec![1; lights], counters: None, mirror_id: None }
    }

    fn save(&self, img: image::DynamicImage, path: &Path) -> Result<()> {
        write_png(img, path)
    }

    /// The colour image, clamped to [0, 1], optionally raised to `1/gamma` for display. A
    /// gamma outside [`GAMMA_RANGE`] (or not a number) is taken as none: check it first with
    /// [`check_gamma`].
    pub fn color_image(&self, gamma: Option<f32>) -> image::RgbImage {
        let gamma = gamma.filter(|g| GAMMA_RANGE.contains(g));
        let encode = |c: f32| {
            let c = c.clamp(0.0, 1.0);
            let c = gamma.map_or(c, |g| c.powf(1.0 / g));
            (c * 255.0).round() as u8
        };
        image::RgbImage::from_fn(self.width, self.height, |x, y| {
            let c = self.color[(y * self.width + x) as usize];
            image::Rgb([encode(c.x), encode(c.y), encode(c.z)])
        })
    }

    /// `id.png`: the face id as a little-endian u32 in R, G, B, A.
    pub fn id_image(&self) -> image::RgbaImage {
        Self::ids_image(&self.id, self.width, self.height)
    }

    /// `id_view.png`: the face ids in false colour for looking at (`id.png` packs each id
    /// into RGBA bytes, which image viewers show as nearly black): each face its own colour,
    /// background black.
    pub fn id_view_image(&self) -> image::RgbImage {
        image::RgbImage::from_fn(self.width, self.height, |x, y| {
            let id = self.id[(y * self.width + x) as usize];
            if id == BACKGROUND {
                return image::Rgb([0, 0, 0]);
            }
            // A multiplicative hash spreads neighbouring ids over the colours.
            let h = id.wrapping_add(1).wrapping_mul(0x9E37_79B9);
            let [r, g, b, _] = h.to_be_bytes();
            image::Rgb([r | 0x30, g | 0x30, b | 0x30])
        })
    }

    fn ids_image(ids: &[u32], width: u32, height: u32) -> image::RgbaImage {
        image::RgbaImage::from_fn(width, height, |x, y| image::Rgba(ids[(y * width + x) as usize].to_le_bytes()))
    }

    /// `light<k>.png`: `round(255 * lit fraction)`, halves away from zero. A fraction that is
    /// `m/n` for the light's `n` samples (every exact stage's) is encoded from `m` and `n`,
    /// so a half is a half however the fraction was summed.
    /// `None` when the frame has no light `k`.
    pub fn light_image(&self, k: usize) -> Option<image::GrayImage> {
        let n = self.light_samples.get(k).copied().unwrap_or(1) as f64;
        let light = self.light.get(k)?;
        Some(image::GrayImage::from_fn(self.width, self.height, |x, y| {
            let f = light[(y * self.width + x) as usize] as f64;
            let m = (f * n).round();
            let exact = if n > 0.0 && (f * n - m).abs() < 1e-4 { 255.0 * m / n } else { 255.0 * f };
            image::Luma([exact.round().clamp(0.0, 255.0) as u8])
        }))
    }

    /// Where pixel `i` stands against light `k`'s samples (seed 000's umbra and penumbra,
    /// `docs/scene-format.md` §6): `None` on background, else umbra (no sample lights the
    /// visible point), penumbra (some do) or lit (all do). A sample counts as lighting the
    /// point by its share of the lit fraction, so a fraction within half a sample's share of
    /// 0 is umbra and within half a share of 1 is lit (the stages' sums of `1/n` round). An
    /// exact fraction (`light_samples[k] == 0`) is umbra at 0 and lit at 1.
    pub fn shade_class(&self, k: usize, i: usize) -> Option<ShadeClass> {
        if self.id.get(i).is_none_or(|&id| id == BACKGROUND) {
            return None;
        }
        let n = self.light_samples.get(k).copied().unwrap_or(1);
        let f = *self.light.get(k)?.get(i)?;
        let half = if n == 0 { 0.0 } else { 0.5 / n as f32 };
        Some(if f <= half {
            ShadeClass::Umbra
        } else if f >= 1.0 - half {
            ShadeClass::Lit
        } else {
            ShadeClass::Penumbra
        })
    }

    /// Whether light `k` is an area light: of more than one sample, or given its exact
    /// fraction.
    pub fn is_area(&self, k: usize) -> bool {
        self.light_samples.get(k).is_some_and(|&n| n != 1)
    }

    /// The visible pixels in the umbra and in the penumbra of the area lights (more than
    /// one sample), summed over them.
    pub(crate) fn umbra_and_penumbra(&self) -> (u64, u64) {
        use rayon::prelude::*;
        let areas: Vec<usize> = (0..self.light.len()).filter(|&k| self.is_area(k)).collect();
        (0..self.id.len())
            .into_par_iter()
            .map(|i| {
                areas.iter().fold((0, 0), |(u, p), &k| match self.shade_class(k, i) {
                    Some(ShadeClass::Umbra) => (u + 1, p),
                    Some(ShadeClass::Penumbra) => (u, p + 1),
                    _ => (u, p),
                })
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
    }

    /// `umbra<k>.png` for an area light `k` ([`Frame::is_area`]): 8-bit grey, 0 umbra, 128
    /// penumbra, 255 lit, and 0 on background (which `id.png` tells apart); `None` for a
    /// light of one sample, which has no penumbra, or no light `k`.
    pub fn umbra_image(&self, k: usize) -> Option<image::GrayImage> {
        if !self.is_area(k) || k >= self.light.len() {
            return None;
        }
        Some(image::GrayImage::from_fn(self.width, self.height, |x, y| {
            let v = match self.shade_class(k, (y * self.width + x) as usize) {
                None | Some(ShadeClass::Umbra) => 0,
                Some(ShadeClass::Penumbra) => 128,
                Some(ShadeClass::Lit) => 255,
            };
            image::Luma([v])
        }))
    }

    /// Draws polygons over a colour image: tinted inside (by the even-odd rule, with the
    /// shared scan converter) and outlined.
    pub fn draw_outlines(img: &mut image::RgbImage, rings: &[Vec<glam::DVec2>], color: [u8; 3]) {
        let (w, h) = img.dimensions();
        let mut table = crate::scan::EdgeTable::new(h);
        let blend = |p: &mut image::Rgb<u8>, a: f32| {
            for (c, t) in p.0.iter_mut().zip(color) {
                *c = (*c as f32 * (1.0 - a) + t as f32 * a).round() as u8;
            }
        };
        for ring in rings {
            crate::scan::for_each_span(&mut table, &[ring], w, h, 0..h, |y, x0, x1| {
                for x in x0..x1 {
                    blend(img.get_pixel_mut(x, y), 0.25);
                }
            });
            for (i, a) in ring.iter().enumerate() {
                let b = ring[(i + 1) % ring.len()];
                let steps = (b - *a).abs().max_element().ceil().min(1e5) as usize + 1;
                for k in 0..=steps {
                    let p = *a + (b - *a) * (k as f64 / steps as f64);
                    if p.x >= 0.0 && p.y >= 0.0 && p.x < w as f64 && p.y < h as f64 {
                        blend(img.get_pixel_mut(p.x as u32, p.y as u32), 0.9);
                    }
                }
            }
        }
    }

    /// Writes the colour image as PNG (see [`check_gamma`] for `gamma`).
    pub fn save_png(&self, path: impl AsRef<Path>, gamma: Option<f32>) -> Result<()> {
        let path = path.as_ref();
        if let Some(g) = gamma {
            check_gamma(g)?;
        }
        self.save(self.color_image(gamma).into(), path)
    }

    /// Writes `id.png` and `light<k>.png` into `dir` (created if missing), `umbra<k>.png`
    /// for each area light ([`Frame::umbra_image`]), `mirror_id.png` when a mirror was seen,
    /// and, when the
    /// frame has per-pixel counters, `depth_complexity.png`, `span_splits.png` and
    /// `shadow_tests.png` in false colour with a legend.
    pub fn save_aovs(&self, dir: impl AsRef<Path>) -> Result<()> {
        let dir = dir.as_ref();
        std::fs::create_dir_all(dir).map_err(|e| Error::Write { path: dir.to_owned(), source: e })?;
        self.save(self.id_image().into(), &dir.join("id.png"))?;
        self.save(self.id_view_image().into(), &dir.join("id_view.png"))?;
        for k in 0..self.light.len() {
            if let Some(img) = self.light_image(k) {
                self.save(img.into(), &dir.join(format!("light{k}.png")))?;
            }
            if let Some(img) = self.umbra_image(k) {
                self.save(img.into(), &dir.join(format!("umbra{k}.png")))?;
            }
        }
        if let Some(m) = &self.mirror_id {
            self.save(Self::ids_image(m, self.width, self.height).into(), &dir.join("mirror_id.png"))?;
        }
        if let Some(c) = &self.counters {
            for (name, values) in [
                ("depth_complexity", &c.depth_complexity),
                ("span_splits", &c.span_splits),
                ("shadow_tests", &c.shadow_tests),
            ] {
                let img = false_colour::image(values, self.width, self.height);
                self.save(img.into(), &dir.join(format!("{name}.png")))?;
            }
        }
        Ok(())
    }

    /// Whether pixel `(x, y)` is id-interior: not on the border, and its 3x3 neighbourhood
    /// has one face id (the pixels visibility stages are compared at).
    pub fn is_id_interior(&self, x: u32, y: u32) -> bool {
        self.uniform_3x3(x, y, false)
    }

    /// Whether pixel `(x, y)` is interior: not on the border, and its 3x3 neighbourhood has
    /// one face id and one lit value per light (the pixels shadow stages are compared at).
    pub fn is_interior(&self, x: u32, y: u32) -> bool {
        self.uniform_3x3(x, y, true)
    }

    fn uniform_3x3(&self, x: u32, y: u32, lights: bool) -> bool {
        if x == 0 || y == 0 || x + 1 >= self.width || y + 1 >= self.height {
            return false;
        }
        let at = |x: u32, y: u32| (y * self.width + x) as usize;
        let c = at(x, y);
        (y - 1..=y + 1).all(|yy| {
            (x - 1..=x + 1).all(|xx| {
                let k = at(xx, yy);
                self.id[k] == self.id[c] && (!lights || self.light.iter().all(|l| l[k] == l[c]))
            })
        })
    }
}

/// The display gammas accepted: 0.1 to 10 (2.2 is the usual one).
pub const GAMMA_RANGE: std::ops::RangeInclusive<f32> = 0.1..=10.0;

/// `Ok` when `gamma` is a number in [`GAMMA_RANGE`].
pub fn check_gamma(gamma: f32) -> Result<()> {
    if GAMMA_RANGE.contains(&gamma) {
        Ok(())
    } else {
        Err(Error::out_of_range(
            "gamma",
            gamma,
            format!("in {}..={} (2.2 is the usual display gamma)", GAMMA_RANGE.start(), GAMMA_RANGE.end()),
        ))
    }
}

/// Encodes `img` as PNG in memory, then writes the file in one call, so that a failed write
/// (a full disk, `/dev/full`) is an error and never a silently truncated file.
/// Missing folders on the way are made first, as `--aov` and `generate` make theirs.
pub(crate) fn write_png(img: image::DynamicImage, path: &Path) -> Result<()> {
    let bytes = png_bytes(&img, path)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::Write { path: dir.to_owned(), source: e })?;
    }
    std::fs::write(path, bytes).map_err(|e| Error::Write { path: path.to_owned(), source: e })
}

/// The image encoded as PNG, in memory.
pub(crate) fn encode_png(img: image::DynamicImage) -> Result<Vec<u8>> {
    png_bytes(&img, Path::new("(in memory)"))
}

fn png_bytes(img: &image::DynamicImage, path: &Path) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| Error::Image { path: path.to_owned(), source: e.into() })?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_halves_round_away_from_zero_from_the_sample_count() {
        // 1 of 2 samples: 127.5 -> 128; 1 of 6: 42.5 -> 43; summed in f32 as the pipeline does.
        let mut f = Frame::new(2, 1, 2, Vec3::ZERO);
        f.light_samples = vec![2, 6];
        f.light[0][0] = 0.5;
        f.light[1][0] = (0..1).map(|_| 1.0f32 / 6.0).sum();
        f.light[1][1] = (0..3).map(|_| 1.0f32 / 6.0).sum::<f32>();
        assert_eq!(f.light_image(0).expect("a light").get_pixel(0, 0).0, [128]);
        assert_eq!(f.light_image(1).expect("a light").get_pixel(0, 0).0, [43]);
        assert_eq!(f.light_image(1).expect("a light").get_pixel(1, 0).0, [128]);
    }
}
