//! Reading a scene file (`SCENE_FORMAT.md` section 1). serde does the parsing with
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

type V3 = [Num; 3];

fn v3(v: V3) -> DVec3 {
    DVec3::new(v[0].0, v[1].0, v[2].0)
}

fn c3(v: V3) -> Vec3 {
    v3(v).as_vec3()
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
    eye: V3,
    target: V3,
    up: Option<V3>,
    fov_y: Option<Num>,
    width: Option<u32>,
    height: Option<u32>,
    near: Option<Num>,
    far: Option<Num>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRender {
    ambient: Option<V3>,
    background: Option<V3>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    name: Spanned<String>,
    color: Option<V3>,
    specular_color: Option<V3>,
    ka: Option<Num>,
    kd: Option<Num>,
    ks: Option<Num>,
    shininess: Option<Num>,
    model: Option<SpecularModel>,
    roughness: Option<Num>,
    fresnel: Option<Num>,
    mirror: Option<Num>,
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
    color: Option<V3>,
    intensity: Option<Num>,
    position: Option<V3>,
    direction: Option<V3>,
    cutoff: Option<Num>,
    exponent: Option<Num>,
    attenuation: Option<V3>,
    corner: Option<V3>,
    edge_u: Option<V3>,
    edge_v: Option<V3>,
    samples: Option<[u32; 2]>,
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
    /// Loads a scene file; meshes are read relative to its folder.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene> {
        let path = path.as_ref();
        let src = std::fs::read_to_string(path).map_err(|e| Error::Io { path: path.to_owned(), source: e })?;
        let dir = path.parent().map(Path::to_owned).unwrap_or_default();
        Scene::from_toml(&src, path, &dir)
    }

    /// Parses scene text; `file` names it in errors and `dir` is where relative mesh paths
    /// start from.
    pub fn from_toml(src: &str, file: &Path, dir: &Path) -> Result<Scene> {
        let cx = Ctx { file, src };
        let raw: RawScene = toml::from_str(src).map_err(|e| {
            let msg = e.message().trim().replace('\n', " ");
            match e.span() {
                Some(span) => cx.err(span, msg),
                None => Error::input(FileLoc::file(file), msg),
            }
        })?;

        let cam_span = raw.camera.span();
        let c = raw.camera.into_inner();
        let camera = Camera {
            eye: v3(c.eye),
            target: v3(c.target),
            up: c.up.map_or(DVec3::Y, v3),
            fov_y: c.fov_y.map_or(45.0, |x| x.0),
            width: c.width.unwrap_or(640),
            height: c.height.unwrap_or(480),
            near: c.near.map_or(0.01, |x| x.0),
            far: c.far.map(|x| x.0),
        };
        camera.validate().map_err(|m| cx.err(cam_span, m))?;

        let render = raw.render.map_or_else(RenderSettings::default, |r| RenderSettings {
            ambient: r.ambient.map_or(Vec3::splat(0.1), c3),
            background: r.background.map_or(Vec3::ZERO, c3),
        });

        let mut materials = Vec::new();
        let mut by_name = HashMap::new();
        for m in raw.material {
            let span = m.span();
            let m = m.into_inner();
            let name = m.name.get_ref().clone();
            if by_name.insert(name.clone(), materials.len()).is_some() {
                return Err(cx.err(m.name.span(), format!("material '{name}' is defined twice")));
            }
            let d = Material::new(name);
            let mat = Material {
                color: m.color.map_or(d.color, c3),
                specular_color: m.specular_color.map_or(d.specular_color, c3),
                ka: m.ka.map_or(d.ka, |x| x.0 as f32),
                kd: m.kd.map_or(d.kd, |x| x.0 as f32),
                ks: m.ks.map_or(d.ks, |x| x.0 as f32),
                shininess: m.shininess.map_or(d.shininess, |x| x.0 as f32),
                model: m.model.unwrap_or(d.model),
                roughness: m.roughness.map_or(d.roughness, |x| x.0 as f32),
                fresnel: m.fresnel.map_or(d.fresnel, |x| x.0 as f32),
                mirror: m.mirror.map_or(d.mirror, |x| x.0 as f32),
                shading: m.shading.unwrap_or(d.shading),
                ..d
            };
            if mat.roughness <= 0.0
                || mat.shininess < 0.0
                || !(0.0..=1.0).contains(&mat.fresnel)
                || !(0.0..=1.0).contains(&mat.mirror)
            {
                return Err(cx.err(span, "roughness must be > 0, shininess >= 0, fresnel and mirror in [0, 1]"));
            }
            materials.push(mat);
        }

        let lights = raw.light.into_iter().map(|l| light(&cx, l)).collect::<Result<Vec<_>>>()?;

        let mut objects = Vec::new();
        let mut meshes: HashMap<PathBuf, Arc<Mesh>> = HashMap::new();
        for o in raw.object {
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
                            let text = std::fs::read_to_string(&path).map_err(|e| {
                                cx.err(rel.span(), format!("cannot read mesh '{}': {e}", path.display()))
                            })?;
                            let m = Arc::new(super::parse_obj(&text, &path)?);
                            meshes.insert(path, m.clone());
                            m
                        }
                    }
                }
            };
            objects.push(Object {
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
            });
        }
        Scene::new(camera, render, materials, lights, objects).map_err(|e| match e {
            Error::Invalid(m) => Error::input(FileLoc::file(file), m),
            e => e,
        })
    }
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
    let unit = |d: DVec3| {
        if d.length() == 0.0 {
            Err(cx.err(span.clone(), "light direction is the zero vector"))
        } else {
            Ok(d.normalize())
        }
    };
    let kind = match kind {
        Point => LightKind::Point { position: need(l.position, "position")? },
        Directional => LightKind::Directional { direction: unit(need(l.direction, "direction")?)? },
        Spot => LightKind::Spot {
            position: need(l.position, "position")?,
            direction: unit(need(l.direction, "direction")?)?,
            cutoff: l.cutoff.map_or(45.0, |x| x.0),
            exponent: l.exponent.map_or(1.0, |x| x.0),
        },
        Area => LightKind::Area {
            corner: need(l.corner, "corner")?,
            edge_u: need(l.edge_u, "edge_u")?,
            edge_v: need(l.edge_v, "edge_v")?,
            samples: l.samples.ok_or_else(|| cx.err(span.clone(), "area light needs 'samples'"))?,
        },
    };
    let light = Light {
        kind,
        color: l.color.map_or(Vec3::ONE, c3),
        intensity: l.intensity.map_or(1.0, |x| x.0 as f32),
        attenuation: l.attenuation.map_or([1.0, 0.0, 0.0], |a| v3(a).to_array()),
    };
    light.validate().map_err(|m| cx.err(span, m))?;
    Ok(light)
}
