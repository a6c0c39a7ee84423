//! The pipeline: scene -> view -> visibility runs -> shadow -> shading -> frame.
//!
//! Visibility resolves every line into runs first (in parallel bands of lines); the shadow
//! stage is then prepared knowing which polygons are seen; finally the frame is shaded in
//! parallel bands, each band's shadow walker stepping down its lines in order as a scanline
//! renderer does.

use crate::error::Result;
use crate::frame::{Frame, PixelCounters};
use crate::progress::{Progress, ProgressFn, Reporter};
use crate::reflection::ReflectionMethod;
use crate::scene::Scene;
use crate::shading::{LineShading, Shader};
use crate::shadow::{ShadowContext, ShadowDatabase, ShadowMethod};
use crate::stats::{Counters, Stats};
use crate::view::{Screen, ScreenSizes, View};
use crate::visibility::{FrameRuns, VisibilityMethod};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What to render with.
#[derive(Debug, Clone)]
pub struct RenderOptions {
    /// The hidden-surface stage.
    pub visibility: VisibilityMethod,
    /// The shadow stage, with its settings.
    pub shadows: ShadowMethod,
    /// Collect per-pixel counters into [`Frame::counters`].
    pub pixel_counters: bool,
    /// How mirrors are rendered.
    pub reflection: crate::reflection::ReflectionMethod,
    /// Keep the screen outlines of the shadow stage's polygons (shadow polygons, detail
    /// polygons) for the first light sample in [`Renderer::outlines`], to draw them over the
    /// image.
    pub outlines: bool,
    /// Leave out of the hidden-surface stage the polygons of closed solids that turn their
    /// backs to the eye (when the eye is outside the solid's bounds): they are never seen.
    /// On by default; the images are the same either way, up to which of two polygons meeting
    /// at a silhouette edge is seen exactly on it.
    pub back_face_cull: bool,
    /// Shastry's soft edges on the shadow stage's answers (`None`, the default: as the stage
    /// gives them): each light sample's lit fractions blurred in a screen buffer
    /// ([`crate::shadow::SoftEdges`]; `docs/algorithms/williams.md`).
    pub soft_edges: Option<crate::shadow::SoftEdges>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            visibility: VisibilityMethod::Scanline,
            shadows: ShadowMethod::DEFAULT,
            outlines: false,
            pixel_counters: false,
            reflection: crate::reflection::ReflectionMethod::default(),
            back_face_cull: true,
            soft_edges: None,
        }
    }
}

impl RenderOptions {
    /// The same options with the shadow stage as its paper publishes it
    /// ([`ShadowMethod::as_published`], the command line's `--paper`), and Shastry's soft
    /// edges, when asked for, in the article's shared buffer.
    ///
    /// ```
    /// use umbra::shadow::{Buffers, SoftEdges};
    /// let opts = umbra::RenderOptions { soft_edges: Some(SoftEdges::default()), ..Default::default() };
    /// let paper = opts.as_published();
    /// assert!(paper.shadows.is_paper());
    /// assert_eq!(paper.soft_edges.unwrap().buffers, Buffers::Shared);
    /// ```
    pub fn as_published(&self) -> RenderOptions {
        let soft_edges =
            self.soft_edges.map(|s| crate::shadow::SoftEdges { buffers: crate::shadow::Buffers::Shared, ..s });
        RenderOptions { shadows: self.shadows.as_published(), soft_edges, ..self.clone() }
    }
}

/// A rendered frame and what it took.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// The image and its analysis buffers.
    pub frame: Frame,
    /// Counters and times.
    pub stats: Stats,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// One band's rows of the frame's buffers.
struct Band<'f> {
    y0: u32,
    color: &'f mut [Vec3],
    id: &'f mut [u32],
    light: Vec<&'f mut [f32]>,
    tests: Option<&'f mut [u32]>,
}

/// How many of the polygons of `screen` cover each pixel centre.
fn depth_complexity(screen: &Screen, w: u32, h: u32) -> Vec<u32> {
    let mut count = vec![0u32; (w * h) as usize];
    let mut table = crate::scan::EdgeTable::new(h);
    for (_, _, ring) in screen.iter() {
        crate::scan::for_each_span(&mut table, &[ring], w, h, 0..h, |y, x0, x1| {
            for c in &mut count[(y * w + x0) as usize..(y * w + x1) as usize] {
                *c += 1;
            }
        });
    }
    count
}

