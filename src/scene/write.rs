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
    pub fn write(&self, path: &Path) -> Result<()> {
        let io = |p: &Path| {
            let p = p.to_owned();
            move |e| Error::Io { path: p, source: e }
        };
        let dir = path.parent().unwrap_or(Path::new(""));
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
        std::fs::create_dir_all(dir.join("meshes")).map_err(io(&dir.join("meshes")))?;
        let c = &self.camera;
        let mut t = String::new();
        // Writing into a String cannot fail.
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
        for m in &self.materials {
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
        for l in &self.lights {
            let _ = write!(t, "\n[[light]]\n");
            match l.kind {
                LightKind::Point { position } => {
                    let _ = writeln!(t, "kind = \"point\"\nposition = {}", d3(position));
                }
                LightKind::Directional { direction } => {
                    let _ = writeln!(t, "kind = \"directional\"\ndirection = {}", d3(direction));
                }
                LightKind::Spot { position, direction, cutoff, exponent } => {
                    let _ = writeln!(
                        t,
                        "kind = \"spot\"\nposition = {}\ndirection = {}\ncutoff = {cutoff:?}\nexponent = {exponent:?}",
                        d3(position),
                        d3(direction)
                    );
                }
                LightKind::Area { corner, edge_u, edge_v, samples } => {
                    let _ = writeln!(
                        t,
                        "kind = \"area\"\ncorner = {}\nedge_u = {}\nedge_v = {}\nsamples = [{}, {}]",
                        d3(corner),
                        d3(edge_u),
                        d3(edge_v),
                        samples[0],
                        samples[1]
                    );
                }
            }
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
        for (i, o) in self.objects.iter().enumerate() {
            let mesh_name = format!("meshes/{stem}_{i}.obj");
            let mut obj = String::new();
            for p in &o.mesh.positions {
                let _ = writeln!(obj, "v {:?} {:?} {:?}", p.x, p.y, p.z);
            }
            for n in &o.mesh.normals {
                let _ = writeln!(obj, "vn {:?} {:?} {:?}", n.x, n.y, n.z);
            }
            for f in &o.mesh.faces {
                obj.push('f');
                for (k, v) in f.vertices.iter().enumerate() {
                    match f.normals.get(k) {
                        Some(n) => {
                            let _ = write!(obj, " {}//{}", v + 1, n + 1);
                        }
                        None => {
                            let _ = write!(obj, " {}", v + 1);
                        }
                    }
                }
                obj.push('\n');
            }
            let mesh_path = dir.join(&mesh_name);
            std::fs::write(&mesh_path, obj).map_err(io(&mesh_path))?;
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
        std::fs::write(path, t).map_err(io(path))
    }
}
