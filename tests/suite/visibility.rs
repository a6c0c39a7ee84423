//! Scanline and z-buffer visibility agree with the ray-cast reference at every pixel but ties
//! (see `umbra::reference`), on every example scene and on hundreds of random scenes.

use crate::common;

use common::*;
use umbra::generate::{random, RandomOptions};
use umbra::{ShadowMethod, VisibilityMethod};

#[test]
fn example_scenes_agree_with_ray_cast() {
    for path in scene_files() {
        let scene = load_scaled(&path, 320);
        let reference = frame(&scene, VisibilityMethod::RayCast, ShadowMethod::None);
        for v in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
            let got = frame(&scene, v, ShadowMethod::None);
            let a = assert_ids_agree(&scene, &reference, &got, &format!("{} {v}", path.display()));
            assert!(a.compared > 1000, "{}: too few pixels ({a:?})", path.display());
        }
    }
}

#[test]
fn random_scenes_agree_with_ray_cast() {
    let mut compared = 0;
    let mut splits = 0;
    let mut clipped = 0;
    for seed in 0..300 {
        let scene = random(seed, RandomOptions { width: 64, height: 48, ..RandomOptions::default() }).unwrap();
        let opts = umbra::RenderOptions { shadows: ShadowMethod::None, ..Default::default() };
        splits += umbra::render(&scene, &opts).unwrap().stats.visibility_counters.get("span_splits");
        let view = umbra::view::View::new(scene.camera());
        clipped += (0..scene.polygons().len())
            .filter(|&i| scene.verts(i).iter().any(|&p| view.to_camera(p).z < scene.camera().near))
            .count();
        let reference = frame(&scene, VisibilityMethod::RayCast, ShadowMethod::None);
        for v in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
            let got = frame(&scene, v, ShadowMethod::None);
            compared += assert_ids_agree(&scene, &reference, &got, &format!("seed {seed} {v}")).compared;
        }
    }
    assert!(compared > 300 * 2 * 500);
    // The random family does exercise interpenetration and near-plane clipping.
    assert!(splits > 100, "only {splits} Watkins span splits in 300 random scenes");
    assert!(clipped > 20, "only {clipped} polygons cross the near plane in 300 random scenes");
}

#[test]
fn generated_benchmark_scenes_agree() {
    let scenes = [
        umbra::generate::cubes(3, true, 160, 90).unwrap(),
        umbra::generate::stacked_quads(16, 160, 90).unwrap(),
        umbra::generate::spheres(2000, 4, 160, 90).unwrap(),
    ];
    for (i, scene) in scenes.iter().enumerate() {
        let reference = frame(scene, VisibilityMethod::RayCast, ShadowMethod::None);
        for v in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
            assert_ids_agree(scene, &reference, &frame(scene, v, ShadowMethod::None), &format!("generated {i} {v}"));
        }
    }
}