/// Refuses a frame whose buffers (colour, face ids, lit fractions, the visibility stage's
/// depth, per-pixel counters) would not fit [`crate::budget::MEMORY_BUDGET`].
fn check_frame_memory(scene: &Scene, opts: &RenderOptions) -> Result<()> {
    let (w, h) = (scene.camera.width as u64, scene.camera.height as u64);
    let per_pixel = 32 + 4 * scene.lights.len() as u64 + if opts.pixel_counters { 12 } else { 0 };
    crate::budget::check(format_args!("a {w}x{h} frame"), crate::budget::mul(w * h, per_pixel))
}

/// Renders frames, keeping the memory each frame used for the next: the frame's colour, id
/// and lit-fraction buffers, the z-buffer's depth and id buffers and Williams' shadow maps.
/// A program that renders many frames (an animation, a benchmark, a study) renders them
/// through one `Renderer`, so that after the first frame the system does not hand out and
/// zero fresh pages for them each time. [`render()`] is the one-call form.
///
/// ```
/// use umbra::{generate, RenderOptions, Renderer};
///
/// let scene = generate::cubes(2, generate::Faces::Quads, 64, 48)?;
/// let mut renderer = Renderer::new();
/// for _ in 0..3 {
///     let out = renderer.render(&scene, &RenderOptions::default())?;
///     assert_eq!(out.frame.id.len(), 64 * 48);
/// }
/// # Ok::<(), umbra::Error>(())
/// ```
#[derive(Default)]
pub struct Renderer {
    pools: crate::pool::Pools,
    awg_database: Option<Arc<Vec<ShadowDatabase>>>,
    progress: Option<Arc<ProgressFn>>,
    last: Option<Rendered>,
    outlines: Vec<Vec<glam::DVec2>>,
}

impl Renderer {
    /// A renderer that keeps nothing yet.
    pub fn new() -> Renderer {
        Renderer::default()
    }

    /// The bytes of frame-sized buffers the renderer keeps for the next frame (shadow
    /// maps, depth and id buffers, stencil counts, lit masks, mirror frames), the last frame
    /// itself and what stages keep of their own (the shadow volumes' adjacency) aside.
    pub fn kept_bytes(&self) -> usize {
        self.pools.bytes()
    }

    /// Lets go of everything kept for the next frame: the buffers of
    /// [`Renderer::kept_bytes`] (which becomes 0) and what stages keep of their own; the
    /// last frame and a shadow database given with `with_shadow_database` stay. After
    /// a frame with large shadow maps, a program that goes on with something smaller calls
    /// it to give their memory back; the next frame allocates what it needs again.
    ///
    /// ```
    /// use umbra::{generate, RenderOptions, Renderer};
    /// let scene = generate::cubes(1, generate::Faces::Quads, 64, 48)?;
    /// let mut renderer = Renderer::new();
    /// renderer.render(&scene, &RenderOptions { shadows: "williams".parse()?, ..Default::default() })?;
    /// assert!(renderer.kept_bytes() > 1 << 20); // a 2048² map
    /// renderer.trim();
    /// assert_eq!(renderer.kept_bytes(), 0);
    /// # Ok::<(), umbra::Error>(())
    /// ```
    pub fn trim(&mut self) {
        self.pools = crate::pool::Pools::default();
    }

    /// Renders `scene` with the chosen stages, into the memory of the last frame; the
    /// result lives until the next call.
    pub fn render(&mut self, scene: &Scene, opts: &RenderOptions) -> Result<&Rendered> {
        let spare = self.last.take().map(|r| r.frame);
        let (out, outlines) = render_with(scene, opts, &self.kept(), spare)?;
        self.outlines = outlines;
        Ok(self.last.insert(out))
    }

    /// The screen outlines of the last frame's shadow-stage polygons (shadow polygons,
    /// detail polygons, shadow-volume polygons) for the first light sample, when
    /// [`RenderOptions::outlines`] asked for them; empty otherwise. What `--debug` draws.
    pub fn outlines(&self) -> &[Vec<glam::DVec2>] {
        &self.outlines
    }

