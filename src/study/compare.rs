//! `umbra compare`: renders one scene with every visibility × shadow combination asked for,
//! times each (median of several runs, through the same [`crate::render()`] the benchmarks
//! call), measures each against the exact ray-cast reference (share of interior pixels wrong,
//! and a diff image), and writes `report.html`, `results.json` and `results.csv`.
//!
//! Every method in [`VisibilityMethod::ALL`] and [`ShadowMethod::ALL`] takes part by
//! default: a new stage appears here without more code. A method that cannot handle the
//! scene (planar shadows with no receiver, say) is reported as not applicable.

use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::render::{render, RenderOptions};
use crate::scene::Scene;
use crate::shadow::ShadowMethod;
use crate::study::bench::{measure, Measured, Spread};
use crate::study::escape;
use crate::visibility::VisibilityMethod;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What to compare.
#[derive(Debug, Clone)]
pub struct CompareOptions {
    /// Visibility stages.
    pub visibility: Vec<VisibilityMethod>,
    /// Shadow stages.
    pub shadows: Vec<ShadowMethod>,
    /// Untimed renders per method before the timed ones.
    pub warmup: usize,
    /// Timed runs per method (the median, least and greatest are reported).
    pub runs: usize,
    /// Output folder.
    pub out: PathBuf,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            visibility: VisibilityMethod::ALL.to_vec(),
            shadows: ShadowMethod::ALL.to_vec(),
            warmup: 1,
            runs: 3,
            out: PathBuf::from("compare"),
        }
    }
}

/// One method's line in the report.
#[derive(Debug, Clone, Serialize)]
pub struct MethodResult {
    /// Visibility stage.
    pub visibility: String,
    /// Shadow stage.
    pub shadows: String,
    /// `ok`, or why the method does not apply.
    pub status: String,
    /// Whether the shadow stage is meant to be exact.
    pub exact: bool,
    /// The frame time over the timed runs (after the warm-up), milliseconds.
    #[serde(flatten)]
    pub time: Spread,
    /// Every timed run's frame time.
    pub times_ms: Vec<f64>,
    /// The median time of each phase over the timed runs.
    pub step_ms: BTreeMap<String, f64>,
    /// Interior pixels of the reference (3×3 uniform in id and light values).
    pub interior_pixels: usize,
    /// Interior pixels where this method's id or a lit value differs from the reference.
    pub wrong_pixels: usize,
    /// `wrong_pixels / interior_pixels`.
    pub error_share: f64,
    /// A shadow map's wrong interior pixels by cause ([`super::map_errors`]); `None` for
    /// other methods.
    pub map_errors: Option<super::map_errors::MapErrors>,
    /// On a scene with area lights: how far the stage's lit fractions of the area lights are
    /// from the exact fraction (`docs/scene-format.md` §3), over the visible pixels in the
    /// exact penumbra where it sees the reference's face. `None` without area lights.
    pub area_error: Option<AreaError>,
    /// The image, relative to the report.
    pub image: String,
    /// The diff image, relative to the report.
    pub diff: String,
    /// Visibility and shadow counters of the median run.
    pub counters: BTreeMap<String, u64>,
}

/// How far a stage's area-light fractions are from the exact ones.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AreaError {
    /// Pixels in the exact penumbra compared, summed over the area lights.
    pub pixels: usize,
    /// The mean of `|fraction − exact|`.
    pub mean: f64,
    /// The largest.
    pub max: f64,
}

impl AreaError {
    /// `got`'s area-light fractions against `exact`'s (the reference with exact fractions).
    pub(crate) fn of(scene: &Scene, exact: &Frame, got: &Frame) -> AreaError {
        let (mut pixels, mut sum, mut max) = (0, 0.0f64, 0.0f64);
        for (l, light) in scene.lights.iter().enumerate() {
            if !matches!(light.kind, crate::scene::LightKind::Area { .. }) {
                continue;
            }
            for k in 0..exact.id.len() {
                let f = exact.light[l][k];
                if exact.id[k] == crate::frame::BACKGROUND || exact.id[k] != got.id[k] || f <= 0.0 || f >= 1.0 {
                    continue;
                }
                let e = (got.light[l][k] as f64 - exact.light[l][k] as f64).abs();
                pixels += 1;
                sum += e;
                max = max.max(e);
            }
        }
        AreaError { pixels, mean: sum / pixels.max(1) as f64, max }
    }
}

