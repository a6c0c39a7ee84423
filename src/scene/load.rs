//! Reading a scene file (`docs/scene-format.md` section 1). serde does the parsing with
//! `deny_unknown_fields`; every later check keeps the span of the value it checks, so each
//! error names the file and line.

use super::{
    Camera, Light, LightKind, Material, Mesh, Object, RenderSettings, Scene, ShadingMode, SpecularModel, Transform,
};
use crate::error::{Error, FileLoc, Result};
use glam::{DVec3, Vec3};
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use toml::Spanned;

/// A finite f64: NaN and infinities are refused where they are read, so the error carries
/// the value's line.
#[derive(Debug, Clone, Copy)]
struct Num(f64);

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let x = f64::deserialize(d)?;
        if x.is_finite() {
            Ok(Num(x))
        } else {
            Err(de::Error::custom(format!("{x} is not a finite number")))
        }
    }
}

/// Exactly `N` finite numbers: a missing or an extra element is an error at the array.
#[derive(Debug, Clone, Copy)]
struct Arr<T, const N: usize>([T; N]);

impl<'de, T: Deserialize<'de> + Copy + Default, const N: usize> Deserialize<'de> for Arr<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V<T, const N: usize>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de> + Copy + Default, const N: usize> Visitor<'de> for V<T, N> {
            type Value = Arr<T, N>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "an array of exactly {N} numbers")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<Arr<T, N>, A::Error> {
                let mut out = [T::default(); N];
                for (i, x) in out.iter_mut().enumerate() {
                    *x = seq.next_element::<T>()?.ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<de::IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(N + 1, &self));
                }
                Ok(Arr(out))
            }
        }
        d.deserialize_seq(V::<T, N>(std::marker::PhantomData))
    }
}

impl Default for Num {
    fn default() -> Self {
        Num(0.0)
    }
}

type V3 = Arr<Num, 3>;

/// A finite number that single precision holds (colours, intensities and material
/// coefficients are kept in f32; a larger value would become infinity there).
#[derive(Debug, Clone, Copy, Default)]
struct Num32(f32);

impl<'de> Deserialize<'de> for Num32 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let x = Num::deserialize(d)?.0;
        if x.abs() <= f32::MAX as f64 {
            Ok(Num32(x as f32))
        } else {
            Err(de::Error::custom(format!(
                "{} is beyond single precision (at most {:e} in size)",
                crate::error::num(x),
                f32::MAX
            )))
        }
    }
}

type C3 = Arr<Num32, 3>;

fn v3(v: V3) -> DVec3 {
    DVec3::new(v.0[0].0, v.0[1].0, v.0[2].0)
}

fn c3(v: C3) -> Vec3 {
    Vec3::new(v.0[0].0, v.0[1].0, v.0[2].0)
}

