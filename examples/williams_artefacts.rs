//! The Williams artefacts image of `docs/algorithms/williams.md`: `scenes/cornell.toml`
//! rendered with five shadow-map settings, side by side, written to
//! `docs/images/williams-artefacts.png`. `cargo run --release --example williams_artefacts`.
use image::{imageops, RgbImage};
use umbra::shadow::{ShadowFilter, WilliamsOptions};
use umbra::{render, RenderOptions, Scene, ShadowMethod};

fn main() -> umbra::Result<()> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::load(root.join("scenes/cornell.toml"))?;
    let panels = [
        // Acne: no bias at all.
        WilliamsOptions {
            map_size: 512,
            bias: Some(0.0),
            slope_bias: 0.0,
            normal_offset: 0.0,
            filter: ShadowFilter::Nearest,
            ..Default::default()
        },
        // Peter-panning: far too much bias.
        WilliamsOptions { bias: Some(0.3), filter: ShadowFilter::Nearest, ..Default::default() },
        // Aliasing: a coarse map, one texel per lookup.
        WilliamsOptions { map_size: 256, filter: ShadowFilter::Nearest, ..Default::default() },
        // The defaults: 2048², 3×3 percentage-closer filtering.
        WilliamsOptions::default(),
        // Seed 002's soft edges.
        WilliamsOptions { filter: ShadowFilter::SoftEdge(3), ..Default::default() },
    ];
    let (w, h, gap) = (320, 240, 4);
    let mut sheet = RgbImage::new(panels.len() as u32 * (w + gap) - gap, h);
    for (i, williams) in panels.into_iter().enumerate() {
        let opts = RenderOptions { shadows: ShadowMethod::Williams(williams), ..Default::default() };
        let image = render(&scene, &opts)?.frame.color_image(None);
        let panel = imageops::resize(&image, w, h, imageops::FilterType::Triangle);
        imageops::replace(&mut sheet, &panel, (i as u32 * (w + gap)) as i64, 0);
    }
    let out = root.join("docs/images/williams-artefacts.png");
    sheet.save(&out).map_err(|e| umbra::Error::Image { path: out.clone(), source: e.into() })?;
    println!("wrote {}", out.display());
    Ok(())
}
