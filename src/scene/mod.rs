//! Scenes: the camera, materials, lights and objects of `docs/scene-format.md`, and the world-space
//! polygons they compile to. Every polygon keeps its global face id.

mod build;
mod load;
mod obj;
mod solids;
pub use build::SceneBuilder;
pub(crate) use obj::ObjText;
pub(crate) use solids::Solid;
#[cfg(test)]
pub(crate) use solids::NO_SOLID;
mod write;

/// No polygon (in [`Scene::across`]).
pub(crate) const NO_POLYGON: u32 = u32::MAX;

pub use obj::parse_obj;

/// Old Mac line endings: a lone `\r` (no `\n` after it) becomes `\n`. Byte offsets do not
/// change, so errors still point at the right line and column.
pub(crate) fn lone_cr_to_lf(text: &str) -> std::borrow::Cow<'_, str> {
    let bytes = text.as_bytes();
    let lone = |i: usize| bytes[i] == b'\r' && bytes.get(i + 1) != Some(&b'\n');
    if !(0..bytes.len()).any(lone) {
        return std::borrow::Cow::Borrowed(text);
    }
    let fixed: Vec<u8> = (0..bytes.len()).map(|i| if lone(i) { b'\n' } else { bytes[i] }).collect();
    // Only ASCII bytes changed, so the text is still UTF-8.
    std::borrow::Cow::Owned(String::from_utf8(fixed).unwrap_or_else(|_| text.to_owned()))
}

use crate::error::{Error, Result};
/// A polygon's plane ([`Polygon::plane`]), and what a light sample's side of it is asked of.
pub use crate::geometry::Plane;
use crate::geometry::{classify_face, newell_normal, FaceShape};
use glam::{DMat3, DMat4, DVec3, Vec3};
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// The pinhole camera of section 3.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: DVec3,
    /// Point looked at.
    pub target: DVec3,
    /// Up hint (default +Y).
    pub up: DVec3,
    /// Vertical field of view in degrees (default 45).
    pub fov_y: f64,
    /// Image width in pixels (default 640).
    pub width: u32,
    /// Image height in pixels (default 480).
    pub height: u32,
    /// Camera-space depth of the near plane (default 0.01).
    pub near: f64,
    /// Camera-space depth of the far plane, if any.
    pub far: Option<f64>,
}

impl Camera {
    /// A camera at `eye` looking at `target` with the contract's defaults.
    pub fn new(eye: DVec3, target: DVec3) -> Self {
        Camera { eye, target, up: DVec3::Y, fov_y: 45.0, width: 640, height: 480, near: 0.01, far: None }
    }

    /// The narrowest field of view accepted, in degrees: narrower, the projection's scale
    /// (`1 / tan(fov_y / 2)`) loses the precision the scan converter needs.
    pub const MIN_FOV_Y: f64 = 1e-4;

    pub(crate) fn validate(&self) -> std::result::Result<(), String> {
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return Err("camera eye, target and up must be finite".into());
        }
        let Some(f) = crate::geometry::unit(self.target - self.eye) else {
            return Err("camera eye and target are the same point (or too far apart for f64)".into());
        };
        let Some(up) = crate::geometry::unit(self.up) else {
            return Err("camera up is the zero vector".into());
        };
        if f.cross(up).length() < 1e-9 {
            return Err("camera up is parallel to the view direction".into());
        }
        if !(self.fov_y >= Self::MIN_FOV_Y && self.fov_y < 180.0) {
            return Err(format!(
                "camera fov_y must be in [{}, 180) degrees, got {}",
                Self::MIN_FOV_Y,
                crate::error::num(self.fov_y)
            ));
        }
        if self.width == 0 || self.height == 0 || self.width > 32768 || self.height > 32768 {
            return Err(format!("camera size {}x{} must be 1..=32768 each way", self.width, self.height));
        }
        if !(self.near > 0.0 && self.near.is_finite()) {
            return Err(format!("camera near must be > 0, got {}", self.near));
        }
        if let Some(far) = self.far {
            if far <= self.near {
                return Err(format!("camera far ({far}) must be beyond near ({})", self.near));
            }
        }
        Ok(())
    }
}

/// The `[render]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    /// Global ambient intensity I_a.
    pub ambient: Vec3,
    /// Background colour.
    pub background: Vec3,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings { ambient: Vec3::splat(0.1), background: Vec3::ZERO }
    }
}

/// Specular reflection model of a material.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpecularModel {
    /// Phong: `(R.V)^n`.
    #[default]
    Phong,
    /// Blinn-Phong: `(N.H)^n`, the halfway-vector highlight of Blinn (1977), not his microfacet
    /// model (`docs/shading.md`, "Against the notes"); `"blinn"` in a scene file.
    Blinn,
    /// Cook-Torrance microfacet model.
    CookTorrance,
}

