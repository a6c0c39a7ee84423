//! Pixels where one shadow stage differs from ray-cast on a scene, and how many of those are
//! ties: `cargo run --release --example exact_one -- scene.toml crow [zfail] [paper]` (`paper`:
//! the method as published, `ShadowMethod::as_published`).
use umbra::shadow::Counting;
use umbra::shadow::VolumeOptions;
use umbra::{render, RenderOptions, Scene, ShadowMethod};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = Scene::load(&a[1]).unwrap();
    let method: ShadowMethod = a[2].parse().unwrap();
    let counting = if a.get(3).is_some_and(|c| c == "zfail") { Counting::ZFail } else { Counting::ZPass };
    let method = match method {
        ShadowMethod::Crow(_) => ShadowMethod::Crow(VolumeOptions { counting, ..Default::default() }),
        ShadowMethod::StencilVolume(_) => ShadowMethod::StencilVolume(VolumeOptions { counting, ..Default::default() }),
        other => other,
    };
    let method = if a.iter().any(|x| x == "paper") { method.as_published() } else { method };
    let go = |s| render(&scene, &RenderOptions { shadows: s, ..Default::default() }).unwrap().frame;
    let want = go(ShadowMethod::RayCast);
    let got = go(method);
    let oracle = umbra::reference::Reference::new(&scene);
    let (mut differ, mut ties) = (0, 0);
    for y in 0..want.height {
        for x in 0..want.width {
            let k = (y * want.width + x) as usize;
            if want.id[k] != got.id[k] || want.light.iter().zip(&got.light).any(|(p, q)| p[k] != q[k]) {
                differ += 1;
                if differ <= 5 {
                    let lit = |f: &umbra::Frame| f.light.iter().map(|l| l[k]).collect::<Vec<_>>();
                    println!("({x}, {y}): id {} / {}, lit {:?} / {:?}", got.id[k], want.id[k], lit(&got), lit(&want));
                }
                ties += usize::from(oracle.is_tie(x, y));
            }
        }
    }
    println!("{} pixels, {differ} differ from ray-cast, {ties} of them ties", want.id.len());
}
