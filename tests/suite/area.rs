//! Nishita & Nakamae's stage: area lights' exact lit fraction (`umbra::reference`'s
//! `exact_fraction`, within one grey level) and every other light's ray-cast answer, behind
//! both visibility stages, on the example scenes and random scenes.

use crate::common;

use common::*;
use umbra::generate::{random, RandomOptions};
use umbra::scene::LightKind;
use umbra::{Scene, ShadowMethod, VisibilityMethod};

const NN: ShadowMethod = ShadowMethod::NishitaNakamae(umbra::shadow::NishitaNakamaeOptions::DEFAULT);

/// The lights of `scene` that are not area lights.
fn point_lights(scene: &Scene) -> Vec<usize> {
    (0..scene.lights().len()).filter(|&l| !matches!(scene.lights()[l].kind, LightKind::Area { .. })).collect()
}

/// Checks the stage on `scene`; returns the area-light pixels compared and those in the penumbra.
fn check(scene: &Scene, label: &str) -> (usize, usize) {
    check_stage(scene, label, &NN)
}

/// [`check`] with the stage's settings `stage`.
fn check_stage(scene: &Scene, label: &str, stage: &ShadowMethod) -> (usize, usize) {
    let want = frame(scene, VisibilityMethod::RayCast, ShadowMethod::RayCast);
    let mut area = (0, 0);
    for v in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
        let got = frame(scene, v, stage.clone());
        let label = format!("{label} {} behind {v}", stage.command_line());
        assert_lights_agree(scene, &want, &got, &label, &point_lights(scene));
        area = assert_area_exact(scene, &got, &label);
    }
    area
}

/// Each step of ours off by itself (`ShadowMethod::variants`: four that buy speed, and the
/// grid's shading in place of Lambert's irradiance) leaves the stage exact: on the example
/// scenes and a few random ones.
#[test]
fn each_step_of_ours_off_leaves_the_fraction_exact() {
    let variants: Vec<ShadowMethod> = NN.variants().into_iter().skip(1).filter(ShadowMethod::is_exact).collect();
    assert_eq!(variants.len(), 5, "{variants:?}");
    for stage in &variants {
        for path in scene_files() {
            check_stage(&load_scaled(&path, 96), &path.display().to_string(), stage);
        }
        for seed in 0..8 {
            let scene = random(seed, RandomOptions { width: 48, height: 36, ..RandomOptions::default() }).unwrap();
            check_stage(&scene, &format!("random scene {seed}"), stage);
        }
    }
}

