//! Scene generators: the benchmark families (a floor with an N×N grid of cubes, D stacked
//! quads of depth complexity D, tessellated spheres) and random test scenes.

use crate::error::Result;
use crate::scene::{Camera, Light, LightKind, Material, Mesh, Object, RenderSettings, Scene, Transform};
use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;
use std::sync::Arc;

fn object(material: usize, mesh: Mesh) -> Object {
    Object {
        name: None,
        material,
        mesh: Arc::new(mesh),
        transform: Transform::default(),
        casts_shadows: true,
        receiver: false,
    }
}

fn material(name: &str, color: [f32; 3]) -> Material {
    Material { color: Vec3::from_array(color), ..Material::new(name) }
}

fn point_light(p: DVec3) -> Light {
    Light { kind: LightKind::Point { position: p }, color: Vec3::ONE, intensity: 1.0, attenuation: [1.0, 0.0, 0.0] }
}

fn camera(eye: DVec3, target: DVec3, width: u32, height: u32) -> Camera {
    Camera { width, height, ..Camera::new(eye, target) }
}

/// Appends an axis-aligned box `lo..hi` to `mesh`, as 6 quads or 12 triangles.
pub(crate) fn add_box(mesh: &mut Mesh, lo: DVec3, hi: DVec3, triangles: bool) {
    let c = |i: usize| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    // Counter-clockwise seen from outside.
    const QUADS: [[usize; 4]; 6] = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let base = mesh.positions.len() as u32;
    mesh.positions.extend((0..8).map(c));
    for q in QUADS {
        let q = q.map(|i| base + i as u32);
        if triangles {
            mesh.faces.push(crate::scene::Face { vertices: vec![q[0], q[1], q[2]], normals: vec![] });
            mesh.faces.push(crate::scene::Face { vertices: vec![q[0], q[2], q[3]], normals: vec![] });
        } else {
            mesh.faces.push(crate::scene::Face { vertices: q.to_vec(), normals: vec![] });
        }
    }
}

fn floor(half: f64) -> Mesh {
    Mesh::from_polygons(&[vec![
        DVec3::new(-half, 0.0, -half),
        DVec3::new(-half, 0.0, half),
        DVec3::new(half, 0.0, half),
        DVec3::new(half, 0.0, -half),
    ]])
}

/// Refuses a generated scene of `polygons` polygons of `corners` corners each whose mesh
/// and compiled polygons would not fit the memory budget (about 100 bytes a corner across
/// the mesh, the world vertices, normals and the stages' per-polygon data).
fn check_size(family: &str, polygons: u64, corners: u64) -> Result<()> {
    let bytes = crate::budget::mul(polygons, crate::budget::mul(corners, 100) + 64);
    crate::budget::check(format_args!("generate {family}: {polygons} polygons"), bytes)
}

/// How a generated box's faces are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Faces {
    /// Six quads.
    Quads,
    /// Twelve triangles.
    Triangles,
}

/// Where [`scattered`] puts its triangles in the cube.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// Uniformly.
    Uniform,
    /// Clustered around the centre (a rough normal distribution).
    Clustered,
}

/// A floor with an `n`×`n` grid of unit cubes, their `faces` quads or triangles, under a
/// point light: 10×10 gives 1,201 polygons as triangles.
pub fn cubes(n: u32, faces: Faces, width: u32, height: u32) -> Result<Scene> {
    let triangles = faces == Faces::Triangles;
    check_size("cubes", crate::budget::mul(n as u64 * n as u64, if triangles { 12 } else { 6 }), 4)?;
    let half = n as f64 + 1.0;
    let mut boxes = Mesh::default();
    for i in 0..n {
        for j in 0..n {
            let x = -(n as f64) + 1.0 + 2.0 * i as f64;
            let z = -(n as f64) + 1.0 + 2.0 * j as f64;
            let h = 1.0 + ((i * 7 + j * 3) % 5) as f64 * 0.25;
            add_box(&mut boxes, DVec3::new(x - 0.5, 0.0, z - 0.5), DVec3::new(x + 0.5, h, z + 0.5), triangles);
        }
    }
    let s = n as f64;
    Scene::new(
        camera(DVec3::new(0.3 * s, 1.1 * s + 2.0, 1.6 * s + 3.0), DVec3::ZERO, width, height),
        RenderSettings::default(),
        vec![material("floor", [0.8, 0.8, 0.8]), material("box", [0.9, 0.5, 0.3])],
        vec![point_light(DVec3::new(-0.6 * s, 1.5 * s + 3.0, 0.4 * s))],
        vec![object(0, floor(half)), object(1, boxes)],
    )
}

