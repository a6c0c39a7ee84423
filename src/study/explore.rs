//! `umbra explore`: a page that shows the algorithms working, line by line.
//!
//! The page (`explore/index.html`, `explore.js`, `explore.css`, shipped inside the binary)
//! asks a small JSON API for what it draws; [`Explorer::handle`] answers it from one
//! read-only [`Scene`], so many requests can be answered at once:
//!
//! | request | answer |
//! | --- | --- |
//! | `GET api/scene` | the scene: image size, lights, bounds, the stages and what each does |
//! | `GET api/frame?shadows=S&width=W&height=H[&light=x,y,z]` | a render: times, counters, the stage's polygons on screen, the pixels where it differs from ray-cast |
//! | `GET api/image?…` (the same parameters) | that render as PNG |
//! | `GET api/trace?line=Y&…` | [`LineTrace`]: what `umbra trace --json` prints for line `Y` |
//! | `GET api/picture?index=K&…` | picture `K` of the frame's `pictures` (Williams: a shadow map) as PNG |
//! | `GET api/light?x=X&line=Y&…` | what the point seen at pixel `(X, Y)` sees of the first area light: the light as the unit square of its coordinates, the part its polygon's plane cuts away, each occluder's shadow, what is left and its area (the exact fraction, `reference::Reference::light_view_at`) |
//!
//! A bad request gets status 400 and `{"error": "…"}`, which the page shows. `light=x,y,z`
//! moves the first light (a point, spot or area light's position or corner; a directional
//! light then shines from there toward the middle of the scene).
//!
//! The `umbra` command serves it on 127.0.0.1 only (its server lives with the tools, in
//! `tools/src/serve.rs`); [`export`] writes the same page as static files with every line
//! precomputed, readable straight from disk.

use super::trace::{trace, trace_lines, LineTrace};
use crate::error::{Error, Result};
use crate::reference::{Reference, Tie};
use crate::render::{render, RenderOptions, Rendered};
use crate::scene::{LightKind, Scene};
use crate::shadow::ShadowMethod;
use glam::DVec3;
use serde::Serialize;
use serde_json::{json, Value};
use std::collections::VecDeque;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::{Arc, Mutex};

const PAGE: &str = include_str!("explore/index.html");
const SCRIPT: &str = include_str!("explore/explore.js");
const STYLE: &str = include_str!("explore/explore.css");

/// The largest image side the page may ask for.
pub const MAX_SIDE: u32 = 2048;
/// At most this many stage polygons are sent for drawing (the rest are counted).
const MAX_OUTLINES: usize = 5000;
/// At most this many differing pixels are listed (the rest are counted).
const MAX_DIFFERS: usize = 20000;
/// Renders kept for `api/image` after `api/frame`.
const CACHE: usize = 16;

/// An answer: status, content type and body.
#[derive(Debug, Clone, PartialEq)]
pub struct Response {
    /// HTTP status: 200, 400 (bad request) or 404 (no such path).
    pub status: u16,
    /// MIME type of the body.
    pub content_type: &'static str,
    /// The body.
    pub body: Vec<u8>,
}

impl Response {
    fn ok(content_type: &'static str, body: impl Into<Vec<u8>>) -> Response {
        Response { status: 200, content_type, body: body.into() }
    }

    fn json(v: &impl Serialize) -> Response {
        match serde_json::to_vec(v) {
            Ok(body) => Response::ok("application/json", body),
            Err(e) => Response::error(500, &e.to_string()),
        }
    }

    /// An error of HTTP status `status`: `{"error": message}`, as the page shows it.
    pub fn error(status: u16, message: &str) -> Response {
        let body = json!({ "error": message }).to_string();
        Response { status, content_type: "application/json", body: body.into_bytes() }
    }
}

/// What the page asks to see: a stage, an image size and where the first light is.
#[derive(Debug, Clone, PartialEq)]
struct Request {
    shadows: ShadowMethod,
    width: u32,
    height: u32,
    light: Option<DVec3>,
}

/// A render, kept for the image requests that follow it.
struct Shown {
    request: Request,
    png: Vec<u8>,
    /// The stage's pictures (Williams: its shadow maps), as PNG.
    pictures: Vec<Vec<u8>>,
    summary: Value,
}

/// Answers the page's requests from one scene.
pub struct Explorer {
    scene: Scene,
    name: String,
    /// Whether the page starts with the paper paths (`--paper`).
    paper: bool,
    shown: Mutex<VecDeque<Arc<Shown>>>,
}

impl Explorer {
    /// An explorer of `scene`, called `name` on the page.
    pub fn new(scene: Scene, name: impl Into<String>) -> Explorer {
        Explorer { scene, name: name.into(), paper: false, shown: Mutex::new(VecDeque::new()) }
    }