/// The paper path (every step of ours off, the premise taken for granted) is exact where the
/// premise holds (the lights scene), and fails where it does not: a card above the nearest
/// corner of a tilted light casts no shadow there, and the floor under it reads lit where
/// the exact fraction is not.
#[test]
fn the_paper_path_fails_only_where_its_premise_does() {
    let paper = NN.as_published();
    assert!(paper.is_paper() && !paper.is_exact());
    let scene = load_scaled(&std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/lights.toml")), 96);
    check_stage(&scene, "lights", &paper);

    let src = "[camera]\neye = [0.0, 6.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 64\nheight = 48\n\
               [[light]]\nkind = \"area\"\ncorner = [-0.5, 1.5, -0.5]\nedge_u = [1.0, 1.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]\nsamples = [4, 4]\n\
               [[object]]\npolygons = [[[-4.0, 0.0, -4.0], [-4.0, 0.0, 4.0], [4.0, 0.0, 4.0], [4.0, 0.0, -4.0]]]\n\
               [[object]]\npolygons = [[[0.2, 1.8, -0.3], [0.2, 1.8, 0.3], [0.8, 1.8, 0.3], [0.8, 1.8, -0.3]]]\n";
    let scene = Scene::from_toml(src, "tilted.toml", ".").unwrap();
    let oracle = umbra::reference::Reference::new(&scene);
    let (exact, published) =
        (frame(&scene, VisibilityMethod::Scanline, NN), frame(&scene, VisibilityMethod::Scanline, paper));
    assert_area_exact(&scene, &exact, "tilted light, nishita-nakamae");
    let mut missing = 0;
    for (k, (&got, &id)) in published.light[0].iter().zip(&published.id).enumerate() {
        let (x, y) = ((k % 64) as f64 + 0.5, (k / 64) as f64 + 0.5);
        let want = oracle.exact_fraction_at(0, x, y);
        if id == 0 && want.is_some_and(|w| w < 0.9) && got == 1.0 {
            missing += 1;
        }
    }
    assert!(missing > 20, "{missing} floor pixels lit by the paper path where the card hides the light");
}

#[test]
fn the_exact_fraction_on_the_example_scenes() {
    let mut penumbra = 0;
    for path in scene_files() {
        let scene = load_scaled(&path, 160);
        penumbra += check(&scene, &path.display().to_string()).1;
    }
    assert!(penumbra > 500, "{penumbra} penumbra pixels compared");
}

#[test]
fn the_exact_fraction_on_random_scenes() {
    let (mut compared, mut penumbra) = (0, 0);
    for seed in 0..60 {
        let scene = random(seed, RandomOptions { width: 64, height: 48, ..RandomOptions::default() }).unwrap();
        let (c, p) = check(&scene, &format!("random scene {seed}"));
        compared += c;
        penumbra += p;
    }
    assert!(compared > 10_000 && penumbra > 1000, "{compared} area-light pixels, {penumbra} in the penumbra");
}

/// The robustness and repro scenes (solids, interpenetrating and coplanar polygons, lights
/// among the polygons, the area-light scenes that once found wrong pixels in other stages),
/// but for those of more than [`LARGE`] polygons.
#[test]
fn the_exact_fraction_on_the_repro_scenes() {
    assert!(repro_scenes(false) > 1000);
}

/// The repro scenes of more than [`LARGE`] polygons: the open bunny and a torus under three
/// area lights, each wider than the scene, take tens of seconds a frame.
#[test]
#[ignore = "a minute: the large repro scenes; run with --ignored"]
fn the_exact_fraction_on_the_large_repro_scenes() {
    assert!(repro_scenes(true) > 100);
}

/// Polygons above which a repro scene is left to the ignored test.
const LARGE: usize = 20_000;

/// Checks the repro scenes of more (`large`) or at most [`LARGE`] polygons; returns the
/// penumbra pixels compared.
fn repro_scenes(large: bool) -> usize {
    let mut penumbra = 0;
    for folder in ["robustness", "solids", "awg-area"] {
        for path in toml_files(&format!("tests/data/{folder}"), 5) {
            let scene = load_scaled(&path, 96);
            if (scene.polygons().len() > LARGE) == large {
                penumbra += check(&scene, &path.display().to_string()).1;
            }
        }
    }
    penumbra
}

/// Convex closed solids (a sphere of 400 triangles, boxes) and an open sheet under a square
/// light: the convex solids' polygons are measured as one shadow each (the counter shows it),
/// and the fraction is still exact, behind both visibility stages.
#[test]
fn convex_solids_hide_as_one() {
    use glam::DVec3;
    use umbra::{Camera, Light, Material, Mesh, Object};
    let floor = Mesh::quad([
        DVec3::new(-4.0, 0.0, -4.0),
        DVec3::new(-4.0, 0.0, 4.0),
        DVec3::new(4.0, 0.0, 4.0),
        DVec3::new(4.0, 0.0, -4.0),
    ]);
    let light = Light::area(DVec3::new(-1.0, 4.0, -1.0), DVec3::new(2.0, 0.0, 0.0), DVec3::new(0.0, 0.2, 2.0), [4, 4]);
    let mut camera = Camera::new(DVec3::new(0.5, 5.0, 7.0), DVec3::ZERO);
    (camera.width, camera.height) = (160, 120);
    let scene = Scene::builder(camera)
        .material(Material::new("m"))
        .light(light)
        .object(Object::new(floor), "m")
        .object(Object::new(Mesh::sphere(DVec3::new(0.3, 1.2, 0.2), 0.8, 400)), "m")
        .object(Object::new(Mesh::cuboid(DVec3::new(-2.0, 0.0, -1.5), DVec3::new(-1.2, 1.5, -0.7))), "m")
        .object(
            Object::new(Mesh::grid(
                DVec3::new(1.0, 0.6, 1.0),
                DVec3::new(0.8, 0.3, 0.0),
                DVec3::new(0.0, 0.2, 0.8),
                4,
                4,
            )),
            "m",
        )
        .build()
        .unwrap();
    for v in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
        let opts = umbra::RenderOptions { visibility: v, shadows: NN, ..Default::default() };
        let r = umbra::render(&scene, &opts).unwrap();
        assert!(r.stats.shadow_counters.get(umbra::Counter::ConvexSolidShadows) > 100, "{:?}", r.stats.shadow_counters);
        let (compared, penumbra) = assert_area_exact(&scene, &r.frame, &format!("convex solids behind {v}"));
        assert!(compared > 10_000 && penumbra > 500, "{compared} compared, {penumbra} in the penumbra");
    }
}