/// `d` quads stacked toward the camera, each covering the whole view (depth complexity `d`
/// at every pixel), each turned a little so that neighbours' depths differ over the screen,
/// lit from the side.
pub fn stacked_quads(d: u32, width: u32, height: u32) -> Result<Scene> {
    check_size("quads", d as u64, 4)?;
    let mut polys = Vec::new();
    let aspect = width as f64 / height as f64;
    for k in 0..d {
        let z = -2.0 - 0.5 * k as f64;
        let dist = 10.0 - z;
        let hh = dist * (22.5f64).to_radians().tan() * 1.2;
        let hw = hh * aspect;
        let tilt = 0.02 * ((k % 5) as f64 - 2.0);
        polys.push(vec![
            DVec3::new(-hw, -hh, z - tilt * hw),
            DVec3::new(hw, -hh, z + tilt * hw),
            DVec3::new(hw, hh, z + tilt * hw),
            DVec3::new(-hw, hh, z - tilt * hw),
        ]);
    }
    Scene::new(
        camera(DVec3::new(0.0, 0.0, 10.0), DVec3::new(0.0, 0.0, 0.0), width, height),
        RenderSettings::default(),
        vec![material("quad", [0.7, 0.7, 0.9])],
        vec![point_light(DVec3::new(3.0, 4.0, 8.0))],
        vec![object(0, Mesh::from_polygons(&polys))],
    )
}

