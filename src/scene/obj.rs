//! Wavefront OBJ reading (and writing, [`ObjText`]): `v`, `vn`, `vt` and `f` (forms `v`, `v/vt`, `v//vn`, `v/vt/vn`,
//! negative indices), faces kept as polygons. Every other statement is ignored.
//!
//! Written by hand rather than with an OBJ crate because the contract needs what those crates
//! do not give: polygons never triangulated, a face id for every `f` line (degenerate ones
//! too), and every error naming its line.

use super::{Face, Mesh};
use crate::error::{Error, FileLoc, Result};
use glam::DVec3;
use std::fmt::Write as _;
use std::path::Path;

/// Parses OBJ text; `file` names it in errors.
pub fn parse_obj(text: &str, file: &Path) -> Result<Mesh> {
    // A UTF-8 byte-order mark is not part of the first line.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let text = &super::lone_cr_to_lf(text);
    let mut mesh = Mesh::default();
    let mut texcoords = 0usize;
    for (n, raw) in text.lines().enumerate() {
        let loc = || FileLoc::line(file, n + 1);
        let line = raw.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => mesh.positions.push(vec3(&mut words, "v", &loc)?),
            Some("vn") => mesh.normals.push(vec3(&mut words, "vn", &loc)?),
            Some("vt") => {
                for w in words {
                    number(w, "vt", &loc)?;
                }
                texcoords += 1;
            }
            Some("f") => {
                let mut face = Face::default();
                let mut with_normals = true;
                for w in words {
                    let mut parts = w.split('/');
                    let counts = [mesh.positions.len(), texcoords, mesh.normals.len()];
                    let names = ["vertex", "texture coordinate", "normal"];
                    let mut got = [None; 3];
                    for k in 0..3 {
                        match parts.next() {
                            Some("") | None => {}
                            Some(s) => got[k] = Some(index(s, counts[k], names[k], &loc)?),
                        }
                    }
                    if parts.next().is_some() {
                        return Err(Error::input(loc(), format!("bad face vertex '{w}'")));
                    }
                    let Some(v) = got[0] else {
                        return Err(Error::input(loc(), format!("face vertex '{w}' has no vertex index")));
                    };
                    face.vertices.push(v);
                    match got[2] {
                        Some(vn) => face.normals.push(vn),
                        None => with_normals = false,
                    }
                }
                if face.vertices.is_empty() {
                    return Err(Error::input(loc(), "face with no vertices"));
                }
                if !with_normals {
                    face.normals.clear();
                }
                mesh.faces.push(face);
            }
            _ => {}
        }
    }
    Ok(mesh)
}

fn number(word: &str, what: &str, loc: &impl Fn() -> FileLoc) -> Result<f64> {
    let x: f64 = word.parse().map_err(|_| Error::input(loc(), format!("bad number '{word}' in '{what}'")))?;
    if !x.is_finite() {
        return Err(Error::input(loc(), format!("non-finite number '{word}' in '{what}'")));
    }
    Ok(x)
}

fn vec3<'a>(words: &mut impl Iterator<Item = &'a str>, what: &str, loc: &impl Fn() -> FileLoc) -> Result<DVec3> {
    let mut c = [0.0; 3];
    for x in &mut c {
        let w = words.next().ok_or_else(|| Error::input(loc(), format!("'{what}' needs three numbers")))?;
        *x = number(w, what, loc)?;
    }
    // An optional fourth (w) component is allowed for `v` (OBJ's weight) and ignored.
    if let Some(w) = words.next() {
        if what != "v" {
            return Err(Error::input(loc(), format!("'{what}' takes three numbers, found a fourth '{w}'")));
        }
        number(w, what, loc)?;
    }
    if let Some(extra) = words.next() {
        return Err(Error::input(loc(), format!("'{what}' takes at most four numbers, found '{extra}'")));
    }
    Ok(DVec3::from_array(c))
}

