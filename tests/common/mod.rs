//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;
use umbra::reference::{Reference, Tie};
use umbra::{render, Frame, RenderOptions, Scene, ShadowMethod, VisibilityMethod};

/// Every scene file in `scenes/`.
pub fn scene_files() -> Vec<PathBuf> {
    toml_files("scenes", 5)
}

/// The `.toml` files of folder `dir` (relative to the crate), sorted; at least `least`.
pub fn toml_files(dir: &str, least: usize) -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    assert!(v.len() >= least, "{} should hold at least {least} scenes: {v:?}", dir.display());
    v
}

/// Loads a scene and shrinks its image to at most `max_width` pixels wide (same aspect).
pub fn load_scaled(path: &PathBuf, max_width: u32) -> Scene {
    let mut s = Scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    if s.camera().width > max_width {
        let h = (s.camera().height as u64 * max_width as u64 / s.camera().width as u64).max(1) as u32;
        {
            let mut c = s.camera().clone();
            c.width = max_width;
            s.set_camera(c).expect("a valid camera");
        }
        {
            let mut c = s.camera().clone();
            c.height = h;
            s.set_camera(c).expect("a valid camera");
        }
    }
    s
}

pub fn frame(scene: &Scene, visibility: VisibilityMethod, shadows: ShadowMethod) -> Frame {
    let opts = RenderOptions { visibility, shadows, ..Default::default() };
    render(scene, &opts).unwrap_or_else(|e| panic!("{e}")).frame
}

/// Every exact stage but the reference, in each of its settings that a study tells apart
/// (`ShadowMethod::variants`), named as on the command line: all of them from the engine's
/// list, so that a new stage is checked against ray-cast as soon as it is registered. The
/// stages that give area lights their exact fraction are judged by `tests/suite/area.rs`.
pub fn exact_stages() -> Vec<(String, ShadowMethod)> {
    ShadowMethod::ALL
        .iter()
        .filter(|m| **m != ShadowMethod::RayCast && !m.exact_area_fraction())
        .flat_map(ShadowMethod::variants)
        .filter(ShadowMethod::is_exact)
        .map(|m| (m.command_line(), m))
        .collect()
}

/// Compares `got` with `reference` at every pixel by `differs(k)`; a pixel that differs is
/// excused only when it is a tie by [`umbra::reference`]'s definition (the exact answer
/// changes within 1e-6 of a pixel of its centre). Panics with the first few pixels that
/// differ and are not ties, or when edge ties are more than 1% of the pixels (an edge tie is
/// a pixel centre exactly on an edge; that many means something else is wrong; a light in
/// the plane of the surface seen can make a whole face a tie). Returns the pixels compared
/// and the ties excused.
fn assert_agree<T: std::fmt::Debug>(
    scene: &Scene,
    reference: &Frame,
    label: &str,
    what: &str,
    differs: impl Fn(u32, u32, usize) -> Vec<T>,
) -> Agreement {
    let oracle = std::cell::OnceCell::new();
    let (mut ties, mut edge_ties, mut bad) = (0, 0, Vec::new());
    for y in 0..reference.height {
        for x in 0..reference.width {
            let found = differs(x, y, (y * reference.width + x) as usize);
            if found.is_empty() {
                continue;
            }
            match oracle.get_or_init(|| Reference::new(scene)).tie(x, y) {
                Some(kind) => {
                    ties += 1;
                    edge_ties += usize::from(kind == Tie::Edge);
                }
                None => bad.extend(found),
            }
        }
    }
    let compared = (reference.width * reference.height) as usize;
    assert!(
        bad.is_empty(),
        "{label}: {} of {compared} pixels differ and are not ties ({what}): {:?}",
        bad.len(),
        &bad[..bad.len().min(10)]
    );
    assert!(edge_ties * 100 <= compared, "{label}: {edge_ties} of {compared} pixels differ at edge ties");
    Agreement { compared, ties }
}

/// What a comparison covered.
#[derive(Debug, Clone, Copy, Default)]
pub struct Agreement {
    /// Pixels compared (all of them).
    pub compared: usize,
    /// Pixels that differed at a tie, excused.
    pub ties: usize,
}

