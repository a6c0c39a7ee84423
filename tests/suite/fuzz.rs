//! A bounded fuzz run, as property tests: whatever the input, the engine answers with an
//! error or an image, never a panic, and no pixel of an image is NaN or infinite.
//!
//! - Random scene files built from adversarial values (zeros, negatives, huge and tiny
//!   numbers, degenerate, repeated and self-intersecting polygons, every light kind), each
//!   loaded and, when it loads, rendered on a tiny frame by every visibility and shadow stage.
//! - The example scenes and OBJ meshes with random bytes deleted, inserted or replaced, and
//!   lines repeated or dropped, each loaded and, when it loads, rendered.
//!
//! proptest shrinks a failure to a small input and records it in `proptest-regressions/`.
//! The runs are seeded, so CI sees the same cases every time; set `UMBRA_FUZZ_SEED` (a
//! number) and `UMBRA_FUZZ_CASES` to go looking for new ones, for example
//! `UMBRA_FUZZ_SEED=$RANDOM UMBRA_FUZZ_CASES=20000 cargo test --release --test fuzz`.

use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use std::path::Path;
use umbra::shadow::WilliamsOptions;
use umbra::{render, RenderOptions, Scene, ShadowMethod, VisibilityMethod};

/// Numbers that break naive code.
fn extreme() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        Just(-0.0),
        Just(1e-300),
        Just(-1e-300),
        Just(3e38),
        Just(1e300),
        Just(-1e300),
        Just(1e-7),
        (-1e6f64..1e6),
    ]
}

/// A coordinate: ordinary mostly, extreme sometimes (any finite coordinate is valid).
fn number() -> impl Strategy<Value = f64> {
    prop_oneof![6 => -3.0f64..3.0, 1 => extreme()]
}

/// A value with a valid range: inside it mostly, anything sometimes.
fn ranged(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    prop_oneof![12 => lo..hi, 1 => extreme()]
}

fn vec3() -> impl Strategy<Value = String> {
    (number(), number(), number()).prop_map(|(x, y, z)| format!("[{x:e}, {y:e}, {z:e}]"))
}

/// A position seen by the camera mostly: above the floor, within it.
fn position() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => (-3.0f64..3.0, 0.1f64..4.0, -3.0f64..3.0).prop_map(|(x, y, z)| format!("[{x:e}, {y:e}, {z:e}]")),
        1 => vec3(),
    ]
}

/// A polygon of 1 to 6 corners drawn from a small lattice (so corners repeat, edges are
/// shared and collinear, polygons cross themselves) or anywhere.
fn polygon() -> impl Strategy<Value = String> {
    let corner = prop_oneof![
        3 => (-2i32..=2, 0i32..=2, -2i32..=2).prop_map(|(x, y, z)| format!("[{x}.0, {y}.0, {z}.0]")),
        1 => vec3(),
    ];
    prop::collection::vec(corner, 1..7).prop_map(|c| format!("[{}]", c.join(", ")))
}

fn light() -> impl Strategy<Value = String> {
    let extra = (prop::option::of(ranged(0.0, 4.0)), prop::option::of(position())).prop_map(|(i, c)| {
        let mut s = String::new();
        if let Some(i) = i {
            s += &format!("intensity = {i:e}\n");
        }
        if let Some(c) = c {
            s += &format!("color = {c}\n");
        }
        s
    });
    let kind = prop_oneof![
        position().prop_map(|p| format!("kind = \"point\"\nposition = {p}\n")),
        vec3().prop_map(|d| format!("kind = \"directional\"\ndirection = {d}\n")),
        (position(), vec3(), ranged(1.0, 180.0), ranged(0.0, 50.0)).prop_map(|(p, d, c, e)| format!(
            "kind = \"spot\"\nposition = {p}\ndirection = {d}\ncutoff = {c:e}\nexponent = {e:e}\n"
        )),
        (position(), vec3(), vec3(), 1u32..4, 1u32..4).prop_map(|(c, u, v, m, n)| format!(
            "kind = \"area\"\ncorner = {c}\nedge_u = {u}\nedge_v = {v}\nsamples = [{m}, {n}]\n"
        )),
    ];
    (kind, extra).prop_map(|(k, e)| format!("[[light]]\n{k}{e}"))
}