/// A geodesic sphere: an icosahedron whose triangles are split in four `levels` times, the
/// new corners pushed out onto the sphere (no two neighbours are coplanar); closed, wound
/// outward. Level 0 is the icosahedron.
pub fn geodesic_sphere(centre: DVec3, r: f64, levels: u32) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut corners: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut middles = std::collections::HashMap::new();
        let mut middle = |a: usize, b: usize, corners: &mut Vec<DVec3>| {
            *middles.entry((a.min(b), a.max(b))).or_insert_with(|| {
                corners.push(((corners[a] + corners[b]) / 2.0).normalize());
                corners.len() - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (middle(a, b, &mut corners), middle(b, c, &mut corners), middle(c, a, &mut corners));
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    let polygons: Vec<Vec<DVec3>> =
        faces.iter().map(|f| f.iter().map(|&k| centre + r * corners[k]).collect()).collect();
    Mesh::from_polygons(&polygons)
}

/// A UV sphere of radius `r` at `c` with as near `triangles` triangles as a UV sphere has:
/// `s` stacks and `2s` slices make `4s² − 4s` triangles, and `s` (at least 2) is the one
/// that comes nearest.
pub fn sphere_mesh(c: DVec3, r: f64, triangles: u32) -> Mesh {
    let made = |s: u32| 4 * s as i64 * s as i64 - 4 * s as i64;
    let guess = ((1.0 + (1.0 + triangles as f64).sqrt()) / 2.0).floor().max(2.0) as u32;
    let stacks = [guess, guess + 1].into_iter().min_by_key(|&s| (made(s) - triangles as i64).abs()).unwrap_or(2);
    let slices = 2 * stacks;
    let mut m = Mesh::default();
    let pos = |i: u32, j: u32| {
        let th = PI * i as f64 / stacks as f64;
        let ph = 2.0 * PI * j as f64 / slices as f64;
        DVec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin())
    };
    // Poles, then rings 1..stacks-1.
    m.positions.push(c + r * DVec3::Y);
    m.positions.push(c - r * DVec3::Y);
    m.normals.push(DVec3::Y);
    m.normals.push(-DVec3::Y);
    for i in 1..stacks {
        for j in 0..slices {
            let p = pos(i, j);
            m.positions.push(c + r * p);
            m.normals.push(p);
        }
    }
    let v = |i: u32, j: u32| 2 + (i - 1) * slices + (j % slices);
    let mut tri =
        |a: u32, b: u32, c: u32| m.faces.push(crate::scene::Face { vertices: vec![a, b, c], normals: vec![a, b, c] });
    for j in 0..slices {
        tri(0, v(1, j + 1), v(1, j));
        tri(1, v(stacks - 1, j), v(stacks - 1, j + 1));
        for i in 1..stacks - 1 {
            tri(v(i, j), v(i, j + 1), v(i + 1, j + 1));
            tri(v(i, j), v(i + 1, j + 1), v(i + 1, j));
        }
    }
    m
}

/// `count` spheres of about `triangles / count` triangles each, scattered on a floor by a
/// seeded generator, under a point light.
pub fn spheres(triangles: u32, count: u32, width: u32, height: u32) -> Result<Scene> {
    check_size("spheres", triangles as u64 + 2 * count as u64, 3)?;
    let count = count.max(1);
    let side = (count as f64).sqrt().ceil() as u32;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut mesh = Mesh::default();
    for k in 0..count {
        let (i, j) = (k % side, k / side);
        let r = if count == 1 { 1.0 } else { rng.gen_range(0.3..0.6) };
        let jitter =
            if count == 1 { DVec3::ZERO } else { DVec3::new(rng.gen_range(-0.3..0.3), 0.0, rng.gen_range(-0.3..0.3)) };
        let c = DVec3::new(2.0 * i as f64 - side as f64 + 1.0, r, 2.0 * j as f64 - side as f64 + 1.0) + jitter;
        let s = sphere_mesh(c, r, triangles / count);
        let base = mesh.positions.len() as u32;
        let nbase = mesh.normals.len() as u32;
        mesh.positions.extend(s.positions);
        mesh.normals.extend(s.normals);
        mesh.faces.extend(s.faces.into_iter().map(|f| crate::scene::Face {
            vertices: f.vertices.iter().map(|v| v + base).collect(),
            normals: f.normals.iter().map(|v| v + nbase).collect(),
        }));
    }
    let s = side as f64;
    let mut ball = material("sphere", [0.4, 0.6, 0.9]);
    ball.shading = crate::scene::ShadingMode::Phong;
    ball.ks = 0.4;
    Scene::new(
        camera(DVec3::new(0.0, 1.2 * s + 1.0, 1.8 * s + 2.0), DVec3::new(0.0, 0.3, 0.0), width, height),
        RenderSettings::default(),
        vec![material("floor", [0.8, 0.8, 0.8]), ball],
        vec![point_light(DVec3::new(-s - 1.0, 2.0 * s + 2.0, 0.5 * s + 1.0))],
        vec![object(0, floor(s + 1.0)), object(1, mesh)],
    )
}

/// Options for [`random`].
#[derive(Debug, Clone, Copy)]
pub struct RandomOptions {
    /// Number of random polygons (besides the floor).
    pub polygons: u32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
}

impl Default for RandomOptions {
    fn default() -> Self {
        RandomOptions { polygons: 8, width: 48, height: 36 }
    }
}

/// A random test scene from `seed`: a floor and random convex and concave (star) polygons in
/// random orientations, some interpenetrating, some passing near or through the camera's near
/// plane, lit by one to three lights of random kinds (point, directional, spot, area): high
/// above, among the polygons, or just above the floor, kept 1e-3 away from every polygon's
/// plane (a light on a plane is a tie in the contract).
pub fn random(seed: u64, opts: RandomOptions) -> Result<Scene> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut polys: Vec<Vec<DVec3>> = vec![vec![
        DVec3::new(-4.0, 0.0, -4.0),
        DVec3::new(-4.0, 0.0, 4.0),
        DVec3::new(4.0, 0.0, 4.0),
        DVec3::new(4.0, 0.0, -4.0),
    ]];
    let eye = DVec3::new(rng.gen_range(-3.0..3.0), rng.gen_range(1.5..4.0), rng.gen_range(3.0..5.0));
    for k in 0..opts.polygons {
        polys.push(random_polygon(&mut rng, k == 0, eye));
    }
    let planes: Vec<_> = polys
        .iter()
        .map(|p| {
            let n = crate::geometry::newell_normal(p).normalize();
            crate::geometry::Plane::new(n, p[0])
        })
        .collect();
    let clear = |p: DVec3| planes.iter().all(|pl| pl.distance(p).abs() > 1e-3);
    let mut lights = Vec::new();
    for _ in 0..rng.gen_range(1..=3) {
        let kind = random_light(&mut rng, &clear);
        lights.push(Light { kind, color: Vec3::ONE, intensity: 0.8, attenuation: [1.0, 0.0, 0.0] });
    }
    let cam = Camera { near: 0.05, ..camera(eye, DVec3::new(0.0, 0.5, 0.0), opts.width, opts.height) };
    Scene::new(
        cam,
        RenderSettings::default(),
        vec![material("a", [0.8, 0.8, 0.8])],
        lights,
        vec![object(0, Mesh::from_polygons(&polys))],
    )
}

