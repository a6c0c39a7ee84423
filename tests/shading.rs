//! Shading against the formula at chosen pixels.

use glam::{DVec3, Vec3};
use std::path::Path;
use umbra::view::View;
use umbra::{render, RenderOptions, Scene, ShadowMethod};

#[test]
fn flat_lambert_quad_under_a_point_light() {
    let src = "[camera]\neye = [0.0, 3.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 64\nheight = 48\n\
               [render]\nambient = [0.1, 0.2, 0.3]\n\
               [[material]]\nname = \"m\"\ncolor = [0.5, 0.6, 0.7]\nka = 0.5\nkd = 0.9\n\
               [[light]]\nkind = \"point\"\nposition = [1.0, 2.0, 0.5]\ncolor = [1.0, 0.8, 0.6]\nintensity = 0.7\n\
               [[object]]\npolygons = [[[-2.0,0.0,-2.0],[-2.0,0.0,2.0],[2.0,0.0,2.0],[2.0,0.0,-2.0]]]\n";
    let scene = Scene::from_toml(src, Path::new("t.toml"), Path::new(".")).unwrap();
    let out = render(&scene, &RenderOptions { shadows: ShadowMethod::None, ..Default::default() }).unwrap();
    // Flat: lit at the centroid (origin) with the plane normal +Y.
    let l = (DVec3::new(1.0, 2.0, 0.5) - DVec3::ZERO).normalize();
    let cos = l.y as f32;
    let od = Vec3::new(0.5, 0.6, 0.7);
    let want = Vec3::new(0.1, 0.2, 0.3) * 0.5 * od + Vec3::new(1.0, 0.8, 0.6) * 0.7 * 0.9 * od * cos;
    let view = View::new(&scene.camera);
    for &(x, y) in &[(32u32, 30u32), (10, 40), (50, 28)] {
        let k = (y * 64 + x) as usize;
        assert_eq!(out.frame.id[k], 0, "pixel ({x},{y}) sees the quad");
        let p = view.point_on(&scene.polygons[0].plane, x as f64 + 0.5, y as f64 + 0.5);
        assert!(p.y.abs() < 1e-12);
        assert!((out.frame.color[k] - want).abs().max_element() < 1e-6, "{} vs {want}", out.frame.color[k]);
        assert_eq!(out.frame.light[0][k], 1.0);
    }
}
