//! Planar mirrors: both of seed 003's methods see, through the mirror, the face that one
//! ray-cast bounce sees, at every interior pixel; a mirror seen from behind reflects nothing.

mod common;

use common::*;
use umbra::frame::BACKGROUND;
use umbra::reflection::{reference_mirror_ids, ReflectionMethod};
use umbra::{render, RenderOptions, Scene};

fn mirror_scene() -> Scene {
    load_scaled(&std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/mirror.toml"), 320)
}

fn mirror_ids(scene: &Scene, reflection: ReflectionMethod) -> umbra::Frame {
    render(scene, &RenderOptions { reflection, ..Default::default() }).unwrap().frame
}

#[test]
fn both_methods_see_what_one_bounce_sees() {
    let scene = mirror_scene();
    let want = reference_mirror_ids(&scene);
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let interior = |x: usize, y: usize| {
        x > 0
            && y > 0
            && x + 1 < w
            && y + 1 < h
            && (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| want[yy * w + xx] == want[y * w + x]))
    };
    for method in [ReflectionMethod::ReflectEye, ReflectionMethod::ReflectScene] {
        let frame = mirror_ids(&scene, method);
        let got = frame.mirror_id.as_ref().expect("the mirror is seen");
        let (mut compared, mut reflected, mut bad) = (0, 0, Vec::new());
        for y in 0..h {
            for x in 0..w {
                if !interior(x, y) {
                    continue;
                }
                compared += 1;
                reflected += (want[y * w + x] != BACKGROUND) as usize;
                if got[y * w + x] != want[y * w + x] {
                    bad.push((x, y, want[y * w + x], got[y * w + x]));
                }
            }
        }
        assert!(bad.is_empty(), "{method:?}: {} of {compared} differ: {:?}", bad.len(), &bad[..bad.len().min(8)]);
        assert!(reflected > 1000, "{method:?}: only {reflected} pixels see something in the mirror");
    }
}

#[test]
fn the_two_methods_agree_on_colour() {
    let scene = mirror_scene();
    let (a, b) = (mirror_ids(&scene, ReflectionMethod::ReflectEye), mirror_ids(&scene, ReflectionMethod::ReflectScene));
    let ids = a.mirror_id.as_ref().unwrap();
    let mut differ = 0;
    for (k, (p, q)) in a.color.iter().zip(&b.color).enumerate() {
        if ids[k] != BACKGROUND && (*p - *q).abs().max_element() > 1e-3 {
            differ += 1;
        }
    }
    // Only pixels on edges of the reflected geometry may differ (ties at pixel centres).
    assert!(differ < 300, "{differ} mirror pixels differ in colour between the methods");
}

#[test]
fn a_mirror_seen_from_behind_reflects_nothing() {
    let mut scene = mirror_scene();
    // Look at the back of the mirror, from behind the wall.
    scene.camera.eye = glam::DVec3::new(0.0, 1.5, -6.0);
    scene.camera.target = glam::DVec3::new(0.0, 1.5, 0.0);
    for method in [ReflectionMethod::ReflectEye, ReflectionMethod::ReflectScene] {
        assert!(mirror_ids(&scene, method).mirror_id.is_none());
    }
    assert!(reference_mirror_ids(&scene).iter().all(|&i| i == BACKGROUND));
}
