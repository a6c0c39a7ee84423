//! `umbra scale`: how cost grows with a scene parameter, after Slater et al., "A statistical
//! comparison of two hidden surface techniques: the scan-line and z-buffer algorithms"
//! (Computer Graphics Forum 1992): a generated scene family is swept over polygon count,
//! depth complexity, polygon size, distribution or resolution; every method asked for is
//! timed (median of runs) with its counters; the results go to a CSV file, a JSON file, plots (SVG and PNG) and a page.

#[cfg(feature = "plots")]
use super::plot::{log_ticks, ErrText};
use crate::error::{Error, Result};
use crate::generate;
use crate::render::RenderOptions;
use crate::scene::Scene;
use crate::shadow::ShadowMethod;
use crate::study::bench::{measure, Spread};
use crate::visibility::VisibilityMethod;
use glam::DVec3;
#[cfg(feature = "plots")]
use plotters::coord::combinators::{BindKeyPoints, LogCoord, WithKeyPoints};
#[cfg(feature = "plots")]
use plotters::coord::{ranged1d::ValueFormatter, Shift};
#[cfg(feature = "plots")]
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::PathBuf;

/// What is swept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sweep {
    /// Floor with an N×N grid of cubes (value: N).
    Cubes,
    /// Stacked quads (value: depth complexity).
    Quads,
    /// Spheres on a floor (value: triangles; `count` spheres).
    Spheres,
    /// Scattered triangles, uniform (value: count; `size` their size).
    Scattered,
    /// Scattered triangles clustered about the centre (value: count).
    Clustered,
    /// Scattered triangles (value: their size; `count` of them).
    Size,
    /// The cubes scene at a resolution (value: width; height is 9/16 of it).
    Resolution,
    /// The cubes scene under a 2×2 square light sampled by an N×N grid (value: N), each
    /// point's error against the exact fraction measured (`Point::area_error`).
    Samples,
}

impl Sweep {
    /// Names on the command line.
    pub const NAMES: [(&'static str, Sweep); 8] = [
        ("cubes", Sweep::Cubes),
        ("quads", Sweep::Quads),
        ("spheres", Sweep::Spheres),
        ("scattered", Sweep::Scattered),
        ("clustered", Sweep::Clustered),
        ("size", Sweep::Size),
        ("resolution", Sweep::Resolution),
        ("samples", Sweep::Samples),
    ];

    /// The sweep's name.
    pub fn name(self) -> &'static str {
        Self::NAMES.iter().find(|n| n.1 == self).map_or("?", |n| n.0)
    }

    /// What the value means.
    pub fn parameter(self) -> &'static str {
        match self {
            Sweep::Cubes => "cubes per side",
            Sweep::Quads => "depth complexity",
            Sweep::Spheres => "triangles",
            Sweep::Scattered | Sweep::Clustered => "triangles",
            Sweep::Size => "triangle size",
            Sweep::Resolution => "image width",
            Sweep::Samples => "samples per side",
        }
    }

    /// The scene for `value`.
    pub fn scene(self, value: f64, o: &ScaleOptions) -> Result<Scene> {
        let (w, h) = (o.width, o.height);
        match self {
            Sweep::Cubes => generate::cubes(value as u32, generate::Faces::Triangles, w, h),
            Sweep::Quads => generate::stacked_quads(value as u32, w, h),
            Sweep::Spheres => generate::spheres(value as u32, o.count, w, h),
            Sweep::Scattered => generate::scattered(value as u32, o.size, generate::Placement::Uniform, w, h),
            Sweep::Clustered => generate::scattered(value as u32, o.size, generate::Placement::Clustered, w, h),
            Sweep::Size => generate::scattered(o.count, value, generate::Placement::Uniform, w, h),
            Sweep::Resolution => {
                generate::cubes(10, generate::Faces::Triangles, value as u32, (value * 9.0 / 16.0).max(1.0) as u32)
            }
            Sweep::Samples => {
                // The cubes' point light made a 2×2 square light (as s1a is s1's).
                let mut scene = generate::cubes(10, generate::Faces::Triangles, w, h)?;
                let crate::scene::LightKind::Point { position: at } = scene.lights[0].kind else {
                    return Err(Error::Internal("the cubes scene's light is not a point light".into()));
                };
                let n = value as u32;
                let square = crate::Light::area(at - DVec3::new(1.0, 0.0, 1.0), DVec3::X * 2.0, DVec3::Z * 2.0, [n, n]);
                scene.set_lights(vec![square])?;
                Ok(scene)
            }
        }
    }
}