/// A random adversarial scene from `seed`, for the differential tests of the culls of ours
/// (`tests/suite/shadows.rs`): [`random`]'s polygons, among them what found the wrong
/// pixels of `tests/data/solids/` and `tests/data/awg-area/`. Open meshes beside closed ones:
/// a bumpy grid sheet, a fan of a non-planar polygon, a box with a face left out; closed
/// solids wound either way, some casting no shadow (an icosahedron, a box); non-planar quads
/// (split into fans) under an area light; and, half the time, a directional light grazing a
/// sheet of coplanar neighbours.
pub fn adversarial(seed: u64, opts: RandomOptions) -> Result<Scene> {
    let base = random(seed, opts)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xad5e_5a11);
    let mut objects = base.objects().to_vec();
    let mut lights = base.lights().to_vec();
    let mut at = || DVec3::new(rng.gen_range(-1.8..1.8), rng.gen_range(0.3..1.8), rng.gen_range(-1.8..1.8));
    let (grid_at, fan_at, box_at, ico_at, quad_at) = (at(), at(), at(), at(), at());
    let mut add = |mesh: Mesh, casts: bool| objects.push(Object { casts_shadows: casts, ..object(0, mesh) });
    add(bumpy_grid(&mut rng, grid_at), true);
    add(Mesh::from_polygons(&[bumpy_fan(&mut rng, fan_at)]), true);
    let mut open_box = Mesh::default();
    add_box(&mut open_box, box_at, box_at + DVec3::splat(rng.gen_range(0.3..0.9)), rng.gen_bool(0.5));
    let keep = open_box.faces.len() - if open_box.faces.len() == 12 { 2 } else { 1 };
    open_box.faces.truncate(keep);
    add(open_box, true);
    let mut ico = geodesic_sphere(ico_at, rng.gen_range(0.3..0.8), 0);
    if rng.gen_bool(0.5) {
        ico.faces.iter_mut().for_each(|f| f.vertices.reverse());
    }
    add(ico, rng.gen_bool(0.5));
    let quads: Vec<Vec<DVec3>> = (0..3).map(|_| bumpy_quad(&mut rng, quad_at)).collect();
    add(Mesh::from_polygons(&quads), true);
    lights.push(Light {
        kind: LightKind::Area {
            corner: quad_at + DVec3::new(-0.5, rng.gen_range(1.0..2.5), -0.5),
            edge_u: DVec3::new(rng.gen_range(0.3..1.0), 0.0, 0.0),
            edge_v: DVec3::new(0.0, 0.0, rng.gen_range(0.3..1.0)),
            samples: [rng.gen_range(1..4), rng.gen_range(1..4)],
        },
        color: Vec3::ONE,
        intensity: 0.5,
        attenuation: [1.0, 0.0, 0.0],
    });
    if rng.gen_bool(0.5) {
        // Grazing the grid sheet's mean plane (y up), a little above it.
        let a = rng.gen_range(0.0..2.0 * PI);
        let direction = DVec3::new(a.cos(), -rng.gen_range(0.01..0.08), a.sin()).normalize();
        lights.push(Light { kind: LightKind::Directional { direction }, ..point_light(DVec3::ZERO) });
    }
    Scene::new(base.camera().clone(), RenderSettings::default(), base.materials().to_vec(), lights, objects)
}

