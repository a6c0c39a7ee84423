//! Renders a scene with every exact shadow stage (and the paper paths) behind both visibility
//! stages and counts,
//! at every pixel, where each differs from the ray-cast reference (face id or lit fraction).
//!
//! `cargo run --release --example exactness -- scene.toml [more.toml ...]`
use umbra::shadow::Counting;
use umbra::shadow::VolumeOptions;
use umbra::{render, RenderOptions, Scene, ShadowMethod, VisibilityMethod};

fn main() {
    for path in std::env::args().skip(1) {
        let scene = match Scene::load(&path) {
            Ok(s) => s,
            Err(e) => {
                println!("{path}: {e}");
                continue;
            }
        };
        let go = |v, s| render(&scene, &RenderOptions { visibility: v, shadows: s, ..Default::default() });
        let reference = go(VisibilityMethod::RayCast, ShadowMethod::RayCast).unwrap().frame;
        let volumes = |counting| VolumeOptions { counting, ..VolumeOptions::default() };
        let stages = [
            ("bk", ShadowMethod::DEFAULT),
            ("awg", ShadowMethod::AthertonWeilerGreenberg(Default::default())),
            ("crow-zpass", ShadowMethod::Crow(volumes(Counting::ZPass))),
            ("crow-zfail", ShadowMethod::Crow(volumes(Counting::ZFail))),
            ("stencil-zpass", ShadowMethod::StencilVolume(volumes(Counting::ZPass))),
            ("stencil-zfail", ShadowMethod::StencilVolume(volumes(Counting::ZFail))),
            ("bk-paper", ShadowMethod::DEFAULT.as_published()),
            ("awg-paper", ShadowMethod::AthertonWeilerGreenberg(Default::default()).as_published()),
            ("crow-1977", ShadowMethod::Crow(volumes(Counting::ZPass)).as_published()),
            ("crow-zfail-uncut", ShadowMethod::Crow(volumes(Counting::ZFail)).as_published()),
        ];
        for vis in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
            for (name, s) in &stages {
                match go(vis, s.clone()) {
                    Err(e) => println!("{path} {vis} {name}: error {e}"),
                    Ok(out) => {
                        let f = out.frame;
                        let (mut ids, mut lit) = (0, 0);
                        for k in 0..f.id.len() {
                            if f.id[k] != reference.id[k] {
                                ids += 1;
                            } else if f.light.iter().zip(&reference.light).any(|(a, b)| a[k] != b[k]) {
                                lit += 1;
                            }
                        }
                        println!("{path} {vis} {name}: {ids} id, {lit} lit differ of {}", f.id.len());
                    }
                }
            }
        }
    }
}
