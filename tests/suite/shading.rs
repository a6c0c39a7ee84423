//! Shading against the formulas at chosen pixels, for each illumination model and shading
//! mode, computed here independently from the scene's numbers.

use glam::{DVec3, Vec3};
use std::path::Path;
use umbra::scene::{Light, LightKind, Material, ShadingMode, SpecularModel};
use umbra::shading::reflect;
use umbra::view::View;
use umbra::{render, Frame, RenderOptions, Scene, ShadowMethod};

const LIGHT: DVec3 = DVec3::new(0.6, 1.5, 0.4);
const EYE: DVec3 = DVec3::new(0.0, 2.0, 2.5);

/// A triangle on the floor y = 0 under a point light, seen from `EYE`.
fn scene(model: &str, shading: &str, extra_light: &str) -> Scene {
    let src = format!(
        "[camera]\neye = [0.0, 2.0, 2.5]\ntarget = [0.0, 0.0, 0.0]\nwidth = 96\nheight = 72\n\
         [render]\nambient = [0.1, 0.2, 0.3]\n\
         [[material]]\nname = \"m\"\ncolor = [0.5, 0.6, 0.7]\nspecular_color = [1.0, 0.9, 0.8]\nka = 0.5\nkd = 0.6\nks = 0.5\n\
         shininess = 30.0\nmodel = \"{model}\"\nroughness = 0.25\nshading = \"{shading}\"\n\
         [[light]]\nkind = \"point\"\nposition = [0.6, 1.5, 0.4]\ncolor = [1.0, 0.8, 0.6]\nintensity = 0.9\n{extra_light}\
         [[object]]\npolygons = [[[-3.0,0.0,-3.0],[-2.0,0.0,3.0],[3.0,0.0,1.0]]]\n"
    );
    Scene::from_toml(&src, Path::new("t.toml"), Path::new(".")).unwrap()
}

fn draw(scene: &Scene) -> Frame {
    render(scene, &RenderOptions { shadows: ShadowMethod::None, ..Default::default() }).unwrap().frame
}

fn ambient() -> Vec3 {
    Vec3::new(0.1, 0.2, 0.3) * 0.5 * Vec3::new(0.5, 0.6, 0.7)
}

/// The light of the test's point light at `p` with normal `n` (no attenuation, no spot).
fn lit_at(m: &Material, p: DVec3, n: DVec3) -> Vec3 {
    Vec3::new(1.0, 0.8, 0.6) * 0.9 * reflect(m, n, (EYE - p).normalize(), (LIGHT - p).normalize())
}

fn pixels(scene: &Scene) -> Vec<(u32, u32, DVec3)> {
    let view = View::new(scene.camera());
    let plane = scene.polygons()[0].plane;
    [(48, 36), (30, 50), (70, 40), (45, 60), (55, 30)]
        .iter()
        .map(|&(x, y)| (x, y, view.point_on(&plane, x as f64 + 0.5, y as f64 + 0.5)))
        .collect()
}

fn assert_close(got: Vec3, want: Vec3, what: &str) {
    assert!((got - want).abs().max_element() < 2e-5, "{what}: got {got}, want {want}");
}

#[test]
fn phong_mode_every_model_matches_the_formula_per_pixel() {
    for model in ["phong", "blinn", "cook-torrance"] {
        let s = scene(model, "phong", "");
        let f = draw(&s);
        for (x, y, p) in pixels(&s) {
            let k = (y * 96 + x) as usize;
            assert_eq!(f.id[k], 0);
            let want = ambient() + lit_at(s.material(0), p, DVec3::Y);
            assert_close(f.color[k], want, &format!("{model} at ({x},{y})"));
        }
    }
}

#[test]
fn flat_mode_lights_the_centroid() {
    for model in ["phong", "blinn", "cook-torrance"] {
        let s = scene(model, "flat", "");
        let f = draw(&s);
        let c = (DVec3::new(-3.0, 0.0, -3.0) + DVec3::new(-2.0, 0.0, 3.0) + DVec3::new(3.0, 0.0, 1.0)) / 3.0;
        let want = ambient() + lit_at(s.material(0), c, DVec3::Y);
        for (x, y, _) in pixels(&s) {
            assert_close(f.color[(y * 96 + x) as usize], want, &format!("{model} flat at ({x},{y})"));
        }
    }
}

#[test]
fn gouraud_mode_interpolates_vertex_colours() {
    // On a triangle, interpolation along edges and spans in world space is the barycentric
    // blend of the vertex colours.
    let v = [DVec3::new(-3.0, 0.0, -3.0), DVec3::new(-2.0, 0.0, 3.0), DVec3::new(3.0, 0.0, 1.0)];
    for model in ["phong", "blinn", "cook-torrance"] {
        let s = scene(model, "gouraud", "");
        let f = draw(&s);
        let colours: Vec<Vec3> = v.iter().map(|&p| lit_at(s.material(0), p, DVec3::Y)).collect();
        for (x, y, p) in pixels(&s) {
            let area = |a: DVec3, b: DVec3, c: DVec3| (b - a).cross(c - a).y;
            let total = area(v[0], v[1], v[2]);
            let w = [area(p, v[1], v[2]) / total, area(v[0], p, v[2]) / total, area(v[0], v[1], p) / total];
            let want = ambient() + colours.iter().zip(w).map(|(&c, w)| c * w as f32).sum::<Vec3>();
            assert_close(f.color[(y * 96 + x) as usize], want, &format!("{model} gouraud at ({x},{y})"));
        }
    }
}

