//! Renders a scene file n times with the given stages (for profiling).
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = umbra::Scene::load(&args[1]).unwrap();
    let opts = umbra::RenderOptions {
        visibility: args[2].parse().unwrap(),
        shadows: args[3].parse().unwrap(),
        ..Default::default()
    };
    let n: u32 = args.get(4).map_or(5, |s| s.parse().unwrap());
    let t = std::time::Instant::now();
    let mut out = None;
    for _ in 0..n {
        out = Some(umbra::render(&scene, &opts).unwrap());
    }
    println!("{:.2} ms per frame", t.elapsed().as_secs_f64() * 1e3 / n as f64);
    if let Some(o) = out {
        println!("{}", serde_json::to_string(&o.stats).unwrap());
    }
}
