//! Visibility at 1920×1080: Watkins' scanline against the z-buffer on the cubes scene, a
//! 100k-triangle sphere and stacked quads of depth complexity 1, 4, 16 and 64. Each bench
//! prepares the stage and walks every line (the visibility stage alone); the `render` group
//! adds shading for the whole pipeline without shadows.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::time::Duration;
use umbra::generate;
use umbra::visibility::resolve_frame;
use umbra::{render, RenderOptions, Scene, ShadowMethod, VisibilityMethod};

const W: u32 = 1920;
const H: u32 = 1080;

fn scenes() -> Vec<(String, Scene)> {
    let mut v = vec![("cubes10".to_string(), generate::cubes(10, generate::Faces::Triangles, W, H).unwrap())];
    for d in [1, 4, 16, 64] {
        v.push((format!("quads{d}"), generate::stacked_quads(d, W, H).unwrap()));
    }
    v.push(("sphere100k".to_string(), generate::spheres(100_000, 1, W, H).unwrap()));
    v
}

fn visibility(c: &mut Criterion) {
    let mut g = c.benchmark_group("visibility");
    g.sample_size(10).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_millis(500));
    for (name, scene) in scenes() {
        for m in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
            g.bench_with_input(BenchmarkId::new(m.name(), &name), &scene, |b, s| b.iter(|| resolve_frame(s, m)));
        }
    }
    g.finish();
}

fn full_render(c: &mut Criterion) {
    let mut g = c.benchmark_group("render");
    g.sample_size(10).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_millis(500));
    for (name, scene) in scenes().into_iter().filter(|(n, _)| n == "cubes10" || n == "quads16") {
        for m in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
            let opts = RenderOptions { visibility: m, shadows: ShadowMethod::None, ..Default::default() };
            g.bench_with_input(BenchmarkId::new(m.name(), &name), &scene, |b, s| b.iter(|| render(s, &opts).unwrap()));
        }
    }
    g.finish();
}

criterion_group!(benches, visibility, full_render);
criterion_main!(benches);
