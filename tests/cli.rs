//! The command line: renders, writes analysis buffers and stats, and fails on bad input with
//! a one-line message.

use std::process::Command;

fn umbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_umbra"))
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("umbra-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn render_writes_image_aovs_and_stats() {
    let d = tmp("render");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/lights.toml");
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

#[test]
fn bad_input_is_one_line_and_non_zero() {
    let d = tmp("bad");
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
    let d = tmp("gen");
    let out = umbra()
        .args(["generate", "cubes", "--n", "2", "--width", "64", "--height", "48", "-o"])
        .arg(d.join("c.toml"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let s = umbra::Scene::load(d.join("c.toml")).unwrap();
    assert_eq!(s.polygons.len(), 1 + 2 * 2 * 12);
    let direct = umbra::generate::cubes(2, true, 64, 48).unwrap();
    assert_eq!(s.vertices, direct.vertices, "written and generated scenes are the same");
}

#[test]
fn export_shadows_writes_an_obj_of_lit_detail_polygons() {
    let d = tmp("export");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell.toml");
    let out = umbra().args(["export-shadows", scene, "-o"]).arg(d.join("lit.obj")).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(d.join("lit.obj")).unwrap();
    let mesh = umbra::scene::parse_obj(&text, std::path::Path::new("lit.obj")).unwrap();
    assert!(mesh.faces.len() > 10);
    // Every group names the source face it lies on.
    assert!(text.lines().filter(|l| l.starts_with("g sample0_face")).count() >= 10);
}
