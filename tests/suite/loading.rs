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
    let scratch = tempfile::Builder::new().prefix("umbra-load-").tempdir().unwrap();
    let dir = scratch.path();
    std::fs::write(dir.join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap();
    let src = format!("{CAMERA}[[object]]\nmesh = \"m.obj\"\n");
    let e = Scene::from_toml(&src, dir.join("s.toml"), dir).unwrap_err().to_string();
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
    // Each camera error names the line of the key that is wrong, not the table's.
    let e = load("[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 5.0]\n").unwrap_err();
    assert!(e.starts_with("s.toml:2:") && e.contains("same point"), "{e}");
    let e = load("[camera]\neye = [0.0, 5.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\n").unwrap_err();
    assert!(e.contains("up is parallel"), "{e}");
    let e = load("[camera]\neye = [0.0, 2.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 1e-310\n").unwrap_err();
    assert!(e.starts_with("s.toml:4:") && e.contains("fov_y") && e.contains("1e-310"), "{e}");
    let e = load("[camera]\neye = [0.0, 2.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 0\n").unwrap_err();
    assert!(e.starts_with("s.toml:4:") && e.contains("size"), "{e}");
    // Huge but finite vectors are scaled before they are normalised: no overflow, no
    // misleading error.
    let s = load("[camera]\neye = [0.0, 2.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nup = [1e308, 1e308, 0.0]\n").unwrap();
    let v = umbra::view::View::new(s.camera());
    assert!(v.r.is_finite() && v.u.is_finite(), "{:?} {:?}", v.r, v.u);
    let s = load(&format!("{CAMERA}[[light]]\nkind = \"directional\"\ndirection = [1e200, -1e200, 0.0]\n")).unwrap();
    assert!(
        matches!(s.lights()[0].kind, umbra::scene::LightKind::Directional { direction } if (direction.length() - 1.0).abs() < 1e-12)
    );
}

#[test]
fn arrays_have_exactly_their_length() {
    let e = load("[camera]\neye = [0.0, 2.0, 6.0, \"junk\"]\ntarget = [0.0, 0.0, 0.0]\n").unwrap_err();
    assert!(e.starts_with("s.toml:2:") && e.contains("exactly 3"), "{e}");
    let e = err("[[light]]\nkind = \"area\"\ncorner = [0.0, 5.0, 0.0]\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]\nsamples = [2, 2, 3]\n");
    assert!(e.starts_with("s.toml:9:") && e.contains("exactly 2"), "{e}");
    let e = err("[[object]]\npolygons = [[[0.0,0.0,0.0],[1.0,0.0,0.0],[0.0,1.0,0.0,1.0]]]\n");
    assert!(e.starts_with("s.toml:5:") && e.contains("exactly 3"), "{e}");
    let e = err("[[object]]\npolygons = [[[0.0,0.0,0.0],[1.0,0.0,0.0],[0.0,1.0]]]\n");
    assert!(e.starts_with("s.toml:5:"), "{e}");
}

#[test]
fn values_beyond_single_precision_are_refused_where_written() {
    let e = err("[[light]]\nkind = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = 1e39\n");
    assert!(e.starts_with("s.toml:7:") && e.contains("beyond single precision"), "{e}");
    let e = err("[[material]]\nname = \"m\"\nks = 1e39\n");
    assert!(e.starts_with("s.toml:6:") && e.contains("1e39"), "{e}");
    let e = err("[[material]]\nname = \"m\"\ncolor = [1e39, 0.0, 0.0]\n");
    assert!(e.starts_with("s.toml:6:"), "{e}");
    let e = err("[[light]]\nkind = \"point\"\nposition = [0.0, 1.0, 0.0]\ncolor = [1e300, 0.0, 0.0]\n");
    assert!(e.starts_with("s.toml:7:"), "{e}");
    // Largest finite f32 values load, and the products that overflow never reach a pixel.
    let s = load(&format!(
        "{CAMERA}width = 16\nheight = 12\n[[light]]\nkind = \"point\"\nposition = [0.0, 1.0, 3.0]\nintensity = 3e38\ncolor = [3e38, 1.0, 0.0]\n\
         [[material]]\nname = \"m\"\nkd = 3e38\nks = 3e38\n[[object]]\nmaterial = \"m\"\npolygons = [[[-2.0,-2.0,0.0],[2.0,-2.0,0.0],[2.0,2.0,0.0],[-2.0,2.0,0.0]]]\n"
    ))
    .unwrap();
    let out = umbra::render(&s, &umbra::RenderOptions::default()).unwrap();
    assert!(out.frame.color.iter().all(|c| c.is_finite()));
}

