//! False-colour images of per-pixel counters, with a legend bar underneath (as pbrt writes
//! its per-pixel statistics): black for zero, then blue, cyan, green, yellow, red for the
//! largest value, with the scale's numbers drawn by a 3×5 bitmap font.

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

fn draw_number(img: &mut RgbImage, mut x: u32, y: u32, n: u64, colour: Rgb<u8>) {
    const SCALE: u32 = 2;
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

/// A false-colour image of `values` (`width × height`, row-major) with a legend bar 24
/// pixels high under it: the ramp from 0 to the largest value, labelled at both ends and in
/// the middle.
pub fn image(values: &[u32], width: u32, height: u32) -> RgbImage {
    let max = values.iter().copied().max().unwrap_or(0).max(1);
    let mut img = RgbImage::new(width, height + 24);
    for (i, &v) in values.iter().enumerate() {
        img.put_pixel(i as u32 % width, i as u32 / width, ramp(v as f64 / max as f64));
    }
    let white = Rgb([255, 255, 255]);
    for x in 0..width {
        let c = ramp(x as f64 / (width - 1).max(1) as f64);
        for y in height + 2..height + 10 {
            img.put_pixel(x, y, c);
        }
    }
    draw_number(&mut img, 1, height + 13, 0, white);
    let mid = (max / 2).to_string().len() as u32 * 8;
    draw_number(&mut img, (width / 2).saturating_sub(mid / 2), height + 13, (max / 2) as u64, white);
    let end = max.to_string().len() as u32 * 8;
    draw_number(&mut img, width.saturating_sub(end + 1), height + 13, max as u64, white);
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_is_black_and_the_legend_spans_the_ramp() {
        let img = image(&[0, 5, 10, 10], 2, 2);
        assert_eq!(img.dimensions(), (2, 26));
        assert_eq!(*img.get_pixel(0, 0), Rgb([0, 0, 0]));
        assert_eq!(*img.get_pixel(0, 1), ramp(1.0));
        assert_eq!(*img.get_pixel(1, 5), ramp(1.0));
    }
}
