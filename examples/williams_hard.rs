//! The share of interior pixels where Williams' shadow map (default options; `SLOPE` and
//! `NORMAL` in the environment set the slope bias and the normal offset) differs from
//! ray-cast, for each scene given:
//! `cargo run --release --example williams_hard -- scenes/grazing-light.toml ...`
use umbra::shadow::WilliamsOptions;
use umbra::study::compare::diff;
use umbra::{render, RenderOptions, Scene, ShadowMethod};

fn main() {
    for path in std::env::args().skip(1) {
        let scene = Scene::load(&path).unwrap();
        let reference =
            render(&scene, &RenderOptions { shadows: ShadowMethod::RayCast, ..Default::default() }).unwrap().frame;
        let var = |name: &str| std::env::var(name).ok().and_then(|v| v.parse::<f64>().ok());
        let d = WilliamsOptions::default();
        let williams = WilliamsOptions {
            slope_bias: var("SLOPE").unwrap_or(d.slope_bias),
            normal_offset: var("NORMAL").unwrap_or(d.normal_offset),
            receiver_plane: var("RPDB").is_some_and(|f| f != 0.0),
            fit_to_view: var("FIT").map_or(d.fit_to_view, |f| f != 0.0),
            map_size: var("MAP").map_or(d.map_size, |m| m as u32),
            ..d
        };
        let opts = RenderOptions { shadows: ShadowMethod::Williams(williams), ..Default::default() };
        let got = render(&scene, &opts).unwrap().frame;
        let (interior, wrong, _) = diff(&reference, &got);
        println!(
            "{path}: {:.2}% ({wrong} of {interior}) interior pixels wrong",
            100.0 * wrong as f64 / interior.max(1) as f64
        );
        if let Ok(out) = std::env::var("DIFF_PNG") {
            // Grey: agrees; red: the map lights what is in shadow; blue: the map shadows what is lit.
            let img = image::RgbImage::from_fn(got.width, got.height, |x, y| {
                let k = (y * got.width + x) as usize;
                let (want, have): (f32, f32) =
                    (reference.light.iter().map(|l| l[k]).sum(), got.light.iter().map(|l| l[k]).sum());
                let g = (40.0 + 60.0 * want) as u8;
                if (want - have).abs() < 0.25 {
                    image::Rgb([g, g, g])
                } else if have > want {
                    image::Rgb([230, 30, 30])
                } else {
                    image::Rgb([30, 60, 230])
                }
            });
            img.save(&out).unwrap();
        }
    }
}
