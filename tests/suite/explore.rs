//! `umbra explore`'s JSON API, answered without a server: the same traces as `trace`, clear
//! errors for bad requests, many requests at once, and the static export. The page itself is
//! tested in a real browser by `tests/browser/explore.test.mjs` (run by `.ci/run`).

use serde_json::Value;
use umbra::shadow::ShadowMethod;
use umbra::study::explore::{export, Explorer, Response};
use umbra::study::trace::trace;
use umbra::Scene;

fn cornell() -> Scene {
    Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell.toml")).unwrap()
}

fn json(r: &Response) -> Value {
    assert_eq!(r.content_type, "application/json");
    serde_json::from_slice(&r.body).unwrap()
}

#[test]
fn a_traced_line_is_what_trace_gives_at_the_requested_size() {
    let explorer = Explorer::new(cornell(), "cornell");
    let mut small = cornell();
    let mut camera = small.camera().clone();
    (camera.width, camera.height) = (320, 240);
    small.set_camera(camera).unwrap();
    for stage in [
        ShadowMethod::BouknightKelley(Default::default()),
        ShadowMethod::Crow(Default::default()),
        ShadowMethod::AthertonWeilerGreenberg(Default::default()),
    ] {
        for line in [0, 77, 130, 239] {
            let r = explorer.handle(&format!("/api/trace?line={line}&shadows={}&width=320&height=240", stage.name()));
            assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
            let want = serde_json::to_string(&trace(&small, line, &stage).unwrap()).unwrap();
            // Both through the same text, so that both round the same way.
            let want: Value = serde_json::from_str(&want).unwrap();
            assert_eq!(json(&r), want, "{} line {line}", stage.name());
        }
    }
}

#[test]
fn the_frame_marks_no_pixel_for_exact_stages_and_is_an_image() {
    let explorer = Explorer::new(cornell(), "cornell");
    let frame = |stage: &str| json(&explorer.handle(&format!("/api/frame?shadows={stage}&width=200&height=150")));
    // Every exact stage the engine lists (the scene's light is a point light: each is held
    // to ray-cast).
    for stage in ShadowMethod::ALL.iter().filter(|m| m.is_exact() && **m != ShadowMethod::RayCast) {
        assert_eq!(frame(stage.name())["differs"]["wrong_total"], 0, "{stage}");
    }
    // The shadow map is approximate: its differences are counted, whatever they are.
    let williams = frame("williams");
    assert!(williams["stats"]["shadow_counters"]["map_lookups"].as_u64().unwrap() > 0);
    assert!(williams["differs"]["wrong_total"].as_u64().is_some());
    // The shadow map's pictures: a point light's six cube faces, each a PNG.
    assert_eq!(williams["pictures"].as_array().unwrap().len(), 6);
    let face = explorer.handle("/api/picture?shadows=williams&width=200&height=150&index=5");
    assert_eq!((face.status, face.content_type), (200, "image/png"));
    assert!(image::load_from_memory(&face.body).unwrap().width() > 100);
    let none = explorer.handle("/api/picture?shadows=williams&width=200&height=150&index=6");
    assert!(none.status == 400 && json(&none)["error"].as_str().unwrap().contains("no such picture"));
    let image = explorer.handle("/api/image?shadows=crow&width=200&height=150");
    assert_eq!((image.status, image.content_type), (200, "image/png"));
    let png = image::load_from_memory(&image.body).unwrap();
    assert_eq!((png.width(), png.height()), (200, 150));
}

#[test]
fn moving_the_light_moves_the_shadows() {
    let explorer = Explorer::new(cornell(), "cornell");
    let at = |q: &str| explorer.handle(&format!("/api/image?shadows=crow&width=160&height=120{q}")).body;
    let (here, there) = (at(""), at("&light=-2,5,2"));
    assert_ne!(here, there);
    let moved = json(&explorer.handle("/api/frame?shadows=crow&width=160&height=120&light=-2%2C5%2C2"));
    assert_eq!(moved["lights"][0]["at"], serde_json::json!([-2.0, 5.0, 2.0]));
    assert_eq!(moved["differs"]["wrong_total"], 0);
}

#[test]
fn bad_requests_get_a_json_error() {
    let explorer = Explorer::new(cornell(), "cornell");
    for (url, says) in [
        ("/api/trace?line=480", "is not inside the image"),
        ("/api/trace?line=-1", "not a line number"),
        ("/api/trace", "missing parameter 'line'"),
        ("/api/trace?line=3&shadows=bogus", "unknown shadow method 'bogus'"),
        ("/api/frame?width=0", "from 1 to 2048"),
        ("/api/frame?height=99999", "from 1 to 2048"),
        ("/api/frame?light=1,NaN,2", "three finite numbers"),
        ("/api/frame?light=1,2", "three finite numbers"),
        ("/api/frame?colour=red", "unknown parameter 'colour'"),
    ] {
        let r = explorer.handle(url);
        assert_eq!(r.status, 400, "{url}");
        let error = json(&r)["error"].as_str().unwrap().to_owned();
        assert!(error.contains(says), "{url}: {error}");
    }
    let r = explorer.handle("/etc/passwd");
    assert_eq!(r.status, 404);
    assert!(json(&r)["error"].as_str().unwrap().contains("no such page"));
}

#[test]
fn many_requests_at_once_are_all_answered_alike() {
    let explorer = Explorer::new(cornell(), "cornell");
    let urls: Vec<String> = (0..16)
        .map(|i| {
            let stage = ["crow", "bouknight-kelley", "ray-cast", "williams"][i % 4];
            format!("/api/trace?line={}&shadows={stage}&width=160&height=120", 7 * i)
        })
        .collect();
    let alone: Vec<Response> = urls.iter().map(|u| explorer.handle(u)).collect();
    let together: Vec<Response> = std::thread::scope(|s| {
        let asks: Vec<_> = urls.iter().map(|u| s.spawn(|| explorer.handle(u))).collect();
        asks.into_iter().map(|a| a.join().unwrap()).collect()
    });
    assert!(alone.iter().all(|r| r.status == 200));
    assert_eq!(alone, together);
}