    /// The same explorer, its page starting with the stages as their papers publish them
    /// (`ShadowMethod::as_published`; the page's "as published" box).
    pub fn with_paper(self, paper: bool) -> Explorer {
        Explorer { paper, ..self }
    }

    /// Answers `GET url` (a path with an optional `?query`).
    pub fn handle(&self, url: &str) -> Response {
        let (path, query) = url.split_once('?').unwrap_or((url, ""));
        let answer = match path.trim_start_matches('/') {
            "" | "index.html" => Ok(Response::ok("text/html; charset=utf-8", PAGE)),
            "explore.js" => Ok(Response::ok("text/javascript; charset=utf-8", SCRIPT)),
            "explore.css" => Ok(Response::ok("text/css; charset=utf-8", STYLE)),
            "api/scene" => Ok(Response::json(&self.describe())),
            "api/frame" => self.request(query).and_then(|r| self.show(&r)).map(|s| Response::json(&s.summary)),
            "api/image" => {
                self.request(query).and_then(|r| self.show(&r)).map(|s| Response::ok("image/png", s.png.clone()))
            }
            "api/trace" => self.trace(query).map(|t| Response::json(&t)),
            "api/picture" => self.picture(query),
            "api/light" => self.light_view(query).map(|v| Response::json(&v)),
            _ => return Response::error(404, &format!("no such page: {path}")),
        };
        answer.unwrap_or_else(|e| Response::error(400, &e.to_string()))
    }

    /// The scene as the page needs it.
    fn describe(&self) -> Value {
        let cam = self.scene.camera();
        let (lo, hi) = self.scene.bounds().unwrap_or((DVec3::ZERO, DVec3::ZERO));
        let lights: Vec<Value> =
            self.scene.lights().iter().map(|l| json!({ "kind": kind_name(&l.kind), "at": at(&l.kind) })).collect();
        let stages: Vec<&str> = ShadowMethod::ALL.iter().map(|m| m.name()).collect();
        let paper_stages: Vec<&str> =
            ShadowMethod::ALL.iter().filter(|m| m.has_paper_path()).map(|m| m.name()).collect();
        let descriptions: serde_json::Map<String, Value> =
            ShadowMethod::ALL.iter().map(|m| (m.name().to_string(), m.description().into())).collect();
        json!({
            "name": self.name,
            "width": cam.width,
            "height": cam.height,
            "polygons": self.scene.polygons().len(),
            "faces": self.scene.face_count(),
            "bounds": [lo.to_array(), hi.to_array()],
            "lights": lights,
            "stages": stages,
            "default_stage": ShadowMethod::DEFAULT.name(),
            "paper_stages": paper_stages,
            "descriptions": descriptions,
            "paper": self.paper,
            "max_side": MAX_SIDE,
        })
    }

    /// Reads a request's stage, size and light from its query.
    fn request(&self, query: &str) -> Result<Request> {
        let cam = self.scene.camera();
        let mut r = Request { shadows: ShadowMethod::DEFAULT, width: cam.width, height: cam.height, light: None };
        let mut paper = false;
        for (key, value) in pairs(query) {
            match key.as_str() {
                "shadows" => r.shadows = value.parse()?,
                "paper" => {
                    paper = match value.as_str() {
                        "1" | "true" => true,
                        "0" | "false" => false,
                        _ => return Err(Error::out_of_range("paper", &value, "1 or 0")),
                    }
                }
                "width" => r.width = side("width", &value)?,
                "height" => r.height = side("height", &value)?,
                "light" => r.light = Some(point(&value)?),
                "line" | "index" | "x" => {}
                _ => {
                    let known = ["shadows", "paper", "width", "height", "light", "line", "index", "x"];
                    return Err(Error::UnknownName {
                        kind: "parameter".into(),
                        name: key,
                        known: known.map(String::from).to_vec(),
                    });
                }
            }
        }
        if paper {
            r.shadows = r.shadows.as_published();
        }
        Ok(r)
    }

