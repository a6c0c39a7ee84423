//! Charts drawn once and written twice: as SVG for the report pages and as PNG for anything
//! that shows images (viewers, slides, issue trackers). Both are drawn by `plotters` from the
//! same code; the PNG's text uses DejaVu Sans, carried inside the program (a 27 kB subset, see
//! `src/study/fonts/LICENSE`), so that it looks the same on every machine.

use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// A chart that can be drawn on any `plotters` backend.
pub(crate) trait Chart {
    /// Its size in pixels.
    fn size(&self) -> (u32, u32);
    /// Draws it on `root`, already filled white.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> std::result::Result<(), String>;
}

/// `plotters`' errors as text, for [`Chart::draw`]'s `?`.
pub(crate) trait ErrText<T> {
    fn err_text(self) -> std::result::Result<T, String>;
}

impl<T, E: std::fmt::Display> ErrText<T> for std::result::Result<T, E> {
    fn err_text(self) -> std::result::Result<T, String> {
        self.map_err(|e| e.to_string())
    }
}

static FONT: &[u8] = include_bytes!("fonts/DejaVuSans-subset.ttf");

/// Makes DejaVu Sans the charts' "sans-serif" (once per process).
fn register_font() -> Result<()> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE.get_or_init(|| plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok());
    ok.then_some(()).ok_or_else(|| Error::Internal("the charts' font does not load".into()))
}

/// Writes `chart` as `<stem>.svg` and `<stem>.png`.
pub(crate) fn save(chart: &impl Chart, stem: &Path) -> Result<()> {
    register_font()?;
    let (svg, png) = (stem.with_extension("svg"), stem.with_extension("png"));
    let fail = |path: &Path| {
        let path = path.display().to_string();
        move |e: String| Error::InvalidOption(format!("{path}: cannot draw the chart: {e}"))
    };
    let size = chart.size();
    let root = SVGBackend::new(&svg, size).into_drawing_area();
    draw_on(chart, &root).map_err(fail(&svg))?;
    drop(root);
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
    draw_on(chart, &root).map_err(fail(&png))?;
    drop(root);
    let img = image::RgbImage::from_raw(size.0, size.1, rgb)
        .ok_or_else(|| Error::Internal(format!("{}: the chart's pixels do not fill it", png.display())))?;
    crate::frame::write_png(img.into(), &png)
}

fn draw_on<DB: DrawingBackend>(chart: &impl Chart, root: &DrawingArea<DB, Shift>) -> std::result::Result<(), String> {
    root.fill(&WHITE).err_text()?;
    chart.draw(root)?;
    root.present().err_text()
}

/// Colours for series on white that colour-blind readers tell apart (Okabe and Ito's
/// palette, its yellow left out: it is too pale on white), in the order they are used.
pub(crate) const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(230, 159, 0),   // orange
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(0, 0, 0),       // black
];

/// The `i`th series' colour (the palette again after seven).
pub(crate) fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// Places labels of size `sizes[i]` (pixels) near points `at[i]` (pixels) so that no two
/// overlap (nor come within a few pixels of another) and none covers a point: each tries
/// slots above and below its point, stepping
/// away until one is free, within the rows `inside` (top, bottom: the plotting area).
/// Returns each label's top-left corner, and whether it had to
/// move away from its point (then a leader line should join them).
pub(crate) fn place_labels(at: &[(i32, i32)], sizes: &[(i32, i32)], inside: (i32, i32)) -> Vec<((i32, i32), bool)> {
    let mut placed: Vec<(i32, i32, i32, i32)> = Vec::new();
    // Boxes keep a gap of `GAP` pixels between them, so that "5" beside "8" never reads "58".
    const GAP: i32 = 4;
    let overlaps = |b: (i32, i32, i32, i32), others: &[(i32, i32, i32, i32)]| {
        let hits_box =
            others.iter().any(|o| b.0 < o.2 + GAP && o.0 < b.2 + GAP && b.1 < o.3 + GAP / 2 && o.1 < b.3 + GAP / 2);
        let hits_point = at.iter().any(|&(px, py)| px + 4 > b.0 && px - 4 < b.2 && py + 4 > b.1 && py - 4 < b.3);
        hits_box || hits_point
    };
    let mut out = Vec::with_capacity(at.len());
    for (&(x, y), &(w, h)) in at.iter().zip(sizes) {
        let mut chosen = None;
        for level in 0..12 {
            let step = 6 + level * (h + 2);
            for dy in [-(step + h), step] {
                let b = (x - w / 2, y + dy, x - w / 2 + w, y + dy + h);
                if b.1 >= inside.0 && b.3 <= inside.1 && !overlaps(b, &placed) {
                    chosen = Some((b, level > 0));
                    break;
                }
            }
            if chosen.is_some() {
                break;
            }
        }
        let (b, moved) = chosen.unwrap_or(((x - w / 2, y - 6 - h, x + w / 2, y - 6), false));
        placed.push(b);
        out.push(((b.0, b.1), moved));
    }
    out
}