impl std::str::FromStr for Sweep {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let all: Vec<Sweep> = Self::NAMES.iter().map(|n| n.1).collect();
        crate::error::parse_named(s, &all, |m| m.name(), "sweep").copied()
    }
}

/// A sweep's settings.
#[derive(Debug, Clone)]
pub struct ScaleOptions {
    /// What to sweep.
    pub sweep: Sweep,
    /// The values.
    pub values: Vec<f64>,
    /// The methods: (visibility, shadows).
    pub methods: Vec<(VisibilityMethod, ShadowMethod)>,
    /// Timed runs per point (median reported).
    pub runs: usize,
    /// Image size (except for the resolution sweep).
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// Spheres for the sphere sweep; triangles for the size sweep.
    pub count: u32,
    /// Triangle size for the scattered sweeps.
    pub size: f64,
    /// A counter to plot besides time (for example `visibility.spans`).
    pub counter: String,
    /// Output folder.
    pub out: PathBuf,
}

/// One point of a sweep.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Point {
    /// The swept value.
    pub value: f64,
    /// Method.
    pub visibility: String,
    /// Method.
    pub shadows: String,
    /// Polygons in the scene.
    pub polygons: usize,
    /// The frame time over the timed runs (after one warm-up render), ms.
    #[serde(flatten)]
    pub time: Spread,
    /// The chosen counter.
    pub counter: u64,
    /// On the samples sweep: the mean of `|fraction − exact|` over the visible pixels in the
    /// exact penumbra (0 for the exact stage).
    pub area_error: Option<f64>,
    /// Why the method was not run at this point (over the memory budget, or not applicable
    /// to the scene); its time and counter are then 0, and the plots leave it out.
    pub refused: Option<String>,
}

/// Runs the sweep, writes `scale.csv`, `scale.json` (the points with what they were
/// measured with) and `index.html` (a page of both), and with the `plots` feature (on by default)
/// `time.svg` and `counter.svg`, into `out`.
pub fn scale(o: &ScaleOptions) -> Result<Vec<Point>> {
    std::fs::create_dir_all(&o.out).map_err(|e| Error::Write { path: o.out.clone(), source: e })?;
    let (kind, name) = o.counter.split_once('.').unwrap_or(("visibility", &o.counter));
    if kind != "visibility" && kind != "shadow" {
        return Err(Error::out_of_range("counter", format!("'{}'", o.counter), "visibility.NAME or shadow.NAME"));
    }
    let mut points = Vec::new();
    let mut known = std::collections::BTreeSet::new();
    // The exact fractions do not depend on the grid: worked out once, on the first scene.
    let mut exact: Option<crate::Frame> = None;
    for (i, &value) in o.values.iter().enumerate() {
        let scene = o.sweep.scene(value, o)?;
        if o.sweep == Sweep::Samples && exact.is_none() {
            exact = Some(super::compare::exact_area_reference(&scene)?);
        }
        for (v, s) in &o.methods {
            let opts = RenderOptions { visibility: *v, shadows: s.clone(), ..RenderOptions::default() };
            let m = match measure(&scene, &opts, 1, o.runs) {
                Ok(m) => m,
                // A method refused at one point (a shadow map per sample of a fine grid) is
                // said so, and the sweep goes on.
                Err(e @ (Error::OverBudget { .. } | Error::NotApplicable { .. })) => {
                    points.push(Point {
                        value,
                        visibility: v.name().into(),
                        shadows: s.label(),
                        polygons: scene.polygons.len(),
                        time: Spread { median_ms: 0.0, min_ms: 0.0, max_ms: 0.0 },
                        counter: 0,
                        area_error: None,
                        refused: Some(e.to_string()),
                    });
                    continue;
                }
                Err(e) => return Err(e),
            };
            let r = &m.last;
            let counters = if kind == "shadow" { &r.stats.shadow_counters } else { &r.stats.visibility_counters };
            known.extend(counters.iter().map(|(k, _)| k));
            let counter = counters.get_named(name).unwrap_or(0);
            let area_error = exact.as_ref().map(|e| super::compare::AreaError::of(&scene, e, &r.frame).mean);
            points.push(Point {
                value,
                visibility: v.name().into(),
                shadows: s.label(),
                polygons: scene.polygons.len(),
                time: m.frame,
                counter,
                area_error,
                refused: None,
            });
        }
        // After the first point every method has reported its counters: a name none of them
        // knows would plot zeros everywhere.
        if i == 0 && !known.is_empty() && !known.contains(name) {
            let names: Vec<&str> = known.iter().copied().collect();
            return Err(Error::UnknownName {
                kind: format!("{kind} counter of these methods"),
                name: o.counter.clone(),
                known: names.iter().map(|n| n.to_string()).collect(),
            });
        }
    }
    let mut csv = format!(
        "{},visibility,shadows,polygons,median_ms,min_ms,max_ms,{},area_error,refused\n",
        o.sweep.name(),
        o.counter
    );
    for p in &points {
        let _ = writeln!(
            csv,
            "{},{},{},{},{:.3},{:.3},{:.3},{},{},\"{}\"",
            p.value,
            p.visibility,
            p.shadows,
            p.polygons,
            p.time.median_ms,
            p.time.min_ms,
            p.time.max_ms,
            p.counter,
            p.area_error.map_or(String::new(), |e| format!("{e:.6}")),
            p.refused.as_deref().unwrap_or("").replace('"', "'")
        );
    }
    let about = super::About::now(format!(
        "sweep {} over {}, {} timed run(s) after one warm-up, {}x{}, methods: {}",
        o.sweep.name(),
        o.values.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", "),
        o.runs.max(1),
        o.width,
        o.height,
        o.methods.iter().map(|(v, s)| format!("{} + {}", v.name(), s.command_line())).collect::<Vec<_>>().join("; ")
    ));
    let json = serde_json::json!({ "about": about, "counter": o.counter, "points": points });
    let path = o.out.join("scale.json");
    std::fs::write(&path, json.to_string()).map_err(|e| Error::Write { path, source: e })?;
    let path = o.out.join("scale.csv");
    std::fs::write(&path, csv).map_err(|e| Error::Write { path, source: e })?;
    #[cfg(feature = "plots")]
    {
        let measured: Vec<Point> = points.iter().filter(|p| p.refused.is_none()).cloned().collect();
        let points = &measured;
        let spread: Bounds = |p| (p.time.min_ms, p.time.max_ms);
        let time = Plot { o, points, label: "frame time (ms)", y: |p: &Point| p.time.median_ms, spread: Some(spread) };
        super::plot::save(&time, &o.out.join("time"))?;
        let counter = Plot { o, points, label: &o.counter, y: |p: &Point| p.counter as f64, spread: None };
        super::plot::save(&counter, &o.out.join("counter"))?;
        if o.sweep == Sweep::Samples {
            let label = "mean |lit fraction − exact| in the penumbra";
            let error = Plot { o, points, label, y: |p: &Point| p.area_error.unwrap_or(0.0), spread: None };
            super::plot::save(&error, &o.out.join("error"))?;
        }
    }
    let path = o.out.join("index.html");
    std::fs::write(&path, page(o, &points, &about)).map_err(|e| Error::Write { path, source: e })?;
    Ok(points)
}

