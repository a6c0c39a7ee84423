//! The paper paths (`ShadowMethod::as_published`, `--paper`): Bouknight-Kelley's compares
//! every ordered pair, Crow 1977 equals ray-cast where its preconditions hold, and every
//! scene of `scenes/paper/` fails where `docs/algorithms/crow.md` says it does, while the
//! engineered default gets it right. (The paper paths of Bouknight-Kelley and
//! Atherton-Weiler-Greenberg are in the exact set, `common::exact_stages`, and are checked
//! against ray-cast wherever the defaults are.)

use crate::common::*;
use glam::DVec3;
use umbra::shadow::{BouknightKelleyOptions, Counting, VolumeOptions};
use umbra::{Light, Scene, ShadowMethod, VisibilityMethod};

fn reference(scene: &Scene) -> umbra::Frame {
    frame(scene, VisibilityMethod::RayCast, ShadowMethod::RayCast)
}

/// The pixels where `got` lights differently from `want` (no tie is excused: the failures
/// are whole regions).
fn wrong(want: &umbra::Frame, got: &umbra::Frame) -> usize {
    (0..want.id.len()).filter(|&k| want.light.iter().zip(&got.light).any(|(a, b)| a[k] != b[k])).count()
}

fn crow(counting: Counting) -> ShadowMethod {
    ShadowMethod::Crow(VolumeOptions { counting, ..Default::default() })
}

/// Each failure scene: the paper path is wrong at at least as many pixels as the docs'
/// table says (a tenth of it, at a quarter of the size), the engineered path nowhere.
#[test]
fn paper_failure_scenes_fail_where_the_docs_say() {
    let cases = [
        ("crow-light-inside.toml", Counting::ZPass, 155_361),
        ("crow-light-inside.toml", Counting::ZFail, 155_361),
        ("crow-open-mesh.toml", Counting::ZPass, 11_663),
        ("zpass-near-plane.toml", Counting::ZPass, 45_542),
        ("zfail-far-plane.toml", Counting::ZFail, 2_560),
    ];
    for (file, counting, at_full_size) in cases {
        let scene = load_scaled(&format!("scenes/paper/{file}").into(), 320);
        let want = reference(&scene);
        for v in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
            let paper = frame(&scene, v, crow(counting).as_published());
            let engineered = frame(&scene, v, crow(counting));
            let (bad, good) = (wrong(&want, &paper), wrong(&want, &engineered));
            assert!(
                bad * 40 >= at_full_size,
                "{file} {counting:?} behind {v}: the paper path is wrong at {bad} pixels"
            );
            assert_eq!(good, 0, "{file} {counting:?} behind {v}: the engineered path is wrong at {good} pixels");
        }
    }
}

/// Where its preconditions hold (closed, outward-wound objects and single polygons turned to
/// the light, lights outside every object, no volume across the near plane, no far plane),
/// Crow's 1977 construction equals ray-cast at every pixel but ties, by z-pass and z-fail,
/// and the stencil stage built the same way does too.
#[test]
fn crow_1977_is_exact_where_its_preconditions_hold() {
    let scenes = [
        umbra::generate::cubes(3, umbra::generate::Faces::Quads, 96, 72).unwrap(),
        umbra::generate::cubes(2, umbra::generate::Faces::Triangles, 96, 72).unwrap(),
        umbra::generate::spheres(800, 4, 96, 72).unwrap(),
    ];
    let lights = [DVec3::new(3.0, 6.0, 2.0), DVec3::new(-4.0, 3.0, -1.0), DVec3::new(0.3, 9.0, 0.2)];
    let mut shadowed_total = 0;
    for (i, base) in scenes.iter().enumerate() {
        for (j, &light) in lights.iter().enumerate() {
            let mut scene = base.clone();
            scene.set_lights(vec![Light::point(light)]).unwrap();
            let want = reference(&scene);
            shadowed_total += shadowed(&want);
            for counting in [Counting::ZPass, Counting::ZFail] {
                for m in [crow(counting), ShadowMethod::StencilVolume(VolumeOptions { counting, ..Default::default() })]
                {
                    let m = m.as_published();
                    assert!(m.is_paper());
                    let got = frame(&scene, VisibilityMethod::Scanline, m.clone());
                    assert_light_agree(&scene, &want, &got, &format!("scene {i} light {j} {}", m.label()));
                }
            }
        }
    }
    assert!(shadowed_total > 1000, "the scenes show only {shadowed_total} shadowed pixels");
}

/// Bouknight-Kelley's paper path makes every polygon the light faces on its seen side a
/// receiver (not only those seen) and compares its extent with every other caster's; on a
/// scene whose polygons all face the eye and the light, that is every ordered pair, n(n−1).
#[test]
fn the_paper_path_compares_every_ordered_pair() {
    // Quads stacked toward the camera, the light behind the camera: every one faces both.
    let mut scene = umbra::generate::stacked_quads(12, 64, 48).unwrap();
    let eye = scene.camera().eye;
    scene.set_lights(vec![Light::point(eye + DVec3::new(0.5, 1.0, 0.5))]).unwrap();
    let n = scene.polygons().len() as u64;
    let run = |o: BouknightKelleyOptions| {
        let opts = umbra::RenderOptions { shadows: ShadowMethod::BouknightKelley(o), ..Default::default() };
        umbra::render(&scene, &opts).unwrap()
    };
    let paper = run(BouknightKelleyOptions::PAPER);
    let c = &paper.stats.shadow_counters;
    assert_eq!(c.get(umbra::Counter::Pairs), n * (n - 1));
    assert_eq!(c.get(umbra::Counter::Receivers), n, "every polygon is a receiver");
    assert_eq!(c.get(umbra::Counter::PairsTestedByPrefilter), n * (n - 1), "every ordered pair is compared");
    assert_eq!(c.get(umbra::Counter::PairsDroppedBehind), 0, "the paper drops nothing unprojected");
    assert_eq!(c.get(umbra::Counter::PairsOutsideReceiver), 0, "the paper has no wedge");
    // The default finds the same shadows with fewer tests, and lights the same pixels.
    let default = run(BouknightKelleyOptions::DEFAULT);
    assert_eq!(default.stats.shadow_counters.get(umbra::Counter::PairsTestedByPrefilter), 0);
    assert_eq!(paper.frame.light, default.frame.light);
}

/// Paper paths say so in reports, and only stages with steps of ours have one.
#[test]
fn paper_paths_are_labelled() {
    for m in ShadowMethod::ALL {
        let p = m.as_published();
        assert_eq!(p.is_paper(), m.has_paper_path(), "{}", m.name());
        assert_eq!(p.label().ends_with(" (paper)"), m.has_paper_path(), "{}", p.label());
        assert!(!m.is_paper(), "{} is engineered by default", m.name());
    }
    assert!(!crow(Counting::ZPass).as_published().is_exact());
    assert!(ShadowMethod::DEFAULT.as_published().is_exact());
}