    /// Renders Atherton-Weiler-Greenberg's shadows from `databases` (one per light, built
    /// beforehand by [`ShadowDatabase::build`] for the scene's lights) instead of building
    /// them in each frame: pass 1 done once for many views.
    pub fn with_shadow_database(mut self, databases: Arc<Vec<ShadowDatabase>>) -> Renderer {
        self.awg_database = Some(databases);
        self
    }

    /// Reports each frame's progress to `report` (the phase, and lines shaded of all):
    /// what the command line draws as a progress bar.
    ///
    /// ```
    /// use umbra::{generate, RenderOptions, Renderer};
    /// use std::sync::atomic::{AtomicU64, Ordering};
    /// use std::sync::Arc;
    ///
    /// let lines = Arc::new(AtomicU64::new(0));
    /// let seen = lines.clone();
    /// let mut renderer = Renderer::new().with_progress(move |p| seen.store(p.done, Ordering::Relaxed));
    /// renderer.render(&generate::cubes(2, generate::Faces::Quads, 64, 48)?, &RenderOptions::default())?;
    /// assert_eq!(lines.load(Ordering::Relaxed), 48);
    /// # Ok::<(), umbra::Error>(())
    /// ```
    pub fn with_progress(mut self, report: impl Fn(Progress<'_>) + Send + Sync + 'static) -> Renderer {
        self.progress = Some(Arc::new(report));
        self
    }

    fn kept(&self) -> Kept<'_> {
        Kept { pools: &self.pools, awg_database: self.awg_database.clone(), progress: self.progress.as_deref() }
    }

    /// The last frame rendered, to keep.
    pub fn into_rendered(self) -> Option<Rendered> {
        self.last
    }
}

/// Renders `scene` with the chosen stages (a fresh [`Renderer`]'s one frame).
pub fn render(scene: &Scene, opts: &RenderOptions) -> Result<Rendered> {
    let kept = Kept { pools: &Default::default(), awg_database: None, progress: None };
    Ok(render_with(scene, opts, &kept, None)?.0)
}

/// The screen outlines of a shadow stage's polygons.
type Outlines = Vec<Vec<glam::DVec2>>;

/// What a renderer keeps between frames and hands to the passes.
struct Kept<'r> {
    pools: &'r crate::pool::Pools,
    awg_database: Option<Arc<Vec<ShadowDatabase>>>,
    progress: Option<&'r ProgressFn>,
}

/// The frame pass, then the reflection pass over it, taking frame-sized buffers from `pools`
/// and `spare`.
fn render_with(scene: &Scene, opts: &RenderOptions, kept: &Kept, spare: Option<Frame>) -> Result<(Rendered, Outlines)> {
    let (mut out, runs, outlines) = frame_pass(scene, opts, kept, spare)?;
    if opts.reflection != ReflectionMethod::Off {
        let t = Instant::now();
        // What a mirror shows is a frame of its own, with one level of reflection.
        let inner = RenderOptions { reflection: ReflectionMethod::Off, pixel_counters: false, ..opts.clone() };
        let mirror_pass = |mirrored: &Scene| {
            // The mirrored scene has other polygons and lights: a database built beforehand
            // for the scene does not apply.
            let inner_kept = Kept { awg_database: None, progress: None, ..*kept };
            let (seen, ..) = frame_pass(mirrored, &inner, &inner_kept, kept.pools.frames.take())?;
            Ok(seen.frame)
        };
        // Each mirror's frame, once blended in, is kept for the next.
        let done = |seen: Frame| kept.pools.frames.give(seen);
        let passes = (&kept.pools.u32, mirror_pass, done);
        if crate::reflection::add_reflections(scene, opts.reflection, &mut out.frame, &runs, passes)? {
            // Blending in what the mirrors show can overflow what the frame pass kept finite.
            out.frame.color.par_chunks_mut(1 << 16).for_each(saturate);
            out.stats.time_ms.reflections = Some(ms(t.elapsed()));
        }
    }
    Ok((out, outlines))
}