/// The sweep as a page: what it was measured with, the plots, and the table.
fn page(o: &ScaleOptions, points: &[Point], about: &super::About) -> String {
    let mut h = format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>umbra scale: {sweep}</title>\n\
         <style>body {{ font-family: sans-serif; margin: 1.5em; }} table {{ border-collapse: collapse; }} \
         td, th {{ border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: right; }} img {{ max-width: 100%; }}</style>\n\
         </head>\n<body>\n<h1>umbra scale: {sweep} sweep</h1>\n{}",
        about.html(),
        sweep = o.sweep.name(),
    );
    if cfg!(feature = "plots") {
        h.push_str(
            "<p><img src=\"time.svg\" alt=\"frame time\"> <a href=\"time.png\">PNG</a></p>\n\
             <p><img src=\"counter.svg\" alt=\"counter\"> <a href=\"counter.png\">PNG</a></p>\n",
        );
        if o.sweep == Sweep::Samples {
            h.push_str("<p><img src=\"error.svg\" alt=\"error against the exact fraction\"> <a href=\"error.png\">PNG</a></p>\n");
        }
    }
    let _ = write!(
        h,
        "<table>\n<tr><th>{}</th><th>method</th><th>polygons</th><th>median ms</th><th>least</th><th>greatest</th><th>{}</th></tr>\n",
        o.sweep.parameter(),
        super::escape(&o.counter)
    );
    for p in points {
        if let Some(why) = &p.refused {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{} + {}</td><td>{}</td><td colspan=\"4\">refused: {}</td></tr>",
                p.value,
                super::method_link(&p.visibility, &o.out),
                super::method_link(&p.shadows, &o.out),
                p.polygons,
                super::escape(why)
            );
            continue;
        }
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{} + {}</td><td>{}</td><td>{:.1}</td><td>{:.1}</td><td>{:.1}</td><td>{}</td></tr>",
            p.value,
            super::method_link(&p.visibility, &o.out),
            super::method_link(&p.shadows, &o.out),
            p.polygons,
            p.time.median_ms,
            p.time.min_ms,
            p.time.max_ms,
            p.counter
        );
    }
    h.push_str("</table>\n</body>\n</html>\n");
    h
}