    /// The scene at the request's size, with its first light moved.
    fn scene_for(&self, r: &Request) -> Result<Scene> {
        let mut scene = self.scene.clone();
        let mut camera = scene.camera().clone();
        (camera.width, camera.height) = (r.width, r.height);
        scene.set_camera(camera)?;
        if let Some(p) = r.light {
            let mut lights = scene.lights().to_vec();
            let middle = scene.bounds().map_or(DVec3::ZERO, |(lo, hi)| (lo + hi) / 2.0);
            let Some(first) = lights.first_mut() else {
                return Err(Error::InvalidOption("the scene has no light to move".into()));
            };
            match &mut first.kind {
                LightKind::Point { position } | LightKind::Spot { position, .. } => *position = p,
                LightKind::Area { corner, .. } => *corner = p,
                LightKind::Directional { direction } => {
                    *direction = crate::geometry::unit(middle - p)
                        .ok_or_else(|| Error::InvalidOption("the light is at the middle of the scene".into()))?
                }
            }
            scene.set_lights(lights)?;
        }
        Ok(scene)
    }

    /// Renders a request (or finds it rendered), with the ray-cast reference to mark the
    /// pixels where the stage differs.
    fn show(&self, r: &Request) -> Result<Arc<Shown>> {
        if let Some(s) = self.lock().iter().find(|s| s.request == *r) {
            return Ok(s.clone());
        }
        let scene = self.scene_for(r)?;
        let opts = |shadows| RenderOptions { shadows, outlines: true, ..RenderOptions::default() };
        let mut renderer = crate::Renderer::new();
        let got = renderer.render(&scene, &opts(r.shadows.clone()))?.clone();
        let reference = render(&scene, &opts(ShadowMethod::RayCast))?;
        let png = crate::frame::encode_png(got.frame.color_image(None).into())?;
        let mut summary = summary(&scene, r, &got, &reference, renderer.outlines());
        // Only the shadow map has pictures; other stages are not prepared a second time.
        let made = match r.shadows {
            ShadowMethod::Williams(_) => super::trace::pictures(&scene, &r.shadows)?,
            _ => Vec::new(),
        };
        let pictures = made.iter().map(|p| crate::frame::encode_png(p.image.clone().into())).collect::<Result<_>>()?;
        summary["pictures"] = made
            .iter()
            .map(|p| json!({ "light": p.light, "sample": p.sample, "face": p.face, "size": p.size }))
            .collect::<Vec<_>>()
            .into();
        let shown = Arc::new(Shown { request: r.clone(), png, pictures, summary });
        let mut kept = self.lock();
        kept.push_front(shown.clone());
        kept.truncate(CACHE);
        Ok(shown)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, VecDeque<Arc<Shown>>> {
        // A panic while holding the lock cannot leave the cache inconsistent: use it anyway.
        self.shown.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// One of the stage's pictures, by its index in the frame's `pictures`.
    fn picture(&self, query: &str) -> Result<Response> {
        let shown = self.show(&self.request(query)?)?;
        let index = pairs(query).find(|(k, _)| k == "index").map_or(Ok(0), |(_, v)| v.parse::<usize>());
        match index.ok().and_then(|i| shown.pictures.get(i)) {
            Some(png) => Ok(Response::ok("image/png", png.clone())),
            None => Err(Error::InvalidOption(format!("no such picture (this stage has {})", shown.pictures.len()))),
        }
    }

    /// What the point seen at pixel `(x, line)` sees of the scene's first area light, as the
    /// reference finds it ([`Reference::light_view_at`]): the light as the unit square of
    /// its coordinates, the part its plane cuts away, each occluder's shadow on it, what is
    /// left and its area, the exact fraction. `{"light": null}` without an area light.
    fn light_view(&self, query: &str) -> Result<Value> {
        let r = self.request(query)?;
        let number = |key: &str, below: u32| -> Result<u32> {
            let (_, v) = pairs(query)
                .find(|(k, _)| k == key)
                .ok_or_else(|| Error::InvalidOption(format!("missing parameter '{key}'")))?;
            match v.parse::<u32>() {
                Ok(n) if n < below => Ok(n),
                _ => Err(Error::out_of_range(key, &v, format!("a whole number below {below}"))),
            }
        };
        let (x, line) = (number("x", r.width)?, number("line", r.height)?);
        let scene = self.scene_for(&r)?;
        let Some(light) = scene.lights().iter().position(|l| matches!(l.kind, LightKind::Area { .. })) else {
            return Ok(json!({ "light": null }));
        };
        let ring = |r: &[glam::DVec2]| r.iter().map(|q| [q.x, q.y]).collect::<Vec<_>>();
        let seen = Reference::new(&scene).light_view_at(light, x as f64 + 0.5, line as f64 + 0.5);
        Ok(match seen {
            None => json!({ "light": light, "x": x, "line": line, "seen": false }),
            Some(v) => json!({
                "light": light,
                "x": x,
                "line": line,
                "seen": true,
                "fraction": v.fraction,
                "cut": ring(&v.cut),
                "hidden": v.hidden.iter().map(|(poly, r)| json!({ "poly": poly, "ring": ring(r) })).collect::<Vec<_>>(),
                "visible": v.visible.iter().map(|r| ring(r)).collect::<Vec<_>>(),
            }),
        })
    }

    /// Traces the requested line.
    fn trace(&self, query: &str) -> Result<LineTrace> {
        let r = self.request(query)?;
        let line = pairs(query)
            .find(|(k, _)| k == "line")
            .ok_or_else(|| Error::InvalidOption("missing parameter 'line'".into()))?
            .1;
        let line: u32 = line.parse().map_err(|_| Error::out_of_range("line", &line, "a line number"))?;
        let scene = self.scene_for(&r)?;
        trace(&scene, line, &r.shadows)
    }
}

/// What the page shows of a render: size, times, counters, the stage's polygons on screen
/// (first light sample), and the pixels where it differs from ray-cast, ties told apart.
fn summary(scene: &Scene, r: &Request, got: &Rendered, reference: &Rendered, outlines: &[Vec<glam::DVec2>]) -> Value {
    let oracle = Reference::new(scene);
    let (mut wrong, mut ties) = (Vec::new(), Vec::new());
    let (mut wrong_total, mut ties_total) = (0usize, 0usize);
    let (w, f, g) = (r.width as usize, &got.frame, &reference.frame);
    for i in 0..f.id.len() {
        let same = f.id[i] == g.id[i] && f.light.iter().zip(&g.light).all(|(a, b)| (a[i] - b[i]).abs() <= 1e-6);
        if same {
            continue;
        }
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        let (list, total) = match oracle.tie(x, y) {
            Some(Tie::Edge | Tie::LightInPlane) => (&mut ties, &mut ties_total),
            None => (&mut wrong, &mut wrong_total),
        };
        *total += 1;
        if list.len() < MAX_DIFFERS {
            list.push([x, y]);
        }
    }
    let outlines: Vec<Vec<[f64; 2]>> =
        outlines.iter().take(MAX_OUTLINES).map(|ring| ring.iter().map(|p| p.to_array()).collect()).collect();
    // Seed 000's penumbra of the first area light (its umbra shows dark in the frame).
    let area = (0..f.light.len()).find(|&k| f.is_area(k));
    let (mut penumbra, mut umbra_total, mut penumbra_total) = (Vec::new(), 0usize, 0usize);
    for (i, k) in area.into_iter().flat_map(|k| (0..f.id.len()).map(move |i| (i, k))) {
        match f.shade_class(k, i) {
            Some(crate::ShadeClass::Umbra) => umbra_total += 1,
            Some(crate::ShadeClass::Penumbra) => {
                penumbra_total += 1;
                if penumbra.len() < MAX_DIFFERS {
                    penumbra.push([(i % w) as u32, (i / w) as u32]);
                }
            }
            _ => {}
        }
    }
    json!({
        "shadows": r.shadows.label(),
        "exact": r.shadows.is_exact(),
        "width": r.width,
        "height": r.height,
        "stats": got.stats,
        "outlines": outlines,
        "outlines_total": outlines.len(),
        "differs": { "wrong": wrong, "wrong_total": wrong_total, "ties": ties, "ties_total": ties_total },
        "penumbra": { "light": area, "pixels": penumbra, "penumbra_total": penumbra_total, "umbra_total": umbra_total },
        "lights": scene.lights().iter().map(|l| json!({ "kind": kind_name(&l.kind), "at": at(&l.kind) })).collect::<Vec<_>>(),
    })
}

fn kind_name(k: &LightKind) -> &'static str {
    match k {
        LightKind::Point { .. } => "point",
        LightKind::Directional { .. } => "directional",
        LightKind::Spot { .. } => "spot",
        LightKind::Area { .. } => "area",
    }
}

/// Where a light is, for the page's controls (a directional light: its direction).
fn at(k: &LightKind) -> [f64; 3] {
    match k {
        LightKind::Point { position } | LightKind::Spot { position, .. } => position.to_array(),
        LightKind::Area { corner, .. } => corner.to_array(),
        LightKind::Directional { direction } => direction.to_array(),
    }
}

/// The `key=value` pairs of a query, percent-decoded.
fn pairs(query: &str) -> impl Iterator<Item = (String, String)> + '_ {
    query.split('&').filter(|p| !p.is_empty()).map(|p| {
        let (k, v) = p.split_once('=').unwrap_or((p, ""));
        (decode(k), decode(v))
    })
}

