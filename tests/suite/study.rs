//! The study tools: compare's report, trace against a hand-worked scanline, scale's files.

use std::path::Path;
use umbra::study::compare::{compare, CompareOptions};
use umbra::{Scene, ShadowMethod};

/// A fresh folder for one test, removed when the test is done with it.
fn tmp(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new().prefix(&format!("umbra-study-{name}-")).tempdir().unwrap()
}

#[test]
#[cfg_attr(
    not(feature = "plots"),
    ignore = "it checks the charts: run with the `plots` feature, as `cargo test` at the top does"
)]
fn compare_reports_every_method_and_a_valid_page() {
    let mut scene = Scene::load(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/lights.toml")).unwrap();
    {
        let mut c = scene.camera().clone();
        c.width = 160;
        scene.set_camera(c).expect("a valid camera");
    }
    {
        let mut c = scene.camera().clone();
        c.height = 120;
        scene.set_camera(c).expect("a valid camera");
    }
    let out_dir = tmp("compare");
    let out = out_dir.path();
    let opts = CompareOptions { runs: 1, out: out.to_path_buf(), ..CompareOptions::default() };
    let report = compare(&scene, "lights", &opts, |_| {}).unwrap();
    assert_eq!(report.results.len(), umbra::VisibilityMethod::ALL.len() * ShadowMethod::ALL.len());
    for r in &report.results {
        let m: ShadowMethod = r.shadows.parse().unwrap();
        match m {
            ShadowMethod::Planar => assert!(r.status.starts_with("not applicable"), "{}", r.status),
            _ if m.is_exact() => {
                assert_eq!((r.status.as_str(), r.wrong_pixels), ("ok", 0), "{} + {}", r.visibility, r.shadows)
            }
            _ => assert!(r.interior_pixels > 1000 && r.status == "ok", "{} + {}", r.visibility, r.shadows),
        }
    }
    // The approximate methods' error is measured, not assumed: none leaves shadows out.
    assert!(report.results.iter().any(|r| r.shadows == "none" && r.wrong_pixels > 100));
    // The area light (light 3): the grid's error against the exact fraction is measured,
    // and Nishita & Nakamae's stage has none beyond a grey level.
    for r in report.results.iter().filter(|r| r.status == "ok") {
        let e = r.area_error.unwrap_or_else(|| panic!("{} + {}: no area error", r.visibility, r.shadows));
        assert!(e.pixels > 100, "{} + {}: {e:?}", r.visibility, r.shadows);
        match r.shadows.as_str() {
            "nishita-nakamae" => assert!(e.max <= 1.0 / 255.0, "{}: {e:?}", r.visibility),
            "bouknight-kelley" | "crow" => assert!(e.mean > 0.01 && e.max > 0.1, "{}: {e:?}", r.visibility),
            _ => {}
        }
    }
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let doc = scraper::Html::parse_document(&html);
    assert!(doc.errors.is_empty(), "HTML parse errors: {:?}", doc.errors);
    let imgs = scraper::Selector::parse("img").unwrap();
    let mut n = 0;
    for img in doc.select(&imgs) {
        let src = img.value().attr("src").unwrap();
        assert!(out.join(src).exists(), "{src} is linked but missing");
        n += 1;
    }
    assert!(n > 20);
    for chart in ["time-error", "phases"] {
        assert!(html.contains(&format!("src=\"{chart}.svg\"")), "{chart} is not in the report");
        assert!(std::fs::read_to_string(out.join(format!("{chart}.svg"))).unwrap().starts_with("<svg"));
        let png = image::open(out.join(format!("{chart}.png"))).unwrap().to_rgb8();
        assert!(png.width() > 800 && png.pixels().any(|p| p.0 != [255; 3]), "{chart}.png is blank");
    }
    // Each method links to its page in docs/algorithms, and every link leads to a file.
    let links = scraper::Selector::parse("td a").unwrap();
    let targets: Vec<&str> = doc.select(&links).filter_map(|a| a.value().attr("href")).collect();
    for page in ["scanline.md", "crow.md", "bouknight-kelley.md", "williams.md"] {
        assert!(targets.iter().any(|t| t.ends_with(page)), "no link to {page}: {targets:?}");
    }
    for t in &targets {
        assert!(out.join(t).exists(), "{t} is linked but missing");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["results"].as_array().unwrap().len(), report.results.len());
    assert_eq!(std::fs::read_to_string(out.join("results.csv")).unwrap().lines().count(), report.results.len() + 1);
    // Every report says what it is: program, machine, date, options; and the spread.
    let about = &json["about"];
    assert_eq!(about["umbra"], env!("CARGO_PKG_VERSION"));
    assert!(about["cores"].as_u64().unwrap() >= 1 && about["date_utc"].as_str().unwrap().starts_with("20"));
    let options = about["options"].as_str().unwrap();
    assert!(
        options.contains("shadow stages: ") && options.contains("crow") && !options.contains("Options {"),
        "{options}"
    );
    assert!(html.contains(about["date_utc"].as_str().unwrap()));
    for r in json["results"].as_array().unwrap().iter().filter(|r| r["status"] == "ok") {
        let (lo, mid, hi) =
            (r["min_ms"].as_f64().unwrap(), r["median_ms"].as_f64().unwrap(), r["max_ms"].as_f64().unwrap());
        assert!(lo <= mid && mid <= hi && lo > 0.0, "{r}");
    }
}

/// A hand-worked scanline. The camera at the origin looks down −z with a 90° field of view
/// on a 16×8 image (aspect 2), so a point (x, y) at depth d lands at
/// X = (x/d/2 + 1)·8, Y = (1 − y/d)·4. Quad A at depth 1 spans x −1..0.5, y −0.5..0.5: X 4..10,
/// Y 2..6. Quad B at depth 2 spans x 0..2, y −1..1: x/d 0..1, X 8..12, Y 2..6. On line 3
/// (y = 3.5) the active edges cross at 4 and 10 (A) and 8 and 12 (B); the spans are 4..8
/// {A}, 8..10 {A, B} where A (1/z = 1) beats B (1/z = 0.5) at both ends, and 10..12 {B};
/// the runs are 4..10 on A and 10..12 on B.
#[test]
fn trace_matches_a_hand_worked_line() {
    let src = "[camera]\neye = [0.0, 0.0, 0.0]\ntarget = [0.0, 0.0, -1.0]\nfov_y = 90.0\nwidth = 16\nheight = 8\n\
               [[light]]\nkind = \"point\"\nposition = [0.0, 0.0, 0.5]\n\
               [[object]]\npolygons = [\n [[-1.0,-0.5,-1.0],[0.5,-0.5,-1.0],[0.5,0.5,-1.0],[-1.0,0.5,-1.0]],\n \
               [[0.0,-1.0,-2.0],[2.0,-1.0,-2.0],[2.0,1.0,-2.0],[0.0,1.0,-2.0]],\n]\n";
    let scene = Scene::from_toml(src, Path::new("t.toml"), Path::new(".")).unwrap();
    let t = umbra::study::trace::trace(&scene, 3, &ShadowMethod::DEFAULT).unwrap();
    let xs: Vec<(f64, u32)> = t.active.clone();
    let want = [(4.0, 0), (8.0, 1), (10.0, 0), (12.0, 1)];
    assert_eq!(xs.len(), 4);
    for ((x, p), (wx, wp)) in xs.iter().zip(want) {
        assert!((x - wx).abs() < 1e-9 && *p == wp, "{xs:?}");
    }
    let spans: Vec<String> = t
        .spans
        .iter()
        .map(|s| {
            format!("{}..{} covered by {} nearest {:?} split {:?}", s.x0, s.x1, s.covering.len(), s.nearest, s.split_at)
        })
        .collect();
    assert_eq!(
        spans,
        [
            "4..8 covered by 1 nearest (0, 0) split None",
            "8..10 covered by 2 nearest (0, 0) split None",
            "10..12 covered by 1 nearest (1, 1) split None"
        ]
    );
    let middle = &t.spans[1].covering;
    assert!((middle[0].2 - 1.0).abs() < 1e-9 || (middle[1].2 - 1.0).abs() < 1e-9);
    assert!(middle.iter().any(|c| c.0 == 1 && (c.2 - 0.5).abs() < 1e-9));
    let runs: Vec<(u32, u32, u32)> = t.runs.iter().map(|r| (r.x0, r.x1, r.poly)).collect();
    assert_eq!(runs, vec![(4, 10, 0), (10, 12, 1)]);
    // Edges: both quads' side edges cover lines 2..6; none enter or leave on line 3.
    assert!(t.entering.is_empty() && t.leaving.is_empty());
    // The light (between the eye and A) casts A's shadow onto B: B's run is shadowed where
    // A's projection from the light covers it, and the decision says what it examined.
    assert_eq!(t.decisions.len(), 2);
    let on_b = &t.decisions[1];
    assert_eq!(on_b.polygon, 1);
    assert!(on_b.decision.note.contains("shadow polygon(s)"), "{}", on_b.decision.note);
    let text = t.text(&scene, None);
    assert!(text.contains("8..10: [face 0 (1/z 1.0000 .. 1.0000), face 1 (1/z 0.5000 .. 0.5000)] -> face 0 nearest at both ends: wins"), "{text}");
}

/// A small sweep of the quads family over `values` for `methods`, written into `out`.
fn quads_sweep(
    out: &std::path::Path,
    values: Vec<f64>,
    methods: Vec<(umbra::VisibilityMethod, ShadowMethod)>,
) -> umbra::study::scale::ScaleOptions {
    umbra::study::scale::ScaleOptions {
        sweep: umbra::study::scale::Sweep::Quads,
        values,
        methods,
        runs: 1,
        width: 160,
        height: 90,
        count: 10,
        size: 0.3,
        counter: "visibility.depth_tests".into(),
        out: out.to_path_buf(),
    }
}

#[test]
#[cfg_attr(
    not(feature = "plots"),
    ignore = "it checks the charts: run with the `plots` feature, as `cargo test` at the top does"
)]
fn scale_writes_csv_and_plots() {
    use umbra::study::scale::scale;
    let out_dir = tmp("scale");
    let out = out_dir.path();
    let methods = vec![
        (umbra::VisibilityMethod::Scanline, ShadowMethod::None),
        (umbra::VisibilityMethod::ZBuffer, ShadowMethod::None),
    ];
    let points = scale(&quads_sweep(out, vec![1.0, 4.0, 16.0], methods)).unwrap();
    assert_eq!(points.len(), 6);
    // The z-buffer tests every covered pixel once per polygon: its depth tests grow with depth
    // complexity, about 160×90 per quad.
    let z: Vec<u64> = points.iter().filter(|p| p.visibility == "zbuffer").map(|p| p.counter).collect();
    assert!(z[2] > 10 * z[0], "{z:?}");
    let csv = std::fs::read_to_string(out.join("scale.csv")).unwrap();
    assert_eq!(csv.lines().count(), 7);
    // Plain names in the CSV: the page's links stay on the page.
    assert!(csv.lines().nth(1).unwrap().starts_with("1,scanline,none,"), "{csv}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("scale.json")).unwrap()).unwrap();
    assert_eq!(json["points"].as_array().unwrap().len(), 6);
    assert!(json["about"]["options"].as_str().unwrap().starts_with("sweep quads"));
    let page = std::fs::read_to_string(out.join("index.html")).unwrap();
    let doc = scraper::Html::parse_document(&page);
    assert!(doc.errors.is_empty(), "HTML parse errors: {:?}", doc.errors);
    assert!(page.contains("src=\"time.svg\"") && page.matches("<tr>").count() == 7);
    assert!(points.iter().all(|p| p.time.min_ms <= p.time.median_ms && p.time.median_ms <= p.time.max_ms));
    for plot in ["time", "counter"] {
        assert!(std::fs::read_to_string(out.join(format!("{plot}.svg"))).unwrap().starts_with("<svg"));
        let png = image::open(out.join(format!("{plot}.png"))).unwrap().to_rgb8();
        assert_eq!(png.dimensions().1, 480);
    }
}

#[test]
#[cfg_attr(
    not(feature = "plots"),
    ignore = "it checks the charts: run with the `plots` feature, as `cargo test` at the top does"
)]
fn the_scale_legend_holds_its_longest_method_name() {
    let out_dir = tmp("scale-legend");
    let out = out_dir.path();
    let methods = vec![(umbra::VisibilityMethod::Scanline, "atherton-weiler-greenberg".parse().unwrap())];
    umbra::study::scale::scale(&quads_sweep(out, vec![1.0, 4.0], methods)).unwrap();
    let png = image::open(out.join("time.png")).unwrap().to_rgb8();
    // The legend's one entry, "scanline + atherton-weiler-greenberg", is drawn near the top:
    // its last dark pixel must stand clear of the image's right edge.
    let (w, _) = png.dimensions();
    let last_ink = (0..w).rev().find(|&x| (20..60).any(|y| png.get_pixel(x, y).0.iter().all(|&c| c < 128)));
    let last_ink = last_ink.expect("the legend is drawn");
    assert!(last_ink + 8 < w, "the legend's text runs to x = {last_ink} of {w}");
}