#[test]
fn the_export_holds_every_line_of_every_applicable_stage() {
    let scratch = tempfile::Builder::new().prefix("umbra-explore-export-").tempdir().unwrap();
    let dir = scratch.path();
    let explorer = Explorer::new(cornell(), "cornell");
    export(&explorer, dir, 64, 48, &ShadowMethod::ALL).unwrap();
    for name in ["index.html", "explore.js", "explore.css", "data.js"] {
        assert!(dir.join(name).is_file(), "{name}");
    }
    let page = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert!(page.contains(r#"<script src="data.js"></script>"#));
    let watkins = std::fs::read_to_string(dir.join("lines/watkins.js")).unwrap();
    assert_eq!(watkins.lines().count(), 48);
    assert!(watkins.lines().all(|l| l.starts_with("umbraLine({") && l.ends_with("});")));
    let watkins = std::fs::read_to_string(dir.join("lines/watkins.js")).unwrap();
    assert_eq!(watkins.lines().count(), 48);
    assert!(watkins.lines().all(|l| l.starts_with("umbraLine({") && l.ends_with("});")));
    for stage in ["bouknight-kelley", "crow", "atherton-weiler-greenberg", "ray-cast", "williams"] {
        let lines = std::fs::read_to_string(dir.join(format!("lines/{stage}.js"))).unwrap();
        assert_eq!(lines.lines().count(), 48, "{stage}");
        assert!(lines.lines().all(|l| l.starts_with(&format!("umbraDecisions(\"{stage}\", ")) && l.ends_with("]);")));
        assert!(dir.join(format!("frames/{stage}.png")).is_file());
    }
}

/// The explorer's frame summary carries seed 000's penumbra of the first area light (the
/// page draws it with its "penumbra" box): on the lights scene, light 3 (4×4 samples), with
/// the same counts as the render's counters.
#[test]
fn the_frame_summary_carries_the_penumbra_of_an_area_light() {
    let scene = umbra::Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/lights.toml")).unwrap();
    let explorer = umbra::study::explore::Explorer::new(scene, "lights");
    let r = explorer.handle("/api/frame?shadows=bouknight-kelley&width=160&height=120");
    assert_eq!(r.status, 200);
    let v: serde_json::Value = serde_json::from_slice(&r.body).unwrap();
    let p = &v["penumbra"];
    assert_eq!(p["light"], 3);
    let (umbra, penumbra) = (p["umbra_total"].as_u64().unwrap(), p["penumbra_total"].as_u64().unwrap());
    assert!(umbra > 0 && penumbra > 0, "{p}");
    assert_eq!(p["pixels"].as_array().unwrap().len() as u64, penumbra);
    let c = &v["stats"]["shadow_counters"];
    assert_eq!((c["umbra_pixels"].as_u64(), c["penumbra_pixels"].as_u64()), (Some(umbra), Some(penumbra)));
}

/// A picked pixel's view of the area light (`api/light`): the reference's visible part of the
/// light, its area the exact fraction `Reference::exact_fraction_at` gives, with the
/// occluders' shadows; a pixel outside the image is refused.
#[test]
fn a_picked_pixel_shows_what_its_point_sees_of_the_area_light() {
    let mut scene = umbra::Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/lights.toml")).unwrap();
    let mut camera = scene.camera().clone();
    (camera.width, camera.height) = (160, 120);
    scene.set_camera(camera).unwrap();
    let explorer = umbra::study::explore::Explorer::new(scene.clone(), "lights");
    let oracle = umbra::reference::Reference::new(&scene);
    let mut penumbra = 0;
    for (x, y) in [(60, 80), (80, 90), (100, 70), (40, 100), (120, 60), (75, 85), (90, 95)] {
        let r = explorer.handle(&format!("/api/light?width=160&height=120&x={x}&line={y}"));
        assert_eq!(r.status, 200);
        let v: Value = serde_json::from_slice(&r.body).unwrap();
        assert_eq!(v["light"], 3);
        let want = oracle.exact_fraction_at(3, x as f64 + 0.5, y as f64 + 0.5).unwrap();
        let got = v["fraction"].as_f64().unwrap();
        assert!((got - want).abs() < 1e-12, "({x}, {y}): {got} against {want}");
        let seen = oracle.light_view_at(3, x as f64 + 0.5, y as f64 + 0.5).unwrap();
        let area: f64 = seen.visible.iter().map(|r| signed_area(r)).sum::<f64>().abs();
        assert!((area - want).abs() < 1e-9, "({x}, {y}): the visible rings' area {area} against {want}");
        if want > 0.0 && want < 1.0 {
            penumbra += 1;
            assert!(!seen.hidden.is_empty(), "({x}, {y}): a penumbra point with no occluder");
        }
    }
    assert!(penumbra > 0, "no pixel of the sample is in the penumbra");
    let r = explorer.handle("/api/light?width=160&height=120&x=160&line=0");
    assert_eq!(r.status, 400);
    assert!(String::from_utf8_lossy(&r.body).contains("x 160 is not a whole number below 160"));
}

/// A ring's signed area (shoelace).
fn signed_area(r: &[glam::DVec2]) -> f64 {
    (0..r.len()).map(|i| r[i].perp_dot(r[(i + 1) % r.len()])).sum::<f64>() / 2.0
}