#[cfg(feature = "plots")]
/// What the x axis shows: what was rendered (the polygons of the scene), except on the
/// sweeps whose parameter is not a polygon count.
fn x_axis(o: &ScaleOptions) -> (&'static str, fn(&Point) -> f64) {
    match o.sweep {
        Sweep::Size => ("triangle size", |p| p.value),
        Sweep::Resolution => ("pixels", |p| p.value * (p.value * 9.0 / 16.0).max(1.0).floor()),
        Sweep::Samples => ("light samples (N×N)", |p| p.value * p.value),
        _ => ("polygons rendered", |p| p.polygons as f64),
    }
}

#[cfg(feature = "plots")]
/// The least and greatest of a point's runs.
type Bounds = fn(&Point) -> (f64, f64);

#[cfg(feature = "plots")]
/// A number as a tick label: short, without trailing zeros.
fn tick(v: f64) -> String {
    let a = v.abs();
    if a > 0.0 && a < 0.01 {
        format!("{v:.0e}")
    } else if a >= 1e6 {
        format!("{}M", trim(v / 1e6))
    } else if a >= 1e4 {
        format!("{}k", trim(v / 1e3))
    } else {
        trim(v)
    }
}

#[cfg(feature = "plots")]
fn trim(v: f64) -> String {
    let s = format!("{v:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_owned()
}

/// The width of a plot, without its legend.
#[cfg(feature = "plots")]
const PLOT_WIDTH: u32 = 640;

#[cfg(feature = "plots")]
/// One plot: `y` of every method against what was rendered, on log axes (linear when the
/// values span less than a decade, where a log axis would show no tick), with the spread as
/// error bars when `spread` gives it, and the legend beside the plot. A quantity that is zero
/// everywhere gets a note instead of an empty plot.
struct Plot<'a, Y> {
    o: &'a ScaleOptions,
    points: &'a [Point],
    label: &'a str,
    y: Y,
    spread: Option<Bounds>,
}

#[cfg(feature = "plots")]
impl<Y: Fn(&Point) -> f64> super::plot::Chart for Plot<'_, Y> {
    fn size(&self) -> (u32, u32) {
        (PLOT_WIDTH + self.legend_width(), 480)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> std::result::Result<(), String> {
        let Plot { o, points, label, spread, .. } = *self;
        let y = &self.y;
        let (x_label, x) = x_axis(o);
        let positive: Vec<&Point> = points.iter().filter(|p| y(p) > 0.0 && x(p) > 0.0).collect();
        if positive.is_empty() {
            let note = format!("{label} is zero for every method and every {}: nothing to plot", o.sweep.parameter());
            return root.draw(&Text::new(note, (40, 230), ("sans-serif", 18))).err_text();
        }
        let (x0, x1) = positive.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(x(p)), b.max(x(p))));
        let range = |p: &Point| spread.map_or((y(p), y(p)), |f| f(p));
        let (y0, y1) = positive.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
            let (lo, hi) = range(p);
            (a.min(lo.max(f64::MIN_POSITIVE)), b.max(hi))
        });
        let (plot_area, legend_area) = root.split_horizontally(PLOT_WIDTH);
        let caption = format!("{label} against {x_label} ({} sweep)", o.sweep.name());
        let mut builder = ChartBuilder::on(&plot_area);
        builder.caption(caption, ("sans-serif", 17)).margin(14).x_label_area_size(44).y_label_area_size(64);
        // Log axes where the data span a decade or more; a narrower span reads better linear,
        // from zero.
        let xs = (x0 / 1.3..x1 * 1.3).log_scale().with_key_points(log_ticks(x0 / 1.3, x1 * 1.3));
        if y1 / y0 >= 10.0 {
            let ys = (y0 / 1.3..y1 * 1.3).log_scale().with_key_points(log_ticks(y0 / 1.3, y1 * 1.3));
            let mut chart = builder.build_cartesian_2d(xs, ys).err_text()?;
            self.series(&mut chart, &positive, x_label, y0)?;
        } else {
            let mut chart = builder.build_cartesian_2d(xs, 0.0..y1 * 1.15).err_text()?;
            self.series(&mut chart, &positive, x_label, 0.0)?;
        }
        self.legend(&legend_area)
    }
}