#[test]
fn phong_highlight_peaks_at_the_mirror_point() {
    let s = scene("phong", "phong", "");
    let f = draw(&s);
    // The mirror point: where the line from the light's mirror image to the eye meets y = 0.
    let mirror = DVec3::new(LIGHT.x, -LIGHT.y, LIGHT.z);
    let t = -mirror.y / (EYE.y - mirror.y);
    let peak = mirror + (EYE - mirror) * t;
    let view = View::new(s.camera());
    let at = view.project(view.to_camera(peak));
    let (mut best, mut bx, mut by) = (0.0f32, 0, 0);
    for y in 0..72 {
        for x in 0..96 {
            let c = f.color[(y * 96 + x) as usize];
            if f.id[(y * 96 + x) as usize] == 0 && c.x > best {
                (best, bx, by) = (c.x, x, y);
            }
        }
    }
    assert!(
        (bx as f64 + 0.5 - at.x).abs() <= 1.0 && (by as f64 + 0.5 - at.y).abs() <= 1.0,
        "peak at ({bx},{by}), mirror point projects to {at}"
    );
    // At the mirror point itself R.V = 1: the value is the full specular plus diffuse.
    let m = s.material(0);
    let want = ambient() + lit_at(m, peak, DVec3::Y);
    let l = (LIGHT - peak).normalize();
    let spec_only = Vec3::new(1.0, 0.8, 0.6) * 0.9 * m.ks * m.specular_color;
    assert_close(want - ambient() - Vec3::new(1.0, 0.8, 0.6) * 0.9 * m.kd * m.color * l.y as f32, spec_only, "R.V = 1");
    assert!((best - want.x).abs() < 0.02, "peak value {best} vs {}", want.x);
}

#[test]
fn attenuation_applies_per_pixel() {
    let mut s = scene("phong", "phong", "");
    let mut lights = s.lights().to_vec();
    lights[0].attenuation = [0.5, 0.3, 0.2];
    s.set_lights(lights).unwrap();
    let f = draw(&s);
    for (x, y, p) in pixels(&s) {
        let d = (LIGHT - p).length();
        let att = (1.0 / (0.5 + 0.3 * d + 0.2 * d * d)).min(1.0) as f32;
        let want = ambient() + lit_at(s.material(0), p, DVec3::Y) * att;
        assert_close(f.color[(y * 96 + x) as usize], want, &format!("attenuated at ({x},{y})"));
    }
}

#[test]
fn spot_cone_edge_is_where_the_cutoff_says() {
    let mut s = scene("phong", "phong", "");
    let axis = (DVec3::new(0.0, 0.0, 0.0) - LIGHT).normalize();
    let mut lights = s.lights().to_vec();
    lights[0].kind = LightKind::Spot { position: LIGHT, direction: axis, cutoff: 25.0, exponent: 3.0 };
    s.set_lights(lights).unwrap();
    let f = draw(&s);
    let view = View::new(s.camera());
    let plane = s.polygons()[0].plane;
    let (mut inside, mut outside) = (0, 0);
    for y in 0..72 {
        for x in 0..96 {
            let k = (y * 96 + x) as usize;
            if f.id[k] != 0 {
                continue;
            }
            let p = view.point_on(&plane, x as f64 + 0.5, y as f64 + 0.5);
            let cos = (p - LIGHT).normalize().dot(axis);
            let want = if cos >= 25f64.to_radians().cos() {
                inside += 1;
                ambient() + lit_at(s.material(0), p, DVec3::Y) * cos.powf(3.0) as f32
            } else {
                outside += 1;
                ambient()
            };
            assert_close(f.color[k], want, &format!("spot at ({x},{y})"));
        }
    }
    assert!(inside > 100 && outside > 100, "the cone edge crosses the view ({inside} in, {outside} out)");
}

