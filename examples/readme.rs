//! The README's library examples, compiled: `tests/suite/readme.rs` checks that every line of
//! the README's Rust blocks is here, in order, so the README cannot drift from code that
//! builds. `cargo run --release --example readme` runs them (it writes `cornell.png`).
use umbra::shadow::{Counting, VolumeOptions};
use umbra::{render, RenderOptions, Scene, ShadowMethod, VisibilityMethod};

fn main() -> Result<(), umbra::Error> {
    first()?;
    let scene = Scene::load("scenes/cornell.toml")?;
    let mut renderer = umbra::Renderer::new();
    for frame in 0..100 {
        let out = renderer.render(&scene, &RenderOptions::default())?;
        println!("{frame}: {:.1} ms", out.stats.time_ms.total);
    }
    built()
}

fn first() -> Result<(), umbra::Error> {
    let scene = Scene::load("scenes/cornell.toml")?;
    // Each shadow method carries its own settings: Crow's volumes counted by z-fail here.
    let crow = VolumeOptions { counting: Counting::ZFail, ..VolumeOptions::default() };
    let options = RenderOptions {
        visibility: VisibilityMethod::Scanline,
        shadows: ShadowMethod::Crow(crow),
        ..RenderOptions::default()
    };
    let out = render(&scene, &options)?;
    out.frame.save_png("cornell.png", None)?;
    println!("{:?}", out.stats.visibility_counters);
    Ok(())
}

fn built() -> Result<(), umbra::Error> {
    use umbra::glam::DVec3;
    use umbra::{Camera, Light, Material, Mesh, Object, Scene};

    let tri = Mesh::from_polygons(&[vec![DVec3::ZERO, DVec3::X, DVec3::Y]]);
    let scene = Scene::builder(Camera::new(DVec3::new(0.0, 1.0, 5.0), DVec3::ZERO))
        .material(Material::new("grey"))
        .light(Light::point(DVec3::new(0.0, 5.0, 2.0)))
        .object(Object::new(tri).named("card"), "grey")
        .build()?;
    println!("{} polygons", scene.polygons().len());
    Ok(())
}