/// One frame, without reflections: view, visibility, shadow preparation, then the shadow
/// walk and shading in parallel bands of lines. Returns the frame and its visible runs.
fn frame_pass(
    scene: &Scene,
    opts: &RenderOptions,
    kept: &Kept,
    spare: Option<Frame>,
) -> Result<(Rendered, FrameRuns, Outlines)> {
    let pools = kept.pools;
    let start = Instant::now();
    // The camera is a public field: a program may have changed it since the scene was built.
    scene.camera.validate().map_err(crate::error::Error::InvalidOption)?;
    check_frame_memory(scene, opts)?;
    let mut stats = Stats {
        visibility: opts.visibility.name().into(),
        shadows: opts.shadows.label(),
        width: scene.camera.width,
        height: scene.camera.height,
        polygons: scene.polygons.len(),
        ..Stats::default()
    };
    let view = View::new(&scene.camera);
    let bar = Reporter::new(kept.progress, view.height as u64, "lines");

    let t = Instant::now();
    bar.phase("view: clipping and projecting");
    let whole = view.solids_past_near_plane(scene);
    let eye = crate::scene::LightSample::Point(view.eye);
    let closed = scene.closed_from(eye);
    let seen = |i: usize| {
        let solid = scene.solid_of[i] as usize;
        !(opts.back_face_cull && whole.get(solid) == Some(&true) && scene.turned_away_on_solid(i, eye, &closed))
    };
    let sizes: ScreenSizes = pools.stash.take();
    let screen = view.screen_polygons_in(scene, seen, Screen::sized(sizes));
    stats.visibility_counters.add(crate::stats::Counter::ScreenPolygons, screen.len() as u64);
    stats.time_ms.view = ms(t.elapsed());

    let t = Instant::now();
    bar.phase(format!("visibility ({})", opts.visibility.name()));
    let (runs, pixel_counters) = visible_runs(scene, opts, &view, &screen, pools, &mut stats.visibility_counters);
    stats.time_ms.visibility = ms(t.elapsed());
    // The screen polygons are done with: let go now, not kept for the next frame, so that
    // they do not sit through the shadow preparation, where the frame's memory peaks (62 MB
    // on s3); the next frame is told each part's size (Williams' light views keep screens of
    // their own in the stash).
    pools.stash.put(screen.let_go());

    let t = Instant::now();
    bar.phase(format!("shadow preparation ({})", opts.shadows.label()));
    let ctx = ShadowContext::new(scene, &view, &runs, opts.outlines)
        .with_pools(pools)
        .with_awg_database(kept.awg_database.clone());
    stats.light_samples = ctx.samples.iter().map(Vec::len).sum();
    let mut shadows = opts.shadows.prepare(&ctx, &mut stats.shadow_counters)?;
    // Shastry's soft edges: ours, a blurred buffer per sample served in place of the
    // stage; the article's shared buffer, a shading pass per sample (below).
    let shared = opts.soft_edges.filter(|s| s.buffers == crate::shadow::Buffers::Shared);
    if let Some(soft) = opts.soft_edges.filter(|_| shared.is_none()) {
        shadows = Box::new(soft_edged(&ctx, shadows.as_ref(), soft)?);
    }
    stats.time_ms.shadow_prepare = ms(t.elapsed());
    stats.shadow_counters.add(crate::stats::Counter::StageBytes, shadows.bytes() as u64);

    let t = Instant::now();
    let (lights, background) = (scene.lights.len(), scene.render.background);
    let mut frame = match spare {
        Some(mut old) => {
            // The last frame's mirror ids go back to the pool, for this frame's mirrors.
            if let Some(ids) = old.mirror_id.take() {
                pools.u32.give(ids);
            }
            Frame::recycle(old, view.width, view.height, lights, background)
        }
        None => Frame::new(view.width, view.height, lights, background),
    };
    frame.light_samples = ctx.samples.iter().map(|s| s.len() as u32).collect();
    // A stage that answers for a whole light gives its exact fraction (`Frame::light_samples`).
    let probe = shadows.walker();
    for (l, n) in frame.light_samples.iter_mut().enumerate() {
        if probe.whole_light(l) {
            *n = 0;
        }
    }
    drop(probe);
    frame.counters = pixel_counters;
    let bands = match shared {
        Some(soft) => shade_shared(&ctx, &*shadows, soft, &mut frame, &bar)?,
        None => {
            bar.phase("shadow walk and shading");
            shade_frame(&ctx, &*shadows, &mut frame, &bar)
        }
    };
    // The bands ran on several threads: the wall-clock time of the pass is split between
    // the shadow walk and the shading in the proportion of their summed band times.
    let pass = ms(t.elapsed());
    let (walking, shading) = bands.iter().fold((0.0, 0.0), |(a, b), band| (a + ms(band.1), b + ms(band.2)));
    let walk_share = if walking + shading > 0.0 { walking / (walking + shading) } else { 0.0 };
    for (shadow, ..) in &bands {
        stats.shadow_counters.merge(shadow);
    }
    stats.time_ms.shadow_walk = pass * walk_share;
    stats.time_ms.shading = pass * (1.0 - walk_share);
    // Seed 000's umbra and penumbra of the area lights, counted over the visible pixels.
    if (0..frame.light.len()).any(|k| frame.is_area(k)) {
        let (umbra, penumbra) = frame.umbra_and_penumbra();
        stats.shadow_counters.add(crate::stats::Counter::UmbraPixels, umbra);
        stats.shadow_counters.add(crate::stats::Counter::PenumbraPixels, penumbra);
    }
    stats.time_ms.total = ms(start.elapsed());
    // Empty unless asked for: the stages keep outlines only then (`ShadowContext::keep_outlines`).
    let outlines = shadows.outlines();
    drop(shadows);
    drop(ctx);
    Ok((Rendered { frame, stats }, runs, outlines))
}