#[test]
fn ranged_keys_name_themselves_and_their_line() {
    let e = err("[[material]]\nname = \"m\"\nroughness = 0.0\n");
    assert_eq!(e, "s.toml:6:13: material roughness must be > 0, got 0");
    let e = err("[[material]]\nname = \"m\"\nkd = 0.5\nmirror = 2.0\n");
    assert_eq!(e, "s.toml:7:10: material mirror must be in [0, 1], got 2");
    let e =
        err("[[light]]\nkind = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\nexponent = -5.0\n");
    assert_eq!(e, "s.toml:8:12: spot exponent must be >= 0, got -5");
    let e = err("[[light]]\nkind = \"point\"\nposition = [0.0, 1.0, 0.0]\nattenuation = [0.0, 0.0, 0.0]\n");
    assert!(e.starts_with("s.toml:7:") && e.contains("attenuation"), "{e}");
}

#[test]
fn byte_order_marks_and_bad_encodings() {
    let scratch = tempfile::Builder::new().prefix("umbra-bom-").tempdir().unwrap();
    let dir = scratch.path();
    std::fs::write(dir.join("m.obj"), "\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let scene = format!("\u{feff}{CAMERA}[[object]]\nmesh = \"m.obj\"\n");
    std::fs::write(dir.join("s.toml"), &scene).unwrap();
    let s = Scene::load(dir.join("s.toml")).unwrap();
    assert_eq!(s.polygons().len(), 1, "the BOM must not eat the first vertex");
    let mut bad = scene.into_bytes();
    bad.extend_from_slice(b"# \xFF\n");
    std::fs::write(dir.join("bad.toml"), &bad).unwrap();
    let e = Scene::load(dir.join("bad.toml")).unwrap_err().to_string();
    assert!(e.contains("bad.toml:6") && e.contains("not UTF-8"), "{e}");
}

#[test]
fn lone_carriage_returns_end_lines() {
    let src = "[camera]\reye = [0.0, 0.0, 5.0]\rtarget = [0.0, 0.0, 0.0]\r[[light]]\rkind = \"point\"\rposition = [1.0, nan, 2.0]\r";
    let e = load(src).unwrap_err();
    assert!(e.starts_with("s.toml:6:"), "{e}");
    let crlf = src.replace('\r', "\r\n");
    let e = load(&crlf).unwrap_err();
    assert!(e.starts_with("s.toml:6:"), "{e}");
    let mesh = umbra::scene::parse_obj("v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\r", Path::new("m.obj")).unwrap();
    assert_eq!((mesh.positions.len(), mesh.faces.len()), (3, 1));
    let e = umbra::scene::parse_obj("v 0 0 0\rv 1 x 0\r", Path::new("m.obj")).unwrap_err().to_string();
    assert!(e.starts_with("m.obj:2:"), "{e}");
}

#[test]
fn transforms_that_overflow_are_refused() {
    let e = err("[[object]]\nscale = 1e308\npolygons = [[[0.0,0.0,0.0],[10.0,0.0,0.0],[0.0,10.0,0.0]]]\n");
    assert!(e.contains("beyond the range of f64"), "{e}");
}