/// The whole comparison.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The program, machine, date and options.
    pub about: super::About,
    /// The scene's name.
    pub scene: String,
    /// Image size.
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// Polygons.
    pub polygons: usize,
    /// The reference image, relative to the report.
    pub reference: String,
    /// One entry per method.
    pub results: Vec<MethodResult>,
}

/// Compares `got` with the reference at the reference's interior pixels: (interior, wrong,
/// diff image). The diff shows the reference in grey, wrong interior pixels in red and
/// differing edge pixels (not counted) in yellow.
pub fn diff(reference: &Frame, got: &Frame) -> (usize, usize, image::RgbImage) {
    diff_within(reference, got, 0)
}

/// [`diff`], with lit fractions that differ by at most `grey_levels` once written as 8-bit
/// grey (`round(255 f)`) counted as equal: the exact area-light fraction, computed two ways,
/// is equal to one grey level.
pub fn diff_within(reference: &Frame, got: &Frame, grey_levels: u8) -> (usize, usize, image::RgbImage) {
    let apart = |a: f32, b: f32| {
        if grey_levels == 0 {
            a != b
        } else {
            ((a * 255.0).round() - (b * 255.0).round()).abs() > grey_levels as f32
        }
    };
    let grey = reference.color_image(None);
    let mut img = image::RgbImage::new(reference.width, reference.height);
    let (mut interior, mut wrong) = (0, 0);
    for y in 0..reference.height {
        for x in 0..reference.width {
            let k = (y * reference.width + x) as usize;
            let differs =
                reference.id[k] != got.id[k] || reference.light.iter().zip(&got.light).any(|(a, b)| apart(a[k], b[k]));
            let g = grey.get_pixel(x, y).0.iter().map(|&c| c as u32).sum::<u32>() / 6;
            let px = if reference.is_interior(x, y) {
                interior += 1;
                wrong += differs as usize;
                if differs {
                    [230, 30, 30]
                } else {
                    [g as u8; 3]
                }
            } else if differs {
                [220, 200, 40]
            } else {
                [g as u8; 3]
            };
            img.put_pixel(x, y, image::Rgb(px));
        }
    }
    (interior, wrong, img)
}

