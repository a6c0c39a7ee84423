//! Resolves visibility for a scene file many times (for profiling).
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = umbra::Scene::load(&args[1]).unwrap();
    let m: umbra::VisibilityMethod = args[2].parse().unwrap();
    let n: u32 = args.get(3).map_or(10, |s| s.parse().unwrap());
    let t = std::time::Instant::now();
    for _ in 0..n {
        std::hint::black_box(umbra::visibility::resolve_frame(&scene, m));
    }
    println!("{:.2} ms per frame", t.elapsed().as_secs_f64() * 1e3 / n as f64);
}
