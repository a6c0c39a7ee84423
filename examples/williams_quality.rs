//! Quality against time for Williams' shadow maps: for each example scene, map sizes 512 to
//! 4096 and several biases, the share of interior pixels whose lit value differs from the
//! ray-cast reference (measured as `umbra compare` measures it) and the render time,
//! printed as a Markdown table. `cargo run --release --example williams_quality`.
use umbra::shadow::{ShadowFilter, WilliamsOptions};
use umbra::study::compare::diff;
use umbra::{render, RenderOptions, Scene, ShadowMethod, VisibilityMethod};

fn main() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    println!("| scene | map | bias | filter | wrong interior pixels | time (ms) |");
    println!("| --- | --- | --- | --- | --- | --- |");
    for name in [
        "cornell",
        "lights",
        "teapot",
        "interpenetrating",
        "light-under-ceiling",
        "grazing-light",
        "directional-large",
        "spot",
        "cube-seams",
    ] {
        let scene = Scene::load(dir.join(format!("{name}.toml"))).unwrap();
        let reference = render(
            &scene,
            &RenderOptions {
                visibility: VisibilityMethod::Scanline,
                shadows: ShadowMethod::RayCast,
                ..Default::default()
            },
        )
        .unwrap()
        .frame;
        let extent = scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length());
        for map_size in [512, 2048, 4096] {
            let d = WilliamsOptions::default();
            for (bias_name, bias, slope, normal) in [
                ("none", Some(0.0), 0.0, 0.0),
                ("1 texel", None, 0.0, 0.0),
                ("default: 1 texel + normal offset 2", None, d.slope_bias, d.normal_offset),
                ("1 texel + slope 1.0", None, 1.0, 0.0),
                ("1% of scene", Some(0.01 * extent), 0.0, 0.0),
            ] {
                for filter in [ShadowFilter::Nearest, ShadowFilter::Pcf(3)] {
                    let williams = WilliamsOptions {
                        map_size,
                        bias,
                        slope_bias: slope,
                        normal_offset: normal,
                        filter,
                        ..Default::default()
                    };
                    let opts = RenderOptions { shadows: ShadowMethod::Williams(williams), ..Default::default() };
                    let mut times = Vec::new();
                    let mut frame = None;
                    for _ in 0..3 {
                        let r = render(&scene, &opts).unwrap();
                        times.push(r.stats.time_ms.total);
                        frame = Some(r.frame);
                    }
                    times.sort_by(f64::total_cmp);
                    let (interior, wrong, _) = diff(&reference, &frame.unwrap());
                    let filter = match filter {
                        ShadowFilter::Nearest => "nearest".to_string(),
                        ShadowFilter::Pcf(n) => format!("pcf {n}x{n}"),
                        ShadowFilter::SoftEdge(n) => format!("soft-edge {n}"),
                        other => format!("{other:?}"),
                    };
                    println!(
                        "| {name} | {map_size} | {bias_name} | {filter} | {:.3}% ({wrong}) | {:.1} |",
                        100.0 * wrong as f64 / interior.max(1) as f64,
                        times[1]
                    );
                }
            }
        }
    }
}
