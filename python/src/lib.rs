//! The umbra engine from Python (`import umbra`): load a scene, render it with any
//! visibility and shadow stage, and get the frame back as numpy arrays; time stages with
//! `bench`. A thin layer over the engine crate: every algorithm is the engine's.

use engine as um;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

create_exception!(
    umbra,
    UmbraError,
    PyException,
    "What the engine refused or could not do: a scene file's problem (the message names the \
     file and line), an unknown stage or option, a frame over the memory budget."
);

fn error(e: um::Error) -> PyErr {
    UmbraError::new_err(e.to_string())
}

/// A scene: geometry, materials, lights and the camera, checked when loaded.
#[pyclass(name = "Scene", module = "umbra", frozen)]
struct Scene {
    inner: um::Scene,
}

#[pymethods]
impl Scene {
    /// Image width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.inner.camera().width
    }

    /// Image height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.inner.camera().height
    }

    /// Number of polygons (after triangulating nothing: the scene's own polygons).
    #[getter]
    fn polygons(&self) -> usize {
        self.inner.polygons().len()
    }

    /// Number of lights.
    #[getter]
    fn lights(&self) -> usize {
        self.inner.lights().len()
    }

    /// The same scene rendered at another image size (the camera's field of view kept).
    fn with_size(&self, width: u32, height: u32) -> PyResult<Scene> {
        let mut inner = self.inner.clone();
        let mut camera = inner.camera().clone();
        camera.width = width;
        camera.height = height;
        inner.set_camera(camera).map_err(error)?;
        Ok(Scene { inner })
    }

    fn __repr__(&self) -> String {
        format!(
            "<umbra.Scene {}x{}, {} polygons, {} lights>",
            self.width(),
            self.height(),
            self.polygons(),
            self.lights()
        )
    }
}

/// A rendered frame: the image, the analysis buffers, and what it took.
#[pyclass(name = "Frame", module = "umbra", frozen, get_all)]
struct Frame {
    /// The image, `(height, width, 3)` `uint8` (sRGB-encoded with `gamma`, else linear).
    image: Py<PyArray3<u8>>,
    /// The face id seen at each pixel centre, `(height, width)` `uint32`; 4294967295 on
    /// background.
    face_ids: Py<PyArray2<u32>>,
    /// Each light's lit fraction at each pixel, `(height, width)` `float32` arrays.
    light: Vec<Py<PyArray2<f32>>>,
    /// The stages' counters, `{"visibility.spans": 1196, "shadow.pairs": 235, ...}`.
    counters: Py<PyDict>,
    /// Milliseconds per phase, `{"view": ..., "visibility": ..., "total": ...}`.
    times: Py<PyDict>,
}

#[pymethods]
impl Frame {
    fn __repr__(&self, py: Python<'_>) -> String {
        let shape = self.image.bind(py).shape().to_vec();
        format!("<umbra.Frame {}x{}, {} lights>", shape[1], shape[0], self.light.len())
    }
}

