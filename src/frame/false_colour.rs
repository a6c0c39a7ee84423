//! False-colour images of per-pixel counters, with a legend bar underneath (as pbrt writes
//! its per-pixel statistics): black for zero, then blue, cyan, green, yellow, red for the
//! largest value, with the scale's tick values drawn by a 3×5 bitmap font at three times its
//! size.

use image::{Rgb, RgbImage};

/// Digits 0-9 as 3×5 bitmaps, one row per 3 bits (most significant bit on the left).
const DIGITS: [[u8; 5]; 10] = [
    [7, 5, 5, 5, 7],
    [2, 6, 2, 2, 7],
    [7, 1, 7, 4, 7],
    [7, 1, 7, 1, 7],
    [5, 5, 7, 1, 1],
    [7, 4, 7, 1, 7],
    [7, 4, 7, 5, 7],
    [7, 1, 2, 2, 2],
    [7, 5, 7, 5, 7],
    [7, 5, 7, 1, 7],
];

/// The colour of `t` in [0, 1].
pub fn ramp(t: f64) -> Rgb<u8> {
    const STOPS: [[f64; 3]; 6] =
        [[0.0, 0.0, 0.0], [0.1, 0.1, 0.9], [0.0, 0.8, 0.9], [0.1, 0.8, 0.1], [0.95, 0.9, 0.1], [0.9, 0.1, 0.1]];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f64;
    let c = |k: usize| ((STOPS[i][k] * (1.0 - f) + STOPS[i + 1][k] * f) * 255.0).round() as u8;
    Rgb([c(0), c(1), c(2)])
}

/// The digits' size: each bitmap pixel drawn as a 3×3 square (9×15 pixels a digit).
const SCALE: u32 = 3;
/// The height of the legend under the image.
const LEGEND: u32 = 36;

fn draw_number(img: &mut RgbImage, mut x: u32, y: u32, n: u64, colour: Rgb<u8>) {
    for ch in n.to_string().bytes() {
        let glyph = DIGITS[(ch - b'0') as usize];
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..3 {
                if bits & (4 >> col) != 0 {
                    for dy in 0..SCALE {
                        for dx in 0..SCALE {
                            let (px, py) = (x + col * SCALE + dx, y + row as u32 * SCALE + dy);
                            if px < img.width() && py < img.height() {
                                img.put_pixel(px, py, colour);
                            }
                        }
                    }
                }
            }
        }
        x += 4 * SCALE;
    }
}

/// The width of `n` drawn by [`draw_number`].
fn number_width(n: u64) -> u32 {
    n.to_string().len() as u32 * 4 * SCALE - SCALE
}

/// The legend's tick values for counts from 0 to `max`: the multiples of a round step (1, 2
/// or 5 times a power of ten) that give at most five ticks, then `max` itself, the ramp's
/// end (counters are whole numbers, so no tick falls between two).
pub(crate) fn ticks(max: u64) -> Vec<u64> {
    let max = max.max(1);
    let mut step = 1u64;
    'find: for power in 0..20 {
        for m in [1, 2, 5] {
            step = m * 10u64.pow(power);
            if max / step <= 4 {
                break 'find;
            }
        }
    }
    let mut t: Vec<u64> = (0..=max / step).map(|k| k * step).collect();
    if t.last() != Some(&max) {
        t.push(max);
    }
    t
}

/// A false-colour image of `values` (`width × height`, row-major) with a legend 36 pixels
/// high under it: the ramp from 0 to the largest value, with a tick and its value at each of
/// [`ticks`] where the value fits without touching its neighbour (the two ends always).
pub fn image(values: &[u32], width: u32, height: u32) -> RgbImage {
    let max = values.iter().copied().max().unwrap_or(0).max(1);
    let mut img = RgbImage::new(width, height + LEGEND);
    for (i, &v) in values.iter().enumerate() {
        img.put_pixel(i as u32 % width, i as u32 / width, ramp(v as f64 / max as f64));
    }
    let white = Rgb([255, 255, 255]);
    let span = (width - 1).max(1);
    for x in 0..width {
        let c = ramp(x as f64 / span as f64);
        for y in height + 2..height + 12 {
            img.put_pixel(x, y, c);
        }
    }
    // Each tick at its value's place on the ramp; its number centred under it, kept inside
    // the image, and left out where it would touch the one before (or the last, kept).
    let ticks = ticks(max as u64);
    let place = |t: u64| {
        let x = (t as f64 / max as f64 * span as f64).round() as u32;
        let w = number_width(t);
        // Two pixels from either border where the image is wide enough.
        let hi = width.saturating_sub(w + 2);
        (x, x.saturating_sub(w / 2).clamp(2.min(hi), hi), w)
    };
    let last = ticks.last().map(|&t| place(t).1).unwrap_or(width);
    let mut free_from = 0;
    for (k, &t) in ticks.iter().enumerate() {
        let (x, left, w) = place(t);
        let is_last = k + 1 == ticks.len();
        if left < free_from || (!is_last && left + w + SCALE * 2 > last) {
            continue;
        }
        for y in height + 12..height + 16 {
            img.put_pixel(x.min(width - 1), y, white);
        }
        draw_number(&mut img, left, height + 18, t, white);
        free_from = left + w + SCALE * 2;
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_is_black_and_the_legend_spans_the_ramp() {
        let img = image(&[0, 5, 10, 10], 2, 2);
        assert_eq!(img.dimensions(), (2, 2 + LEGEND));
        assert_eq!(*img.get_pixel(0, 0), Rgb([0, 0, 0]));
        assert_eq!(*img.get_pixel(0, 1), ramp(1.0));
        assert_eq!(*img.get_pixel(1, 5), ramp(1.0));
    }

    #[test]
    fn the_legend_ticks_are_round_values_up_to_the_largest() {
        assert_eq!(ticks(1), [0, 1]);
        assert_eq!(ticks(4), [0, 1, 2, 3, 4]);
        assert_eq!(ticks(7), [0, 2, 4, 6, 7]);
        assert_eq!(ticks(37), [0, 10, 20, 30, 37]);
        assert_eq!(ticks(1000), [0, 500, 1000]);
        assert_eq!(ticks(0), [0, 1]);
    }

    /// A counter whose largest value is 1 (a shadow test per pixel) reads 0 and 1 under its
    /// ramp, at each end, not "0 ... 0 ... 1".
    #[test]
    fn a_zero_or_one_counter_is_labelled_0_and_1() {
        let img = image(&vec![1; 200 * 10], 200, 10);
        let lit = |x0: u32, x1: u32| (x0..x1).any(|x| (10 + 18..10 + 33).any(|y| img.get_pixel(x, y).0 == [255; 3]));
        assert!(lit(0, 12) && lit(188, 200), "both ends labelled");
        assert!(!lit(40, 160), "nothing between them");
    }
}