/// Runs the comparison and writes the report into `opts.out`, telling `progress` which
/// method is being measured and how many renders are done.
pub fn compare(
    scene: &Scene,
    name: &str,
    opts: &CompareOptions,
    progress: impl Fn(crate::Progress<'_>) + Send + Sync,
) -> Result<Report> {
    let img_dir = opts.out.join("img");
    std::fs::create_dir_all(&img_dir).map_err(|e| Error::Write { path: img_dir.clone(), source: e })?;
    let save = |img: image::RgbImage, file: &str| -> Result<String> {
        let path = img_dir.join(file);
        crate::frame::write_png(img.into(), &path)?;
        Ok(format!("img/{file}"))
    };
    let reference_opts = RenderOptions {
        visibility: VisibilityMethod::RayCast,
        shadows: ShadowMethod::RayCast,
        ..RenderOptions::default()
    };
    let reference = render(scene, &reference_opts)?.frame;
    let reference_image = save(reference.color_image(None), "reference.png")?;
    // Nishita & Nakamae's stage gives area lights their exact fraction, not the grid's: it is
    // judged against the reference with the exact fractions in place (to a grey level). Every
    // stage's area-light error is measured against those fractions too.
    let exact = std::cell::OnceCell::new();
    let exact_reference = || exact.get_or_init(|| with_exact_area_fractions(scene, &reference));
    let total = (opts.visibility.len() * opts.shadows.len() * opts.runs.max(1)) as u64;
    let bar = crate::progress::Reporter::new(Some(&progress), total, "renders");
    let mut results = Vec::new();
    for &v in &opts.visibility {
        for s in &opts.shadows {
            bar.phase(format!("{v} + {s}"));
            let ropts = RenderOptions { visibility: v, shadows: s.clone(), ..RenderOptions::default() };
            let (status, measured) = match measure(scene, &ropts, opts.warmup, opts.runs) {
                Ok(m) => ("ok".to_string(), Some(m)),
                Err(Error::NotApplicable { why, .. }) => (format!("not applicable: {why}"), None),
                Err(e @ Error::Internal(_)) => (format!("failed: {e}"), None),
                Err(e) => return Err(e),
            };
            bar.advance(opts.runs.max(1) as u64);
            results.push(match measured {
                None => MethodResult::not_run(v, s, status),
                Some(m) => {
                    let judge = match s {
                        s if s.exact_area_fraction() && has_area_light(scene) => (exact_reference(), 1),
                        _ => (&reference, 0),
                    };
                    let mut r = MethodResult::measured(v, s, status, &m, judge, |img, file| save(img, file))?;
                    r.map_errors = super::map_errors::measure(scene, &ropts, &m.last.frame, &reference)?;
                    if has_area_light(scene) {
                        r.area_error = Some(AreaError::of(scene, exact_reference(), &m.last.frame));
                    }
                    r
                }
            });
        }
    }
    let report = Report {
        about: super::About::now(format!(
            "warmup {}, runs {}, shadow stages: {}",
            opts.warmup,
            opts.runs,
            opts.shadows.iter().map(ShadowMethod::command_line).collect::<Vec<_>>().join("; ")
        )),
        scene: name.into(),
        width: scene.camera.width,
        height: scene.camera.height,
        polygons: scene.polygons.len(),
        reference: reference_image,
        results,
    };
    write_files(&report, &opts.out)?;
    Ok(report)
}

/// Whether `scene` has an area light.
fn has_area_light(scene: &Scene) -> bool {
    scene.lights.iter().any(|l| matches!(l.kind, crate::scene::LightKind::Area { .. }))
}

/// The ray-cast reference frame of `scene` with each area light's exact fractions.
pub(crate) fn exact_area_reference(scene: &Scene) -> Result<Frame> {
    let opts = RenderOptions {
        visibility: VisibilityMethod::RayCast,
        shadows: ShadowMethod::RayCast,
        ..RenderOptions::default()
    };
    Ok(with_exact_area_fractions(scene, &render(scene, &opts)?.frame))
}

/// The ray-cast `reference` with each area light's lit fractions replaced by the exact ones
/// (`docs/scene-format.md` §3, [`crate::reference::exact_fraction`]), pixel by pixel in
/// parallel.
fn with_exact_area_fractions(scene: &Scene, reference: &Frame) -> Frame {
    use rayon::prelude::*;
    let oracle = crate::reference::Reference::new(scene);
    let mut out = reference.clone();
    let w = reference.width as usize;
    for (l, light) in out.light.iter_mut().enumerate() {
        if !matches!(scene.lights[l].kind, crate::scene::LightKind::Area { .. }) {
            continue;
        }
        light.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, f) in row.iter_mut().enumerate() {
                let at = oracle.exact_fraction_at(l, x as f64 + 0.5, y as f64 + 0.5);
                *f = at.map_or(*f, |v| v as f32);
            }
        });
    }
    out
}

impl MethodResult {
    /// A method that was not measured (not applicable to the scene, or failed), with why.
    fn not_run(v: VisibilityMethod, s: &ShadowMethod, status: String) -> MethodResult {
        MethodResult {
            visibility: v.name().into(),
            shadows: s.label(),
            status,
            exact: s.is_exact(),
            time: Spread { median_ms: 0.0, min_ms: 0.0, max_ms: 0.0 },
            times_ms: Vec::new(),
            step_ms: BTreeMap::new(),
            interior_pixels: 0,
            wrong_pixels: 0,
            error_share: 0.0,
            map_errors: None,
            area_error: None,
            image: String::new(),
            diff: String::new(),
            counters: BTreeMap::new(),
        }
    }

