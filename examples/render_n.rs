//! Renders a scene file n times with the given stages (for profiling), and prints the
//! median and least time of the whole frame and of each phase.
//!
//! `cargo run --release --example render_n -- scene.toml scanline williams 40`
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = umbra::Scene::load(&args[1]).unwrap();
    let opts = umbra::RenderOptions {
        visibility: args[2].parse().unwrap(),
        shadows: args[3].parse().unwrap(),
        ..Default::default()
    };
    let n: usize = args.get(4).map_or(5, |s| s.parse().unwrap());
    let mut walls = Vec::new();
    let mut phases: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
    for _ in 0..n {
        let t = std::time::Instant::now();
        let out = umbra::render(&scene, &opts).unwrap();
        for (k, v) in out.stats.time_ms.steps().chain([("total", out.stats.time_ms.total)]) {
            phases.entry(k.to_string()).or_default().push(v);
        }
        drop(out);
        walls.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let summary = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        format!("median {:.2} ms, least {:.2} ms", v[v.len() / 2], v[0])
    };
    // Written with errors ignored: piped into `head`, the rest is simply not wanted.
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "frame: {}", summary(&mut walls));
    for (k, v) in &mut phases {
        let _ = writeln!(out, "  {k}: {}", summary(v));
    }
}