#[test]
fn area_light_half_lit_pixel() {
    // Two samples at x = -0.5 and x = +0.5 above the floor; a wall at x = 0 between them
    // blocks exactly one sample for every floor point under it.
    let src = "[camera]\neye = [0.0, 1.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 64\nheight = 48\n\
               [render]\nambient = [0.0, 0.0, 0.0]\n\
               [[material]]\nname = \"m\"\ncolor = [1.0, 1.0, 1.0]\nkd = 1.0\nshading = \"phong\"\n\
               [[light]]\nkind = \"area\"\ncorner = [-1.0, 2.0, -0.05]\nedge_u = [2.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.1]\nsamples = [2, 1]\n\
               [[object]]\npolygons = [[[-3.0,0.0,-3.0],[-3.0,0.0,3.0],[3.0,0.0,3.0],[3.0,0.0,-3.0]]]\nmaterial = \"m\"\n\
               [[object]]\npolygons = [[[0.0,0.2,-3.0],[0.0,0.2,3.0],[0.0,1.9,3.0],[0.0,1.9,-3.0]]]\nmaterial = \"m\"\n";
    let s = Scene::from_toml(src, Path::new("t.toml"), Path::new(".")).unwrap();
    let f = render(&s, &RenderOptions { shadows: ShadowMethod::RayCast, ..Default::default() }).unwrap().frame;
    // A floor point at x = 0.3 sees the +0.5 sample; its segment to the -0.5 sample crosses
    // x = 0 at height 0.75, through the wall (y 0.2..1.9).
    let view = View::new(s.camera());
    let px = view.project(view.to_camera(DVec3::new(0.3, 0.0, 0.5)));
    let (x, y) = (px.x as u32, px.y as u32);
    let k = (y * 64 + x) as usize;
    assert_eq!(f.id[k], 0);
    assert_eq!(f.light[0][k], 0.5);
    let p = view.point_on(&s.polygons()[0].plane, x as f64 + 0.5, y as f64 + 0.5);
    let sample = DVec3::new(0.5, 2.0, 0.0);
    let want = 0.5 * (sample - p).normalize().y as f32;
    assert!((f.color[k].x - want).abs() < 1e-5, "{} vs {want}", f.color[k].x);
}

#[test]
fn gouraud_equals_flat_when_vertex_normals_are_the_face_normal() {
    let mut flat = scene("phong", "flat", "");
    let mut materials = flat.materials().to_vec();
    materials[0].ks = 0.0;
    flat.set_materials(materials).unwrap();
    let light = Light {
        kind: LightKind::Directional { direction: DVec3::new(0.3, -1.0, 0.2).normalize() },
        ..flat.lights()[0].clone()
    };
    flat.set_lights(vec![light]).unwrap();
    let mut gouraud = flat.clone();
    let mut materials = gouraud.materials().to_vec();
    materials[0].shading = ShadingMode::Gouraud;
    gouraud.set_materials(materials).unwrap();
    // Inline polygons share no vertices: their averaged normals are the face normal.
    assert!((0..gouraud.polygons().len())
        .all(|i| gouraud.vertex_normals(i).iter().all(|n| (*n - DVec3::Y).length() < 1e-12)));
    let (a, b) = (draw(&flat), draw(&gouraud));
    for (p, q) in a.color.iter().zip(&b.color) {
        assert!((*p - *q).abs().max_element() < 1e-6);
    }
}

#[test]
fn phong_shading_of_a_sphere_converges_to_the_analytic_sphere() {
    let mut errors = Vec::new();
    for triangles in [200, 800, 3200, 12800] {
        let mesh = umbra::generate::sphere_mesh(DVec3::ZERO, 1.0, triangles);
        let mut m = Material::new("m");
        m.shading = ShadingMode::Phong;
        m.ks = 0.5;
        m.model = SpecularModel::Blinn;
        m.shininess = 20.0;
        let mut cam = umbra::scene::Camera::new(DVec3::new(0.0, 0.5, 4.0), DVec3::ZERO);
        cam.width = 96;
        cam.height = 96;
        let light = Light {
            kind: LightKind::Directional { direction: DVec3::new(-0.5, -0.7, -0.6).normalize() },
            color: Vec3::ONE,
            intensity: 1.0,
            attenuation: [1.0, 0.0, 0.0],
        };
        let obj = umbra::scene::Object {
            name: None,
            material: 0,
            mesh: std::sync::Arc::new(mesh),
            transform: Default::default(),
            casts_shadows: true,
            receiver: false,
        };
        let s = Scene::new(cam, Default::default(), vec![m.clone()], vec![light.clone()], vec![obj]).unwrap();
        let f = draw(&s);
        let view = View::new(s.camera());
        let (mut sum, mut n) = (0.0f64, 0);
        for y in 0..96 {
            for x in 0..96 {
                let d = view.ray(x as f64 + 0.5, y as f64 + 0.5).normalize();
                // Analytic sphere: nearest hit of the ray with |p| = 1, well inside the outline.
                let b = view.eye.dot(d);
                let disc = b * b - (view.eye.length_squared() - 1.0);
                if disc < 0.05 || f.id[(y * 96 + x) as usize] == u32::MAX {
                    continue;
                }
                let p = view.eye + d * (-b - disc.sqrt());
                let l = -DVec3::new(-0.5, -0.7, -0.6).normalize();
                let want = Vec3::splat(0.1) * m.color + reflect(&m, p, (view.eye - p).normalize(), l);
                sum += (f.color[(y * 96 + x) as usize] - want).abs().max_element() as f64;
                n += 1;
            }
        }
        errors.push(sum / n as f64);
    }
    for w in errors.windows(2) {
        assert!(w[1] < w[0] * 0.7, "error does not fall with tessellation: {errors:?}");
    }
    assert!(errors[3] < 0.01, "{errors:?}");
}