/// Tick positions for a log axis over `lo..hi`: 1, 2 and 5 times the powers of ten, every
/// digit where that gives fewer than four, only the powers of ten where it gives more than
/// ten (plotters alone labels only powers of ten, which leaves a narrow axis bare).
pub(crate) fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return Vec::new();
    }
    let decades = lo.log10().floor() as i32..=hi.log10().ceil() as i32;
    let at = |steps: &[f64]| -> Vec<f64> {
        decades
            .clone()
            .flat_map(|k| steps.iter().map(move |m| m * 10f64.powi(k)))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let ticks = at(&[1.0, 2.0, 5.0]);
    match ticks.len() {
        0..=3 => at(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]),
        4..=10 => ticks,
        _ => at(&[1.0]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Label;

    impl Chart for Label {
        fn size(&self) -> (u32, u32) {
            (120, 40)
        }
        fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> std::result::Result<(), String> {
            root.draw(&plotters::element::Text::new("ms 1.5", (10, 10), ("sans-serif", 20))).err_text()
        }
    }

    /// Labels of points that crowd together are spread out until none overlaps another or
    /// covers a point.
    #[test]
    fn crowded_labels_never_overlap() {
        let at: Vec<(i32, i32)> = (0..8).map(|i| (100 + 3 * i, 200)).collect();
        let sizes = vec![(14, 11); 8];
        let placed = place_labels(&at, &sizes, (0, 400));
        for (i, &((x, y), _)) in placed.iter().enumerate() {
            for &((u, v), _) in &placed[..i] {
                assert!(x + 18 <= u || u + 18 <= x || y + 13 <= v || v + 13 <= y, "labels {i} touch");
            }
            for &(px, py) in &at {
                assert!(px + 4 <= x || px - 4 >= x + 14 || py + 4 <= y || py - 4 >= y + 11, "label {i} covers a point");
            }
        }
        assert!(placed.iter().any(|p| p.1), "some had to move away");
    }

    #[test]
    fn log_ticks_label_narrow_and_wide_axes() {
        assert_eq!(log_ticks(38.0, 1000.0), vec![50.0, 100.0, 200.0, 500.0, 1000.0]);
        assert_eq!(log_ticks(15.0, 45.0), vec![20.0, 30.0, 40.0]);
        assert_eq!(log_ticks(0.5, 5e7), (0..8).map(|k| 10f64.powi(k)).collect::<Vec<_>>());
        assert!(log_ticks(0.0, 1.0).is_empty() && log_ticks(2.0, 1.0).is_empty());
    }

    #[test]
    fn a_chart_is_written_as_svg_and_as_png_with_its_text_drawn() {
        let scratch = tempfile::Builder::new().prefix("umbra-plot-").tempdir().unwrap();
        let dir = scratch.path();
        save(&Label, &dir.join("label")).unwrap();
        let svg = std::fs::read_to_string(dir.join("label.svg")).unwrap();
        assert!(svg.contains("ms 1.5"), "{svg}");
        let png = image::open(dir.join("label.png")).unwrap().to_rgb8();
        assert_eq!(png.dimensions(), (120, 40));
        // The text is drawn in dark pixels on the white background.
        let dark = png.pixels().filter(|p| p.0.iter().all(|&c| c < 128)).count();
        assert!(dark > 20, "only {dark} dark pixels: the text was not drawn");
    }
}