fn scene_text() -> impl Strategy<Value = String> {
    let eye = prop_oneof![
        6 => (-4.0f64..4.0, 0.5f64..5.0, 4.0f64..8.0).prop_map(|(x, y, z)| format!("[{x:e}, {y:e}, {z:e}]")),
        1 => vec3(),
    ];
    let camera = (
        eye,
        position(),
        prop::option::of(vec3()),
        prop::option::of(ranged(1.0, 170.0)),
        1u32..24,
        1u32..18,
        prop::option::of(ranged(1e-3, 1.0)),
    )
        .prop_map(|(eye, target, up, fov, w, h, near)| {
            let mut s = format!("[camera]\neye = {eye}\ntarget = {target}\nwidth = {w}\nheight = {h}\n");
            if let Some(up) = up {
                s += &format!("up = {up}\n");
            }
            if let Some(f) = fov {
                s += &format!("fov_y = {f:e}\n");
            }
            if let Some(n) = near {
                s += &format!("near = {n:e}\n");
            }
            s
        });
    let material = (ranged(0.0, 1.0), ranged(0.0, 1.0), ranged(0.0, 200.0), ranged(0.01, 1.0), 0usize..3).prop_map(|(kd, ks, sh, r, m)| {
        let model = ["phong", "blinn", "cook-torrance"][m];
        format!("[[material]]\nname = \"m\"\nkd = {kd:e}\nks = {ks:e}\nshininess = {sh:e}\nroughness = {r:e}\nmodel = \"{model}\"\n")
    });
    let object = (prop::collection::vec(polygon(), 1..5), any::<bool>(), prop::option::of(ranged(0.1, 3.0))).prop_map(
        |(polys, casts, scale)| {
            let mut s = format!("[[object]]\npolygons = [{}]\ncasts_shadows = {casts}\n", polys.join(", "));
            if let Some(k) = scale {
                s += &format!("scale = {k:e}\n");
            }
            s
        },
    );
    (camera, prop::collection::vec(light(), 0..3), prop::option::of(material), prop::collection::vec(object, 0..4))
        .prop_map(|(c, lights, m, objects)| {
            // The floor and the camera looking at it make most cases render something.
            let floor = "[[object]]\npolygons = [[[-3.0,0.0,-3.0],[-3.0,0.0,3.0],[3.0,0.0,3.0],[3.0,0.0,-3.0]]]\n";
            format!("{c}{}{}{floor}{}", lights.concat(), m.unwrap_or_default(), objects.concat())
        })
}

/// `cases` cases from a fixed seed, unless `UMBRA_FUZZ_SEED` / `UMBRA_FUZZ_CASES` say
/// otherwise.
fn config(cases: u32) -> ProptestConfig {
    let var = |name: &str| std::env::var(name).ok().and_then(|v| v.parse::<u64>().ok());
    ProptestConfig {
        cases: var("UMBRA_FUZZ_CASES").map_or(cases, |n| n as u32),
        rng_seed: RngSeed::Fixed(var("UMBRA_FUZZ_SEED").unwrap_or(1977)),
        ..ProptestConfig::default()
    }
}

/// Renders with every visibility and shadow stage and checks the answer's invariants.
fn render_all(scene: &Scene) {
    let small_map = WilliamsOptions { map_size: 16, ..WilliamsOptions::default() };
    for v in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer, VisibilityMethod::RayCast] {
        for s in ShadowMethod::ALL {
            let s = match s {
                ShadowMethod::Williams(_) => ShadowMethod::Williams(small_map.clone()),
                other => other,
            };
            let opts = RenderOptions { visibility: v, shadows: s.clone(), ..Default::default() };
            // An error is an answer; a panic fails the test.
            let Ok(out) = render(scene, &opts) else { continue };
            let f = &out.frame;
            assert!(f.color.iter().all(|c| c.is_finite()), "{v} {s}: a non-finite pixel");
            for l in &f.light {
                assert!(l.iter().all(|x| (0.0..=1.0).contains(x)), "{v} {s}: a lit fraction outside [0, 1]");
            }
        }
    }
}

fn load(text: &str) -> Option<Scene> {
    Scene::from_toml(text, Path::new("fuzz.toml"), Path::new(env!("CARGO_MANIFEST_DIR"))).ok()
}