#[test]
fn unknown_method_names_list_the_known_ones() {
    let e = "magic".parse::<ShadowMethod>().unwrap_err().to_string();
    for m in ShadowMethod::ALL {
        assert!(e.contains(m.name()), "{e}");
    }
    let e = "painter".parse::<umbra::VisibilityMethod>().unwrap_err().to_string();
    assert!(e.contains("scanline") && e.contains("zbuffer"), "{e}");
}

/// Series of equal values in scale's charts are noted in the legend (their lines lie on one
/// another), and the charts draw in the colour-blind-safe palette, with no pale yellow.
#[test]
#[cfg_attr(
    not(feature = "plots"),
    ignore = "it checks the charts: run with the `plots` feature, as `cargo test` at the top does"
)]
fn scale_notes_series_of_equal_values() {
    let out_dir = tmp("scale-equal");
    let out = out_dir.path();
    let methods = vec![
        (umbra::VisibilityMethod::Scanline, ShadowMethod::None),
        (umbra::VisibilityMethod::Scanline, "crow".parse().unwrap()),
        (umbra::VisibilityMethod::ZBuffer, ShadowMethod::None),
    ];
    umbra::study::scale::scale(&quads_sweep(out, vec![1.0, 4.0], methods)).unwrap();
    let svg = std::fs::read_to_string(out.join("counter.svg")).unwrap();
    assert!(svg.contains("scanline + crow (equal to 1, on its line)"), "the note is missing");
    assert!(!svg.contains("zbuffer + none (equal"), "the z-buffer's depth tests differ");
    let png = image::open(out.join("counter.png")).unwrap().to_rgb8();
    let yellow = png.pixels().filter(|p| p.0[0] > 200 && p.0[1] > 200 && p.0[2] < 100).count();
    assert_eq!(yellow, 0, "pale yellow on white");
}