/// The visibility stage: every line's visible runs, and the per-pixel counters of the
/// visible surface when asked for.
fn visible_runs(
    scene: &Scene,
    opts: &RenderOptions,
    view: &View,
    screen: &Screen,
    pools: &crate::pool::Pools,
    counters: &mut Counters,
) -> (FrameRuns, Option<PixelCounters>) {
    let (w, h) = (view.width, view.height);
    let visibility = opts.visibility.prepare(scene, view, screen, pools, counters);
    let runs = crate::visibility::resolve(&*visibility, h, counters);
    let pixel_counters = opts.pixel_counters.then(|| {
        let mut splits = vec![0u16; (w * h) as usize];
        visibility.span_splits(0..h, &mut splits);
        PixelCounters {
            // Every polygon in front of the eye counts, those the hidden-surface stage
            // left out as turned away included.
            depth_complexity: if opts.back_face_cull {
                depth_complexity(&view.screen_polygons(scene), w, h)
            } else {
                depth_complexity(screen, w, h)
            },
            span_splits: splits.into_iter().map(u32::from).collect(),
            shadow_tests: vec![0; (w * h) as usize],
        }
    });
    (runs, pixel_counters)
}

/// What one band of lines took: the shadow stage's counters, the time walking, the time
/// shading.
type BandWork = (Counters, Duration, Duration);

/// The shadow walk and shading of the whole frame, in parallel bands of lines, each band
/// writing its own rows of every buffer.
fn shade_frame(
    ctx: &ShadowContext,
    shadows: &dyn crate::shadow::ShadowStage,
    frame: &mut Frame,
    progress: &Reporter,
) -> Vec<BandWork> {
    // A stage that gives an area light's irradiance vectors lights its diffuse term.
    let probe = shadows.walker();
    let lambert = (0..ctx.scene.lights.len()).map(|l| probe.irradiance(l).then(|| ctx.vector_row(l))).collect();
    drop(probe);
    let shader = Shader::with_irradiance(ctx.scene, ctx.view, &ctx.samples, lambert);
    let w = frame.width;
    let band = crate::scan::band_height(frame.height);
    let chunk = (band * w) as usize;
    let mut light_rows: Vec<_> = frame.light.iter_mut().map(|l| l.chunks_mut(chunk)).collect();
    let mut test_rows = frame.counters.as_mut().map(|c| c.shadow_tests.chunks_mut(chunk));
    let mut jobs: Vec<Band> = frame
        .color
        .chunks_mut(chunk)
        .zip(frame.id.chunks_mut(chunk))
        .enumerate()
        .map(|(b, (color, id))| Band {
            y0: b as u32 * band,
            color,
            id,
            light: light_rows.iter_mut().flat_map(|rows| rows.next()).collect(),
            tests: test_rows.as_mut().and_then(|rows| rows.next()),
        })
        .collect();
    // Neighbouring bands cost alike (a mesh in the middle of the frame makes a few heavy
    // bands in a row), and rayon first hands each thread a run of consecutive tasks: taken
    // in the order 0, T, 2T, ..., 1, T + 1, ... (T threads), each thread's run holds every
    // T-th band. Each band is a task of its own, so a thread that finishes early takes
    // over single bands.
    let threads = rayon::current_num_threads().max(1) as u32;
    jobs.sort_by_key(|j| ((j.y0 / band) % threads, j.y0));
    jobs.into_par_iter()
        .with_max_len(1)
        .map(|job| {
            let lines = job.y0..job.y0 + (job.id.len() / w as usize) as u32;
            let work = shade_band(ctx, shadows, &shader, job);
            progress.advance(lines.len() as u64);
            work
        })
        .collect()
}