#[test]
fn obj_vertices_take_three_numbers_and_an_optional_weight() {
    let e = umbra::scene::parse_obj("v 0 0 0 1 7\n", Path::new("m.obj")).unwrap_err().to_string();
    assert_eq!(e, "m.obj:1: 'v' takes at most four numbers, found '7'");
    let e = umbra::scene::parse_obj("vn 0 0 1 1\n", Path::new("m.obj")).unwrap_err().to_string();
    assert_eq!(e, "m.obj:1: 'vn' takes three numbers, found a fourth '1'");
    assert!(umbra::scene::parse_obj("v 0 0 0 1\n", Path::new("m.obj")).is_ok());
}

#[test]
fn face_ids_run_across_objects_and_fans_keep_theirs() {
    let s = load(&format!(
        "{CAMERA}[[object]]\npolygons = [\n [[0.0,0.0,0.0],[1.0,0.0,0.0],[0.0,1.0,0.0]],\n [[0.0,0.0,0.0],[1.0,0.0,0.0]],\n]\n\
         [[object]]\npolygons = [\n [[0.0,0.0,0.0],[1.0,0.0,0.0],[1.0,1.0,0.5],[0.0,1.0,0.0]],\n]\n"
    ))
    .unwrap();
    assert_eq!(s.face_count(), 3);
    // Face 1 is degenerate (two vertices): it keeps its id and draws nothing.
    let faces: Vec<u32> = s.polygons().iter().map(|p| p.face).collect();
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
    assert_eq!(s.face_count(), 18);
    assert!(s.polygons().len() > 18, "the non-planar wall is split into a fan");
}

/// A program cannot break what the loader checked: the camera, lights and materials are
/// replaced through setters that check them, and asking a frame for a light it does not
/// have is an answer, not a panic.
#[test]
fn the_api_keeps_the_loaders_invariants() {
    let mut s =
        load(&format!("{CAMERA}width = 16\nheight = 12\n[[light]]\nkind = \"point\"\nposition = [0.0, 3.0, 0.0]\n"))
            .unwrap();
    let mut c = s.camera().clone();
    c.width = 0;
    assert!(s.set_camera(c).unwrap_err().to_string().contains("size"));
    let mut lights = s.lights().to_vec();
    lights[0].attenuation = [0.0, 0.0, 0.0];
    assert!(s.set_lights(lights).is_err());
    let mut materials = s.materials().to_vec();
    materials[0].roughness = f32::NAN;
    assert!(s.set_materials(materials).is_err());
    assert!(s.set_materials(Vec::new()).is_ok(), "no object refers to a material here");
    assert!(s.set_receiver(3, true).is_err());
    let f = umbra::render(&s, &umbra::RenderOptions::default()).unwrap().frame;
    assert!(f.light_image(0).is_some() && f.light_image(1).is_none());
}

/// The mesh and transform constructors make what a scene file would: a closed box, a quad,
/// a grid of quads and a sphere, placed by a transform, render and load their polygons.
#[test]
fn mesh_and_transform_constructors_build_scenes() {
    use umbra::glam::DVec3;
    use umbra::scene::Transform;
    use umbra::{Camera, Light, Material, Mesh, Object, Scene};
    let grid = Mesh::grid(DVec3::new(-3.0, 0.0, 3.0), DVec3::new(6.0, 0.0, 0.0), DVec3::new(0.0, 0.0, -6.0), 4, 3);
    assert_eq!(grid.faces.len(), 12);
    let cube = Object::new(Mesh::cuboid(DVec3::ZERO, DVec3::ONE))
        .placed(Transform::translation(DVec3::new(-1.5, 0.0, 0.0)).scaled(DVec3::splat(0.8)));
    let scene = Scene::builder(Camera::new(DVec3::new(0.0, 3.0, 6.0), DVec3::ZERO))
        .material(Material::new("m"))
        .light(Light::point(DVec3::new(1.0, 5.0, 2.0)))
        .object(Object::new(grid), "m")
        .object(cube, "m")
        .object(Object::new(Mesh::sphere(DVec3::new(1.0, 0.6, 0.0), 0.6, 200)), "m")
        .object(Object::new(Mesh::quad([DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y, DVec3::ZERO])), "m")
        .build()
        .unwrap();
    assert_eq!(scene.polygons().len(), 12 + 6 + 224 + 1);
    let (lo, hi) = scene.bounds().unwrap();
    assert!((lo.x - -3.0).abs() < 1e-12 && (hi.x - 3.0).abs() < 1e-12, "{lo} {hi}");
    // The cube went where its transform put it: its top corner at 0.8 high.
    assert!(scene.vertices().iter().any(|v| (*v - DVec3::new(-0.7, 0.8, 0.8)).length() < 1e-12));
}