#[cfg(feature = "plots")]
impl<Y: Fn(&Point) -> f64> Plot<'_, Y> {
    /// The mesh, and each method's line, points and error bars (clipped below at `floor`).
    fn series<DB: DrawingBackend, YC>(
        &self,
        chart: &mut ChartContext<'_, DB, Cartesian2d<WithKeyPoints<LogCoord<f64>>, YC>>,
        positive: &[&Point],
        x_label: &str,
        floor: f64,
    ) -> std::result::Result<(), String>
    where
        YC: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let (_, x) = x_axis(self.o);
        let same = self.equal_to_earlier();
        chart
            .configure_mesh()
            .light_line_style(TRANSPARENT)
            .bold_line_style(BLACK.mix(0.08))
            .x_labels(12)
            .y_labels(12)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .x_desc(x_label)
            .y_desc(self.label)
            .draw()
            .err_text()?;
        for (i, (v, s)) in self.o.methods.iter().enumerate() {
            let colour = super::plot::colour(i);
            let mine: Vec<&Point> =
                positive.iter().copied().filter(|p| p.visibility == v.name() && p.shadows == s.label()).collect();
            let series: Vec<(f64, f64)> = mine.iter().map(|p| (x(p), (self.y)(p))).collect();
            // A series that later ones lie on (equal values: the legend says so) is drawn
            // thicker, one step for each, so that it still shows round them.
            let under = same.iter().skip(i + 1).filter(|&&j| j == Some(i)).count() as u32;
            let (width, radius) = (2 + 3 * under, 3 + 2 * under);
            chart.draw_series(LineSeries::new(series.clone(), colour.stroke_width(width))).err_text()?;
            chart.draw_series(series.into_iter().map(|p| Circle::new(p, radius, colour.filled()))).err_text()?;
            if let Some(f) = self.spread {
                let bars = mine.iter().map(|p| {
                    let (lo, hi) = f(p);
                    PathElement::new(vec![(x(p), lo.max(floor)), (x(p), hi)], colour.stroke_width(1))
                });
                chart.draw_series(bars).err_text()?;
            }
        }
        Ok(())
    }

    /// For each method, the first earlier one whose values it equals at every point (its
    /// line lies on that one's).
    fn equal_to_earlier(&self) -> Vec<Option<usize>> {
        let values = |v: &VisibilityMethod, s: &ShadowMethod| -> Vec<u64> {
            let mine = self.points.iter().filter(|p| p.visibility == v.name() && p.shadows == s.label());
            mine.map(|p| (self.y)(p).to_bits()).collect()
        };
        let all: Vec<Vec<u64>> = self.o.methods.iter().map(|(v, s)| values(v, s)).collect();
        (0..all.len()).map(|i| (0..i).find(|&j| !all[i].is_empty() && all[j] == all[i])).collect()
    }

    /// The legend's entries: each method's name (a paper path's with " (paper)"), and, where
    /// its values equal an earlier method's at every point, which one its line lies on.
    fn entries(&self) -> impl Iterator<Item = String> + '_ {
        let same = self.equal_to_earlier();
        self.o.methods.iter().enumerate().map(move |(i, (v, s))| {
            let mine = || self.points.iter().filter(|p| p.visibility == v.name() && p.shadows == s.label());
            if mine().all(|p| (self.y)(p) <= 0.0) {
                return format!("{v} + {} (zero everywhere: not drawn)", s.label());
            }
            match same[i] {
                Some(j) => format!("{v} + {} (equal to {}, on its line)", s.label(), j + 1),
                None => format!("{v} + {}", s.label()),
            }
        })
    }

    /// The legend's width: room for its longest entry (at most 8 pixels a character at the
    /// legend's 13-pixel type, after the 36 pixels of the colour line), 220 pixels at least.
    fn legend_width(&self) -> u32 {
        let longest = self.entries().map(|e| e.chars().count()).max().unwrap_or(0) as u32;
        (44 + 8 * (longest + 4)).max(220)
    }

    /// The methods' colours beside the plot.
    fn legend<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> std::result::Result<(), String> {
        for (i, entry) in self.entries().enumerate() {
            let colour = super::plot::colour(i);
            let row = 40 + 22 * i as i32;
            area.draw(&PathElement::new(vec![(8, row), (30, row)], colour.stroke_width(3))).err_text()?;
            area.draw(&Text::new(format!("{}. {entry}", i + 1), (36, row - 7), ("sans-serif", 13))).err_text()?;
        }
        if self.spread.is_some() {
            let row = 52 + 22 * self.o.methods.len() as i32;
            area.draw(&Text::new("bars: least to greatest run", (8, row), ("sans-serif", 12))).err_text()?;
        }
        Ok(())
    }
}