/// `scale = 2.0` or `scale = [sx, sy, sz]`.
#[derive(Debug, Clone, Copy)]
struct Scale(DVec3);

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Scale;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or [sx, sy, sz]")
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> std::result::Result<Scale, E> {
                if x.is_finite() {
                    Ok(Scale(DVec3::splat(x)))
                } else {
                    Err(E::custom(format!("{x} is not a finite number")))
                }
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> std::result::Result<Scale, E> {
                Ok(Scale(DVec3::splat(x as f64)))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<Scale, A::Error> {
                let mut c = [0.0; 3];
                for (i, x) in c.iter_mut().enumerate() {
                    *x = seq.next_element::<Num>()?.ok_or_else(|| de::Error::invalid_length(i, &self))?.0;
                }
                if seq.next_element::<Num>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                Ok(Scale(DVec3::from_array(c)))
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    camera: Spanned<RawCamera>,
    render: Option<RawRender>,
    #[serde(default)]
    material: Vec<Spanned<RawMaterial>>,
    #[serde(default)]
    light: Vec<Spanned<RawLight>>,
    #[serde(default)]
    object: Vec<Spanned<RawObject>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    eye: Spanned<V3>,
    target: V3,
    up: Option<Spanned<V3>>,
    fov_y: Option<Spanned<Num>>,
    width: Option<Spanned<i64>>,
    height: Option<Spanned<i64>>,
    near: Option<Spanned<Num>>,
    far: Option<Spanned<Num>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRender {
    ambient: Option<C3>,
    background: Option<C3>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    name: Spanned<String>,
    color: Option<C3>,
    specular_color: Option<C3>,
    ka: Option<Num32>,
    kd: Option<Num32>,
    ks: Option<Num32>,
    shininess: Option<Spanned<Num32>>,
    model: Option<SpecularModel>,
    roughness: Option<Spanned<Num32>>,
    fresnel: Option<Spanned<Num32>>,
    mirror: Option<Spanned<Num32>>,
    shading: Option<ShadingMode>,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "lowercase")]
enum RawLightKind {
    Point,
    Directional,
    Spot,
    Area,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLight {
    kind: RawLightKind,
    color: Option<C3>,
    intensity: Option<Num32>,
    position: Option<V3>,
    direction: Option<Spanned<V3>>,
    cutoff: Option<Spanned<Num>>,
    exponent: Option<Spanned<Num>>,
    attenuation: Option<Spanned<V3>>,
    corner: Option<V3>,
    edge_u: Option<V3>,
    edge_v: Option<V3>,
    samples: Option<Spanned<Arr<u32, 2>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObject {
    name: Option<String>,
    material: Option<Spanned<String>>,
    mesh: Option<Spanned<String>>,
    polygons: Option<Vec<Vec<V3>>>,
    scale: Option<Scale>,
    rotate: Option<V3>,
    translate: Option<V3>,
    casts_shadows: Option<bool>,
    receiver: Option<bool>,
}

struct Ctx<'a> {
    file: &'a Path,
    src: &'a str,
}

impl Ctx<'_> {
    fn err(&self, span: Range<usize>, msg: impl Into<String>) -> Error {
        Error::input(FileLoc::at_offset(self.file, self.src, span.start), msg)
    }
}

impl Scene {
    /// Loads a scene file (`docs/scene-format.md`); meshes are read relative to its folder.
    /// Any problem is one [`Error`] naming the file and line:
    ///
    /// ```
    /// use umbra::{Error, Scene};
    ///
    /// let scene = Scene::load("scenes/cornell.toml")?;
    /// assert!(scene.lights().len() >= 1);
    ///
    /// let broken = std::env::temp_dir().join("umbra-broken.toml");
    /// std::fs::write(&broken, "[camera]\neye = [0, 0, 1]\ntarget = [0, 0, 0]\nfov = 45\n")?;
    /// match Scene::load(&broken) {
    ///     Err(Error::Load { loc, message }) => assert_eq!((loc.line, message.contains("fov")), (Some(4), true)),
    ///     other => panic!("{other:?}"),
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn load(path: impl AsRef<Path>) -> Result<Scene> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| Error::Io { path: path.to_owned(), source: e })?;
        let src = utf8(bytes, path)?;
        let dir = path.parent().map(Path::to_owned).unwrap_or_default();
        Scene::from_toml(&src, path, &dir)
    }

    /// Parses scene text; `file` names it in errors and `dir` is where relative mesh paths
    /// start from.
    pub fn from_toml(src: &str, file: impl AsRef<Path>, dir: impl AsRef<Path>) -> Result<Scene> {
        let (file, dir) = (file.as_ref(), dir.as_ref());
        // A UTF-8 byte-order mark is not part of the first line.
        let src = src.strip_prefix('\u{feff}').unwrap_or(src);
        let src = &crate::scene::lone_cr_to_lf(src);
        let cx = Ctx { file, src };
        let raw: RawScene = toml::from_str(src).map_err(|e| {
            let msg = e.message().trim().replace('\n', " ");
            match e.span() {
                Some(span) => cx.err(span, msg),
                None => Error::input(FileLoc::file(file), msg),
            }
        })?;

        let camera = camera(&cx, raw.camera)?;
        let render = raw.render.map_or_else(RenderSettings::default, |r| RenderSettings {
            ambient: r.ambient.map_or(Vec3::splat(0.1), c3),
            background: r.background.map_or(Vec3::ZERO, c3),
        });
        let (materials, by_name) = materials(&cx, raw.material)?;
        let lights = raw.light.into_iter().map(|l| light(&cx, l)).collect::<Result<Vec<_>>>()?;
        let mut meshes: HashMap<PathBuf, Arc<Mesh>> = HashMap::new();
        let objects =
            raw.object.into_iter().map(|o| object(&cx, o, &by_name, dir, &mut meshes)).collect::<Result<Vec<_>>>()?;
        Scene::new(camera, render, materials, lights, objects).map_err(|e| match e {
            Error::InvalidScene { part, problem } => Error::input(FileLoc::file(file), format!("{part}: {problem}")),
            e => e,
        })
    }
}