    /// A measured method: its times, its last frame against `reference` (the image and the
    /// wrong pixels, written by `save`), and its counters.
    fn measured(
        v: VisibilityMethod,
        s: &ShadowMethod,
        status: String,
        m: &Measured,
        (reference, grey_levels): (&Frame, u8),
        save: impl Fn(image::RgbImage, &str) -> Result<String>,
    ) -> Result<MethodResult> {
        let id = format!("{v}-{s}{}", if s.is_paper() { "-paper" } else { "" });
        let run = &m.last;
        let (interior, wrong, diff_img) = diff_within(reference, &run.frame, grey_levels);
        let counters = run
            .stats
            .visibility_counters
            .iter()
            .map(|(k, v)| (format!("visibility.{k}"), v))
            .chain(run.stats.shadow_counters.iter().map(|(k, v)| (format!("shadow.{k}"), v)))
            .collect();
        Ok(MethodResult {
            visibility: v.name().into(),
            shadows: s.label(),
            status,
            exact: s.is_exact(),
            time: m.frame,
            times_ms: m.times_ms.clone(),
            step_ms: m.phases.iter().map(|(k, v)| (k.clone(), v.median_ms)).collect(),
            interior_pixels: interior,
            wrong_pixels: wrong,
            error_share: wrong as f64 / interior.max(1) as f64,
            map_errors: None,
            area_error: None,
            image: save(run.frame.color_image(None), &format!("{id}.png"))?,
            diff: save(diff_img, &format!("{id}-diff.png"))?,
            counters,
        })
    }
}

fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::Write { path: path.to_owned(), source: e })
}

fn write_files(report: &Report, out: &Path) -> Result<()> {
    let json = serde_json::to_string_pretty(report).map_err(|e| Error::Internal(e.to_string()))?;
    write(&out.join("results.json"), &json)?;
    let mut csv = String::from(
        "visibility,shadows,status,exact,median_ms,min_ms,max_ms,interior_pixels,wrong_pixels,error_share,area_mean_error,area_max_error\n",
    );
    for r in &report.results {
        let _ = writeln!(
            csv,
            "{},{},\"{}\",{},{:.3},{:.3},{:.3},{},{},{:.6},{},{}",
            r.visibility,
            r.shadows,
            r.status.replace('"', "'"),
            r.exact,
            r.time.median_ms,
            r.time.min_ms,
            r.time.max_ms,
            r.interior_pixels,
            r.wrong_pixels,
            r.error_share,
            r.area_error.map_or(String::new(), |a| format!("{:.6}", a.mean)),
            r.area_error.map_or(String::new(), |a| format!("{:.6}", a.max))
        );
    }
    write(&out.join("results.csv"), &csv)?;
    #[cfg(feature = "plots")]
    charts::draw(report, out)?;
    write(&out.join("report.html"), &html(report, out))
}

/// The report's two charts, in SVG and PNG: frame time against wrong pixels for every method,
/// and each method's frame split into its phases.
#[cfg(feature = "plots")]
mod charts {
    use super::{MethodResult, Report};
    use crate::error::Result;
    use crate::study::plot::{colour, log_ticks, place_labels, save, Chart, ErrText};
    use plotters::coord::combinators::BindKeyPoints;
    use plotters::coord::Shift;
    use plotters::prelude::*;
    use std::path::Path;

    /// The phases in the pipeline's order.
    pub(super) const PHASES: [&str; 6] =
        ["view", "visibility", "shadow_prepare", "shadow_walk", "shading", "reflections"];

    pub(super) fn draw(report: &Report, out: &Path) -> Result<()> {
        let ok: Vec<&MethodResult> = report.results.iter().filter(|r| r.status == "ok").collect();
        save(&TimeAgainstError(&ok), &out.join("time-error"))?;
        save(&Phases(&ok), &out.join("phases"))
    }