/// The sampling-versus-analytic study: the grid's error against the exact fraction falls as
/// its side grows, the exact stage's is nothing, and the error is plotted.
#[test]
#[cfg_attr(
    not(feature = "plots"),
    ignore = "it checks the charts: run with the `plots` feature, as `cargo test` at the top does"
)]
fn the_samples_sweep_measures_the_grid_against_the_exact_fraction() {
    use umbra::study::scale::{scale, Sweep};
    let out_dir = tmp("scale-samples");
    let out = out_dir.path();
    let methods = vec![
        (umbra::VisibilityMethod::Scanline, ShadowMethod::Crow(Default::default())),
        (umbra::VisibilityMethod::Scanline, ShadowMethod::NishitaNakamae(Default::default())),
    ];
    let opts = umbra::study::scale::ScaleOptions {
        sweep: Sweep::Samples,
        counter: "shadow.pairs".into(),
        ..quads_sweep(out, vec![1.0, 4.0, 8.0], methods)
    };
    let points = scale(&opts).unwrap();
    let error = |shadows: &str| -> Vec<f64> {
        points.iter().filter(|p| p.shadows == shadows).map(|p| p.area_error.unwrap()).collect()
    };
    let (grid, exact) = (error("crow"), error("nishita-nakamae"));
    assert!(grid[0] > 0.1 && grid[0] > grid[1] && grid[1] > grid[2] && grid[2] > 0.0, "{grid:?}");
    assert_eq!(exact, vec![0.0; 3]);
    assert!(out.join("error.svg").exists());
}