/// Resolves a 1-based (or negative, relative) OBJ index against `count` items read so far.
fn index(word: &str, count: usize, what: &str, loc: &impl Fn() -> FileLoc) -> Result<u32> {
    let i: i64 = word.parse().map_err(|_| Error::input(loc(), format!("bad {what} index '{word}'")))?;
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || resolved < 0 || resolved >= count as i64 {
        return Err(Error::input(loc(), format!("{what} index {i} out of range ({count} defined so far)")));
    }
    Ok(resolved as u32)
}

/// Wavefront OBJ text, written: vertices, normals, groups and faces with 1-based indices.
/// The one writer that the scene writer's meshes and the shadow database's export share.
#[derive(Default)]
pub(crate) struct ObjText {
    text: String,
    vertices: usize,
}

impl ObjText {
    /// A file that starts with `header` lines (comments, `#` included).
    pub(crate) fn with_header(header: &str) -> ObjText {
        ObjText { text: header.to_owned(), vertices: 0 }
    }

    /// A `v` line; returns its 1-based index.
    pub(crate) fn vertex(&mut self, p: DVec3) -> usize {
        let _ = writeln!(self.text, "v {:?} {:?} {:?}", p.x, p.y, p.z);
        self.vertices += 1;
        self.vertices
    }

    /// A `vn` line.
    pub(crate) fn normal(&mut self, n: DVec3) {
        let _ = writeln!(self.text, "vn {:?} {:?} {:?}", n.x, n.y, n.z);
    }

    /// A `g` line.
    pub(crate) fn group(&mut self, name: &str) {
        let _ = writeln!(self.text, "g {name}");
    }

    /// An `f` line of 1-based vertex indices, each with its 1-based normal index if any.
    pub(crate) fn face(&mut self, corners: impl IntoIterator<Item = (usize, Option<usize>)>) {
        self.text.push('f');
        for (v, n) in corners {
            let _ = match n {
                Some(n) => write!(self.text, " {v}//{n}"),
                None => write!(self.text, " {v}"),
            };
        }
        self.text.push('\n');
    }

    /// Writes the text to `path` in one call.
    pub(crate) fn save(self, path: &Path) -> Result<()> {
        std::fs::write(path, self.text).map_err(|e| Error::Write { path: path.to_owned(), source: e })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Mesh> {
        parse_obj(text, Path::new("m.obj"))
    }

    #[test]
    fn forms_and_negative_indices() {
        let m = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nvn 0 0 1\nvt 0 0\nf 1 2 3\nf -3//1 -2//1 -1//1\nf 1/1 2/1 3/1/1\n")
            .unwrap();
        assert_eq!(m.faces.len(), 3);
        assert_eq!(m.faces[1].vertices, vec![0, 1, 2]);
        assert_eq!(m.faces[1].normals, vec![0, 0, 0]);
        assert!(m.faces[2].normals.is_empty(), "normals only when every vertex has one");
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("v 0 0 0\nv 1 x 0\n").unwrap_err().to_string();
        assert_eq!(e, "m.obj:2: bad number 'x' in 'v'");
        let e = parse("v 0 0 0\nf 1 2 3\n").unwrap_err().to_string();
        assert_eq!(e, "m.obj:2: vertex index 2 out of range (1 defined so far)");
        let e = parse("v nan 0 0\n").unwrap_err().to_string();
        assert_eq!(e, "m.obj:1: non-finite number 'nan' in 'v'");
        let e = parse("v 0 0 0\nf\n").unwrap_err().to_string();
        assert_eq!(e, "m.obj:2: face with no vertices");
        let e = parse("v 0 0 0\nf 0\n").unwrap_err().to_string();
        assert_eq!(e, "m.obj:2: vertex index 0 out of range (1 defined so far)");
    }

    #[test]
    fn short_faces_are_faces() {
        let m = parse("v 0 0 0\nv 1 0 0\nf 1\nf 1 2\n").unwrap();
        assert_eq!(m.faces.len(), 2);
    }
}
