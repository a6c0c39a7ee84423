//! Building a scene in code: constructors for lights and objects, and [`SceneBuilder`], which
//! refers to materials by name as a scene file does.

use super::{Camera, Light, LightKind, Material, Mesh, Object, RenderSettings, Scene, Transform};
use crate::error::{Error, Result};
use glam::{DVec3, Vec3};
use std::sync::Arc;

impl Light {
    /// A white point light of intensity 1 at `position`, not attenuated.
    pub fn point(position: DVec3) -> Light {
        Light::of(LightKind::Point { position })
    }

    /// A white directional light of intensity 1 travelling along `direction` (normalised).
    pub fn directional(direction: DVec3) -> Light {
        Light::of(LightKind::Directional { direction: direction.normalize_or_zero() })
    }

    /// A white spot light of intensity 1 at `position`, its cone of half-angle `cutoff`
    /// degrees along `direction` (normalised), falling off as `cos¹`.
    pub fn spot(position: DVec3, direction: DVec3, cutoff: f64) -> Light {
        Light::of(LightKind::Spot { position, direction: direction.normalize_or_zero(), cutoff, exponent: 1.0 })
    }

    /// A white area light of intensity 1: the parallelogram at `corner` spanned by `edge_u`
    /// and `edge_v`, sampled by an `m` x `n` grid of point lights.
    pub fn area(corner: DVec3, edge_u: DVec3, edge_v: DVec3, [m, n]: [u32; 2]) -> Light {
        Light::of(LightKind::Area { corner, edge_u, edge_v, samples: [m, n] })
    }

    fn of(kind: LightKind) -> Light {
        Light { kind, color: Vec3::ONE, intensity: 1.0, attenuation: [1.0, 0.0, 0.0] }
    }

    /// The same light with colour `color` and intensity `intensity`.
    pub fn with(self, color: Vec3, intensity: f32) -> Light {
        Light { color, intensity, ..self }
    }
}

impl Object {
    /// `mesh` where it stands, with the first material, casting shadows.
    pub fn new(mesh: Mesh) -> Object {
        Object {
            name: None,
            material: 0,
            mesh: Arc::new(mesh),
            transform: Transform::default(),
            casts_shadows: true,
            receiver: false,
        }
    }

    /// The same object, named.
    pub fn named(self, name: impl Into<String>) -> Object {
        Object { name: Some(name.into()), ..self }
    }

    /// The same object, placed by `transform`.
    pub fn placed(self, transform: Transform) -> Object {
        Object { transform, ..self }
    }
}

/// Builds a [`Scene`] in code, part by part; objects name their material as a scene file's
/// `[[object]]` does. Nothing is checked until [`SceneBuilder::build`], which checks
/// everything the loader checks.
///
/// ```
/// use umbra::glam::{DVec3, Vec3};
/// use umbra::scene::{Camera, Light, Material, Mesh, Object};
/// use umbra::{render, RenderOptions, Scene};
///
/// let floor = Mesh::from_polygons(&[vec![
///     DVec3::new(-4.0, 0.0, -4.0),
///     DVec3::new(-4.0, 0.0, 4.0),
///     DVec3::new(4.0, 0.0, 4.0),
///     DVec3::new(4.0, 0.0, -4.0),
/// ]]);
/// let card = Mesh::from_polygons(&[vec![
///     DVec3::new(-1.0, 1.0, 0.0),
///     DVec3::new(1.0, 1.0, 0.0),
///     DVec3::new(0.0, 1.0, 1.0),
/// ]]);
/// let scene = Scene::builder(Camera { width: 80, height: 60, ..Camera::new(DVec3::new(0.0, 4.0, 6.0), DVec3::ZERO) })
///     .material(Material::new("grey"))
///     .material(Material { color: Vec3::new(0.8, 0.2, 0.2), ..Material::new("red") })
///     .light(Light::point(DVec3::new(0.0, 5.0, 0.0)))
///     .object(Object::new(floor).named("floor"), "grey")
///     .object(Object::new(card), "red")
///     .build()?;
/// let out = render(&scene, &RenderOptions::default())?;
/// // The card's shadow falls on the floor (face 0): some of its pixels are dark, most lit.
/// let floor: Vec<f32> = (0..out.frame.id.len()).filter(|&k| out.frame.id[k] == 0).map(|k| out.frame.light[0][k]).collect();
/// let dark = floor.iter().filter(|&&l| l == 0.0).count();
/// assert!(dark > 0 && dark < floor.len() / 2, "{dark} of {}", floor.len());
/// # Ok::<(), umbra::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct SceneBuilder {
    camera: Camera,
    render: RenderSettings,
    materials: Vec<Material>,
    lights: Vec<Light>,
    objects: Vec<(Object, String)>,
}

