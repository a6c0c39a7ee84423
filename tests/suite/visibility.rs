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
        splits += umbra::render(&scene, &opts).unwrap().stats.visibility_counters.get(umbra::Counter::SpanSplits);
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
        umbra::generate::cubes(3, umbra::generate::Faces::Triangles, 160, 90).unwrap(),
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

/// Closed solids' polygons turned away from the eye are left out of the hidden-surface
/// stage: about half of a scene of spheres, with nothing seen changed (both frames agree
/// with ray-cast), and none of a solid that the near plane cuts open or that holds the eye.
#[test]
fn back_faces_of_closed_solids_are_left_out_and_nothing_seen_changes() {
    let screen = |scene: &umbra::Scene, cull: bool, v: VisibilityMethod| {
        let opts = umbra::RenderOptions {
            visibility: v,
            shadows: ShadowMethod::None,
            back_face_cull: cull,
            ..Default::default()
        };
        let r = umbra::render(scene, &opts).unwrap();
        (r.stats.visibility_counters.get(umbra::Counter::ScreenPolygons), r.frame)
    };
    let spheres = umbra::generate::spheres(2000, 4, 160, 90).unwrap();
    let reference = frame(&spheres, VisibilityMethod::RayCast, ShadowMethod::None);
    for v in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
        let ((culled, a), (all, b)) = (screen(&spheres, true, v), screen(&spheres, false, v));
        assert!(culled * 10 < all * 6 && culled * 10 > all * 3, "{v}: {culled} of {all} screen polygons kept");
        assert_ids_agree(&spheres, &reference, &a, &format!("{v} culled"));
        assert_ids_agree(&spheres, &reference, &b, &format!("{v} not culled"));
    }
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/robustness");
    // The near plane cuts the torus open: none left out. The eye is inside the room: only
    // the three faces of the box in the room that turn away from it are left out.
    for (name, left_out) in [("torus_near_cut.toml", 0), ("eye_inside_box.toml", 3)] {
        let scene = umbra::Scene::load(data.join(name)).unwrap();
        let (culled, _) = screen(&scene, true, VisibilityMethod::Scanline);
        let (all, _) = screen(&scene, false, VisibilityMethod::Scanline);
        assert_eq!(all - culled, left_out, "{name}");
    }
}