/// How a polygon's interior is coloured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShadingMode {
    /// One colour per polygon, lit at its centroid.
    #[default]
    Flat,
    /// Vertex colours interpolated.
    Gouraud,
    /// Vertex normals interpolated, lit per pixel.
    Phong,
}

/// A `[[material]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Name objects refer to it by.
    pub name: String,
    /// Diffuse (object) colour O_d.
    pub color: Vec3,
    /// Specular colour O_s.
    pub specular_color: Vec3,
    /// Ambient coefficient.
    pub ka: f32,
    /// Diffuse coefficient.
    pub kd: f32,
    /// Specular coefficient.
    pub ks: f32,
    /// Specular exponent n.
    pub shininess: f32,
    /// Specular model.
    pub model: SpecularModel,
    /// Cook-Torrance roughness (Beckmann m).
    pub roughness: f32,
    /// Cook-Torrance Fresnel reflectance at normal incidence F0 (Schlick); default 0.04.
    pub fresnel: f32,
    /// Planar mirror reflectance (0: not a mirror); its front side reflects.
    pub mirror: f32,
    /// Shading mode.
    pub shading: ShadingMode,
}

impl Material {
    /// The loader's checks: finite values, `roughness > 0`, `shininess >= 0`, `fresnel` and
    /// `mirror` in [0, 1].
    pub(crate) fn validate(&self) -> std::result::Result<(), String> {
        let finite = self.color.is_finite()
            && self.specular_color.is_finite()
            && [self.ka, self.kd, self.ks, self.shininess, self.roughness, self.fresnel, self.mirror]
                .iter()
                .all(|x| x.is_finite());
        if !finite {
            return Err("values must be finite".into());
        }
        if self.roughness <= 0.0 {
            return Err(format!("roughness must be > 0, got {}", self.roughness));
        }
        if self.shininess < 0.0 {
            return Err(format!("shininess must be >= 0, got {}", self.shininess));
        }
        if !(0.0..=1.0).contains(&self.fresnel) || !(0.0..=1.0).contains(&self.mirror) {
            return Err("fresnel and mirror must be in [0, 1]".into());
        }
        Ok(())
    }

    /// A material with the contract's defaults.
    pub fn new(name: impl Into<String>) -> Self {
        Material {
            name: name.into(),
            color: Vec3::splat(0.8),
            specular_color: Vec3::ONE,
            ka: 1.0,
            kd: 0.8,
            ks: 0.0,
            shininess: 32.0,
            model: SpecularModel::Phong,
            roughness: 0.3,
            fresnel: 0.04,
            mirror: 0.0,
            shading: ShadingMode::Flat,
        }
    }
}

/// What kind of light, with its geometry.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum LightKind {
    /// A point light.
    Point {
        /// Where.
        position: DVec3,
    },
    /// A light at infinity.
    Directional {
        /// The unit direction the light travels.
        direction: DVec3,
    },
    /// A point light with a cone.
    Spot {
        /// Where.
        position: DVec3,
        /// Unit axis of the cone (the way the light travels).
        direction: DVec3,
        /// Half-angle of the cone in degrees.
        cutoff: f64,
        /// Falloff `cos^exponent` inside the cone.
        exponent: f64,
    },
    /// A parallelogram sampled by a fixed grid of point lights.
    Area {
        /// One corner.
        corner: DVec3,
        /// First edge.
        edge_u: DVec3,
        /// Second edge.
        edge_v: DVec3,
        /// Grid size `[m, n]`.
        samples: [u32; 2],
    },
}

/// A `[[light]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    /// Geometry.
    pub kind: LightKind,
    /// Colour.
    pub color: Vec3,
    /// Intensity (shared among an area light's samples).
    pub intensity: f32,
    /// Attenuation `[a, b, c]`: `f_att = min(1, 1/(a + b d + c d^2))`.
    pub attenuation: [f64; 3],
}

/// One point of a light that shadows are computed for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightSample {
    /// A point light, or one sample of a spot or area light.
    Point(DVec3),
    /// A directional light: the unit direction the light travels.
    Directional(DVec3),
}

impl LightSample {
    /// Whether the light is on the side of `plane` that the eye is on (the same-side rule of
    /// section 3). Both distances must be non-zero; a light on the plane lights neither side.
    pub fn on_seen_side(&self, plane: &Plane, eye: DVec3) -> bool {
        let (e, l) = (plane.distance(eye), self.side_of(plane));
        e != 0.0 && l != 0.0 && (e > 0.0) == (l > 0.0)
    }