/// The `[camera]` table, checked; an error names the line of the key that is wrong.
fn camera(cx: &Ctx, raw: Spanned<RawCamera>) -> Result<Camera> {
    let cam_span = raw.span();
    let c = raw.into_inner();
    let num = |x: &Option<Spanned<Num>>| x.as_ref().map(|x| x.get_ref().0);
    // A side outside u32 (a negative width) is named with the range, as any other size is.
    let side = |x: &Option<Spanned<i64>>, name: &str, default: u32| match x {
        None => Ok(default),
        Some(v) => u32::try_from(*v.get_ref())
            .map_err(|_| cx.err(v.span(), format!("camera {name} {} must be 1..=32768 (pixels)", v.get_ref()))),
    };
    let (width, height) = (side(&c.width, "width", 640)?, side(&c.height, "height", 480)?);
    let camera = Camera {
        eye: v3(*c.eye.get_ref()),
        target: v3(c.target),
        up: c.up.as_ref().map_or(DVec3::Y, |u| v3(*u.get_ref())),
        fov_y: num(&c.fov_y).unwrap_or(45.0),
        width,
        height,
        near: num(&c.near).unwrap_or(0.01),
        far: num(&c.far),
    };
    // A camera error names the line of the key that is wrong.
    let key_span = |m: &str| {
        let span = |key: &str| match key {
            "eye" => Some(c.eye.span()),
            "up" => c.up.as_ref().map(Spanned::span),
            "fov_y" => c.fov_y.as_ref().map(Spanned::span),
            "size" => c.width.as_ref().or(c.height.as_ref()).map(Spanned::span),
            "near" => c.near.as_ref().map(Spanned::span),
            "far" => c.far.as_ref().map(Spanned::span),
            _ => None,
        };
        let key = m.strip_prefix("camera ").and_then(|r| r.split_whitespace().next()).unwrap_or("");
        span(key).unwrap_or(cam_span.clone())
    };
    camera.validate().map_err(|m| cx.err(key_span(&m), m))?;
    Ok(camera)
}