    /// Frame time (log) against the share of interior pixels wrong: exact methods lie on
    /// the zero line, the approximate ones above it.
    struct TimeAgainstError<'a>(&'a [&'a MethodResult]);

    impl Chart for TimeAgainstError<'_> {
        fn size(&self) -> (u32, u32) {
            (980, 560)
        }

        fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> std::result::Result<(), String> {
            let ok = self.0;
            let (t0, t1) =
                ok.iter().fold((f64::INFINITY, 0.0f64), |(a, b), r| (a.min(r.time.min_ms), b.max(r.time.max_ms)));
            let e1 = ok.iter().fold(0.0f64, |m, r| m.max(100.0 * r.error_share)).max(1.0);
            if ok.is_empty() || t0.is_nan() || t0 <= 0.0 {
                return Ok(());
            }
            let (plot_area, key) = root.split_horizontally(620);
            let times = (t0 / 1.3..t1 * 1.3).log_scale().with_key_points(log_ticks(t0 / 1.3, t1 * 1.3));
            let mut chart = ChartBuilder::on(&plot_area)
                .caption("frame time against error", ("sans-serif", 17))
                .margin(16)
                .x_label_area_size(44)
                .y_label_area_size(64)
                .build_cartesian_2d(times, -0.05 * e1..e1 * 1.15)
                .err_text()?;
            chart
                .configure_mesh()
                .light_line_style(TRANSPARENT)
                .bold_line_style(BLACK.mix(0.08))
                .x_labels(12)
                .x_label_formatter(&|v| format!("{v}"))
                .x_desc("frame time, ms (median; bar: least to greatest)")
                .y_desc("interior pixels wrong, %")
                .draw()
                .err_text()?;
            // Each point numbered, and the key beside the plot. The numbers are placed in
            // pixels so that none overlaps another or covers a point; one moved away from its
            // point is joined to it by a thin leader line.
            let mut by_time = ok.to_vec();
            by_time.sort_by(|a, b| a.time.median_ms.total_cmp(&b.time.median_ms));
            let (exact, approximate) = (colour(0), colour(1));
            let at: Vec<(f64, f64)> = by_time.iter().map(|r| (r.time.median_ms, 100.0 * r.error_share)).collect();
            let pixels: Vec<(i32, i32)> = at.iter().map(|&p| chart.backend_coord(&p)).collect();
            let font = ("sans-serif", 12).into_font();
            let sizes: Vec<(i32, i32)> = (1..=at.len())
                .map(|i| {
                    root.estimate_text_size(&i.to_string(), &font.clone().into_text_style(root))
                        .map_or((14, 12), |(w, h)| (w as i32, h as i32))
                })
                .collect();
            let rows = chart.plotting_area().get_pixel_range().1;
            let places = place_labels(&pixels, &sizes, (rows.start, rows.end));
            let origin = plot_area.get_base_pixel();
            for (i, r) in by_time.iter().enumerate() {
                let c = if r.exact { exact } else { approximate };
                let bar = vec![(r.time.min_ms, at[i].1), (r.time.max_ms, at[i].1)];
                chart.draw_series([PathElement::new(bar, c.stroke_width(1))]).err_text()?;
                chart.draw_series([Circle::new(at[i], 4, c.filled())]).err_text()?;
                let ((x, y), moved) = places[i];
                let (x, y) = (x - origin.0, y - origin.1);
                if moved {
                    let (px, py) = (pixels[i].0 - origin.0, pixels[i].1 - origin.1);
                    let end = (x + sizes[i].0 / 2, if y > py { y } else { y + sizes[i].1 });
                    plot_area.draw(&PathElement::new(vec![(px, py), end], BLACK.mix(0.35))).err_text()?;
                }
                plot_area.draw(&Text::new(format!("{}", i + 1), (x, y), font.clone())).err_text()?;
                let line =
                    format!("{:>2}. {} + {}: {:.1} ms, {:.3}%", i + 1, r.visibility, r.shadows, at[i].0, at[i].1);
                key.draw(&Text::new(line, (4, 24 + 18 * i as i32), ("sans-serif", 12).into_font().color(&c)))
                    .err_text()?;
            }
            let note = "blue: exact; vermillion: approximate";
            key.draw(&Text::new(note, (4, 24 + 18 * at.len() as i32 + 8), ("sans-serif", 12))).err_text()?;
            Ok(())
        }
    }

