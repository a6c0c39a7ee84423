//! Shadow stages at 1920×1080, each beside the same render without shadows: the 10×10
//! cubes scene (1,201 polygons), spheres of 10k and 100k triangles, stacked quads. The
//! Atherton-Weiler-Greenberg group separates pass 1 (the database), the view pass with a
//! prebuilt database, and ten views of one database.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::sync::Arc;
use std::time::Duration;
use umbra::shadow::{BouknightKelleyOptions, ShadowDatabase, ShadowFilter, WilliamsOptions};
use umbra::{generate, render, Counters, RenderOptions, Renderer, Scene, ShadowMethod, VisibilityMethod};

const W: u32 = 1920;
const H: u32 = 1080;

fn opts(shadows: ShadowMethod) -> RenderOptions {
    RenderOptions { visibility: VisibilityMethod::Scanline, shadows, ..RenderOptions::default() }
}

fn group<'a>(c: &'a mut Criterion, name: &str) -> criterion::BenchmarkGroup<'a, criterion::measurement::WallTime> {
    let mut g = c.benchmark_group(name);
    g.sample_size(10).measurement_time(Duration::from_secs(4)).warm_up_time(Duration::from_millis(500));
    g
}

fn stages(c: &mut Criterion) {
    let scenes: Vec<(&str, Scene)> = vec![
        ("cubes10", generate::cubes(10, generate::Faces::Triangles, W, H).unwrap()),
        ("sphere10k", generate::spheres(10_000, 1, W, H).unwrap()),
        ("sphere100k", generate::spheres(100_000, 1, W, H).unwrap()),
        ("quads16", generate::stacked_quads(16, W, H).unwrap()),
    ];
    let mut g = group(c, "shadows");
    for (name, scene) in &scenes {
        // Every stage the engine lists (but Atherton-Weiler-Greenberg on the largest sphere,
        // where a run takes minutes), and Bouknight-Kelley without its prefilter; a stage that
        // does not apply to the scene (planar shadows with no receiver) is left out.
        let mut methods: Vec<ShadowMethod> = ShadowMethod::ALL
            .into_iter()
            .filter(|m| *name != "sphere100k" || !matches!(m, ShadowMethod::AthertonWeilerGreenberg(_)))
            .collect();
        if *name != "sphere100k" {
            methods
                .push(ShadowMethod::BouknightKelley(BouknightKelleyOptions { prefilter: false, ..Default::default() }));
        }
        for m in methods {
            let o = opts(m);
            match render(scene, &o) {
                Err(umbra::Error::NotApplicable { .. }) => continue,
                r => drop(r.unwrap()),
            }
            let label = o.shadows.command_line().replace(' ', "");
            g.bench_with_input(BenchmarkId::new(label, name), scene, |b, s| b.iter(|| render(s, &o).unwrap()));
        }
    }
    g.finish();
}

fn atherton_weiler_greenberg(c: &mut Criterion) {
    let mut g = group(c, "awg");
    for (name, scene) in [
        ("cubes10", generate::cubes(10, generate::Faces::Triangles, W, H).unwrap()),
        ("sphere10k", generate::spheres(10_000, 1, W, H).unwrap()),
    ] {
        g.bench_function(BenchmarkId::new("pass1", name), |b| {
            b.iter(|| ShadowDatabase::build(&scene, 0, Default::default(), &mut Counters::default()).unwrap())
        });
        let db =
            Arc::new(vec![ShadowDatabase::build(&scene, 0, Default::default(), &mut Counters::default()).unwrap()]);
        let view_pass = opts(ShadowMethod::AthertonWeilerGreenberg(Default::default()));
        let mut renderer = Renderer::new().with_shadow_database(db.clone());
        g.bench_function(BenchmarkId::new("view-pass", name), |b| {
            b.iter(|| renderer.render(&scene, &view_pass).unwrap().stats.polygons)
        });
        let mut views = Vec::new();
        for k in 0..10 {
            let mut s = scene.clone();
            let a = k as f64 * 0.2;
            let mut c = s.camera().clone();
            c.eye =
                glam::DVec3::new(c.eye.x * a.cos() - c.eye.z * a.sin(), c.eye.y, c.eye.x * a.sin() + c.eye.z * a.cos());
            s.set_camera(c).unwrap();
            views.push(s);
        }
        g.bench_function(BenchmarkId::new("ten-views-one-database", name), |b| {
            b.iter(|| views.iter().map(|s| renderer.render(s, &view_pass).unwrap().stats.polygons).sum::<usize>())
        });
    }
    g.finish();
}

/// Blinn's planar shadows need a receiver: the generated scenes' floor, marked.
fn planar(c: &mut Criterion) {
    let mut g = group(c, "planar");
    for (name, mut scene) in [
        ("cubes10", generate::cubes(10, generate::Faces::Triangles, W, H).unwrap()),
        ("sphere100k", generate::spheres(100_000, 1, W, H).unwrap()),
    ] {
        scene.set_receiver(0, true).unwrap();
        let o = opts(ShadowMethod::Planar);
        g.bench_function(BenchmarkId::new("planar", name), |b| b.iter(|| render(&scene, &o).unwrap()));
    }
    g.finish();
}

/// Williams' method on its own ground: behind z-buffer visibility, against the same render
/// without shadows; and with the nearest-texel filter of the 1978 paper.
fn williams(c: &mut Criterion) {
    let mut g = group(c, "williams");
    for (name, scene) in [
        ("cubes10", generate::cubes(10, generate::Faces::Triangles, W, H).unwrap()),
        ("sphere100k", generate::spheres(100_000, 1, W, H).unwrap()),
    ] {
        let nearest = WilliamsOptions { filter: ShadowFilter::Nearest, ..Default::default() };
        for (label, visibility, m) in [
            ("zbuffer-none", VisibilityMethod::ZBuffer, ShadowMethod::None),
            ("zbuffer-williams-2048", VisibilityMethod::ZBuffer, ShadowMethod::Williams(Default::default())),
            ("scanline-williams-2048-nearest", VisibilityMethod::Scanline, ShadowMethod::Williams(nearest.clone())),
        ] {
            let o = RenderOptions { visibility, ..opts(m) };
            g.bench_with_input(BenchmarkId::new(label, name), &scene, |b, s| b.iter(|| render(s, &o).unwrap()));
        }
    }
    g.finish();
}

criterion_group!(benches, stages, atherton_weiler_greenberg, planar, williams);
criterion_main!(benches);