/// One band, line by line in order: the shadow stage's walk along the line (with the
/// same-side rule), then the shading of each run from the lit fractions it left.
fn shade_band(ctx: &ShadowContext, shadows: &dyn crate::shadow::ShadowStage, shader: &Shader, job: Band) -> BandWork {
    let Band { y0, color, id, mut light, mut tests } = job;
    let w = ctx.view.width;
    let y1 = y0 + (id.len() / w as usize) as u32;
    let mut shadow = Counters::default();
    let mut walker = shadows.walker();
    // Each sample's lit fraction along the line, sample by sample.
    let mut lit = vec![0.0f32; ctx.lit_rows() * w as usize];
    let mut line_shading = LineShading::default();
    let (mut self_shadowed, mut walking, mut shading) = (0u64, Duration::ZERO, Duration::ZERO);
    // Each sample's light, and the share of its light's lit fraction it holds.
    let samples: Vec<(usize, usize, f32)> =
        ctx.all_samples().map(|(l, s, _)| (l, s, 1.0 / ctx.samples[l].len() as f32)).collect();
    for (y, runs) in (y0..y1).zip(&ctx.runs.lines[y0 as usize..y1 as usize]) {
        let row = ((y - y0) * w) as usize;
        let t = Instant::now();
        walker.start_line(y);
        let mut tests = tests.as_deref_mut().map(|t| &mut t[row..row + w as usize]);
        self_shadowed += walk_line(ctx, walker.as_mut(), y, runs, &mut lit, |_, _, _, asked, walker, _| {
            // The per-pixel counter image: what the stage tested at each pixel.
            if let Some(tests) = tests.as_deref_mut().filter(|_| asked) {
                for (x0, x1, n) in walker.decision().tested {
                    for t in &mut tests[x0 as usize..x1 as usize] {
                        *t += n;
                    }
                }
            }
        });
        let t2 = Instant::now();
        walking += t2 - t;
        // The frame comes in with last frame's pixels: every one is written here, the
        // runs' pixels by the runs and the rest as background.
        let mut gap = row;
        for run in runs {
            let (a, b) = (row + run.x0 as usize, row + run.x1 as usize);
            clear(gap..a, id, &mut light);
            id[a..b].fill(ctx.scene.polygons[run.poly as usize].face);
            for (k, &(l, s, share)) in samples.iter().enumerate() {
                let lit = &lit[k * w as usize + run.x0 as usize..][..b - a];
                if walker.whole_light(l) {
                    // The stage's answer for the whole light is its fraction.
                    if s == 0 {
                        light[l][a..b].copy_from_slice(lit);
                    }
                    continue;
                }
                // A light's first sample writes its lit fraction, the others add to it.
                for (f, &v) in light[l][a..b].iter_mut().zip(lit) {
                    *f = if s == 0 { v * share } else { *f + v * share };
                }
            }
            gap = b;
        }
        clear(gap..row + w as usize, id, &mut light);
        shader.shade_line(&mut line_shading, y, runs, &lit, &mut color[row..row + w as usize]);
        shading += t2.elapsed();
    }
    walker.finish(&mut shadow);
    shadow.add(crate::stats::Counter::SelfShadowedRuns, self_shadowed);
    shadow.add(crate::stats::Counter::DarkRuns, line_shading.dark_runs());
    (shadow, walking, shading)
}