/// Errors carry what went wrong as data a program can match on: the unknown name and the
/// known ones, the setting with its value and what is allowed, the scene part and its
/// problem, the stage that does not apply.
#[test]
fn errors_are_typed_data() {
    use umbra::shadow::WilliamsOptions;
    use umbra::{generate, render, Error, Light, RenderOptions, ShadowMethod};
    match "chalk".parse::<ShadowMethod>() {
        Err(Error::UnknownName { kind, name, known }) => {
            assert_eq!((kind.as_str(), name.as_str()), ("shadow method", "chalk"));
            assert_eq!(known.len(), ShadowMethod::ALL.len());
        }
        other => panic!("{other:?}"),
    }
    let scene = generate::cubes(2, generate::Faces::Quads, 32, 24).unwrap();
    let williams = ShadowMethod::Williams(WilliamsOptions { map_size: 0, ..Default::default() });
    match render(&scene, &RenderOptions { shadows: williams, ..Default::default() }) {
        Err(Error::OutOfRange { setting, value, allowed }) => {
            assert_eq!((setting.as_str(), value.as_str()), ("williams: map size", "0"));
            assert!(allowed.starts_with("in 1..="), "{allowed}");
        }
        other => panic!("{:?}", other.map(|_| ())),
    }
    match umbra::check_gamma(0.0) {
        Err(Error::OutOfRange { setting, .. }) => assert_eq!(setting, "gamma"),
        other => panic!("{other:?}"),
    }
    let mut s = scene.clone();
    match s.set_lights(vec![Light::point(glam::DVec3::new(f64::NAN, 1.0, 0.0))]) {
        Err(Error::InvalidScene { part, problem }) => {
            assert_eq!(part, "light 0");
            assert!(problem.contains("finite"), "{problem}");
        }
        other => panic!("{other:?}"),
    }
    match render(&scene, &RenderOptions { shadows: ShadowMethod::Planar, ..Default::default() }) {
        Err(Error::NotApplicable { stage, why }) => {
            assert_eq!(stage, "planar");
            assert!(why.contains("receiver"), "{why}");
        }
        other => panic!("{:?}", other.map(|_| ())),
    }
}

