//! Prints what each stage gives at one pixel: `cargo run --release --example pixel -- scene.toml X Y`.
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = umbra::Scene::load(&a[1]).unwrap();
    let (x, y): (u32, u32) = (a[2].parse().unwrap(), a[3].parse().unwrap());
    let oracle = umbra::reference::Reference::new(&scene);
    println!("oracle {:?} tie {}", oracle.at(x as f64 + 0.5, y as f64 + 0.5), oracle.is_tie(x, y));
    for s in ["ray-cast", "bouknight-kelley", "atherton-weiler-greenberg", "crow"] {
        let o = umbra::RenderOptions { shadows: s.parse().unwrap(), ..Default::default() };
        let f = umbra::render(&scene, &o).unwrap().frame;
        let k = (y * f.width + x) as usize;
        println!("{s}: id {} lit {:?}", f.id[k], f.light.iter().map(|l| l[k]).collect::<Vec<_>>());
    }
}