/// Shastry's soft edges on `stage`, ours: every light sample's term walked into a screen
/// buffer of its own (step 1 of [`crate::shadow::soft_edges`]), then blurred.
fn soft_edged(
    ctx: &ShadowContext,
    stage: &dyn crate::shadow::ShadowStage,
    soft: crate::shadow::SoftEdges,
) -> Result<crate::shadow::soft_edges::SoftEdged> {
    soft.check()?;
    let (w, h) = (ctx.view.width as usize, ctx.view.height);
    let samples: usize = ctx.samples.iter().map(Vec::len).sum();
    // The terms and their blurred copies, and one pass's scratch.
    let bytes = crate::budget::mul(crate::budget::mul(samples as u64 + 1, w as u64 * h as u64), 8);
    crate::budget::check(format_args!("soft edges: {samples} screen buffer(s) of {w}x{h}"), bytes)?;
    let terms = shadow_terms(ctx, stage, 0..samples);
    let first = (0..ctx.samples.len()).map(|l| ctx.sample_index(l, 0)).collect();
    Ok(crate::shadow::soft_edges::SoftEdged::new(terms, w, h as usize, first, soft))
}

/// Shastry's soft edges as the article keeps them: one 8-bit screen buffer shared by every
/// light sample. An ambient pass, then per sample: its term walked into the buffer, blurred,
/// and a shading pass lit by it alone, added to the frame (as the article's passes are
/// blended). Returns every pass's band work.
fn shade_shared(
    ctx: &ShadowContext,
    stage: &dyn crate::shadow::ShadowStage,
    soft: crate::shadow::SoftEdges,
    frame: &mut Frame,
    bar: &Reporter,
) -> Result<Vec<BandWork>> {
    use crate::shadow::soft_edges::SoftEdged;
    soft.check()?;
    let (w, h) = (ctx.view.width as usize, ctx.view.height as usize);
    let samples: usize = ctx.samples.iter().map(Vec::len).sum();
    // The ambient frame and the sum of the passes (colour), and one pass's term and blur.
    let bytes = crate::budget::mul(w as u64 * h as u64, 2 * 12 + 4 * 4);
    crate::budget::check(format_args!("soft edges: a shared screen buffer of {w}x{h}"), bytes)?;
    let first: Vec<usize> = (0..ctx.samples.len()).map(|l| ctx.sample_index(l, 0)).collect();
    bar.again("soft edges, shared buffer: the ambient pass");
    let mut bands = shade_frame(ctx, &SoftEdged::shared(None, w, first.clone()), frame, bar);
    let ambient = frame.color.clone();
    let mut color = ambient.clone();
    let mut light = frame.light.clone();
    for k in 0..samples {
        bar.again(format!("soft edges, shared buffer: sample {} of {samples}", k + 1));
        let term = shadow_terms(ctx, stage, k..k + 1).pop().unwrap_or_default();
        let pass = SoftEdged::shared(Some((k, soft.blurred_8bit(&term, w, h))), w, first.clone());
        bands.extend(shade_frame(ctx, &pass, frame, bar));
        color.par_iter_mut().zip(&frame.color).zip(&ambient).for_each(|((sum, &c), &a)| *sum += c - a);
        for (sum, pass) in light.iter_mut().zip(&frame.light) {
            sum.par_iter_mut().zip(pass).for_each(|(s, &v)| *s += v);
        }
    }
    frame.color = color;
    frame.light = light;
    Ok(bands)
}

/// Step 1 of [`crate::shadow::soft_edges`]: the lit fraction of the flat light samples in
/// `keep` at every pixel, one `w×h` buffer each (1 where nothing is seen), walked in
/// parallel bands.
fn shadow_terms(
    ctx: &ShadowContext,
    stage: &dyn crate::shadow::ShadowStage,
    keep: std::ops::Range<usize>,
) -> Vec<Vec<f32>> {
    let (w, h) = (ctx.view.width as usize, ctx.view.height);
    let rows = ctx.lit_rows();
    let band = crate::scan::band_height(h);
    let bands: Vec<Vec<f32>> = (0..h.div_ceil(band))
        .into_par_iter()
        .map(|b| {
            let (y0, y1) = (b * band, ((b + 1) * band).min(h));
            let mut walker = stage.walker();
            let mut lit = vec![0.0f32; rows * w];
            // Sample-major rows of this band: `out[k][(y - y0) * w + x]`, 1 where nothing is seen.
            let per_sample = (y1 - y0) as usize * w;
            let mut out = vec![1.0f32; keep.len() * per_sample];
            for y in y0..y1 {
                walker.start_line(y);
                let runs = &ctx.runs.lines[y as usize];
                walk_line(ctx, walker.as_mut(), y, runs, &mut lit, |_, _, _, _, _, _| {});
                for run in runs {
                    for (i, k) in keep.clone().enumerate() {
                        let (a, b) = (run.x0 as usize, run.x1 as usize);
                        let at = i * per_sample + (y - y0) as usize * w;
                        out[at + a..at + b].copy_from_slice(&lit[k * w + a..k * w + b]);
                    }
                }
            }
            out
        })
        .collect();
    let mut terms = vec![Vec::with_capacity(w * h as usize); keep.len()];
    for (b, out) in bands.iter().enumerate() {
        let rows = (((b as u32 + 1) * band).min(h) - b as u32 * band) as usize;
        for (i, term) in terms.iter_mut().enumerate() {
            term.extend_from_slice(&out[i * rows * w..(i + 1) * rows * w]);
        }
    }
    terms
}