fn decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex =
            b.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok()).and_then(|h| u8::from_str_radix(h, 16).ok());
        match (b[i], hex) {
            (b'%', Some(v)) => {
                out.push(v);
                i += 3;
            }
            (b'+', _) => {
                out.push(b' ');
                i += 1;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn side(name: &str, value: &str) -> Result<u32> {
    match value.parse::<u32>() {
        Ok(v) if (1..=MAX_SIDE).contains(&v) => Ok(v),
        _ => Err(Error::out_of_range(name, value, format!("a whole number from 1 to {MAX_SIDE}"))),
    }
}

fn point(value: &str) -> Result<DVec3> {
    let v: Vec<f64> = value.split(',').filter_map(|c| c.trim().parse().ok()).filter(|c: &f64| c.is_finite()).collect();
    match v[..] {
        [x, y, z] if value.split(',').count() == 3 => Ok(DVec3::new(x, y, z)),
        _ => Err(Error::out_of_range("light", value, "three finite numbers x,y,z")),
    }
}

/// Writes the page with every line of every applicable stage precomputed into `dir`, at
/// `width` x `height`, for reading from disk or any static web host.
pub fn export(
    explorer: &Explorer,
    dir: impl AsRef<Path>,
    width: u32,
    height: u32,
    stages: &[ShadowMethod],
) -> Result<()> {
    let dir = dir.as_ref();
    let io = |path: &Path, e: std::io::Error| Error::Write { path: path.to_owned(), source: e };
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
        }
        std::fs::write(&path, bytes).map_err(|e| io(&path, e))
    };
    let (width, height) = (side("width", &width.to_string())?, side("height", &height.to_string())?);
    let mut frames = serde_json::Map::new();
    let mut watkins = String::new();
    for shadows in stages {
        let r = Request { shadows: shadows.clone(), width, height, light: None };
        let shown = match explorer.show(&r) {
            Err(Error::NotApplicable { .. }) => continue,
            other => other?,
        };
        let name = shadows.name();
        write(&format!("frames/{name}.png"), &shown.png)?;
        for (k, png) in shown.pictures.iter().enumerate() {
            write(&format!("pictures/{name}-{k}.png"), png)?;
        }
        // The visibility part of a line is the same for every stage: written once.
        let first = watkins.is_empty();
        let mut decisions = String::new();
        trace_lines(&explorer.scene_for(&r)?, 0..height, shadows, |mut t| {
            // Bouknight-Kelley's pairs per receiver repeat on every run of the receiver: the
            // static page leaves them out (the live page shows them).
            let mut d = serde_json::to_value(&t.decisions).map_err(|e| Error::Internal(e.to_string()))?;
            for detail in d.as_array_mut().into_iter().flatten().filter_map(|d| d["decision"]["detail"].as_object_mut())
            {
                detail.remove("pairs");
            }
            let _ = writeln!(decisions, "umbraDecisions({:?}, {}, {});", name, t.line, to_json(&rounded(d))?);
            if first {
                t.decisions.clear();
                let line = serde_json::to_value(&t).map_err(|e| Error::Internal(e.to_string()))?;
                let _ = writeln!(watkins, "umbraLine({});", to_json(&rounded(line))?);
            }
            Ok(())
        })?;
        write(&format!("lines/{name}.js"), decisions.as_bytes())?;
        frames.insert(name.into(), shown.summary.clone());
    }
    write("lines/watkins.js", watkins.as_bytes())?;
    let mut scene = explorer.describe();
    scene["width"] = width.into();
    scene["height"] = height.into();
    let data = json!({ "scene": scene, "frames": frames });
    write("data.js", format!("window.UMBRA_STATIC = {data};\n").as_bytes())?;
    write("index.html", PAGE.replace("<!--static-->", r#"<script src="data.js"></script>"#).as_bytes())?;
    write("explore.js", SCRIPT.as_bytes())?;
    write("explore.css", STYLE.as_bytes())
}

/// Every fractional number in `v` kept to 7 significant digits (what the page shows, and
/// a third of the bytes of the shortest exact form).
fn rounded(v: Value) -> Value {
    match v {
        Value::Array(a) => Value::Array(a.into_iter().map(rounded).collect()),
        Value::Object(o) => Value::Object(o.into_iter().map(|(k, v)| (k, rounded(v))).collect()),
        Value::Number(n) if !n.is_i64() && !n.is_u64() => {
            let x = n.as_f64().unwrap_or(0.0);
            let short: f64 = format!("{x:.6e}").parse().unwrap_or(x);
            serde_json::Number::from_f64(short).map_or(Value::Null, Value::Number)
        }
        other => other,
    }
}

/// `v` as JSON text, for the exported scripts.
fn to_json(v: &impl Serialize) -> Result<String> {
    serde_json::to_string(v).map_err(|e| Error::Internal(e.to_string()))
}