    /// Each method's median frame split into its phases, as stacked horizontal bars.
    struct Phases<'a>(&'a [&'a MethodResult]);

    /// The phases' colours, in [`PHASES`]' order: the view in grey, the rest from the
    /// colour-blind-safe palette.
    const COLOURS: [RGBColor; 6] =
        [RGBColor(150, 150, 150), colour_at(0), colour_at(1), colour_at(2), colour_at(3), colour_at(4)];

    const fn colour_at(i: usize) -> RGBColor {
        crate::study::plot::PALETTE[i]
    }

    fn total(r: &MethodResult) -> f64 {
        PHASES.iter().filter_map(|p| r.step_ms.get(*p)).sum()
    }

    impl Chart for Phases<'_> {
        fn size(&self) -> (u32, u32) {
            (960, (60 + 22 * self.0.len() as u32).max(120))
        }

        fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> std::result::Result<(), String> {
            let longest = self.0.iter().map(|r| total(r)).fold(0.0f64, f64::max).max(1e-3);
            // The bars start after the longest name, however long.
            let name = |r: &MethodResult| format!("{} + {}", r.visibility, r.shadows);
            let style = ("sans-serif", 12).into_text_style(root);
            let names = self.0.iter().map(|r| root.estimate_text_size(&name(r), &style).map_or(220, |s| s.0));
            let left = (names.max().unwrap_or(200) as f64 + 20.0).max(230.0);
            let (right, top) = (self.size().0 as f64 - left - 70.0, 40);
            let text = |s: String, x: i32, y: i32| Text::new(s, (x, y), ("sans-serif", 12));
            root.draw(&text("median time per phase, ms".into(), 10, 12)).err_text()?;
            // The legend's entries one after another, each as wide as its text: never two on
            // one another, however long the names.
            let mut x = left as i32;
            for (p, c) in PHASES.iter().zip(COLOURS) {
                let name = p.replace('_', " ");
                let width = root
                    .estimate_text_size(&name, &("sans-serif", 12).into_text_style(root))
                    .map_or(90, |s| s.0 as i32);
                root.draw(&Rectangle::new([(x, 8), (x + 10, 18)], c.filled())).err_text()?;
                root.draw(&text(name, x + 14, 8)).err_text()?;
                x += 14 + width + 18;
            }
            for (i, r) in self.0.iter().enumerate() {
                let y = top + 22 * i as i32;
                root.draw(&text(name(r), 10, y + 3)).err_text()?;
                let mut x = left;
                for (p, c) in PHASES.iter().zip(COLOURS) {
                    let w = r.step_ms.get(*p).copied().unwrap_or(0.0) / longest * right;
                    root.draw(&Rectangle::new([(x as i32, y), ((x + w) as i32, y + 16)], c.filled())).err_text()?;
                    x += w;
                }
                root.draw(&text(format!("{:.1}", total(r)), x as i32 + 6, y + 3)).err_text()?;
            }
            Ok(())
        }
    }
}

/// Each counter across the methods that report it, as bars (one chart a counter, not one
/// table a method); counters that are zero for every method are named in a line.
fn counters_html(report: &Report, h: &mut String) {
    let mut names: Vec<&String> = report.results.iter().flat_map(|r| r.counters.keys()).collect();
    names.sort();
    names.dedup();
    let (mut zero, mut charts) = (Vec::new(), String::new());
    for name in names {
        let rows: Vec<(String, u64)> = report
            .results
            .iter()
            .filter_map(|r| r.counters.get(name).map(|&v| (format!("{} + {}", r.visibility, r.shadows), v)))
            .collect();
        let most = rows.iter().map(|r| r.1).max().unwrap_or(0);
        if most == 0 {
            zero.push(escape(name));
            continue;
        }
        let _ = writeln!(charts, "<h3>{}</h3>\n<table class=\"bars\">", escape(name));
        for (method, v) in rows {
            let width = 100.0 * v as f64 / most as f64;
            let _ = writeln!(
                charts,
                "<tr><td class=\"name\">{method}</td><td class=\"bar\"><div style=\"width:{width:.1}%\"></div></td><td>{v}</td></tr>"
            );
        }
        charts.push_str("</table>\n");
    }
    h.push_str("<h2 id=\"counters\">Counters</h2>\n<p>Each counter across the methods that count it (bars to scale within a counter).");
    if !zero.is_empty() {
        let _ = write!(h, " Zero for every method: {}.", zero.join(", "));
    }
    h.push_str("</p>\n");
    h.push_str(&charts);
}