    /// Where the light lies relative to `plane`: positive on the side its normal points to,
    /// negative behind, zero in it (a point light's signed distance; for a directional light,
    /// `−n·d`). The one faces-the-light test: the same-side rule, the projection's side and
    /// Williams' front-face culling all read it.
    pub fn side_of(&self, plane: &Plane) -> f64 {
        match *self {
            LightSample::Point(s) => plane.distance(s),
            LightSample::Directional(d) => -plane.n.dot(d),
        }
    }

    /// Unit vector from `p` toward the light, and the distance (infinite for directional).
    pub fn toward(&self, p: DVec3) -> (DVec3, f64) {
        match *self {
            LightSample::Point(s) => {
                let v = s - p;
                let d = v.length();
                (v / d, d)
            }
            LightSample::Directional(d) => (-d, f64::INFINITY),
        }
    }
}

impl Light {
    /// The light's samples: one for point, spot and directional lights, `m*n` for area lights
    /// at `corner + (i+0.5)/m edge_u + (j+0.5)/n edge_v`.
    pub fn samples(&self) -> Vec<LightSample> {
        match self.kind {
            LightKind::Point { position } | LightKind::Spot { position, .. } => {
                vec![LightSample::Point(position)]
            }
            LightKind::Directional { direction } => vec![LightSample::Directional(direction)],
            LightKind::Area { corner, edge_u, edge_v, samples: [m, n] } => (0..m)
                .flat_map(|i| {
                    (0..n).map(move |j| {
                        let u = (i as f64 + 0.5) / m as f64;
                        let v = (j as f64 + 0.5) / n as f64;
                        LightSample::Point(corner + u * edge_u + v * edge_v)
                    })
                })
                .collect(),
        }
    }

    /// Number of samples.
    pub fn sample_count(&self) -> usize {
        match self.kind {
            LightKind::Area { samples: [m, n], .. } => (m * n) as usize,
            _ => 1,
        }
    }

    fn validate(&self) -> std::result::Result<(), String> {
        let finite = match &self.kind {
            LightKind::Point { position } => position.is_finite(),
            LightKind::Directional { direction } => direction.is_finite(),
            LightKind::Spot { position, direction, cutoff, exponent } => {
                position.is_finite() && direction.is_finite() && cutoff.is_finite() && exponent.is_finite()
            }
            LightKind::Area { corner, edge_u, edge_v, .. } => {
                corner.is_finite() && edge_u.is_finite() && edge_v.is_finite()
            }
        };
        if !finite || !self.color.is_finite() || !self.intensity.is_finite() {
            return Err("light position, direction, edges, colour and intensity must be finite".into());
        }
        if let LightKind::Spot { exponent, .. } = self.kind {
            if exponent < 0.0 {
                return Err(format!("spot exponent must be >= 0, got {exponent}"));
            }
        }
        let a = self.attenuation;
        if a.iter().any(|&c| c.is_nan() || c < 0.0) || a.iter().all(|&c| c == 0.0) {
            return Err(format!("attenuation {a:?} must be >= 0 and not all zero"));
        }
        match &self.kind {
            LightKind::Directional { direction } | LightKind::Spot { direction, .. }
                if (direction.length() - 1.0).abs() > 1e-9 =>
            {
                Err("light direction must be a unit vector".into())
            }
            LightKind::Spot { cutoff, .. } if !(*cutoff > 0.0 && *cutoff <= 180.0) => {
                Err(format!("spot cutoff must be in (0, 180] degrees, got {cutoff}"))
            }
            LightKind::Area { edge_u, edge_v, samples, .. } => {
                if samples[0] == 0 || samples[1] == 0 || samples[0] as u64 * samples[1] as u64 > 4096 {
                    Err(format!("area light samples {samples:?} must each be >= 1, at most 4096 in all"))
                } else if edge_u.cross(*edge_v).length() == 0.0 {
                    Err("area light edges edge_u and edge_v are parallel or zero".into())
                } else {
                    Ok(())
                }
            }
            _ => Ok(()),
        }
    }
}

/// A polygon mesh as read: positions, normals and faces that index them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Vertex normals (`vn`).
    pub normals: Vec<DVec3>,
    /// Faces, in file order (each one a face id).
    pub faces: Vec<Face>,
}

/// One face of a [`Mesh`]: 0-based indices.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Face {
    /// Position indices.
    pub vertices: Vec<u32>,
    /// Normal indices, one per vertex, or empty.
    pub normals: Vec<u32>,
}

impl Mesh {
    /// An axis-aligned box from corner `lo` to corner `hi`: six quads, wound counter-clockwise
    /// seen from outside (a closed solid).
    ///
    /// ```
    /// use umbra::{glam::DVec3, Mesh};
    /// let cube = Mesh::cuboid(DVec3::ZERO, DVec3::ONE);
    /// assert_eq!((cube.positions.len(), cube.faces.len()), (8, 6));
    /// ```
    pub fn cuboid(lo: DVec3, hi: DVec3) -> Mesh {
        let mut mesh = Mesh::default();
        crate::generate::add_box(&mut mesh, lo, hi, false);
        mesh
    }