impl Scene {
    /// A builder for a scene seen by `camera`.
    pub fn builder(camera: Camera) -> SceneBuilder {
        SceneBuilder {
            camera,
            render: RenderSettings::default(),
            materials: Vec::new(),
            lights: Vec::new(),
            objects: Vec::new(),
        }
    }
}

impl SceneBuilder {
    /// The ambient light and background.
    pub fn settings(self, render: RenderSettings) -> SceneBuilder {
        SceneBuilder { render, ..self }
    }

    /// Adds a material (named by its `name`).
    pub fn material(mut self, material: Material) -> SceneBuilder {
        self.materials.push(material);
        self
    }

    /// Adds a light.
    pub fn light(mut self, light: Light) -> SceneBuilder {
        self.lights.push(light);
        self
    }

    /// Adds an object made of the material named `material`.
    pub fn object(mut self, object: Object, material: impl Into<String>) -> SceneBuilder {
        self.objects.push((object, material.into()));
        self
    }

    /// The scene, checked and compiled; an object whose material was not added, or a value
    /// the loader would refuse, is an error.
    pub fn build(self) -> Result<Scene> {
        let mut objects = Vec::with_capacity(self.objects.len());
        for (i, (mut o, name)) in self.objects.into_iter().enumerate() {
            o.material = self.materials.iter().position(|m| m.name == name).ok_or_else(|| {
                Error::scene(format!("object {i}"), format!("no material named '{name}' (add it with .material())"))
            })?;
            objects.push(o);
        }
        for (i, m) in self.materials.iter().enumerate() {
            if self.materials[..i].iter().any(|n| n.name == m.name) {
                return Err(Error::scene(format!("material '{}'", m.name), "is added twice"));
            }
        }
        Scene::new(self.camera, self.render, self.materials, self.lights, objects)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The builder refuses what the loader refuses: a light at NaN or infinity (which once
    /// rendered, with the exact stages disagreeing), a camera or a material value that is
    /// not finite.
    #[test]
    fn values_the_loader_refuses_are_refused_by_the_builder_too() {
        let camera = || Camera::new(DVec3::new(0.0, 1.0, 5.0), DVec3::ZERO);
        let build = |camera: Camera, light: Light, material: Material| {
            Scene::builder(camera)
                .material(material)
                .light(light)
                .object(Object::new(Mesh::from_polygons(&[vec![DVec3::X, DVec3::Y, DVec3::Z]])), "m")
                .build()
        };
        let good = || Material::new("m");
        assert!(build(camera(), Light::point(DVec3::Y * 3.0), good()).is_ok());
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let e = build(camera(), Light::point(DVec3::new(bad, 3.0, 0.0)), good()).unwrap_err().to_string();
            assert!(e.contains("light 0") && e.contains("finite"), "{e}");
            let mut light = Light::point(DVec3::Y * 3.0);
            light.intensity = bad as f32;
            assert!(build(camera(), light, good()).is_err());
            let eye = Camera { eye: DVec3::new(0.0, bad, 5.0), ..camera() };
            assert!(build(eye, Light::point(DVec3::Y * 3.0), good()).is_err());
            let mut m = good();
            m.kd = bad as f32;
            assert!(build(camera(), Light::point(DVec3::Y * 3.0), m).is_err());
        }
    }

    #[test]
    fn an_unknown_material_name_is_an_error_naming_it() {
        let tri = Mesh::from_polygons(&[vec![DVec3::ZERO, DVec3::X, DVec3::Y]]);
        let e = Scene::builder(Camera::new(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO))
            .material(Material::new("grey"))
            .object(Object::new(tri), "gray")
            .build()
            .unwrap_err()
            .to_string();
        assert!(e.contains("no material named 'gray'"), "{e}");
    }

    #[test]
    fn objects_take_the_material_they_name() {
        let tri = || Mesh::from_polygons(&[vec![DVec3::ZERO, DVec3::X, DVec3::Y]]);
        let scene = Scene::builder(Camera::new(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO))
            .material(Material::new("a"))
            .material(Material::new("b"))
            .object(Object::new(tri()), "b")
            .object(Object::new(tri()).named("second"), "a")
            .build()
            .unwrap();
        assert_eq!(scene.objects()[0].material, 1);
        assert_eq!(scene.objects()[1].material, 0);
        assert_eq!(scene.object_named("second"), Some(1));
    }
}