/// The options of one render from the Python arguments.
fn options(
    visibility: &str,
    shadows: &str,
    paper: bool,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<um::RenderOptions> {
    let method: um::ShadowMethod = shadows.parse().map_err(error)?;
    let opts = um::RenderOptions {
        visibility: visibility.parse().map_err(error)?,
        shadows: method.with_settings(&stage_settings(settings)?),
        ..Default::default()
    };
    Ok(if paper { opts.as_published() } else { opts })
}

/// The stages' settings from keyword arguments, each named as its field in the engine's
/// options (`prefilter=False`, `counting="zfail"`, `map_size=1024`); a setting names the
/// same field of every stage that has it (`solid_cull`). Unknown names are refused with the
/// known ones.
fn stage_settings(settings: Option<&Bound<'_, PyDict>>) -> PyResult<um::shadow::StageSettings> {
    let mut s = um::shadow::StageSettings::default();
    let Some(settings) = settings else { return Ok(s) };
    for (key, value) in settings.iter() {
        let key: String = key.extract()?;
        let Some((_, set)) = SETTINGS.iter().find(|(name, _)| *name == key) else {
            let known: Vec<&str> = SETTINGS.iter().map(|(name, _)| *name).collect();
            return Err(UmbraError::new_err(format!("unknown stage setting '{key}' (known: {})", known.join(", "))));
        };
        set(&mut s, &value)?;
    }
    Ok(s)
}

/// Sets one setting from a Python value.
type Setter = fn(&mut um::shadow::StageSettings, &Bound<'_, PyAny>) -> PyResult<()>;

/// A setting parsed by its engine name (`counting = "zfail"`).
fn named<T: std::str::FromStr<Err = um::Error>>(v: &Bound<'_, PyAny>) -> PyResult<T> {
    v.extract::<String>()?.parse().map_err(error)
}

/// Every keyword setting [`stage_settings`] knows, by name.
const SETTINGS: [(&str, Setter); 33] = [
    ("prefilter", |s, v| v.extract().map(|x| s.bouknight_kelley.prefilter = x)),
    ("sphere_grid", |s, v| v.extract().map(|x| s.bouknight_kelley.sphere_grid = x)),
    ("seen_receivers", |s, v| v.extract().map(|x| s.bouknight_kelley.seen_receivers = x)),
    ("drop_behind", |s, v| v.extract().map(|x| s.bouknight_kelley.drop_behind = x)),
    ("wedge", |s, v| v.extract().map(|x| s.bouknight_kelley.wedge = x)),
    ("slab", |s, v| v.extract().map(|x| s.bouknight_kelley.slab = x)),
    ("solid_outlines", |s, v| v.extract().map(|x| s.bouknight_kelley.solid_outlines = x)),
    ("own_solid", |s, v| v.extract().map(|x| s.bouknight_kelley.own_solid = x)),
    ("solid_cull", |s, v| {
        let on = v.extract()?;
        s.bouknight_kelley.solid_cull = on;
        s.atherton_weiler_greenberg.solid_cull = on;
        s.nishita_nakamae.solid_cull = on;
        Ok(())
    }),
    ("convex_split", |s, v| v.extract().map(|x| s.atherton_weiler_greenberg.convex_split = x)),
    ("backgrounds", |s, v| v.extract().map(|x| s.atherton_weiler_greenberg.backgrounds = x)),
    ("lone_sheets", |s, v| v.extract().map(|x| s.atherton_weiler_greenberg.lone_sheets = x)),
    ("whole_solids", |s, v| v.extract().map(|x| s.atherton_weiler_greenberg.whole_solids = x)),
    ("tiling", |s, v| v.extract().map(|x| s.atherton_weiler_greenberg.tiling = x)),
    ("face_binning", |s, v| v.extract().map(|x| s.atherton_weiler_greenberg.face_binning = x)),
    ("sort_grid", |s, v| v.extract().map(|x| s.atherton_weiler_greenberg.sort_grid = x)),
    ("counting", |s, v| named(v).map(|x| s.volumes.counting = x)),
    ("construction", |s, v| named(v).map(|x| s.volumes.construction = x)),
    ("sight_cuts", |s, v| v.extract().map(|x| s.volumes.sight_cuts = x)),
    ("far_outline", |s, v| v.extract().map(|x| s.volumes.far_outline = x)),
    ("front_outline", |s, v| v.extract().map(|x| s.volumes.front_outline = x)),
    ("map_size", |s, v| v.extract().map(|x| s.williams.map_size = x)),
    ("bias", |s, v| v.extract().map(|x| s.williams.bias = x)),
    ("slope_bias", |s, v| v.extract().map(|x| s.williams.slope_bias = x)),
    ("normal_offset", |s, v| v.extract().map(|x| s.williams.normal_offset = x)),
    ("receiver_plane", |s, v| v.extract().map(|x| s.williams.receiver_plane = x)),
    ("cull_front", |s, v| v.extract().map(|x| s.williams.cull_front = x)),
    ("fit_to_view", |s, v| v.extract().map(|x| s.williams.fit_to_view = x)),
    ("hull_cull", |s, v| v.extract().map(|x| s.nishita_nakamae.hull_cull = x)),
    ("convex_bodies", |s, v| v.extract().map(|x| s.nishita_nakamae.convex_bodies = x)),
    ("same_solid", |s, v| v.extract().map(|x| s.nishita_nakamae.same_solid = x)),
    ("lambert", |s, v| v.extract().map(|x| s.nishita_nakamae.lambert = x)),
    ("premise_fallback", |s, v| v.extract().map(|x| s.nishita_nakamae.premise_fallback = x)),
];

/// Loads a scene file (`docs/scene-format.md`). Raises `UmbraError` naming the file and
/// line of a problem, `OSError`-like failures included.
#[pyfunction]
fn load(path: PathBuf) -> PyResult<Scene> {
    um::Scene::load(&path).map(|inner| Scene { inner }).map_err(error)
}

/// Renders `scene` with the visibility stage `visibility` (`scanline`, `zbuffer`,
/// `ray-cast`) and the shadow stage `shadows` (`bouknight-kelley`, `crow`,
/// `atherton-weiler-greenberg`, `nishita-nakamae`, `williams`, `stencil-volume`, `planar`,
/// `ray-cast`, `none`); `paper=True` runs the stage as its paper publishes it, and keyword
/// settings set the stage's options by their names in the engine (`prefilter=False`,
/// `counting="zfail"`, `map_size=1024`, `same_solid=False`). `gamma` encodes the image
/// (None: linear). The engine runs without the GIL, on every core.
#[pyfunction]
#[pyo3(signature = (scene, visibility = "scanline", shadows = "bouknight-kelley", paper = false, gamma = Some(2.2), **settings))]
fn render(
    py: Python<'_>,
    scene: &Scene,
    visibility: &str,
    shadows: &str,
    paper: bool,
    gamma: Option<f32>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Frame> {
    let opts = options(visibility, shadows, paper, settings)?;
    let rendered = py.allow_threads(|| um::render(&scene.inner, &opts)).map_err(error)?;
    frame(py, &rendered, gamma)
}

/// The numpy arrays and dicts of a rendered frame.
fn frame(py: Python<'_>, r: &um::Rendered, gamma: Option<f32>) -> PyResult<Frame> {
    let f = &r.frame;
    let (w, h) = (f.width as usize, f.height as usize);
    let shape = |e| PyErr::new::<pyo3::exceptions::PyValueError, _>(format!("frame shape: {e}"));
    let rgb = f.color_image(gamma).into_raw();
    let image = Array3::from_shape_vec((h, w, 3), rgb).map_err(shape)?.into_pyarray(py).unbind();
    let face_ids = Array2::from_shape_vec((h, w), f.id.clone()).map_err(shape)?.into_pyarray(py).unbind();
    let light = f
        .light
        .iter()
        .map(|l| Ok(Array2::from_shape_vec((h, w), l.clone()).map_err(shape)?.into_pyarray(py).unbind()))
        .collect::<PyResult<_>>()?;
    Ok(Frame { image, face_ids, light, counters: counters(py, &r.stats)?, times: times(py, &r.stats)? })
}

/// `{"visibility.<name>": n, "shadow.<name>": n}`.
fn counters(py: Python<'_>, stats: &um::Stats) -> PyResult<Py<PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in stats.visibility_counters.iter() {
        d.set_item(format!("visibility.{k}"), v)?;
    }
    for (k, v) in stats.shadow_counters.iter() {
        d.set_item(format!("shadow.{k}"), v)?;
    }
    Ok(d.unbind())
}

/// `{"view": ms, ..., "total": ms}`.
fn times(py: Python<'_>, stats: &um::Stats) -> PyResult<Py<PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in stats.time_ms.steps() {
        d.set_item(k, v)?;
    }
    d.set_item("total", stats.time_ms.total)?;
    Ok(d.unbind())
}

/// Times every pair of `visibility` and `shadows` stages on `scene`: `warmup` renders
/// untimed, then `runs` timed. Returns one dict per pair: `visibility`, `shadows` (the
/// stage's label), `median_ms`, `min_ms`, `max_ms`, `times_ms` (each run's frame), `phases`
/// (each phase's median, ms) and `counters` (the last run's). Keyword settings as
/// `render`'s, for every stage.
#[pyfunction(name = "bench")]
#[pyo3(signature = (scene, shadows = vec!["bouknight-kelley".to_string()], visibility = vec!["scanline".to_string()], runs = 5, warmup = 1, paper = false, **settings))]
#[allow(clippy::too_many_arguments)]
fn bench_stages(
    py: Python<'_>,
    scene: &Scene,
    shadows: Vec<String>,
    visibility: Vec<String>,
    runs: usize,
    warmup: usize,
    paper: bool,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<Py<PyDict>>> {
    if runs == 0 {
        return Err(UmbraError::new_err("bench: runs must be at least 1"));
    }
    let mut rows = Vec::new();
    for v in &visibility {
        for s in &shadows {
            let opts = options(v, s, paper, settings)?;
            let timed = py
                .allow_threads(|| {
                    let mut renderer = um::Renderer::new();
                    for _ in 0..warmup {
                        renderer.render(&scene.inner, &opts)?;
                    }
                    (0..runs)
                        .map(|_| renderer.render(&scene.inner, &opts).map(|r| r.stats.clone()))
                        .collect::<um::Result<Vec<_>>>()
                })
                .map_err(error)?;
            rows.push(row(py, v, &opts, timed)?);
        }
    }
    Ok(rows)
}

/// One bench row from the runs' stats.
fn row(py: Python<'_>, visibility: &str, opts: &um::RenderOptions, runs: Vec<um::Stats>) -> PyResult<Py<PyDict>> {
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let totals: Vec<f64> = runs.iter().map(|s| s.time_ms.total).collect();
    let d = PyDict::new(py);
    d.set_item("visibility", visibility)?;
    d.set_item("shadows", opts.shadows.label())?;
    d.set_item("median_ms", median(totals.clone()))?;
    d.set_item("min_ms", totals.iter().copied().fold(f64::INFINITY, f64::min))?;
    d.set_item("max_ms", totals.iter().copied().fold(0.0, f64::max))?;
    d.set_item("times_ms", totals)?;
    let phases = PyDict::new(py);
    let last = &runs[runs.len() - 1];
    for (k, _) in last.time_ms.steps() {
        let each = runs.iter().filter_map(|s| s.time_ms.steps().find(|(n, _)| *n == k).map(|(_, v)| v)).collect();
        phases.set_item(k, median(each))?;
    }
    d.set_item("phases", phases)?;
    d.set_item("counters", counters(py, last)?)?;
    Ok(d.unbind())
}

/// The module `umbra`.
#[pymodule]
#[pyo3(name = "umbra")]
fn umbra_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("UmbraError", m.py().get_type::<UmbraError>())?;
    m.add_class::<Scene>()?;
    m.add_class::<Frame>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(bench_stages, m)?)?;
    Ok(())
}