/// What the frame spent outside the table's four phase columns (the view, reflections, the
/// frame's own setup), so that the row's columns add up to its median frame.
fn rest(r: &MethodResult) -> String {
    if r.status != "ok" {
        return String::new();
    }
    let named: f64 =
        ["visibility", "shadow_prepare", "shadow_walk", "shading"].iter().filter_map(|k| r.step_ms.get(*k)).sum();
    format!("{:.1}", (r.time.median_ms - named).max(0.0))
}

/// The table of times and errors, one row a method, sortable by any column.
fn results_table(report: &Report, out: &Path, h: &mut String) {
    h.push_str(
        "<h2>Times and errors</h2>\n<p>Click a column to sort. Times are the median (least–greatest) of the \
         timed runs after the warm-up; red where the runs spread over a fifth of the median (a busy machine). \
         The phase columns are medians of each phase; <em>rest</em> is the frame less the four phases (the view, \
         reflections, the frame's setup), so that a row adds up to its frame.</p>\n<table id=\"results\">\n<thead><tr>",
    );
    for col in [
        "visibility",
        "shadows",
        "status",
        "exact",
        "time (ms): median (min–max)",
        "visibility (ms)",
        "shadow prepare (ms)",
        "shadow walk (ms)",
        "shading (ms)",
        "rest (ms)",
        "wrong / interior",
        "error",
        "shadow map's wrong pixels: acne / detached / aliasing / resolution",
        "area lights: mean / largest |fraction − exact|",
    ] {
        let _ = write!(h, "<th>{col}</th>");
    }
    h.push_str("</tr></thead>\n<tbody>\n");
    for r in &report.results {
        let step = |k: &str| r.step_ms.get(k).map_or(String::new(), |v| format!("{v:.1}"));
        let class = if r.status == "ok" { "" } else { " class=\"na\"" };
        // A spread over a fifth of the median: the machine was busy; say so.
        let noisy = if r.time.max_ms - r.time.min_ms > 0.2 * r.time.median_ms {
            " class=\"noisy\" title=\"noisy: the runs spread over a fifth of the median\""
        } else {
            ""
        };
        if r.status != "ok" {
            // Not run: no time, no error, said so.
            let _ = writeln!(
                h,
                "<tr{class}><td class=\"name\">{}</td><td class=\"name\">{}</td><td class=\"name\">{}</td><td>{}</td>{}</tr>",
                super::method_link(&r.visibility, out),
                super::method_link(&r.shadows, out),
                escape(&r.status),
                if r.exact { "yes" } else { "no" },
                "<td>—</td>".repeat(10)
            );
            continue;
        }
        let _ = writeln!(
            h,
            "<tr{class}><td class=\"name\">{}</td><td class=\"name\">{}</td><td class=\"name\">{}</td><td>{}</td><td{noisy}>{:.1} ({:.1}–{:.1})</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{} / {}</td><td>{:.4}%</td><td>{}</td><td>{}</td></tr>",
            super::method_link(&r.visibility, out),
            super::method_link(&r.shadows, out),
            escape(&r.status),
            if r.exact { "yes" } else { "no" },
            r.time.median_ms,
            r.time.min_ms,
            r.time.max_ms,
            step("visibility"),
            step("shadow_prepare"),
            step("shadow_walk"),
            step("shading"),
            rest(r),
            r.wrong_pixels,
            r.interior_pixels,
            100.0 * r.error_share,
            r.map_errors.map_or(String::new(), |c| format!("{} / {} / {} / {}", c.acne, c.detached, c.aliasing, c.resolution)),
            r.area_error.map_or(String::new(), |a| format!("{:.4} / {:.3}", a.mean, a.max))
        );
    }
    h.push_str("</tbody>\n</table>\n");
    h.push_str(
        "<p>A shadow map's wrong interior pixels by cause: <em>acne</em>, darker than exact away from every \
         shadow edge (a lit surface shadowing itself); <em>detached</em>, lighter than exact where the same map \
         without bias is right (the bias let the receiver pass its caster); <em>aliasing</em>, wrong within three \
         pixels of a shadow edge of the exact image; <em>resolution</em>, lighter than exact away from every edge \
         and wrong without bias too (a caster lost between texels).</p>\n",
    );
}