/// The `[[material]]` tables, each ranged key checked where it is written, and the index of
/// each by name.
fn materials(cx: &Ctx, raw: Vec<Spanned<RawMaterial>>) -> Result<(Vec<Material>, HashMap<String, usize>)> {
    let mut materials = Vec::new();
    let mut by_name = HashMap::new();
    for m in raw {
        let span = m.span();
        let m = m.into_inner();
        let name = m.name.get_ref().clone();
        if by_name.insert(name.clone(), materials.len()).is_some() {
            return Err(cx.err(m.name.span(), format!("material '{name}' is defined twice")));
        }
        let d = Material::new(name);
        // Each ranged key is checked where it is written.
        let ranged = |v: &Option<Spanned<Num32>>, key: &str, ok: fn(f32) -> bool, rule: &str, default: f32| match v {
            None => Ok(default),
            Some(x) if ok(x.get_ref().0) => Ok(x.get_ref().0),
            Some(x) => Err(cx.err(x.span(), format!("material {key} must be {rule}, got {}", x.get_ref().0))),
        };
        let unit = |x: f32| (0.0..=1.0).contains(&x);
        let mat = Material {
            color: m.color.map_or(d.color, c3),
            specular_color: m.specular_color.map_or(d.specular_color, c3),
            ka: m.ka.map_or(d.ka, |x| x.0),
            kd: m.kd.map_or(d.kd, |x| x.0),
            ks: m.ks.map_or(d.ks, |x| x.0),
            shininess: ranged(&m.shininess, "shininess", |x| x >= 0.0, ">= 0", d.shininess)?,
            model: m.model.unwrap_or(d.model),
            roughness: ranged(&m.roughness, "roughness", |x| x > 0.0, "> 0", d.roughness)?,
            fresnel: ranged(&m.fresnel, "fresnel", unit, "in [0, 1]", d.fresnel)?,
            mirror: ranged(&m.mirror, "mirror", unit, "in [0, 1]", d.mirror)?,
            shading: m.shading.unwrap_or(d.shading),
            ..d
        };
        let _ = span;
        materials.push(mat);
    }
    Ok((materials, by_name))
}

/// One `[[object]]` table: its material by name, its mesh (an OBJ file, read once however
/// many objects name it, or inline polygons) and its transform.
fn object(
    cx: &Ctx,
    o: Spanned<RawObject>,
    by_name: &HashMap<String, usize>,
    dir: &Path,
    meshes: &mut HashMap<PathBuf, Arc<Mesh>>,
) -> Result<Object> {
    let span = o.span();
    let o = o.into_inner();
    let material = match &o.material {
        None => 0,
        Some(name) => *by_name
            .get(name.get_ref())
            .ok_or_else(|| cx.err(name.span(), format!("no material named '{}'", name.get_ref())))?,
    };
    let mesh = match (o.mesh, o.polygons) {
        (Some(_), Some(_)) => return Err(cx.err(span, "object has both 'mesh' and 'polygons'")),
        (None, None) => return Err(cx.err(span, "object needs 'mesh' or 'polygons'")),
        (None, Some(polys)) => {
            let polys: Vec<Vec<DVec3>> = polys.into_iter().map(|p| p.into_iter().map(v3).collect()).collect();
            if polys.iter().any(Vec::is_empty) {
                return Err(cx.err(span, "a polygon in 'polygons' has no vertices"));
            }
            Arc::new(Mesh::from_polygons(&polys))
        }
        (Some(rel), None) => {
            let path = dir.join(rel.get_ref());
            match meshes.get(&path) {
                Some(m) => m.clone(),
                None => {
                    let bytes = std::fs::read(&path)
                        .map_err(|e| cx.err(rel.span(), format!("cannot read mesh '{}': {e}", path.display())))?;
                    let text = utf8(bytes, &path)?;
                    let m = Arc::new(super::parse_obj(&text, &path)?);
                    meshes.insert(path, m.clone());
                    m
                }
            }
        }
    };
    Ok(Object {
        name: o.name,
        material,
        mesh,
        transform: Transform {
            scale: o.scale.map_or(DVec3::ONE, |s| s.0),
            rotate: o.rotate.map_or(DVec3::ZERO, v3),
            translate: o.translate.map_or(DVec3::ZERO, v3),
        },
        casts_shadows: o.casts_shadows.unwrap_or(true),
        receiver: o.receiver.unwrap_or(false),
    })
}

/// The text of a file, or an error naming the line of its first byte that is not UTF-8.
fn utf8(bytes: Vec<u8>, path: &Path) -> Result<String> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let before = &e.as_bytes()[..at];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        Error::input(FileLoc::line(path, line), format!("not UTF-8 text (byte {at})"))
    })
}