/// Background pixels: no polygon, no light.
fn clear(pixels: std::ops::Range<usize>, id: &mut [u32], light: &mut [&mut [f32]]) {
    id[pixels.clone()].fill(crate::frame::BACKGROUND);
    for l in light {
        l[pixels.clone()].fill(0.0);
    }
}

/// The shadow stage's walk along line `y`: for every run and light sample, the lit fraction
/// of each pixel into `lit[k * width + x]` (`k` the sample's flat index), 0 where the
/// sample is behind the run's seen side (the same-side rule, asked before the stage; it is
/// applied here and nowhere else); for a light the stage answers as a whole with its
/// irradiance vector, the vector's components into the light's rows from
/// `ctx.vector_row(l)` (`lit` holds `ctx.lit_rows()` rows). After each run and sample, `after(run, light, sample,
/// asked, walker, lit)` sees what was decided (`asked`: whether the stage was). Returns the
/// runs the same-side rule settled.
pub(crate) fn walk_line(
    ctx: &ShadowContext,
    walker: &mut dyn crate::shadow::ShadowWalker,
    y: u32,
    runs: &[crate::visibility::Run],
    lit: &mut [f32],
    mut after: impl FnMut(&crate::visibility::Run, usize, usize, bool, &dyn crate::shadow::ShadowWalker, &[f32]),
) -> u64 {
    let width = ctx.view.width as usize;
    let mut self_shadowed = 0;
    for run in runs {
        let plane = &ctx.scene.polygons[run.poly as usize].plane;
        for (k, (l, s, sample)) in ctx.all_samples().enumerate() {
            let row = k * width + run.x0 as usize..k * width + run.x1 as usize;
            if walker.whole_light(l) {
                // The stage answers for the whole light: sample 0's row holds the answer,
                // copied to the others'.
                if s == 0 {
                    walker.lit(l, 0, y, run, &mut lit[row.clone()]);
                    if walker.irradiance(l) {
                        let at = ctx.vector_row(l) * width;
                        let (x, rest) = lit[at..].split_at_mut(width);
                        let (y, z) = rest.split_at_mut(width);
                        let span = run.x0 as usize..run.x1 as usize;
                        walker.light_vector(l, [&mut x[span.clone()], &mut y[span.clone()], &mut z[span]]);
                    }
                    after(run, l, 0, true, walker, &lit[row]);
                } else {
                    lit.copy_within(row.start - s * width..row.end - s * width, row.start);
                }
                continue;
            }
            let out = &mut lit[row];
            let asked = sample.on_seen_side(plane, ctx.view.eye);
            if asked {
                walker.lit(l, s, y, run, out);
            } else {
                out.fill(0.0);
                self_shadowed += 1;
            }
            after(run, l, s, asked, walker, out);
        }
    }
    self_shadowed
}

/// Every input is finite in single precision, but products of large ones can overflow: a
/// channel that overflowed to infinity, or to NaN (infinity times zero, or less infinity),
/// is set to the largest finite value, so no NaN or infinity ever reaches a pixel (it
/// encodes as full brightness, as an overflow should).
fn saturate(color: &mut [Vec3]) {
    for c in color {
        if !c.is_finite() {
            *c = crate::shading::finite(*c);
        }
    }
}
