//! Builds one Atherton-Weiler-Greenberg shadow database for a scene's first light and
//! renders it from the scene's camera and from a second viewpoint, the lit detail polygons
//! drawn over each image: `cargo run --release --example awg_views SCENE OUT_DIR`.
use std::sync::Arc;
use umbra::shadow::ShadowDatabase;
use umbra::{Counters, Frame, RenderOptions, Renderer, Scene, ShadowMethod};

fn main() -> umbra::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let (scene_path, out) = (&args[1], std::path::Path::new(&args[2]));
    let mut scene = Scene::load(scene_path)?;
    let mut counters = Counters::default();
    let db = Arc::new(vec![ShadowDatabase::build(&scene, 0, Default::default(), &mut counters)?]);
    println!("{}", serde_json::to_string(&counters).unwrap_or_default());
    let opts = RenderOptions {
        shadows: ShadowMethod::AthertonWeilerGreenberg(Default::default()),
        outlines: true,
        ..Default::default()
    };
    let mut renderer = Renderer::new().with_shadow_database(db);
    std::fs::create_dir_all(out).map_err(|e| umbra::Error::Io { path: out.to_owned(), source: e })?;
    for (name, eye) in [("awg-detail", scene.camera().eye), ("awg-second-view", glam::DVec3::new(2.2, 4.8, 2.6))] {
        {
            let mut c = scene.camera().clone();
            c.eye = eye;
            scene.set_camera(c).expect("a valid camera");
        }
        let r = renderer.render(&scene, &opts)?;
        let mut img = r.frame.color_image(None);
        Frame::draw_outlines(&mut img, renderer.outlines(), [255, 40, 200]);
        let path = out.join(format!("{name}.png"));
        img.save(&path).map_err(|e| umbra::Error::Image { path, source: e.into() })?;
    }
    Ok(())
}