/// The scene builder refuses what the loader refuses: each bad value, written in a scene file
/// and given to `Scene::builder`, is an error both ways (the builder's names the part).
#[test]
fn the_builder_refuses_what_the_loader_refuses() {
    use umbra::glam::{DVec3, Vec3};
    use umbra::{Camera, Error, Light, Material, Mesh, Object};
    let point = || Light::point(DVec3::new(0.0, 3.0, 0.0));
    let spot = || Light::spot(DVec3::new(0.0, 3.0, 0.0), DVec3::NEG_Y, 30.0);
    let grey = || Material::new("m");
    type Case = (&'static str, &'static str, Box<dyn Fn() -> (Camera, Light, Material)>);
    let camera = || Camera::new(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO);
    let light_toml = "[[light]]\nkind = \"point\"\nposition = [0.0, 3.0, 0.0]\n";
    let cases: Vec<Case> = vec![
        (
            "light position",
            "[[light]]\nkind = \"point\"\nposition = [nan, 3.0, 0.0]\n",
            Box::new(move || (camera(), Light::point(DVec3::new(f64::NAN, 3.0, 0.0)), grey())),
        ),
        (
            "light position",
            "[[light]]\nkind = \"point\"\nposition = [inf, 3.0, 0.0]\n",
            Box::new(move || (camera(), Light::point(DVec3::new(f64::INFINITY, 3.0, 0.0)), grey())),
        ),
        (
            "intensity",
            "[[light]]\nkind = \"point\"\nposition = [0.0, 3.0, 0.0]\nintensity = inf\n",
            Box::new(move || (camera(), point().with(Vec3::ONE, f32::INFINITY), grey())),
        ),
        (
            "attenuation",
            "[[light]]\nkind = \"point\"\nposition = [0.0, 3.0, 0.0]\nattenuation = [0.0, 0.0, 0.0]\n",
            Box::new(move || {
                let mut l = point();
                l.attenuation = [0.0; 3];
                (camera(), l, grey())
            }),
        ),
        (
            "spot exponent",
            "[[light]]\nkind = \"spot\"\nposition = [0.0, 3.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\nexponent = -5.0\n",
            Box::new(move || {
                let mut l = spot();
                if let umbra::scene::LightKind::Spot { exponent, .. } = &mut l.kind {
                    *exponent = -5.0;
                }
                (camera(), l, grey())
            }),
        ),
        (
            "roughness",
            "[[material]]\nname = \"m\"\nroughness = 0.0\n",
            Box::new(move || (camera(), point(), Material { roughness: 0.0, ..grey() })),
        ),
        (
            "mirror",
            "[[material]]\nname = \"m\"\nmirror = 2.0\n",
            Box::new(move || (camera(), point(), Material { mirror: 2.0, ..grey() })),
        ),
        (
            "shininess",
            "[[material]]\nname = \"m\"\nshininess = -1.0\n",
            Box::new(move || (camera(), point(), Material { shininess: -1.0, ..grey() })),
        ),
        (
            "kd",
            "[[material]]\nname = \"m\"\nkd = nan\n",
            Box::new(move || (camera(), point(), Material { kd: f32::NAN, ..grey() })),
        ),
        ("camera size", "[camera]\nwidth = 0\n", Box::new(move || (Camera { width: 0, ..camera() }, point(), grey()))),
        (
            "camera fov",
            "[camera]\nfov_y = 0.0\n",
            Box::new(move || (Camera { fov_y: 0.0, ..camera() }, point(), grey())),
        ),
        (
            "camera eye",
            "[camera]\neye = [0.0, 0.0, 0.0]\n",
            Box::new(move || (Camera { eye: DVec3::ZERO, ..camera() }, point(), grey())),
        ),
    ];
    for (what, toml, build) in cases {
        // The file: the bad value in its table, the rest as the builder's scene has it.
        let src = if let Some(camera_keys) = toml.strip_prefix("[camera]\n") {
            format!("[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n{camera_keys}{light_toml}").replacen(
                "eye = [0.0, 0.0, 5.0]\n",
                if camera_keys.starts_with("eye") { "" } else { "eye = [0.0, 0.0, 5.0]\n" },
                1,
            )
        } else if toml.starts_with("[[light]]") {
            format!("{CAMERA}{toml}")
        } else {
            format!("{CAMERA}{light_toml}{toml}")
        };
        assert!(load(&src).is_err(), "{what}: the loader took\n{src}");
        let (camera, light, material) = build();
        let built = Scene::builder(camera)
            .material(material)
            .light(light)
            .object(Object::new(Mesh::quad([DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y, DVec3::ZERO])), "m")
            .build();
        assert!(matches!(built, Err(Error::InvalidScene { .. })), "{what}: the builder gave {:?}", built.map(|_| ()));
    }
}
