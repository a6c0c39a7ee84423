//! Writing a scene back out as a scene file and OBJ meshes (used by `umbra generate`).

use super::{LightKind, Scene, ShadingMode, SpecularModel};
use crate::error::{Error, Result};
use glam::{DVec3, Vec3};
use std::fmt::Write as _;
use std::path::Path;

fn d3(v: DVec3) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

fn f3(v: Vec3) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

impl Scene {
    /// Writes the scene to `path` (a `.toml` file) with each object's mesh as an OBJ file in
    /// `meshes/` beside it, named after the scene file.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let dir = path.parent().unwrap_or(Path::new(""));
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
        let meshes = dir.join("meshes");
        std::fs::create_dir_all(&meshes).map_err(|e| Error::Write { path: meshes.clone(), source: e })?;
        let mut t = String::new();
        self.write_camera(&mut t);
        for m in &self.materials {
            write_material(&mut t, m);
        }
        for l in &self.lights {
            write_light(&mut t, l);
        }
        for (i, o) in self.objects.iter().enumerate() {
            let mesh_name = format!("meshes/{stem}_{i}.obj");
            mesh_obj(&o.mesh).save(&dir.join(&mesh_name))?;
            self.write_object(&mut t, o, &mesh_name);
        }
        std::fs::write(path, t).map_err(|e| Error::Write { path: path.to_owned(), source: e })
    }

    /// The `[camera]` and `[render]` tables. (Writing into a String cannot fail.)
    fn write_camera(&self, t: &mut String) {
        let c = &self.camera;
        let _ = writeln!(
            t,
            "# written by umbra\n[camera]\neye = {}\ntarget = {}\nup = {}",
            d3(c.eye),
            d3(c.target),
            d3(c.up)
        );
        let _ = writeln!(t, "fov_y = {:?}\nwidth = {}\nheight = {}\nnear = {:?}", c.fov_y, c.width, c.height, c.near);
        if let Some(far) = c.far {
            let _ = writeln!(t, "far = {far:?}");
        }
        let r = &self.render;
        let _ = writeln!(t, "\n[render]\nambient = {}\nbackground = {}", f3(r.ambient), f3(r.background));
    }

    /// One `[[object]]` table, its mesh in `mesh_name`.
    fn write_object(&self, t: &mut String, o: &super::Object, mesh_name: &str) {
        let tr = &o.transform;
        let _ = write!(t, "\n[[object]]\n");
        if let Some(name) = &o.name {
            let _ = writeln!(t, "name = {name:?}");
        }
        let _ = writeln!(
            t,
            "material = {:?}\nmesh = {:?}\nscale = {}\nrotate = {}\ntranslate = {}\ncasts_shadows = {}",
            self.materials[o.material].name,
            mesh_name,
            d3(tr.scale),
            d3(tr.rotate),
            d3(tr.translate),
            o.casts_shadows
        );
        if o.receiver {
            let _ = writeln!(t, "receiver = true");
        }
    }
}

/// One `[[material]]` table.
fn write_material(t: &mut String, m: &super::Material) {
    let model = match m.model {
        SpecularModel::Phong => "phong",
        SpecularModel::Blinn => "blinn",
        SpecularModel::CookTorrance => "cook-torrance",
    };
    let shading = match m.shading {
        ShadingMode::Flat => "flat",
        ShadingMode::Gouraud => "gouraud",
        ShadingMode::Phong => "phong",
    };
    let _ = writeln!(
        t,
        "\n[[material]]\nname = {:?}\ncolor = {}\nspecular_color = {}\nka = {:?}\nkd = {:?}\nks = {:?}\nshininess = {:?}\nmodel = \"{model}\"\nroughness = {:?}\nfresnel = {:?}\nmirror = {:?}\nshading = \"{shading}\"",
        m.name, f3(m.color), f3(m.specular_color), m.ka, m.kd, m.ks, m.shininess, m.roughness, m.fresnel, m.mirror
    );
}

/// One `[[light]]` table.
fn write_light(t: &mut String, l: &super::Light) {
    let _ = write!(t, "\n[[light]]\n");
    let _ = match l.kind {
        LightKind::Point { position } => writeln!(t, "kind = \"point\"\nposition = {}", d3(position)),
        LightKind::Directional { direction } => writeln!(t, "kind = \"directional\"\ndirection = {}", d3(direction)),
        LightKind::Spot { position, direction, cutoff, exponent } => writeln!(
            t,
            "kind = \"spot\"\nposition = {}\ndirection = {}\ncutoff = {cutoff:?}\nexponent = {exponent:?}",
            d3(position),
            d3(direction)
        ),
        LightKind::Area { corner, edge_u, edge_v, samples } => writeln!(
            t,
            "kind = \"area\"\ncorner = {}\nedge_u = {}\nedge_v = {}\nsamples = [{}, {}]",
            d3(corner),
            d3(edge_u),
            d3(edge_v),
            samples[0],
            samples[1]
        ),
    };
    let a = l.attenuation;
    let _ = writeln!(
        t,
        "color = {}\nintensity = {:?}\nattenuation = [{:?}, {:?}, {:?}]",
        f3(l.color),
        l.intensity,
        a[0],
        a[1],
        a[2]
    );
}

/// A mesh as OBJ: its positions, normals and faces as they are.
fn mesh_obj(mesh: &super::Mesh) -> super::obj::ObjText {
    let mut obj = super::obj::ObjText::default();
    for &p in &mesh.positions {
        obj.vertex(p);
    }
    for &n in &mesh.normals {
        obj.normal(n);
    }
    for f in &mesh.faces {
        obj.face(
            f.vertices.iter().enumerate().map(|(k, &v)| (v as usize + 1, f.normals.get(k).map(|&n| n as usize + 1))),
        );
    }
    obj
}
