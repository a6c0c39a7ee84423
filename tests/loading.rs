//! Scene and mesh loading: face ids, the planarity rule, and one-line errors that name the
//! file and line.

use std::path::Path;
use umbra::Scene;

fn load(src: &str) -> Result<Scene, String> {
    Scene::from_toml(src, Path::new("s.toml"), Path::new(env!("CARGO_MANIFEST_DIR"))).map_err(|e| e.to_string())
}

const CAMERA: &str = "[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n";

fn err(body: &str) -> String {
    let e = load(&format!("{CAMERA}{body}")).unwrap_err();
    assert!(!e.contains('\n'), "error is not one line: {e}");
    e
}

#[test]
fn unknown_key_names_key_and_line() {
    let e = err("[[material]]\nname = \"a\"\ncolour = [1.0, 0.0, 0.0]\n");
    assert!(e.starts_with("s.toml:6:"), "{e}");
    assert!(e.contains("unknown field `colour`"), "{e}");
}

#[test]
fn bad_number_and_nan() {
    let e = err("[[light]]\nkind = \"point\"\nposition = [1.0, \"x\", 2.0]\n");
    assert!(e.starts_with("s.toml:6:"), "{e}");
    let e = err("[[light]]\nkind = \"point\"\nposition = [1.0, nan, 2.0]\n");
    assert!(e.starts_with("s.toml:6:") && e.contains("not a finite number"), "{e}");
    let e = err("[[object]]\npolygons = [[[0.0,0.0,0.0],[1.0,0.0,0.0],[0.0,inf,0.0]]]\n");
    assert!(e.starts_with("s.toml:5:") && e.contains("not a finite number"), "{e}");
}

#[test]
fn broken_toml() {
    let e = err("[[object]\n");
    assert!(e.starts_with("s.toml:4:"), "{e}");
}

#[test]
fn missing_material() {
    let e = err("[[object]]\nmaterial = \"gold\"\npolygons = []\n");
    assert_eq!(e, "s.toml:5:12: no material named 'gold'");
}

#[test]
fn unreadable_mesh() {
    let e = err("[[object]]\nmesh = \"no/such.obj\"\n");
    assert!(e.starts_with("s.toml:5:8: cannot read mesh"), "{e}");
}

#[test]
fn bad_obj_line_names_the_obj_file() {
    let dir = std::env::temp_dir().join(format!("umbra-load-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap();
    let src = format!("{CAMERA}[[object]]\nmesh = \"m.obj\"\n");
    let e = Scene::from_toml(&src, &dir.join("s.toml"), &dir).unwrap_err().to_string();
    assert!(e.ends_with("m.obj:4: vertex index 4 out of range (3 defined so far)"), "{e}");
}

#[test]
fn light_keys_checked_per_kind() {
    assert_eq!(
        err("[[light]]\nkind = \"spot\"\nposition = [0.0, 1.0, 0.0]\n"),
        "s.toml:4:1: spot light needs 'direction'"
    );
    let e = err("[[light]]\nkind = \"point\"\nposition = [0.0, 1.0, 0.0]\ncutoff = 10.0\n");
    assert!(e.contains("'cutoff/exponent' applies to spot lights only"), "{e}");
    let e = err("[[light]]\nkind = \"laser\"\n");
    assert!(e.starts_with("s.toml:5:") && e.contains("unknown variant `laser`"), "{e}");
}

#[test]
fn camera_checks() {
    let e = load("[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 5.0]\n").unwrap_err();
    assert!(e.starts_with("s.toml:1:") && e.contains("same point"), "{e}");
    let e = load("[camera]\neye = [0.0, 5.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\n").unwrap_err();
    assert!(e.contains("up is parallel"), "{e}");
}

#[test]
fn face_ids_run_across_objects_and_fans_keep_theirs() {
    let s = load(&format!(
        "{CAMERA}[[object]]\npolygons = [\n [[0.0,0.0,0.0],[1.0,0.0,0.0],[0.0,1.0,0.0]],\n [[0.0,0.0,0.0],[1.0,0.0,0.0]],\n]\n\
         [[object]]\npolygons = [\n [[0.0,0.0,0.0],[1.0,0.0,0.0],[1.0,1.0,0.5],[0.0,1.0,0.0]],\n]\n"
    ))
    .unwrap();
    assert_eq!(s.face_count, 3);
    // Face 1 is degenerate (two vertices): it keeps its id and draws nothing.
    let faces: Vec<u32> = s.polygons.iter().map(|p| p.face).collect();
    assert_eq!(faces, vec![0, 2, 2], "the non-planar face 2 is a fan of two triangles");
}

#[test]
fn transforms_apply_scale_rotate_translate_in_order() {
    let s = load(&format!(
        "{CAMERA}[[object]]\npolygons = [[[1.0,0.0,0.0],[0.0,1.0,0.0],[0.0,0.0,1.0]]]\nscale = 2.0\nrotate = [0.0, 0.0, 90.0]\ntranslate = [10.0, 0.0, 0.0]\n"
    ))
    .unwrap();
    // (1,0,0) -> scale (2,0,0) -> rotate 90° about Z (0,2,0) -> translate (10,2,0).
    let v = s.verts(0)[0];
    assert!((v - glam::DVec3::new(10.0, 2.0, 0.0)).length() < 1e-12, "{v}");
}

#[test]
fn every_example_scene_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            Scene::load(&p).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

#[test]
fn cornell_obj_negative_indices_and_fan() {
    let s = Scene::load(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-obj.toml")).unwrap();
    assert_eq!(s.face_count, 18);
    assert!(s.polygons.len() > 18, "the non-planar wall is split into a fan");
}