proptest! {
    #![proptest_config(config(1500))]

    /// Adversarial scene files: loaded, or refused with a one-line error naming the file;
    /// rendered by every stage without a panic or a non-finite pixel.
    #[test]
    fn adversarial_scenes(text in scene_text()) {
        match Scene::from_toml(&text, Path::new("fuzz.toml"), Path::new(".")) {
            Ok(scene) => render_all(&scene),
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(!msg.contains('\n') && msg.starts_with("fuzz.toml"), "{}", msg);
            }
        }
    }
}

/// One random edit of `text`: a byte deleted, inserted or replaced, or a line repeated or
/// dropped.
fn mutate(text: &str, edits: &[(u8, usize, u8)]) -> String {
    let mut bytes = text.as_bytes().to_vec();
    for &(op, at, b) in edits {
        if bytes.is_empty() {
            break;
        }
        let at = at % bytes.len();
        const JUNK: &[u8] = b"[]{}=,.\"#-+0123456789eE\n nan inf \xEF\xBB\xBF \xFF";
        let junk = JUNK[b as usize % JUNK.len()];
        match op % 5 {
            0 => {
                bytes.remove(at);
            }
            1 => bytes.insert(at, junk),
            2 => bytes[at] = junk,
            3 => {
                let start = bytes[..at].iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
                let end = bytes[at..].iter().position(|&c| c == b'\n').map_or(bytes.len(), |p| at + p + 1);
                let line = bytes[start..end].to_vec();
                bytes.splice(start..start, line);
            }
            _ => {
                let start = bytes[..at].iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
                let end = bytes[at..].iter().position(|&c| c == b'\n').map_or(bytes.len(), |p| at + p + 1);
                bytes.drain(start..end);
            }
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

const SEEDS: [&str; 3] = [
    include_str!("../../scenes/cornell.toml"),
    include_str!("../data/robustness/crow_pentagram_even_odd.toml"),
    include_str!("../data/robustness/crow_light_at_cube_vertex.toml"),
];

proptest! {
    #![proptest_config(config(1500))]

    /// Mangled scene files: an error or a scene, never a panic; a scene renders (shrunk to a
    /// tiny frame) with the default stages.
    #[test]
    fn mangled_scene_files(seed in 0usize..SEEDS.len(), edits in prop::collection::vec((any::<u8>(), any::<usize>(), any::<u8>()), 1..6)) {
        let text = mutate(SEEDS[seed], &edits);
        if let Some(mut scene) = load(&text) {
            {
                let mut c = scene.camera().clone();
                c.width = scene.camera().width.min(12);
                scene.set_camera(c).expect("a valid camera");
            }
            {
                let mut c = scene.camera().clone();
                c.height = scene.camera().height.min(9);
                scene.set_camera(c).expect("a valid camera");
            }
            if let Ok(out) = render(&scene, &RenderOptions::default()) {
                prop_assert!(out.frame.color.iter().all(|c| c.is_finite()));
            }
        }
    }

    /// Mangled OBJ text: an error naming the file, or a mesh.
    #[test]
    fn mangled_obj_files(edits in prop::collection::vec((any::<u8>(), any::<usize>(), any::<u8>()), 1..6)) {
        let text = mutate(include_str!("../data/robustness/closed_box.obj"), &edits);
        if let Err(e) = umbra::scene::parse_obj(&text, Path::new("m.obj")) {
            let msg = e.to_string();
            prop_assert!(!msg.contains('\n') && msg.starts_with("m.obj"), "{}", msg);
        }
    }
}

/// The adversarial family must mostly reach the renderer, or the fuzz run tests only the
/// loader's refusals: count how many of its scenes load.
#[test]
fn adversarial_scenes_mostly_load() {
    use proptest::strategy::ValueTree;
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let n = 300;
    let loaded = (0..n)
        .filter(|_| {
            let text = scene_text().new_tree(&mut runner).map(|t| t.current()).unwrap_or_default();
            load(&text).is_some()
        })
        .count();
    eprintln!("{loaded} of {n} adversarial scenes loaded");
    assert!(loaded * 2 > n, "only {loaded} of {n} adversarial scenes loaded");
}
