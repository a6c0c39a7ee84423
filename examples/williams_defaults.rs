//! Williams' defaults, chosen by measurement: for a family of scenes (the example scenes; the
//! open Stanford bunny on a floor under three point lights, 1280×720; 4,000 small
//! interpenetrating cards in a slab, lit from overhead and grazing), each candidate setting's
//! share of wrong interior pixels against the ray-cast reference, by cause
//! (`umbra::study::map_errors`), printed as Markdown tables: one row per scene and setting,
//! then each setting's worst and median share over the family.
//! `cargo run --release --example williams_defaults`.
use umbra::glam::DVec3;
use umbra::shadow::{ShadowFilter, WilliamsOptions};
use umbra::study::compare::diff;
use umbra::study::map_errors::{classify, without_bias};
use umbra::{render, RenderOptions, Scene, ShadowMethod, VisibilityMethod};

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut scenes: Vec<(String, Scene)> = [
        "cornell",
        "lights",
        "teapot",
        "interpenetrating",
        "light-under-ceiling",
        "grazing-light",
        "directional-large",
        "spot",
        "cube-seams",
    ]
    .iter()
    .map(|n| (n.to_string(), Scene::load(root.join(format!("scenes/{n}.toml"))).unwrap()))
    .collect();
    scenes.push(("bunny, 3 lights".into(), Scene::from_toml(&bunny(), root.join("bunny.toml"), root).unwrap()));
    for (name, dir) in [("cards, overhead", [0.1, -1.0, 0.05]), ("cards, grazing", [1.0, -0.12, 0.3])] {
        scenes.push((name.into(), Scene::from_toml(&cards(dir), root.join("cards.toml"), root).unwrap()));
    }
    let d = WilliamsOptions::default();
    let candidates: Vec<(&str, WilliamsOptions)> = vec![
        ("default: 2048, 1 texel + normal offset 2, pcf 3", d.clone()),
        ("normal offset 1", WilliamsOptions { normal_offset: 1.0, ..d.clone() }),
        ("normal offset 3", WilliamsOptions { normal_offset: 3.0, ..d.clone() }),
        ("normal offset 1.5 + slope 0.5", WilliamsOptions { normal_offset: 1.5, slope_bias: 0.5, ..d.clone() }),
        ("receiver plane", WilliamsOptions { receiver_plane: true, normal_offset: 1.0, ..d.clone() }),
        ("4096", WilliamsOptions { map_size: 4096, ..d.clone() }),
        ("nearest", WilliamsOptions { filter: ShadowFilter::Nearest, ..d.clone() }),
        (
            "nearest, normal offset 1",
            WilliamsOptions { filter: ShadowFilter::Nearest, normal_offset: 1.0, ..d.clone() },
        ),
        (
            "nearest, normal offset 1.5",
            WilliamsOptions { filter: ShadowFilter::Nearest, normal_offset: 1.5, ..d.clone() },
        ),
        ("nearest, 4096", WilliamsOptions { filter: ShadowFilter::Nearest, map_size: 4096, ..d.clone() }),
    ];
    println!("| scene | setting | wrong interior pixels | acne | detached | aliasing | resolution |");
    println!("| --- | --- | ---: | ---: | ---: | ---: | ---: |");
    let mut shares: Vec<Vec<f64>> = vec![Vec::new(); candidates.len()];
    for (name, scene) in &scenes {
        let go = |s: ShadowMethod| {
            render(scene, &RenderOptions { visibility: VisibilityMethod::Scanline, shadows: s, ..Default::default() })
                .unwrap()
                .frame
        };
        let reference = go(ShadowMethod::RayCast);
        for (c, (label, o)) in candidates.iter().enumerate() {
            let m = ShadowMethod::Williams(o.clone());
            let got = go(m.clone());
            let unbiased = go(without_bias(&m).unwrap());
            let (interior, wrong, _) = diff(&reference, &got);
            let e = classify(&reference, &got, &unbiased);
            let share = 100.0 * wrong as f64 / interior.max(1) as f64;
            shares[c].push(share);
            println!(
                "| {name} | {label} | {share:.3}% ({wrong}) | {} | {} | {} | {} |",
                e.acne, e.detached, e.aliasing, e.resolution
            );
        }
    }
    println!("\n| setting | worst scene | median scene |\n| --- | ---: | ---: |");
    for (c, (label, _)) in candidates.iter().enumerate() {
        let mut s = shares[c].clone();
        s.sort_by(f64::total_cmp);
        println!("| {label} | {:.3}% | {:.3}% |", s[s.len() - 1], s[s.len() / 2]);
    }
}

/// The open Stanford bunny on a floor under three point lights, 1280×720.
fn bunny() -> String {
    let light = |p: [f64; 3]| format!("[[light]]\nkind = \"point\"\nposition = {p:?}\nintensity = 0.4\n");
    format!(
        "[camera]\neye = [0.0, 0.15, 0.35]\ntarget = [-0.02, 0.1, 0.0]\nfov_y = 40.0\nwidth = 1280\nheight = 720\n\
         {}{}{}\
         [[object]]\npolygons = [[[-1.0, 0.03, -1.0], [-1.0, 0.03, 1.0], [1.0, 0.03, 1.0], [1.0, 0.03, -1.0]]]\n\
         [[object]]\nmesh = \"scenes/meshes/stanford-bunny.obj\"\n",
        light([0.3, 0.5, 0.3]),
        light([-0.4, 0.3, 0.2]),
        light([0.1, 0.6, -0.3])
    )
}

/// 4,000 small cards (quads about 0.08 across, random orientation) interpenetrating in a
/// slab 2 × 0.3 × 2 over a floor, under a directional light along `dir`, 640×480.
fn cards(dir: [f64; 3]) -> String {
    let mut state = 12345u64;
    let mut rnd = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut polys = Vec::new();
    for _ in 0..4000 {
        let c = DVec3::new(rnd() * 2.0 - 1.0, 0.3 + rnd() * 0.3, rnd() * 2.0 - 1.0);
        let n = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize_or(DVec3::Y);
        let a = n.any_orthonormal_vector() * 0.04;
        let b = n.cross(a);
        let p = |v: DVec3| format!("[{}, {}, {}]", v.x, v.y, v.z);
        polys.push(format!("[{}, {}, {}, {}]", p(c - a - b), p(c + a - b), p(c + a + b), p(c - a + b)));
    }
    format!(
        "[camera]\neye = [0.0, 2.2, 2.6]\ntarget = [0.0, 0.2, 0.0]\nwidth = 640\nheight = 480\n\
         [[light]]\nkind = \"directional\"\ndirection = {dir:?}\n\
         [[object]]\npolygons = [[[-2.0, 0.0, -2.0], [-2.0, 0.0, 2.0], [2.0, 0.0, 2.0], [2.0, 0.0, -2.0]]]\n\
         [[object]]\npolygons = [{}]\n",
        polys.join(", ")
    )
}