/// A method over the memory budget at one point of a sweep is marked refused there, with the
/// budget's message, and the sweep goes on; the error is typed.
#[test]
fn a_sweep_point_over_the_budget_is_refused_and_the_sweep_goes_on() {
    use umbra::study::scale::{scale, Sweep};
    let out_dir = tmp("scale-refused");
    let out = out_dir.path();
    let williams = (umbra::VisibilityMethod::Scanline, ShadowMethod::Williams(Default::default()));
    let opts = umbra::study::scale::ScaleOptions {
        sweep: Sweep::Samples,
        counter: "shadow.map_lookups".into(),
        ..quads_sweep(out, vec![1.0, 12.0], vec![williams])
    };
    let points = scale(&opts).unwrap();
    assert!(points[0].refused.is_none() && points[0].time.median_ms > 0.0);
    let why = points[1].refused.as_deref().unwrap();
    assert!(why.contains("memory budget"), "{why}");
    assert!(std::fs::read_to_string(out.join("index.html")).unwrap().contains("refused: "));
    let scene = umbra::study::scale::Sweep::Samples.scene(12.0, &opts).unwrap();
    let opts = umbra::RenderOptions { shadows: ShadowMethod::Williams(Default::default()), ..Default::default() };
    assert!(matches!(umbra::render(&scene, &opts), Err(umbra::Error::OverBudget { budget, .. }) if budget == 8 << 30));
}
