//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;
use umbra::shadow::ShadowOptions;
use umbra::{render, Frame, RenderOptions, Scene, ShadowMethod, VisibilityMethod};

/// Every scene file in `scenes/`.
pub fn scene_files() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("scenes/ exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    assert!(v.len() >= 5, "scenes/ should hold the example scenes");
    v
}

/// Loads a scene and shrinks its image to at most `max_width` pixels wide (same aspect).
pub fn load_scaled(path: &PathBuf, max_width: u32) -> Scene {
    let mut s = Scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    if s.camera.width > max_width {
        let h = (s.camera.height as u64 * max_width as u64 / s.camera.width as u64).max(1) as u32;
        s.camera.width = max_width;
        s.camera.height = h;
    }
    s
}

pub fn frame(scene: &Scene, visibility: VisibilityMethod, shadows: ShadowMethod) -> Frame {
    frame_with(scene, visibility, shadows, ShadowOptions::default())
}

pub fn frame_with(
    scene: &Scene,
    visibility: VisibilityMethod,
    shadows: ShadowMethod,
    shadow_options: ShadowOptions,
) -> Frame {
    let opts = RenderOptions { visibility, shadows, shadow_options, ..Default::default() };
    render(scene, &opts).unwrap_or_else(|e| panic!("{e}")).frame
}

/// The exact scanline-family stages, with the options that make them exact.
pub fn exact_stages() -> Vec<(String, ShadowMethod, ShadowOptions)> {
    use umbra::shadow::volumes::Counting;
    let d = ShadowOptions::default;
    vec![
        ("bouknight-kelley".into(), ShadowMethod::BouknightKelley, d()),
        (
            "bouknight-kelley --no-prefilter".into(),
            ShadowMethod::BouknightKelley,
            ShadowOptions { prefilter: false, ..d() },
        ),
        ("atherton-weiler-greenberg".into(), ShadowMethod::AthertonWeilerGreenberg, d()),
        ("crow zpass".into(), ShadowMethod::Crow, ShadowOptions { crow_count: Counting::ZPass, ..d() }),
        ("crow zfail".into(), ShadowMethod::Crow, ShadowOptions { crow_count: Counting::ZFail, ..d() }),
        (
            "stencil-volume zpass".into(),
            ShadowMethod::StencilVolume,
            ShadowOptions { crow_count: Counting::ZPass, ..d() },
        ),
        (
            "stencil-volume zfail".into(),
            ShadowMethod::StencilVolume,
            ShadowOptions { crow_count: Counting::ZFail, ..d() },
        ),
    ]
}

/// Compares `got` with `reference` at the pixels `interior` picks, collecting `wrong(k)`'s
/// findings; panics with the first few when there are any. Returns the pixels compared.
fn assert_agree<T: std::fmt::Debug>(
    reference: &Frame,
    label: &str,
    what: &str,
    interior: impl Fn(u32, u32) -> bool,
    wrong: impl Fn(u32, u32, usize) -> Vec<T>,
) -> usize {
    let mut compared = 0;
    let mut bad = Vec::new();
    for y in 0..reference.height {
        for x in 0..reference.width {
            if interior(x, y) {
                compared += 1;
                bad.extend(wrong(x, y, (y * reference.width + x) as usize));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "{label}: {} of {compared} interior pixels differ ({what}): {:?}",
        bad.len(),
        &bad[..bad.len().min(10)]
    );
    compared
}

/// Asserts that `got` sees the same face as `reference` at every pixel whose 3x3
/// neighbourhood in `reference` has one face id. Returns the number of pixels compared.
pub fn assert_ids_agree(reference: &Frame, got: &Frame, label: &str) -> usize {
    assert_agree(
        reference,
        label,
        "x, y, want, got",
        |x, y| reference.is_id_interior(x, y),
        |x, y, k| {
            if reference.id[k] != got.id[k] {
                vec![(x, y, reference.id[k], got.id[k])]
            } else {
                vec![]
            }
        },
    )
}

/// Asserts that `got` has the same face id and lit fraction of every light as `reference`
/// at every pixel whose 3x3 neighbourhood in `reference` is uniform in id and light values.
pub fn assert_light_agree(reference: &Frame, got: &Frame, label: &str) -> usize {
    assert_agree(
        reference,
        label,
        "x, y, light, want, got",
        |x, y| reference.is_interior(x, y),
        |x, y, k| {
            (0..reference.light.len())
                .filter(|&l| reference.id[k] != got.id[k] || reference.light[l][k] != got.light[l][k])
                .map(|l| (x, y, l, reference.light[l][k], got.light[l][k]))
                .collect()
        },
    )
}

/// Interior pixels of `reference` (as in [`assert_light_agree`]) where some light is not
/// fully lit: evidence that a test compares shadows, not just lit floors.
pub fn shadowed_interior(reference: &Frame) -> usize {
    let mut n = 0;
    for y in 0..reference.height {
        for x in 0..reference.width {
            let k = (y * reference.width + x) as usize;
            if reference.is_interior(x, y) && reference.id[k] != u32::MAX && reference.light.iter().any(|l| l[k] < 1.0)
            {
                n += 1;
            }
        }
    }
    n
}