/// A 4 x 4 grid of triangles around `c`, its heights random: an open, non-planar sheet.
fn bumpy_grid(rng: &mut ChaCha8Rng, c: DVec3) -> Mesh {
    let h: Vec<f64> = (0..25).map(|_| rng.gen_range(-0.15..0.15)).collect();
    let p = |x: usize, z: usize| c + DVec3::new(x as f64 * 0.3 - 0.6, h[x * 5 + z], z as f64 * 0.3 - 0.6);
    let mut tris = Vec::new();
    for x in 0..4 {
        for z in 0..4 {
            tris.push(vec![p(x, z), p(x, z + 1), p(x + 1, z)]);
            tris.push(vec![p(x + 1, z), p(x, z + 1), p(x + 1, z + 1)]);
        }
    }
    Mesh::from_polygons(&tris)
}

/// A non-planar polygon of 5 to 9 corners around `c` (the loader splits it into a fan).
fn bumpy_fan(rng: &mut ChaCha8Rng, c: DVec3) -> Vec<DVec3> {
    let n = rng.gen_range(5..10);
    let r = rng.gen_range(0.3..0.9);
    (0..n)
        .map(|i| {
            let t = 2.0 * PI * i as f64 / n as f64;
            c + DVec3::new(r * t.cos(), rng.gen_range(-0.3..0.3), r * t.sin())
        })
        .collect()
}

/// A non-planar quad near `c`.
fn bumpy_quad(rng: &mut ChaCha8Rng, c: DVec3) -> Vec<DVec3> {
    let mut j = || DVec3::new(rng.gen_range(-0.6..0.6), rng.gen_range(-0.3..0.3), rng.gen_range(-0.6..0.6));
    let o = c + j() * 0.5;
    let s = 0.5;
    vec![
        o + j() * 0.2,
        o + DVec3::new(s, 0.0, 0.0) + j() * 0.2,
        o + DVec3::new(s, 0.0, s) + j() * 0.2,
        o + DVec3::new(0.0, 0.0, s) + j() * 0.2,
    ]
}

/// One random polygon of [`random`]: convex, or a star (concave), in a random orientation;
/// the first may straddle the camera's near plane.
fn random_polygon(rng: &mut ChaCha8Rng, first: bool, eye: DVec3) -> Vec<DVec3> {
    let near_eye = first && rng.gen_bool(0.5);
    let center = if near_eye {
        // Straddles the camera's near plane: the eye sits almost on it.
        eye + DVec3::new(rng.gen_range(-0.3..0.3), rng.gen_range(-0.3..0.3), -0.2)
    } else {
        DVec3::new(rng.gen_range(-2.0..2.0), rng.gen_range(0.2..2.0), rng.gen_range(-2.0..2.0))
    };
    let n =
        DVec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)).normalize_or(DVec3::Y);
    let a = n.any_orthonormal_vector();
    let b = n.cross(a);
    let star = rng.gen_bool(0.4);
    let sides = if star { 2 * rng.gen_range(3..6) } else { rng.gen_range(3..7) };
    let r = rng.gen_range(0.4..1.4);
    let phase = rng.gen_range(0.0..PI);
    (0..sides)
        .map(|i| {
            let t = phase + 2.0 * PI * i as f64 / sides as f64;
            let rr = if star && i % 2 == 1 { r * 0.45 } else { r };
            center + rr * (t.cos() * a + t.sin() * b)
        })
        .collect()
}