    /// One quad with corners `corners`, in order (its front is the side they run
    /// counter-clockwise round).
    pub fn quad(corners: [DVec3; 4]) -> Mesh {
        Mesh::from_polygons(&[corners.to_vec()])
    }

    /// A flat grid of `nu × nv` quads from `origin` along `u` and `v` (the whole grid's
    /// edges), front on the side `u × v` points to: a floor or a wall made of many polygons.
    pub fn grid(origin: DVec3, u: DVec3, v: DVec3, nu: u32, nv: u32) -> Mesh {
        let (nu, nv) = (nu.max(1), nv.max(1));
        let at = |i: u32, j: u32| origin + u * (i as f64 / nu as f64) + v * (j as f64 / nv as f64);
        let quads: Vec<Vec<DVec3>> = (0..nv)
            .flat_map(|j| (0..nu).map(move |i| (i, j)))
            .map(|(i, j)| vec![at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)])
            .collect();
        Mesh::from_polygons(&quads)
    }

    /// A UV sphere round `centre` of radius `r`, as near `triangles` triangles as a UV sphere
    /// has, with vertex normals (a closed solid; [`crate::generate::sphere_mesh`]).
    pub fn sphere(centre: DVec3, r: f64, triangles: u32) -> Mesh {
        crate::generate::sphere_mesh(centre, r, triangles)
    }

    /// A mesh of separate polygons (the `polygons = [...]` form).
    pub fn from_polygons(polys: &[Vec<DVec3>]) -> Mesh {
        let mut mesh = Mesh::default();
        for p in polys {
            let first = mesh.positions.len() as u32;
            mesh.positions.extend_from_slice(p);
            mesh.faces.push(Face { vertices: (first..first + p.len() as u32).collect(), normals: Vec::new() });
        }
        mesh
    }
}

/// Object transform `M = T(translate) Rz Ry Rx S(scale)`, angles in degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    /// Scale per axis.
    pub scale: DVec3,
    /// Rotation about X, then Y, then Z, degrees.
    pub rotate: DVec3,
    /// Translation.
    pub translate: DVec3,
}

impl Transform {
    /// A move by `t`.
    pub fn translation(t: DVec3) -> Transform {
        Transform { translate: t, ..Transform::default() }
    }

    /// A scale by `s` per axis.
    pub fn scaling(s: DVec3) -> Transform {
        Transform { scale: s, ..Transform::default() }
    }

    /// A rotation by `degrees` about X, then Y, then Z.
    pub fn rotation(degrees: DVec3) -> Transform {
        Transform { rotate: degrees, ..Transform::default() }
    }

    /// The same transform, moved by `t` as well (after scaling and rotating).
    pub fn translated(self, t: DVec3) -> Transform {
        Transform { translate: t, ..self }
    }

    /// The same transform, scaled by `s` first.
    pub fn scaled(self, s: DVec3) -> Transform {
        Transform { scale: s, ..self }
    }

    /// The same transform, rotated by `degrees` (after scaling, before moving).
    pub fn rotated(self, degrees: DVec3) -> Transform {
        Transform { rotate: degrees, ..self }
    }
}

impl Default for Transform {
    fn default() -> Self {
        Transform { scale: DVec3::ONE, rotate: DVec3::ZERO, translate: DVec3::ZERO }
    }
}

impl Transform {
    /// The matrix `T Rz Ry Rx S`.
    pub fn matrix(&self) -> DMat4 {
        let r = self.rotate * (std::f64::consts::PI / 180.0);
        DMat4::from_translation(self.translate)
            * DMat4::from_rotation_z(r.z)
            * DMat4::from_rotation_y(r.y)
            * DMat4::from_rotation_x(r.x)
            * DMat4::from_scale(self.scale)
    }
}

/// An `[[object]]`: a mesh placed in the world with a material.
#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    /// Optional name.
    pub name: Option<String>,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// The mesh in object space.
    pub mesh: Arc<Mesh>,
    /// Placement.
    pub transform: Transform,
    /// Whether its polygons cast shadows.
    pub casts_shadows: bool,
    /// Whether Blinn's planar shadows are projected onto its polygons.
    pub receiver: bool,
}

/// A world-space planar polygon. Its vertices are `scene.vertices[start..start+len]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Polygon {
    /// Global face id (pieces of a non-planar face share it).
    pub face: u32,
    /// Index into [`Scene::objects`].
    pub object: u32,
    /// First vertex in [`Scene::vertices`].
    pub start: u32,
    /// Vertex count (at least 3).
    pub len: u32,
    /// Its plane; the normal is the Newell normal (front side counter-clockwise).
    pub plane: Plane,
}