/// The reference, and each method's image beside its diff.
fn images_html(report: &Report, h: &mut String) {
    h.push_str("<h2>Images</h2>\n<div class=\"grid\">\n");
    let _ = writeln!(
        h,
        "<figure><img src=\"{}\" alt=\"reference\"><figcaption>reference (ray-cast)</figcaption></figure>",
        report.reference
    );
    for r in report.results.iter().filter(|r| !r.image.is_empty()) {
        let label = format!("{} + {}", r.visibility, r.shadows);
        let _ = writeln!(
            h,
            "<figure><img src=\"{}\" alt=\"{label}\"><figcaption>{label}: {:.1} ms</figcaption></figure>\n<figure><img src=\"{}\" alt=\"{label} diff\"><figcaption>{label}: {} wrong</figcaption></figure>",
            r.image, r.time.median_ms, r.diff, r.wrong_pixels
        );
    }
    h.push_str("</div>\n");
}

fn html(report: &Report, out: &Path) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>umbra compare: {scene}</title>\n<style>\n\
         body {{ font-family: sans-serif; margin: 1.5em; }}\ntable {{ border-collapse: collapse; font-size: 0.9em; }}\n\
         th, td {{ border: 1px solid #ccc; padding: 0.25em 0.5em; text-align: right; }}\nth {{ cursor: pointer; background: #eee; }}\n\
         td.name {{ text-align: left; }}\n.na {{ color: #888; }}\n.noisy {{ color: #b3261e; }}\n.bars td {{ border: none; padding: 0.1em 0.5em; }}\n\
         td.bar {{ width: 360px; }}\ntd.bar div {{ background: #4682b4; height: 0.9em; }}\n.grid {{ display: flex; flex-wrap: wrap; gap: 1em; }}\n\
         figure {{ margin: 0; }}\nfigure img {{ width: 320px; image-rendering: pixelated; }}\nfigcaption {{ font-size: 0.85em; }}\n</style>\n</head>\n<body>\n\
         <h1>umbra compare: {scene}</h1>\n<p>{w}&times;{h} pixels, {n} polygons. Errors are counted at the reference's interior pixels \
         (3&times;3 neighbourhood uniform in face id and lit values); the reference is ray-cast visibility with ray-cast shadows. \
         In the diff images, red marks wrong interior pixels and yellow marks differing pixels on edges (not counted).</p>\n",
        scene = escape(&report.scene),
        w = report.width,
        h = report.height,
        n = report.polygons
    );
    h.push_str(&report.about.html());
    results_table(report, out, &mut h);
    if cfg!(feature = "plots") {
        h.push_str(
            "<h2>Time against error</h2>\n<p>Exact methods (blue) lie on the zero line; bars span the least to \
             the greatest run.</p>\n<img src=\"time-error.svg\" alt=\"frame time against wrong pixels\"> \
             <a href=\"time-error.png\">PNG</a>\n<h2>Where the time goes</h2>\n<img src=\"phases.svg\" alt=\"time per phase\"> \
             <a href=\"phases.png\">PNG</a>\n",
        );
    }
    images_html(report, &mut h);
    counters_html(report, &mut h);
    h.push_str(
        "<script>\ndocument.querySelectorAll('#results th').forEach((th, i) => th.addEventListener('click', () => {\n\
         const body = th.closest('table').tBodies[0];\n\
         const rows = Array.from(body.rows);\n\
         const key = r => { const t = r.cells[i].textContent; const n = parseFloat(t); return isNaN(n) ? t : n; };\n\
         const dir = th.dataset.dir === 'up' ? -1 : 1; th.dataset.dir = dir === 1 ? 'up' : 'down';\n\
         rows.sort((a, b) => (key(a) > key(b) ? 1 : key(a) < key(b) ? -1 : 0) * dir).forEach(r => body.appendChild(r));\n\
         }));\n</script>\n</body>\n</html>\n",
    );
    h
}
