//! The command line: renders, writes analysis buffers and stats, and fails on bad input with
//! a one-line message.

use std::process::Command;

fn umbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_umbra"))
}

/// A fresh folder for one test, removed when the test is done with it.
fn tmp(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new().prefix(&format!("umbra-cli-{name}-")).tempdir().unwrap()
}

#[test]
fn render_writes_image_aovs_and_stats() {
    let d_dir = tmp("render");
    let d = d_dir.path();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/lights.toml");
    let out = umbra()
        .args(["render", scene, "-o"])
        .arg(d.join("o.png"))
        .arg("--aov")
        .arg(d.join("aov"))
        .args(["--stats", "--visibility", "zbuffer", "--shadows", "ray-cast"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stats: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(stats["visibility"], "zbuffer");
    assert!(stats["shadow_counters"]["shadow_rays"].as_u64().unwrap() > 0);
    // The process's peak resident memory: more than the 640×480 frame's buffers alone.
    assert!(stats["peak_rss_mb"].as_f64().unwrap() > 1.0);
    let id = image::open(d.join("aov/id.png")).unwrap().to_rgba8();
    assert_eq!(id.dimensions(), (640, 480));
    // Top-left corner is background.
    assert_eq!(id.get_pixel(0, 0).0, [255, 255, 255, 255]);
    for k in 0..4 {
        let l = image::open(d.join(format!("aov/light{k}.png"))).unwrap();
        assert_eq!(l.color(), image::ColorType::L8);
    }
    assert!(!d.join("aov/light4.png").exists());
}

/// `--stats` with Williams' shadow maps gives the map's wrong pixels by cause
/// (`umbra::study::map_errors`), and their sum is the wrong pixels `compare` counts; other
/// stages have no such entry.
#[test]
fn stats_give_a_shadow_maps_errors_by_cause() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/lights.toml");
    let stats = |shadows: &str| -> serde_json::Value {
        let out = umbra().args(["render", scene, "-o", "/dev/null", "--stats", "--shadows", shadows]).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let w = &stats("williams")["map_errors"];
    let count = |k: &str| w[k].as_u64().unwrap_or_else(|| panic!("{k} in {w}"));
    assert!(count("detached") > 0 && count("aliasing") > 0, "{w}");
    let sum: u64 = ["acne", "detached", "aliasing", "resolution"].iter().map(|k| count(k)).sum();
    let s = umbra::Scene::load(scene).unwrap();
    let go =
        |v, m| umbra::render(&s, &umbra::RenderOptions { visibility: v, shadows: m, ..Default::default() }).unwrap();
    let reference = go(umbra::VisibilityMethod::RayCast, umbra::ShadowMethod::RayCast).frame;
    let got = go(umbra::VisibilityMethod::Scanline, umbra::ShadowMethod::Williams(Default::default())).frame;
    let (_, wrong, _) = umbra::study::compare::diff(&reference, &got);
    assert_eq!(sum, wrong as u64, "every wrong interior pixel has one cause here (none sees another face)");
    assert!(stats("bouknight-kelley").get("map_errors").is_none());
}

#[test]
fn bad_input_is_one_line_and_non_zero() {
    let d_dir = tmp("bad");
    let d = d_dir.path();
    let bad = d.join("bad.toml");
    std::fs::write(&bad, "[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nzoom = 2\n").unwrap();
    let out = umbra().arg("render").arg(&bad).arg("-o").arg(d.join("o.png")).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("bad.toml:4:") && err.contains("zoom"), "{err}");

    let out = umbra().args(["render", "/no/such/scene.toml"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/no/such/scene.toml"));

    let out = umbra().args(["render", "x.toml", "--shadows", "magic"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("known: none"));

    let good = d.join("good.toml");
    std::fs::write(&good, "[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n").unwrap();
    let out = umbra().arg("render").arg(&good).args(["--shadows", "williams", "--pcf-size", "2"]).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("kernel size 2"), "{err}");
}

#[test]
fn generate_writes_a_loadable_scene() {
    let d_dir = tmp("gen");
    let d = d_dir.path();
    let out = umbra()
        .args(["generate", "cubes", "--n", "2", "--width", "64", "--height", "48", "-o"])
        .arg(d.join("c.toml"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let s = umbra::Scene::load(d.join("c.toml")).unwrap();
    assert_eq!(s.polygons().len(), 1 + 2 * 2 * 12);
    let direct = umbra::generate::cubes(2, umbra::generate::Faces::Triangles, 64, 48).unwrap();
    assert_eq!(s.vertices(), direct.vertices(), "written and generated scenes are the same");
}

#[test]
fn export_shadows_writes_an_obj_of_lit_detail_polygons() {
    let d_dir = tmp("export");
    let d = d_dir.path();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/cornell.toml");
    let out = umbra().args(["export-shadows", scene, "-o"]).arg(d.join("lit.obj")).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(d.join("lit.obj")).unwrap();
    let mesh = umbra::scene::parse_obj(&text, std::path::Path::new("lit.obj")).unwrap();
    assert!(mesh.faces.len() > 10);
    // Every group names the source face it lies on.
    assert!(text.lines().filter(|l| l.starts_with("g sample0_face")).count() >= 10);
}

/// Runs umbra with `args`; returns (success, stderr).
fn run(args: &[&str]) -> (bool, String) {
    let out = umbra().args(args).output().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Asserts a failure with exactly one line on stderr, containing `want`.
fn refused(args: &[&str], want: &str) {
    let (ok, err) = run(args);
    assert!(!ok, "{args:?} succeeded");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    assert!(err.contains(want), "{args:?}: {err}");
}

const SMALL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/robustness/crow_pentagram_even_odd.toml");

#[test]
fn failed_writes_are_errors() {
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full");
    if full.is_err() {
        return; // no /dev/full on this system
    }
    let out = umbra().args(["render", SMALL, "-o", "/dev/null", "--stats"]).stdout(full.unwrap()).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("standard output"));
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let out = umbra().args(["trace", SMALL, "--line", "30"]).stdout(full).output().unwrap();
    assert!(!out.status.success());
    refused(&["render", SMALL, "-o", "/dev/full"], "/dev/full");
}

#[test]
fn options_are_checked_wherever_they_are_used() {
    refused(&["render", SMALL, "-o", "x.jpg"], "PNG only");
    refused(
        &["export-shadows", SMALL, "-o", "x.obj", "--light", "5"],
        "crow_pentagram_even_odd.toml: no light 5 (the scene has 1 light(s)",
    );
    refused(&["render", SMALL, "-o", "x.png", "--gamma", "0"], "gamma");
    refused(&["render", SMALL, "-o", "x.png", "--gamma", "nan"], "gamma");
    refused(&["trace", SMALL, "--line", "3", "--x", "5000"], "outside the image");
    // Williams' options: the same checks from render, trace and compare.
    let w = ["--shadows", "williams"];
    refused(
        &[&["render", SMALL, "-o", "/dev/null", "--map-size", "2", "--shadow-filter", "pcf"][..], &w].concat(),
        "kernel size 3 is not within the 2x2 map",
    );
    refused(
        &[&["render", SMALL, "-o", "/dev/null", "--map-size", "4", "--pcf-size", "5"][..], &w].concat(),
        "within the 4x4 map",
    );
    refused(&[&["trace", SMALL, "--line", "3", "--map-size", "0"][..], &w].concat(), "map size 0");
    refused(&[&["trace", SMALL, "--line", "3", "--pcf-size", "2"][..], &w].concat(), "kernel size 2");
    refused(&[&["trace", SMALL, "--line", "3", "--bias", "nan"][..], &w].concat(), "bias");
    let d_dir = tmp("compare-map");
    let d = d_dir.path();
    let out = d.join("c");
    refused(
        &["compare", SMALL, "--shadows", "williams", "--map-size", "0", "--out", out.to_str().unwrap()],
        "map size 0",
    );
    let sc = d.join("s");
    let sc = sc.to_str().unwrap();
    let sweep = ["scale", "--sweep", "cubes", "--values", "1", "--width", "32", "--height", "24", "--out", sc];
    refused(
        &[&sweep[..], &["--counter", "nope"]].concat(),
        "unknown visibility counter of these methods 'nope' (known: ",
    );
    refused(&[&sweep[..], &["--counter", "colour.spans"]].concat(), "not visibility.NAME or shadow.NAME");
    let (ok, err) = run(&[&sweep[..], &["--counter", "visibility.spans"]].concat());
    assert!(ok, "{err}");
    // A kernel as wide as the map is fine.
    let (ok, err) = run(&[&["render", SMALL, "-o", "/dev/null", "--map-size", "3"][..], &w].concat());
    assert!(ok, "{err}");
}

#[test]
fn work_beyond_the_memory_budget_is_refused_before_it_starts() {
    let d_dir = tmp("budget");
    let d = d_dir.path();
    let big = d.join("big.toml");
    std::fs::write(
        &big,
        "[camera]\neye = [0.0, 2.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 32768\nheight = 32768\n\
         [[object]]\npolygons = [[[0.0,0.0,0.0],[1.0,0.0,0.0],[0.0,1.0,0.0]]]\n",
    )
    .unwrap();
    refused(&["render", big.to_str().unwrap(), "-o", "/dev/null"], "memory budget");
    let g = d.join("g.toml");
    refused(&["generate", "cubes", "--n", "100000", "-o", g.to_str().unwrap()], "memory budget");
    refused(&["generate", "spheres", "--triangles", "4000000000", "-o", g.to_str().unwrap()], "memory budget");
    refused(
        &["scale", "--sweep", "cubes", "--values", "1000000", "--out", d.join("s").to_str().unwrap()],
        "memory budget",
    );
    // 4,096 samples of an area light, each with a 2048² cube map: refused with the estimate.
    let area = d.join("area.toml");
    std::fs::write(
        &area,
        "[camera]\neye = [0.0, 2.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 32\nheight = 24\n\
         [[light]]\nkind = \"area\"\ncorner = [0.0, 4.0, 0.0]\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]\nsamples = [64, 64]\n\
         [[object]]\npolygons = [[[0.0,0.0,0.0],[1.0,0.0,0.0],[0.0,1.0,0.0]]]\n",
    )
    .unwrap();
    refused(&["render", area.to_str().unwrap(), "-o", "/dev/null", "--shadows", "williams"], "memory budget");
}

/// `bench` times each visibility × shadow pair with warm-up in one process and reports the
/// frame's and each phase's median, least and greatest time, the peak memory, the threads and
/// the cores other processes used meanwhile, as one JSON object per row.
#[test]
fn bench_reports_spread_phases_and_memory() {
    let out = umbra()
        .args(["bench", SMALL, "--visibility", "scanline,zbuffer", "--shadows", "none,crow", "--runs", "3"])
        .args(["--warmup", "1", "--threads", "2", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let rows: Vec<serde_json::Value> =
        String::from_utf8_lossy(&out.stdout).lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(rows.len(), 4);
    for r in &rows {
        let (min, median, max) =
            (r["min_ms"].as_f64().unwrap(), r["median_ms"].as_f64().unwrap(), r["max_ms"].as_f64().unwrap());
        assert!(0.0 < min && min <= median && median <= max, "{r}");
        for phase in ["view", "visibility", "shadow_prepare", "shadow_walk", "shading"] {
            assert!(r["phases"][phase]["median_ms"].as_f64().is_some(), "{phase} missing in {r}");
        }
        assert!(r["peak_rss_mb"].as_f64().unwrap() > 1.0, "{r}");
        assert!(r["peak_mb"].as_f64().unwrap() > 0.0, "{r}");
        assert_eq!(r["runs"], 3);
        assert_eq!(r["threads"], 2);
        assert_eq!(r["tries"], 1, "timed once unless asked to wait for a quiet machine");
        assert!(r["contention"].is_null(), "the cores are probed only when asked to wait");
        // Rows this short (under a second) give no figure for the others' cores: too few
        // of /proc's ticks to mean anything.
        assert!(r["foreign_cores"].is_null(), "{r}");
    }
    assert_eq!(rows[3]["visibility"], "zbuffer");
    assert_eq!(rows[3]["shadows"], "crow");
    assert!(rows.iter().all(|r| r["speedup"].is_null() && r["speedup_best"].is_null()), "one count, no speed-up");
    refused(&["bench", SMALL, "--runs", "0"], "bench: timed runs 0 is not at least 1");
    refused(&["bench", SMALL, "--threads", "1,0"], "bench: threads 0 is not at least 1");
}

/// `bench --threads 1,2` renders each method at one and two threads in turn, one row per
/// count, and gives the two-thread row's speed-up over the one-thread row.
#[test]
fn bench_compares_thread_counts_frame_by_frame() {
    let out = umbra()
        .args(["bench", SMALL, "--shadows", "none,crow", "--runs", "3", "--warmup", "1", "--threads", "1,2", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let rows: Vec<serde_json::Value> =
        String::from_utf8_lossy(&out.stdout).lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let seen: Vec<(&str, u64)> =
        rows.iter().map(|r| (r["shadows"].as_str().unwrap(), r["threads"].as_u64().unwrap())).collect();
    assert_eq!(seen, [("none", 1), ("none", 2), ("crow", 1), ("crow", 2)]);
    for pair in rows.chunks(2) {
        assert_eq!(pair[0]["speedup"], 1.0, "the first count against itself");
        let (one, two) = (pair[0]["median_ms"].as_f64().unwrap(), pair[1]["median_ms"].as_f64().unwrap());
        let speedup = pair[1]["speedup"].as_f64().unwrap();
        // The median of per-run ratios lies between the extreme runs' ratios.
        let (lo, hi) = (
            pair[0]["min_ms"].as_f64().unwrap() / pair[1]["max_ms"].as_f64().unwrap(),
            pair[0]["max_ms"].as_f64().unwrap() / pair[1]["min_ms"].as_f64().unwrap(),
        );
        assert!(lo <= speedup && speedup <= hi, "{speedup} outside {lo}..{hi} ({one} ms / {two} ms)");
        // The fastest frames against each other.
        let best = pair[1]["speedup_best"].as_f64().unwrap();
        let fastest = pair[0]["min_ms"].as_f64().unwrap() / pair[1]["min_ms"].as_f64().unwrap();
        assert!((best - fastest).abs() <= 1e-9 * fastest, "{best} against {fastest}");
        assert_eq!(pair[0]["speedup_best"], 1.0);
    }
}

/// Commands that write files say what they wrote and refuse to overwrite without `--force`;
/// `--debug shadow-polygons` is refused where the stage has no polygons to draw; `--aov`
/// writes a viewable face-id image beside the packed one.
#[test]
fn nothing_silent() {
    let d_dir = tmp("silent");
    let d = d_dir.path();
    let g = d.join("g.toml");
    let gen = ["generate", "cubes", "--n", "1", "--width", "32", "--height", "24", "-o", g.to_str().unwrap()];
    let (ok, err) = run(&gen);
    assert!(ok && err.contains("wrote") && err.contains("g.toml"), "{err}");
    refused(&gen, "exists; pass --force");
    let (ok, err) = run(&[&gen[..], &["--force"]].concat());
    assert!(ok, "{err}");
    let obj = d.join("lit.obj");
    let export = ["export-shadows", SMALL, "-o", obj.to_str().unwrap()];
    let (ok, err) = run(&export);
    assert!(ok && err.contains("wrote") && err.contains("lit detail polygon"), "{err}");
    refused(&export, "exists; pass --force");
    for s in ["williams", "ray-cast", "none", "stencil-volume"] {
        refused(
            &["render", SMALL, "-o", "/dev/null", "--shadows", s, "--debug", "shadow-polygons"],
            "has none to draw",
        );
    }
    let aov = d.join("aov");
    let (ok, err) = run(&["render", SMALL, "-o", "/dev/null", "--aov", aov.to_str().unwrap()]);
    assert!(ok && err.contains("wrote /dev/null and the analysis buffers in"), "{err}");
    let view = image::open(aov.join("id_view.png")).unwrap().to_rgb8();
    let packed = image::open(aov.join("id.png")).unwrap().to_rgba8();
    // Background black, faces bright: every pixel with a face shows it.
    for (v, p) in view.pixels().zip(packed.pixels()) {
        assert_eq!(p.0 == [255; 4], v.0 == [0, 0, 0]);
    }
}

#[test]
fn receiver_makes_planar_shadows_usable_on_any_scene() {
    let cornell = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/cornell.toml");
    let d_dir = tmp("receiver");
    let d = d_dir.path();
    let out = d.join("planar.png");
    let out = out.to_str().unwrap();
    refused(&["render", cornell, "--shadows", "planar", "-o", out], "receiver");
    let stats = |args: &[&str]| -> serde_json::Value {
        let o =
            umbra().args(["render", cornell, "--shadows", "planar", "--stats", "-o", out]).args(args).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    // By name, by index, and the flat objects chosen automatically (the two side walls:
    // the floor, ceiling and back wall are one object, which is not flat).
    assert_eq!(stats(&["--receiver", "left wall"])["shadow_counters"]["receivers"], 1);
    assert_eq!(stats(&["--receiver", "2"])["shadow_counters"]["receivers"], 1);
    assert_eq!(stats(&["--receiver", "auto"])["shadow_counters"]["receivers"], 2);
    refused(
        &["render", cornell, "--shadows", "planar", "--receiver", "the moon", "-o", out],
        "--receiver the moon: no object",
    );
    refused(
        &["render", cornell, "--shadows", "planar", "--receiver", "9", "-o", out],
        "object 9 is not an object of the scene",
    );
    refused(&["scale", "--sweep", "cubes", "--values", "1", "--receiver", "auto"], "cannot be used here");
}

/// Reports a reader takes in without the source: every printed table of `compare` and
/// `scale` starts with a header line, and a stage that does not apply reads as such, with
/// the fix, in place of zero times and errors.
#[test]
fn printed_tables_have_headers_and_say_not_applicable() {
    let d_dir = tmp("tables");
    let d = d_dir.path();
    let out = umbra()
        .args([
            "compare",
            SMALL,
            "--shadows",
            "crow,planar",
            "--visibility",
            "scanline",
            "--runs",
            "1",
            "--warmup",
            "0",
        ])
        .arg("--out")
        .arg(d.join("cmp"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default();
    assert!(header.contains("visibility") && header.contains("wrong / interior"), "{text}");
    let planar = lines.find(|l| l.contains("planar")).unwrap_or_default();
    assert!(planar.contains("not applicable") && planar.contains("--receiver auto"), "{planar}");
    assert!(!planar.contains("0.0"), "a row that did not run shows no time: {planar}");
    // The HTML report says the same, and names the options as the command line does.
    let html = std::fs::read_to_string(d.join("cmp/report.html")).unwrap();
    assert!(!html.contains("Options {") && html.contains("shadow stages: crow; planar"), "options as Rust text");
    let row = html.lines().find(|l| l.contains("<tr") && l.contains("not applicable")).unwrap_or_default();
    assert!(row.contains("—") && !row.contains("0.0000%"), "{row}");
    let out = umbra()
        .args(["scale", "--sweep", "cubes", "--values", "1,2", "--runs", "1", "--width", "32", "--height", "24"])
        .arg("--out")
        .arg(d.join("scale"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let header = text.lines().next().unwrap_or_default();
    assert!(header.contains("cubes") && header.contains("visibility.depth_tests"), "{text}");
}

/// `-o` into a folder that does not exist makes it, as `--aov` and `generate` do; where it
/// cannot be made the message says the write failed.
#[test]
fn output_folders_are_made_and_failed_writes_say_so() {
    let d_dir = tmp("folders");
    let d = d_dir.path();
    let png = d.join("new/deeper/o.png");
    let out = umbra().args(["render", SMALL, "-o"]).arg(&png).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(png.exists());
    refused(&["render", SMALL, "-o", "/proc/no-such-folder/o.png"], "could not write");
}

/// A negative image size is named with the range, like any other bad size, not as a type.
#[test]
fn a_negative_size_is_named_with_its_range() {
    let d_dir = tmp("negative");
    let d = d_dir.path();
    let bad = d.join("neg.toml");
    std::fs::write(&bad, "[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = -5\n").unwrap();
    let out = umbra().arg("render").arg(&bad).arg("-o").arg(d.join("o.png")).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("neg.toml:4:") && err.contains("width -5 must be 1..=32768"), "{err}");
}

/// Generated spheres come as near the triangles asked for as UV spheres can, and the
/// message says how many were written.
#[test]
fn generated_spheres_come_near_the_triangles_asked_for() {
    let d_dir = tmp("spheres");
    let d = d_dir.path();
    let out = umbra()
        .args(["generate", "spheres", "--triangles", "5000", "--count", "3", "-o"])
        .arg(d.join("s.toml"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let s = umbra::Scene::load(d.join("s.toml")).unwrap();
    let spheres = s.polygons().len() as i64 - 1;
    assert!((spheres - 5000).abs() <= 5000 / 50, "{spheres} triangles for 5,000 asked");
    assert!(String::from_utf8_lossy(&out.stderr).contains(&format!("{} polygons", spheres + 1)));
}

/// `bench` gives each row its own peak memory: a row without shadows after a row of
/// Williams' 2048² maps (tens of MB) shows its own few MB, not the maps' high-water mark;
/// and its table fits 120 columns, with a header.
#[test]
fn bench_rows_have_their_own_peak_memory_and_the_table_fits() {
    let out = umbra()
        .args(["bench", SMALL, "--shadows", "williams,none", "--runs", "1", "--warmup", "0", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let rows: Vec<serde_json::Value> =
        String::from_utf8_lossy(&out.stdout).lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let peak = |r: &serde_json::Value| r["peak_mb"].as_f64().unwrap();
    assert!(peak(&rows[0]) > 4.0 * peak(&rows[1]), "williams {} MB, none {} MB", peak(&rows[0]), peak(&rows[1]));
    assert!(rows[1]["peak_rss_mb"].as_f64().unwrap() >= peak(&rows[0]), "the high-water mark stays high");
    let out = umbra()
        .args([
            "bench",
            SMALL,
            "--visibility",
            "scanline,zbuffer",
            "--shadows",
            "bouknight-kelley,atherton-weiler-greenberg",
        ])
        .args(["--runs", "1", "--warmup", "0", "--threads", "1,2"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(text.lines().next().is_some_and(|h| h.contains("peak MB") && h.contains("speed-up")), "{text}");
    assert!(text.lines().all(|l| l.chars().count() <= 120), "wider than 120 columns:\n{text}");
}

#[test]
fn the_command_stops_on_a_bad_scene_before_serving() {
    let out = umbra().args(["explore", "no-such-scene.toml", "--port", "0"]).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("no-such-scene.toml") && !err.contains("http://"), "{err}");

    let scratch = tempfile::Builder::new().prefix("umbra-explore-cli-").tempdir().unwrap();
    let dir = scratch.path();
    std::fs::write(dir.join("keep.txt"), "mine").unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/cornell.toml");
    let out = umbra().args(["explore", scene, "--export"]).arg(dir).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("pass --force"));
    let out = umbra().args(["explore", scene, "--size", "9999x10", "--export"]).arg(dir).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("WIDTHxHEIGHT"));
}