fn light(cx: &Ctx, l: Spanned<RawLight>) -> Result<Light> {
    let span = l.span();
    let l = l.into_inner();
    let kind = l.kind;
    let need = |v: Option<V3>, key: &str| {
        v.map(v3).ok_or_else(|| cx.err(span.clone(), format!("{kind:?} light needs '{key}'").to_lowercase()))
    };
    let refuse = |present: bool, key: &str, kinds: &str| {
        if present {
            Err(cx.err(span.clone(), format!("'{key}' applies to {kinds} lights only")))
        } else {
            Ok(())
        }
    };
    use RawLightKind::*;
    refuse(l.position.is_some() && !matches!(kind, Point | Spot), "position", "point and spot")?;
    refuse(l.direction.is_some() && !matches!(kind, Directional | Spot), "direction", "directional and spot")?;
    refuse((l.cutoff.is_some() || l.exponent.is_some()) && kind != Spot, "cutoff/exponent", "spot")?;
    let area_keys = l.corner.is_some() || l.edge_u.is_some() || l.edge_v.is_some() || l.samples.is_some();
    refuse(area_keys && kind != Area, "corner/edge_u/edge_v/samples", "area")?;
    // Any length of direction: it is scaled before it is normalised, so a huge one does not
    // overflow.
    let direction = || {
        let d = l
            .direction
            .as_ref()
            .ok_or_else(|| cx.err(span.clone(), format!("{kind:?} light needs 'direction'").to_lowercase()))?;
        crate::geometry::unit(v3(*d.get_ref())).ok_or_else(|| cx.err(d.span(), "light direction is the zero vector"))
    };
    // Checked where written: the key's own line.
    let at = |v: &Option<Spanned<Num>>, default: f64, ok: fn(f64) -> bool, rule: &str, key: &str| match v {
        None => Ok(default),
        Some(x) if ok(x.get_ref().0) => Ok(x.get_ref().0),
        Some(x) => Err(cx.err(x.span(), format!("spot {key} must be {rule}, got {}", x.get_ref().0))),
    };
    let kind = match kind {
        Point => LightKind::Point { position: need(l.position, "position")? },
        Directional => LightKind::Directional { direction: direction()? },
        Spot => LightKind::Spot {
            position: need(l.position, "position")?,
            direction: direction()?,
            cutoff: at(&l.cutoff, 45.0, |c| c > 0.0 && c <= 180.0, "in (0, 180] degrees", "cutoff")?,
            exponent: at(&l.exponent, 1.0, |e| e >= 0.0, ">= 0", "exponent")?,
        },
        Area => LightKind::Area {
            corner: need(l.corner, "corner")?,
            edge_u: need(l.edge_u, "edge_u")?,
            edge_v: need(l.edge_v, "edge_v")?,
            samples: l
                .samples
                .as_ref()
                .map(|s| s.get_ref().0)
                .ok_or_else(|| cx.err(span.clone(), "area light needs 'samples'"))?,
        },
    };
    let light = Light {
        kind,
        color: l.color.map_or(Vec3::ONE, c3),
        intensity: l.intensity.map_or(1.0, |x| x.0),
        attenuation: l.attenuation.as_ref().map_or([1.0, 0.0, 0.0], |a| v3(*a.get_ref()).to_array()),
    };
    // What is left to check names the key whose value is wrong.
    let key_span = |m: &str| {
        let spanned = if m.starts_with("attenuation") {
            l.attenuation.as_ref().map(Spanned::span)
        } else if m.starts_with("area light samples") {
            l.samples.as_ref().map(Spanned::span)
        } else {
            None
        };
        spanned.unwrap_or(span.clone())
    };
    light.validate().map_err(|m| cx.err(key_span(&m), m))?;
    Ok(light)
}