/// A scene, as described and as compiled to world-space polygons. Its parts are read through
/// getters; the camera and the lights can be replaced through setters that check them, so a
/// scene that loaded (or was built by [`Scene::new`]) stays valid: its compiled polygons
/// always match its objects, and its camera and lights always pass the loader's checks.
#[derive(Debug, Clone)]
pub struct Scene {
    pub(crate) camera: Camera,
    pub(crate) render: RenderSettings,
    pub(crate) materials: Vec<Material>,
    pub(crate) lights: Vec<Light>,
    pub(crate) objects: Vec<Object>,
    /// World-space polygons, degenerate faces left out, non-planar faces split into fans.
    pub(crate) polygons: Vec<Polygon>,
    /// Vertex positions of all polygons.
    pub(crate) vertices: Vec<DVec3>,
    /// Unit vertex normals, parallel to `vertices`.
    pub(crate) normals: Vec<DVec3>,
    pub(crate) face_count: u32,
    /// Each polygon's closed solid (an index into `solids`), or [`NO_SOLID`].
    pub(crate) solid_of: Vec<u32>,
    /// The closed, consistently wound surfaces among the objects' polygons (see `solids`).
    pub(crate) solids: Vec<Solid>,
    /// Parallel to `vertices`: the polygon across the edge from each corner to the next,
    /// where exactly one other polygon of the object runs that edge the other way (between
    /// the same welded positions), or [`NO_POLYGON`].
    pub(crate) across: Vec<u32>,
    /// Which compiled polygons these are: a number of its own for every compile (and every
    /// change of the polygons since), shared by clones, so that what a renderer derives from
    /// the polygons (Crow's edge adjacency) can be kept for the next frame of the same scene.
    pub(crate) polygons_id: u64,
    /// The vertices' bounds, found when they change.
    bounds: Option<(DVec3, DVec3)>,
}

