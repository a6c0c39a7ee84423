//! How far an area light's grid of samples is from the exact lit fraction
//! (`umbra::reference::exact_fraction`), pixel by pixel: for each grid size, the mean and the
//! largest |grid − exact| over the visible pixels lit by some but not all of the light, at a
//! small size (the exact fraction is brute force).
//!
//! `cargo run --release --example area_error -- SCENE.toml [WIDTH] [m,m,...]`
//! (default 320 pixels wide, grids 2,4,8,16).
use umbra::scene::LightKind;
use umbra::{reference, Scene};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let mut scene = Scene::load(&a[1]).expect("a scene file");
    let width: u32 = a.get(2).map_or(320, |w| w.parse().expect("a width"));
    let grids: Vec<u32> = a.get(3).map_or(vec![2, 4, 8, 16], |g| g.split(',').map(|v| v.parse().unwrap()).collect());
    let mut camera = scene.camera().clone();
    camera.height = (camera.height as u64 * width as u64 / camera.width as u64).max(1) as u32;
    camera.width = width;
    scene.set_camera(camera.clone()).unwrap();
    let Some(k) = scene.lights().iter().position(|l| matches!(l.kind, LightKind::Area { .. })) else {
        return println!("{}: no area light", a[1]);
    };
    // The exact fraction at every visible pixel centre.
    let oracle = reference::Reference::new(&scene);
    let mut exact = Vec::new();
    for y in 0..camera.height {
        for x in 0..camera.width {
            let v = oracle.visible(x as f64 + 0.5, y as f64 + 0.5);
            exact.push(v.and_then(|(poly, p)| reference::exact_fraction(&scene, k, p, poly)));
        }
    }
    let penumbra = exact.iter().flatten().filter(|&&f| f > 1e-9 && f < 1.0 - 1e-9).count();
    println!(
        "{}: {}x{}, light {k}; {penumbra} visible pixels in the exact penumbra",
        a[1], camera.width, camera.height
    );
    for m in grids {
        let mut lights = scene.lights().to_vec();
        if let LightKind::Area { samples, .. } = &mut lights[k].kind {
            *samples = [m, m];
        }
        let mut s = scene.clone();
        s.set_lights(lights).unwrap();
        let grid = reference::Reference::new(&s);
        let (mut sum, mut worst, mut n) = (0.0f64, 0.0f64, 0usize);
        for (i, e) in exact.iter().enumerate() {
            let Some(e) = *e else { continue };
            if e <= 1e-9 || e >= 1.0 - 1e-9 {
                continue;
            }
            let (x, y) = ((i as u32 % camera.width) as f64 + 0.5, (i as u32 / camera.width) as f64 + 0.5);
            let g = grid.at(x, y).lit[k] as f64;
            sum += (g - e).abs();
            worst = worst.max((g - e).abs());
            n += 1;
        }
        println!(
            "  {m}x{m} samples: mean |grid - exact| {:.4}, largest {:.4} over {n} penumbra pixels",
            sum / n.max(1) as f64,
            worst
        );
    }
}
