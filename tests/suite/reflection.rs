//! Planar mirrors: both methods of the "Special Effect" notes see, through the mirror, the face that one
//! ray-cast bounce sees, at every interior pixel; a mirror seen from behind reflects nothing.

use crate::common;

use common::*;
use umbra::reference::mirror_ids as reference_mirror_ids;
use umbra::ReflectionMethod;
use umbra::BACKGROUND;
use umbra::{render, RenderOptions, Scene};

fn mirror_scene() -> Scene {
    load_scaled(&std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/mirror.toml"), 320)
}

fn mirror_ids(scene: &Scene, reflection: ReflectionMethod) -> umbra::Frame {
    render(scene, &RenderOptions { reflection, ..Default::default() }).unwrap().frame
}

#[test]
fn both_methods_see_what_one_bounce_sees() {
    let reflected = agree_with_one_bounce(&mirror_scene());
    assert!(reflected > 1000, "only {reflected} pixels see something in the mirror");
}

/// The far plane cuts a reflection where the eye sees it, at the depth of the virtual image
/// behind the mirror (eye to mirror to object): both methods and the one-bounce reference
/// agree wherever the far plane is, including where it cuts the reflection partly.
#[test]
fn the_far_plane_cuts_reflections_at_the_virtual_image() {
    let full = agree_with_one_bounce(&mirror_scene());
    let mut partly = false;
    for far in [6.0, 9.0, 11.0, 13.0, 16.0, 20.0] {
        let mut scene = mirror_scene();
        {
            let mut c = scene.camera().clone();
            c.far = Some(far);
            scene.set_camera(c).expect("a valid camera");
        }
        let seen = agree_with_one_bounce(&scene);
        partly |= seen > 100 && seen + 100 < full;
    }
    assert!(partly, "no far plane tried cuts the reflection partly");
}

/// Asserts that both methods see, through the mirror, what one ray-cast bounce sees at every
/// interior pixel; returns how many interior pixels see something in the mirror.
fn agree_with_one_bounce(scene: &Scene) -> usize {
    let want = reference_mirror_ids(scene);
    let (w, h) = (scene.camera().width as usize, scene.camera().height as usize);
    let interior = |x: usize, y: usize| {
        x > 0
            && y > 0
            && x + 1 < w
            && y + 1 < h
            && (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| want[yy * w + xx] == want[y * w + x]))
    };
    let mut seen = 0;
    for method in [ReflectionMethod::ReflectEye, ReflectionMethod::ReflectScene] {
        let frame = mirror_ids(scene, method);
        let none = vec![BACKGROUND; w * h];
        let got = frame.mirror_id.as_ref().unwrap_or(&none);
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
        seen = reflected;
    }
    seen
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
    {
        let mut c = scene.camera().clone();
        c.eye = glam::DVec3::new(0.0, 1.5, -6.0);
        scene.set_camera(c).expect("a valid camera");
    }
    {
        let mut c = scene.camera().clone();
        c.target = glam::DVec3::new(0.0, 1.5, 0.0);
        scene.set_camera(c).expect("a valid camera");
    }
    for method in [ReflectionMethod::ReflectEye, ReflectionMethod::ReflectScene] {
        assert!(mirror_ids(&scene, method).mirror_id.is_none());
    }
    assert!(reference_mirror_ids(&scene).iter().all(|&i| i == BACKGROUND));
}

/// A mirror's scene is the scene's polygons clipped, mirrored and renumbered, so the closed
/// solids of the scene are not its solids: Bouknight-Kelley's solid cull must see none there.
/// With the mirror listed first (every polygon after it renumbered), a closed block and, after
/// it, a card turned away from the light, the cull still changes no pixel of the frame or of
/// what the mirror shows.
#[test]
fn the_solid_cull_changes_nothing_in_a_mirror() {
    use umbra::shadow::{BouknightKelleyOptions, ShadowMethod};
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/mirror.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let mirror = "[[object]]\nname = \"mirror\"\nmaterial = \"mirror\"\npolygons = [ [[-2.5,0.3,-2.45],[1.5,0.3,-2.45],[1.5,2.8,-2.45],[-2.5,2.8,-2.45]] ]\n";
    assert!(text.contains(mirror));
    let bottom = "  [[-0.5,-0.5,-0.5],[0.5,-0.5,-0.5],[0.5,-0.5,0.5],[-0.5,-0.5,0.5]],\n]\nscale = [1.0, 1.6, 1.0]";
    let text = text.replacen(mirror, "", 1).replacen("]\nscale = [1.0, 1.6, 1.0]", bottom, 1);
    let text = text.replacen("[[object]]\nname = \"floor\"", &format!("{mirror}\n[[object]]\nname = \"floor\""), 1);
    // A card after the block, turned away from the light: not part of any solid.
    let card = "translate = [-1.2, 0.8, -0.3]\n\n[[object]]\nname = \"card\"\nmaterial = \"yellow\"\npolygons = [ [[-0.4,1.5,0.8],[0.4,1.5,0.8],[0.4,1.5,1.6],[-0.4,1.5,1.6]] ]\n";
    let text = text.replacen("translate = [-1.2, 0.8, -0.3]\n", card, 1);
    let mut scene = Scene::from_toml(&text, &path, path.parent().unwrap()).unwrap();
    let mut c = scene.camera().clone();
    (c.width, c.height) = (240, 180);
    scene.set_camera(c).unwrap();
    let render_with = |solid_cull| {
        let shadows = ShadowMethod::BouknightKelley(BouknightKelleyOptions { solid_cull, ..Default::default() });
        render(&scene, &RenderOptions { shadows, ..Default::default() }).unwrap()
    };
    let (on, off) = (render_with(true), render_with(false));
    assert!(on.stats.shadow_counters.get(umbra::Counter::CastersDroppedFacingAway) > 0, "the closed block is culled");
    assert_eq!(on.frame.light, off.frame.light);
    let differ = on.frame.color.iter().zip(&off.frame.color).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} pixels differ");
}