/// The next [`Scene::polygons_id`].
static NEXT_POLYGONS_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fn next_polygons_id() -> u64 {
    NEXT_POLYGONS_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl Scene {
    /// Builds a scene from its parts, checking values and compiling the world polygons.
    /// An empty `materials` gets the grey default.
    pub fn new(
        camera: Camera,
        render: RenderSettings,
        mut materials: Vec<Material>,
        lights: Vec<Light>,
        objects: Vec<Object>,
    ) -> Result<Scene> {
        camera.validate().map_err(|m| Error::scene("camera", m))?;
        for (i, l) in lights.iter().enumerate() {
            l.validate().map_err(|m| Error::scene(format!("light {i}"), m))?;
        }
        if materials.is_empty() {
            materials.push(Material::new("default"));
        }
        for m in &materials {
            m.validate().map_err(|e| Error::scene(format!("material '{}'", m.name), e))?;
        }
        for (i, o) in objects.iter().enumerate() {
            if o.material >= materials.len() {
                return Err(Error::scene(format!("object {i}"), format!("material index {} out of range", o.material)));
            }
            let m = &o.mesh;
            let bad = m.faces.iter().any(|f| {
                f.vertices.iter().any(|&v| v as usize >= m.positions.len())
                    || f.normals.iter().any(|&v| v as usize >= m.normals.len())
                    || (!f.normals.is_empty() && f.normals.len() != f.vertices.len())
            });
            if bad {
                return Err(Error::scene(format!("object {i}"), "face index out of range"));
            }
            let finite = m.positions.iter().chain(&m.normals).all(|p| p.is_finite());
            let t = &o.transform;
            if !(finite && t.scale.is_finite() && t.rotate.is_finite() && t.translate.is_finite()) {
                return Err(Error::scene(format!("object {i}"), "non-finite coordinate"));
            }
        }
        let mut scene = Scene {
            camera,
            render,
            materials,
            lights,
            objects,
            polygons: Vec::new(),
            vertices: Vec::new(),
            normals: Vec::new(),
            face_count: 0,
            solid_of: Vec::new(),
            solids: Vec::new(),
            across: Vec::new(),
            polygons_id: next_polygons_id(),
            bounds: None,
        };
        scene.compile()?;
        Ok(scene)
    }

    fn compile(&mut self) -> Result<()> {
        // Reserved as planar faces need (a fan piece's corners may grow them): a million
        // triangles' lists are most of a scene's memory, and doubling them as they fill left
        // a third of it unused.
        let faces = self.objects.iter().flat_map(|o| &o.mesh.faces);
        let corners: usize = faces.clone().map(|f| f.vertices.len()).sum();
        self.polygons.reserve_exact(faces.count());
        self.solid_of.reserve_exact(self.polygons.capacity());
        for list in [&mut self.vertices, &mut self.normals] {
            list.reserve_exact(corners);
        }
        self.across.reserve_exact(corners);
        for (oi, obj) in self.objects.iter().enumerate() {
            let m = obj.transform.matrix();
            let nm = DMat3::from_mat4(m).inverse().transpose();
            let mesh = &obj.mesh;
            let world: Vec<DVec3> = mesh.positions.iter().map(|&p| m.transform_point3(p)).collect();
            if !world.iter().all(|p| p.is_finite()) {
                let name = obj.name.as_deref().map_or(String::new(), |n| format!(" '{n}'"));
                return Err(Error::scene(
                    format!("object {oi}{name}"),
                    "its transform takes vertices beyond the range of f64",
                ));
            }
            let vn: Vec<DVec3> = mesh.normals.iter().map(|&n| (nm * n).normalize_or_zero()).collect();
            // Averaged normals for faces without `vn`: area-weighted face normals summed over
            // every face that shares the vertex's position (meshes often repeat a position
            // along a texture seam; welding keeps the seam from showing).
            let mut weld: FxHashMap<[u64; 3], usize> = FxHashMap::default();
            weld.reserve(world.len());
            let rep: Vec<usize> = world
                .iter()
                .enumerate()
                .map(|(i, p)| *weld.entry(p.to_array().map(f64::to_bits)).or_insert(i))
                .collect();
            let mut avg = vec![DVec3::ZERO; world.len()];
            for f in mesh.faces.iter().filter(|f| f.normals.is_empty()) {
                let pts: Vec<DVec3> = f.vertices.iter().map(|&v| world[v as usize]).collect();
                let n = newell_normal(&pts);
                for &v in &f.vertices {
                    avg[rep[v as usize]] += n;
                }
            }
            let avg: Vec<DVec3> = rep.iter().map(|&r| avg[r]).collect();
            let mut pts = Vec::new();
            // The object's polygons as (first vertex, count) from `v0`, and each vertex's
            // welded position id: what finding its solids needs.
            let (v0, mut ranges, mut keys) = (self.vertices.len() as u32, Vec::new(), Vec::new());
            for (fi, f) in mesh.faces.iter().enumerate() {
                let face = self.face_count + fi as u32;
                pts.clear();
                pts.extend(f.vertices.iter().map(|&v| world[v as usize]));
                let normal = |k: usize, plane: &Plane| {
                    let n = if f.normals.is_empty() { avg[f.vertices[k] as usize] } else { vn[f.normals[k] as usize] };
                    let n = n.normalize_or_zero();
                    if n == DVec3::ZERO {
                        plane.n
                    } else {
                        n
                    }
                };
                let mut push = |idx: &[usize], plane: Plane| {
                    let start = self.vertices.len() as u32;
                    for &k in idx {
                        self.vertices.push(pts[k]);
                        self.normals.push(normal(k, &plane));
                        keys.push(rep[f.vertices[k] as usize] as u32);
                    }
                    ranges.push((start - v0, idx.len() as u32));
                    self.polygons.push(Polygon { face, object: oi as u32, start, len: idx.len() as u32, plane });
                };
                match classify_face(&pts) {
                    FaceShape::Degenerate => {}
                    FaceShape::Planar(idx, plane) => push(&idx, plane),
                    FaceShape::Fan(tris) => {
                        for (tri, plane) in tris {
                            push(&tri, plane);
                        }
                    }
                }
            }
            self.face_count += mesh.faces.len() as u32;
            let corners = solids::Corners { ranges: &ranges, keys: &keys, verts: &self.vertices[v0 as usize..] };
            let found = solids::find(&corners, self.solids.len() as u32);
            self.solid_of.extend(found.solid_of);
            self.solids.extend(found.solids);
            let p0 = self.polygons.len() as u32 - ranges.len() as u32;
            self.across
                .extend(found.across.into_iter().map(|q| if q == solids::NO_SOLID { NO_POLYGON } else { p0 + q }));
        }
        self.polygons.shrink_to_fit();
        self.solid_of.shrink_to_fit();
        self.vertices.shrink_to_fit();
        self.normals.shrink_to_fit();
        self.across.shrink_to_fit();
        self.bounds = self.vertex_bounds();
        Ok(())
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Replaces the camera, after the checks the loader makes (an error leaves the scene as
    /// it was).
    ///
    /// ```
    /// let mut scene = umbra::generate::cubes(1, umbra::generate::Faces::Quads, 64, 48)?;
    /// let mut camera = scene.camera().clone();
    /// camera.width = 32;
    /// scene.set_camera(camera.clone())?;
    /// camera.width = 0;
    /// assert!(scene.set_camera(camera).is_err());
    /// assert_eq!(scene.camera().width, 32);
    /// # Ok::<(), umbra::Error>(())
    /// ```
    pub fn set_camera(&mut self, camera: Camera) -> Result<()> {
        camera.validate().map_err(|m| Error::scene("camera", m))?;
        self.camera = camera;
        Ok(())
    }

    /// Global settings.
    pub fn settings(&self) -> &RenderSettings {
        &self.render
    }

    /// The materials (at least one).
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Replaces the materials, after the checks the loader makes; every object's material
    /// index must stay in range. An empty list gets the grey default, as in [`Scene::new`].
    pub fn set_materials(&mut self, mut materials: Vec<Material>) -> Result<()> {
        if materials.is_empty() {
            materials.push(Material::new("default"));
        }
        for m in &materials {
            m.validate().map_err(|e| Error::scene(format!("material '{}'", m.name), e))?;
        }
        if let Some((i, o)) = self.objects.iter().enumerate().find(|(_, o)| o.material >= materials.len()) {
            return Err(Error::scene(format!("object {i}"), format!("material index {} out of range", o.material)));
        }
        self.materials = materials;
        Ok(())
    }

    /// The lights, in file order.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// Replaces the lights, after the checks the loader makes.
    pub fn set_lights(&mut self, lights: Vec<Light>) -> Result<()> {
        for (i, l) in lights.iter().enumerate() {
            l.validate().map_err(|m| Error::scene(format!("light {i}"), m))?;
        }
        self.lights = lights;
        Ok(())
    }

    /// The objects, in file order.
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// Marks object `object` as a receiver of Blinn's planar shadows, or not.
    pub fn set_receiver(&mut self, object: usize, receiver: bool) -> Result<()> {
        let count = self.objects.len();
        let o = self
            .objects
            .get_mut(object)
            .ok_or_else(|| Error::out_of_range("object", object, format!("an object of the scene (it has {count})")))?;
        o.receiver = receiver;
        Ok(())
    }

    /// The index of the object called `name`.
    pub fn object_named(&self, name: &str) -> Option<usize> {
        self.objects.iter().position(|o| o.name.as_deref() == Some(name))
    }

    /// Marks the large planar objects as receivers of Blinn's planar shadows, and returns
    /// them: every object whose polygons all lie in one plane (normals within 10⁻⁶, offsets
    /// within 10⁻⁶ of the scene's size) and whose area is at least a tenth of the largest
    /// such object's. On a typical scene that is the ground and the walls; an object that
    /// is not flat (a cube, a sphere) is never one.
    pub fn mark_planar_receivers(&mut self) -> Vec<usize> {
        let size = self.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length().max(f64::MIN_POSITIVE));
        let mut area = vec![Some(0.0f64); self.objects.len()];
        let mut plane: Vec<Option<crate::geometry::Plane>> = vec![None; self.objects.len()];
        for (i, p) in self.polygons.iter().enumerate() {
            let o = p.object as usize;
            let same = |q: &crate::geometry::Plane| {
                (q.n - p.plane.n).length() <= 1e-6 && (q.d - p.plane.d).abs() <= 1e-6 * size
            };
            match plane[o] {
                Some(q) if !same(&q) => area[o] = None,
                _ => plane[o] = Some(p.plane),
            }
            if let Some(a) = &mut area[o] {
                *a += 0.5 * crate::geometry::newell_normal(self.verts(i)).length();
            }
        }
        let largest = area.iter().flatten().fold(0.0f64, |m, &a| m.max(a));
        let chosen: Vec<usize> =
            (0..self.objects.len()).filter(|&o| area[o].is_some_and(|a| a > 0.0 && a >= 0.1 * largest)).collect();
        for &o in &chosen {
            self.objects[o].receiver = true;
        }
        chosen
    }

    /// The compiled world-space polygons: degenerate faces left out, non-planar faces split
    /// into fans.
    pub fn polygons(&self) -> &[Polygon] {
        &self.polygons
    }

    /// The vertex positions of all polygons.
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// The number of face ids (degenerate faces included).
    pub fn face_count(&self) -> u32 {
        self.face_count
    }

    /// The vertices of polygon `i`.
    #[inline]
    pub fn verts(&self, i: usize) -> &[DVec3] {
        let p = &self.polygons[i];
        &self.vertices[p.start as usize..(p.start + p.len) as usize]
    }

    /// Each closed solid's polygons, in increasing order (`members[s]` for solid `s`).
    pub(crate) fn solid_members(&self) -> Vec<Vec<u32>> {
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); self.solids.len()];
        for (i, &s) in self.solid_of.iter().enumerate() {
            if let Some(m) = members.get_mut(s as usize) {
                m.push(i as u32);
            }
        }
        members
    }

    /// `closed[s]`: whether solid `s` is closed as seen from `from` (a light sample or the
    /// eye), which lies outside its bounds. [`Scene::turned_away_on_solid`] needs it.
    pub(crate) fn closed_from(&self, from: LightSample) -> Vec<bool> {
        self.solids.iter().map(|s| s.closed_from(from)).collect()
    }

    /// Whether polygon `i` belongs to a solid closed as seen from `from` (`closed`, from
    /// [`Scene::closed_from`]) and turns its back to `from`. Seen from `from`, such a polygon
    /// is covered everywhere by a polygon of the same solid that faces `from`, nearer along
    /// every ray (where the two meet, at their shared edge, at the same distance): it never
    /// casts a shadow, and is never the nearest polygon seen. Ours, not the papers'; see
    /// `docs/algorithms/bouknight-kelley.md`, "Speed-ups that are ours", and
    /// `docs/algorithms/scanline.md`.
    pub(crate) fn turned_away_on_solid(&self, i: usize, from: LightSample, closed: &[bool]) -> bool {
        self.turned_away_at(i, from.side_of(&self.polygons[i].plane), closed)
    }

    /// [`Scene::turned_away_on_solid`], given `side`, `from`'s side of polygon `i`'s plane
    /// ([`LightSample::side_of`]).
    #[inline]
    pub(crate) fn turned_away_at(&self, i: usize, side: f64, closed: &[bool]) -> bool {
        let s = self.solid_of[i] as usize;
        closed.get(s) == Some(&true) && side * self.solids[s].sign < 0.0
    }

    /// Whether polygon `i` is one piece of a non-planar face split into a fan (its face has
    /// other polygons, which lie next to it in the list).
    #[inline]
    pub(crate) fn fan_piece(&self, i: usize) -> bool {
        let face = self.polygons[i].face;
        [i.checked_sub(1), Some(i + 1)]
            .into_iter()
            .flatten()
            .any(|q| self.polygons.get(q).is_some_and(|o| o.face == face))
    }

    /// For each corner of polygon `i`, the polygon across the edge to the next corner, or
    /// [`NO_POLYGON`] (see [`Scene::across`]).
    #[inline]
    pub(crate) fn across(&self, i: usize) -> &[u32] {
        let p = &self.polygons[i];
        &self.across[p.start as usize..(p.start + p.len) as usize]
    }

    /// The vertex normals of polygon `i`.
    #[inline]
    pub fn vertex_normals(&self, i: usize) -> &[DVec3] {
        let p = &self.polygons[i];
        &self.normals[p.start as usize..(p.start + p.len) as usize]
    }

    /// Records that the polygons were changed since compile (a mirror's scene: clipped, left
    /// out, renumbered): the closed solids and edge neighbours found then are forgotten (they are not known for
    /// the new polygons), and the polygons take a new [`Scene::polygons_id`].
    pub(crate) fn polygons_changed(&mut self) {
        self.solids.clear();
        self.solid_of.clear();
        self.solid_of.resize(self.polygons.len(), solids::NO_SOLID);
        self.across.clear();
        self.across.resize(self.vertices.len(), NO_POLYGON);
        self.polygons_id = next_polygons_id();
        self.bounds = self.vertex_bounds();
    }

    /// Whether polygon `i` casts shadows.
    #[inline]
    pub fn casts_shadows(&self, i: usize) -> bool {
        self.objects[self.polygons[i].object as usize].casts_shadows
    }

    /// The material of polygon `i`.
    #[inline]
    pub fn material(&self, i: usize) -> &Material {
        &self.materials[self.material_index(i)]
    }

    /// The index in the materials of polygon `i`'s material.
    #[inline]
    pub(crate) fn material_index(&self, i: usize) -> usize {
        self.objects[self.polygons[i].object as usize].material
    }

    /// The axis-aligned bounds of all polygons (`None` when there are none).
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        self.bounds
    }

    fn vertex_bounds(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.vertices.first()?;
        Some(self.vertices.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))))
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_flat_ground_is_the_planar_receiver_and_no_cube_is() {
        let mut scene = crate::generate::cubes(3, crate::generate::Faces::Quads, 64, 48).unwrap();
        assert!(scene.objects().iter().all(|o| !o.receiver));
        let chosen = scene.mark_planar_receivers();
        assert_eq!(chosen.len(), 1);
        let ground = chosen[0];
        assert!(scene.objects()[ground].receiver);
        // The ground is flat: every polygon of it in one plane; no other object is.
        let planes: Vec<_> = scene.polygons().iter().filter(|p| p.object as usize == ground).map(|p| p.plane).collect();
        assert!(planes.windows(2).all(|w| (w[0].n - w[1].n).length() < 1e-9));
        assert_eq!(scene.objects().iter().filter(|o| o.receiver).count(), 1);
    }
}