impl std::ops::AddAssign for Agreement {
    fn add_assign(&mut self, o: Agreement) {
        self.compared += o.compared;
        self.ties += o.ties;
    }
}

/// Asserts that `got` sees the same face as `reference` at every pixel but ties.
pub fn assert_ids_agree(scene: &Scene, reference: &Frame, got: &Frame, label: &str) -> Agreement {
    assert_agree(scene, reference, label, "x, y, want, got", |x, y, k| {
        if reference.id[k] != got.id[k] {
            vec![(x, y, reference.id[k], got.id[k])]
        } else {
            vec![]
        }
    })
}

/// Asserts that `got` has the same face id and lit fraction of every light as `reference`
/// at every pixel but ties.
pub fn assert_light_agree(scene: &Scene, reference: &Frame, got: &Frame, label: &str) -> Agreement {
    assert_lights_agree(scene, reference, got, label, &(0..reference.light.len()).collect::<Vec<_>>())
}

/// [`assert_light_agree`] on the lights `lights` only.
pub fn assert_lights_agree(scene: &Scene, reference: &Frame, got: &Frame, label: &str, lights: &[usize]) -> Agreement {
    assert_agree(scene, reference, label, "x, y, light, want, got", |x, y, k| {
        lights
            .iter()
            .copied()
            .filter(|&l| reference.id[k] != got.id[k] || reference.light[l][k] != got.light[l][k])
            .map(|l| (x, y, l, reference.light[l][k], got.light[l][k]))
            .collect()
    })
}

/// Pixels of `reference` that see a surface some light does not fully reach: evidence that a
/// test compares shadows, not just lit floors.
pub fn shadowed(reference: &Frame) -> usize {
    (0..reference.id.len())
        .filter(|&k| reference.id[k] != u32::MAX && reference.light.iter().any(|l| l[k] < 1.0))
        .count()
}

/// Asserts that `got`'s lit fraction of every area light is the exact fraction
/// (`umbra::reference::exact_fraction`) within one grey level: `round(255 f)` one apart at
/// most, at every pixel whose seen face is the reference's at the centre and 1e-6 of a pixel
/// around it (elsewhere the pixel is an edge tie). Returns the pixels compared and, of them,
/// those in the exact penumbra.
pub fn assert_area_exact(scene: &Scene, got: &Frame, label: &str) -> (usize, usize) {
    let oracle = Reference::new(scene);
    let areas: Vec<usize> = (0..scene.lights().len())
        .filter(|&l| matches!(scene.lights()[l].kind, umbra::scene::LightKind::Area { .. }))
        .collect();
    let (mut compared, mut penumbra, mut bad) = (0, 0, Vec::new());
    let t = umbra::reference::TIE_DELTA;
    for y in 0..got.height {
        for x in 0..got.width {
            let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
            let Some((poly, _)) = oracle.visible(cx, cy) else { continue };
            let face = scene.polygons()[poly].face;
            let around = [(-t, -t), (t, -t), (-t, t), (t, t), (0.0, t), (0.0, -t), (t, 0.0), (-t, 0.0)];
            let edge = around
                .iter()
                .any(|&(dx, dy)| oracle.visible(cx + dx, cy + dy).map(|(q, _)| scene.polygons()[q].face) != Some(face));
            let k = (y * got.width + x) as usize;
            if edge || got.id[k] != face {
                continue;
            }
            for &l in &areas {
                let Some(want) = oracle.exact_fraction_at(l, cx, cy) else { continue };
                compared += 1;
                penumbra += usize::from(want > 1e-9 && want < 1.0 - 1e-9);
                let (a, b) = ((want * 255.0).round(), (got.light[l][k] as f64 * 255.0).round());
                if (a - b).abs() > 1.0 {
                    bad.push((x, y, l, want, got.light[l][k]));
                }
            }
        }
    }
    assert!(
        bad.is_empty(),
        "{label}: {} of {compared} area-light pixels off by more than a grey level (x, y, light, exact, got): {:?}",
        bad.len(),
        &bad[..bad.len().min(10)]
    );
    (compared, penumbra)
}