/// One random light of [`random`], of a random kind, placed high above, among the
/// polygons, or just above the floor, with every sample `clear` of every polygon's plane.
fn random_light(rng: &mut ChaCha8Rng, clear: &dyn Fn(DVec3) -> bool) -> LightKind {
    loop {
        // High above, among the polygons (planes through the light cut them), or just
        // above the floor (a light close to a receiving plane).
        let y = match rng.gen_range(0..6) {
            0 | 1 => rng.gen_range(0.3..2.0),
            2 => rng.gen_range(0.02..0.1),
            _ => rng.gen_range(2.5..5.0),
        };
        let pos = DVec3::new(rng.gen_range(-3.0..3.0), y, rng.gen_range(-3.0..3.0));
        let kind = match rng.gen_range(0..4) {
            0 => LightKind::Point { position: pos },
            1 => LightKind::Directional {
                direction: DVec3::new(rng.gen_range(-0.5..0.5), -1.0, rng.gen_range(-0.5..0.5)).normalize(),
            },
            2 => LightKind::Spot { position: pos, direction: (-pos).normalize(), cutoff: 60.0, exponent: 1.0 },
            _ => LightKind::Area {
                corner: pos,
                edge_u: DVec3::new(rng.gen_range(0.2..0.8), 0.0, 0.0),
                edge_v: DVec3::new(0.0, 0.05, rng.gen_range(0.2..0.8)),
                samples: [2, 2],
            },
        };
        let ok = Light { kind: kind.clone(), color: Vec3::ONE, intensity: 1.0, attenuation: [1.0, 0.0, 0.0] }
            .samples()
            .iter()
            .all(|s| match s {
                crate::scene::LightSample::Point(p) => clear(*p),
                crate::scene::LightSample::Directional(_) => true,
            });
        if ok {
            return kind;
        }
    }
}

/// `n` random triangles with edges about `size` long, scattered through a cube of side 4 —
/// uniformly, or clustered around its centre (`placement`) — over a floor, for Slater et
/// al.'s study of polygon count, size and distribution.
pub fn scattered(n: u32, size: f64, placement: Placement, width: u32, height: u32) -> Result<Scene> {
    let clustered = placement == Placement::Clustered;
    check_size("scattered triangles", n as u64, 3)?;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut tris = Vec::with_capacity(n as usize);
    for _ in 0..n {
        let c = if clustered {
            // A rough normal distribution: the mean of three uniforms.
            DVec3::new(
                (0..3).map(|_| rng.gen_range(-2.0..2.0)).sum::<f64>() / 3.0,
                (0..3).map(|_| rng.gen_range(0.0..4.0)).sum::<f64>() / 3.0,
                (0..3).map(|_| rng.gen_range(-2.0..2.0)).sum::<f64>() / 3.0,
            )
        } else {
            DVec3::new(rng.gen_range(-2.0..2.0), rng.gen_range(0.0..4.0), rng.gen_range(-2.0..2.0))
        };
        let mut corner =
            || c + DVec3::new(rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5)) * size;
        tris.push(vec![corner(), corner(), corner()]);
    }
    Scene::new(
        camera(DVec3::new(0.0, 3.0, 8.0), DVec3::new(0.0, 1.5, 0.0), width, height),
        RenderSettings::default(),
        vec![material("floor", [0.8, 0.8, 0.8]), material("tri", [0.5, 0.7, 0.9])],
        vec![point_light(DVec3::new(-3.0, 8.0, 4.0))],
        vec![object(0, floor(4.0)), object(1, Mesh::from_polygons(&tris))],
    )
}
