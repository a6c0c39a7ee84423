//! The `umbra` command line: a thin layer over the library.

mod progress;
mod serve;

use clap::{Parser, Subcommand, ValueEnum};
use progress::TerminalBar;
use std::alloc::{GlobalAlloc, Layout};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicIsize, Ordering::Relaxed};
use std::sync::Arc;
use umbra::shadow::Counting;
use umbra::shadow::{
    AthertonWeilerGreenbergOptions, BouknightKelleyOptions, Construction, NishitaNakamaeOptions, ShadowFilter,
    StageSettings, VolumeOptions, WilliamsOptions,
};
use umbra::study::compare::{compare, CompareOptions};
use umbra::study::scale::{scale, ScaleOptions, Sweep};
use umbra::ReflectionMethod;
use umbra::{generate, Error, RenderOptions, Renderer, Scene, ShadowMethod, VisibilityMethod};

/// Frame-sized buffers are allocated and freed every frame; glibc's allocator returns them
/// to the system each time and the next frame faults their pages in again (about a fifth of
/// an s3 frame). mimalloc keeps them, once told not to purge them ([`keep_freed_memory`]).
#[global_allocator]
static ALLOCATOR: Counted = Counted(mimalloc::MiMalloc);

/// mimalloc, with the bytes in use and their peak counted, so that `bench` can give each
/// row its own peak memory ([`umbra::study::bench::HeapProbe`]): the resident high-water
/// mark only rises, and mimalloc keeps what it frees ([`keep_freed_memory`]). It counts only
/// while `bench` asks ([`count_heap`]), for one untimed frame a row: counting every
/// allocation in shared atomics makes threads fight over them (Atherton-Weiler-Greenberg
/// on s4 ran no faster at two threads than at one), so the timed frames must not pay it.
struct Counted(mimalloc::MiMalloc);

/// Whether allocations are being counted.
static COUNTING: AtomicBool = AtomicBool::new(false);
/// Bytes allocated and not yet freed since counting started (a free of older memory can
/// take it below zero).
static IN_USE: AtomicIsize = AtomicIsize::new(0);
/// The most bytes in use since counting started.
static PEAK: AtomicIsize = AtomicIsize::new(0);

/// `bytes` allocated (positive) or freed (negative).
fn moved(bytes: isize) {
    if COUNTING.load(Relaxed) {
        let now = IN_USE.fetch_add(bytes, Relaxed) + bytes;
        PEAK.fetch_max(now, Relaxed);
    }
}

fn grew(bytes: usize) {
    moved(bytes as isize);
}

/// Starts counting from zero (`true`), or stops (`false`).
fn count_heap(on: bool) {
    if on {
        IN_USE.store(0, Relaxed);
        PEAK.store(0, Relaxed);
    }
    COUNTING.store(on, Relaxed);
}

fn peak_bytes() -> u64 {
    PEAK.load(Relaxed).max(0) as u64
}

// SAFETY: every call is passed on to mimalloc unchanged; only counters are updated beside.
unsafe impl GlobalAlloc for Counted {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as the caller promised for `layout`.
        let p = unsafe { self.0.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as the caller promised for `layout`.
        let p = unsafe { self.0.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from this allocator with `layout`, as the caller promised.
        unsafe { self.0.dealloc(ptr, layout) };
        moved(-(layout.size() as isize));
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as the caller promised for `ptr`, `layout` and `new_size`.
        let p = unsafe { self.0.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            moved(new_size as isize - layout.size() as isize);
        }
        p
    }
}

/// Tells mimalloc never to give freed memory back to the system. By default it does so 10 ms
/// after a free, and a shadow stage that builds many short-lived lists (Bouknight-Kelley's
/// candidates on s3: 271,000 page faults over six frames) then faults its pages in again,
/// zeroed, every frame. The cost is a higher peak: the process keeps what it once used.
fn keep_freed_memory() {
    /// `mi_option_purge_delay` in mimalloc's `mi_option_e` (v2 and v3 alike).
    const PURGE_DELAY: libmimalloc_sys::mi_option_t = 15;
    // SAFETY: `mi_option_set` only stores the value in mimalloc's option table; it may be
    // called at any time, and -1 ("never purge") is a documented value of this option.
    unsafe { libmimalloc_sys::mi_option_set(PURGE_DELAY, -1) };
}

#[derive(Parser)]
#[command(
    name = "umbra",
    version,
    about = "Classic scanline hidden-surface and shadow algorithms, reproduced and measured"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to a PNG.
    Render(RenderArgs),
    /// Render a scene with every visibility × shadow combination, measure each against the
    /// ray-cast reference, and write report.html, results.json and results.csv.
    Compare(CompareArgs),
    /// Time each method on one scene: warm-up frames, then timed frames in one process; the
    /// median, least and greatest of the frame and of every phase, and the peak memory.
    Bench(BenchArgs),
    /// Sweep a generated scene family over a parameter and plot time and a counter.
    Scale(ScaleArgs),
    /// Show what Watkins' algorithm and a shadow stage did on one scanline.
    Trace(TraceArgs),
    /// Watch the algorithms work: a page in the browser, served on 127.0.0.1, that draws what
    /// `trace` prints for any line and stage, with the frame, its counters and the pixels
    /// where a stage differs from ray-cast.
    Explore(ExploreArgs),
    /// Write a generated benchmark scene (scene file plus OBJ meshes).
    Generate(GenerateArgs),
    /// Build the Atherton-Weiler-Greenberg shadow database of a light (its lit detail
    /// polygons, independent of the camera) and write it as an OBJ file.
    ExportShadows(ExportArgs),
}

/// Options of the shadow stages, shared by every command that renders.
/// Atherton-Weiler-Greenberg's switches, each putting the paper's way back (for `render`,
/// `bench` and the like, and for `export-shadows`).
#[derive(clap::Args)]
struct AwgFlags {
    /// Atherton-Weiler-Greenberg: clip every pair of pieces in the light view with Weiler
    /// and Atherton's clipper, as the paper does, instead of splitting convex pieces by each
    /// other's edges (to measure what splitting saves).
    #[arg(long)]
    no_convex_split: bool,
    /// Atherton-Weiler-Greenberg: sort the polygons that lie behind everything they overlap
    /// in the light view (a floor) with the rest, as the paper does, instead of lighting them
    /// with the visible pieces over them cut out as holes.
    #[arg(long)]
    no_backgrounds: bool,
    /// Atherton-Weiler-Greenberg: sort the polygons that nothing else in the light view
    /// meets with the rest, as the paper does, instead of finding them sheet by sheet and
    /// lighting them whole.
    #[arg(long)]
    no_lone_sheets: bool,
    /// Atherton-Weiler-Greenberg: take each polygon of a closed solid through the lone-sheet
    /// step alone, instead of settling the solid's whole side facing the light at once where
    /// it lies in one light view.
    #[arg(long)]
    no_whole_solids: bool,
    /// Atherton-Weiler-Greenberg: sort each light view whole, as the paper does, instead of
    /// cutting it into regions of at most 1,024 casters sorted apart.
    #[arg(long)]
    no_tiling: bool,
    /// Atherton-Weiler-Greenberg: map every polygon into all six views of the cube around a
    /// point light, instead of a polygon wholly inside one face into that face alone.
    #[arg(long)]
    no_face_binning: bool,
    /// Atherton-Weiler-Greenberg: hand each front polygon every piece still in the sort, as
    /// the paper's clipper takes the whole list, instead of those a grid finds near it.
    #[arg(long)]
    no_sort_grid: bool,
}

impl AwgFlags {
    /// Atherton-Weiler-Greenberg's settings from these flags and `--no-solid-cull`.
    fn options(&self, solid_cull: bool) -> AthertonWeilerGreenbergOptions {
        AthertonWeilerGreenbergOptions {
            convex_split: !self.no_convex_split,
            backgrounds: !self.no_backgrounds,
            lone_sheets: !self.no_lone_sheets,
            whole_solids: !self.no_whole_solids,
            solid_cull,
            tiling: !self.no_tiling,
            face_binning: !self.no_face_binning,
            sort_grid: !self.no_sort_grid,
        }
    }
}

#[derive(clap::Args)]
struct ShadowArgs {
    /// Run Bouknight-Kelley, Atherton-Weiler-Greenberg, Crow and stencil-volume as their
    /// papers publish them, every step of ours off (`ShadowMethod::as_published`; each step
    /// and its switch are in docs/algorithms/). Crow's 1977 construction is exact only where
    /// its preconditions hold.
    #[arg(long)]
    paper: bool,
    /// Bouknight-Kelley: project every pair, without the sphere prefilter (to measure it).
    #[arg(long)]
    no_prefilter: bool,
    /// Bouknight-Kelley: compare the sphere extents of every ordered pair, as the paper does,
    /// instead of finding the overlapping ones in a grid (ours).
    #[arg(long)]
    no_sphere_grid: bool,
    /// Bouknight-Kelley: make every polygon the light faces a receiver, as the paper does,
    /// not only those seen at some pixel (ours).
    #[arg(long)]
    all_receivers: bool,
    /// Bouknight-Kelley: project casters wholly behind the receiver and find the projection
    /// empty, as the paper does, instead of dropping them first (ours).
    #[arg(long)]
    no_drop_behind: bool,
    /// Bouknight-Kelley: project casters outside a triangle receiver's wedge from the light,
    /// as the paper does, instead of dropping them first (ours).
    #[arg(long)]
    no_wedge: bool,
    /// Bouknight-Kelley: project casters whose plane's slab lies apart from the hull of the
    /// light and the receiver, as the paper does, instead of dropping them first (ours).
    #[arg(long)]
    no_slab: bool,
    /// Bouknight-Kelley: project each polygon of a closed solid onto a receiver under it,
    /// as the paper does, instead of counting the solid's shadow polygons as the outline of
    /// their union (ours).
    #[arg(long)]
    no_solid_outlines: bool,
    /// Bouknight-Kelley: gather each caster on a receiver's own closed solid and find it
    /// behind the receiver, instead of taking only the solid's front set of that receiver
    /// (ours).
    #[arg(long)]
    no_own_solid: bool,
    /// Bouknight-Kelley, Atherton-Weiler-Greenberg and Nishita-Nakamae: keep the polygons of
    /// closed solids that face away from the light (as casters; in AWG's light views), as the
    /// papers do (to measure what dropping them saves).
    #[arg(long)]
    no_solid_cull: bool,
    /// Nishita-Nakamae: take every polygon as a possible occluder of every receiver, as the
    /// papers do, instead of those within the hull of the receiver and the light (ours).
    #[arg(long)]
    no_hull_cull: bool,
    /// Nishita-Nakamae: each polygon of a convex solid hides on its own at a penumbra pixel,
    /// instead of the solid as one hull (ours).
    #[arg(long)]
    no_convex_bodies: bool,
    /// Nishita-Nakamae: take the polygons of a receiver's own convex solid as casters too
    /// (ours leaves them out: none can come between it and the light).
    #[arg(long)]
    no_same_solid: bool,
    /// Nishita-Nakamae: shade an area light's diffuse term from the grid's samples, each
    /// weighted by the exact fraction, as the sampling stages do, instead of from the
    /// irradiance of the part of the light a pixel sees (Lambert's contour formula).
    #[arg(long)]
    no_lambert: bool,
    /// Nishita-Nakamae: leave out a caster for which the papers' premise fails (it reaches
    /// as near the light as its nearest corner, or the light is cut by the receiver's plane),
    /// as the papers assume it never arises, instead of taking it at every pixel (ours; off,
    /// the stage is not exact).
    #[arg(long)]
    no_premise_fallback: bool,
    #[command(flatten)]
    awg: AwgFlags,
    /// Crow and stencil-volume: count shadow volumes from the eye with the eye's own count
    /// (zpass), from infinity (zfail), or from zero at the eye (naive-zpass, wrong when the
    /// eye is in shadow).
    #[arg(long, default_value = "zpass", value_parser = parse::<Counting>)]
    crow_count: Counting,
    /// Crow and stencil-volume: how the volumes are built: merged (Bergeron 1986, the sides
    /// neighbouring polygons share merged; the default), per-polygon (every polygon its own
    /// volume, to measure what merging saves), or crow-1977 (Crow's one volume per object on
    /// its contour edges, with one starting count for the image; the paper's, wrong where
    /// its preconditions fail).
    #[arg(long, default_value = "merged", value_parser = parse::<Construction>)]
    volumes: Construction,
    /// Crow and stencil-volume: give every polygon its own volume (`--volumes per-polygon`).
    #[arg(long)]
    no_silhouettes: bool,
    /// Crow and stencil-volume: extrude the volumes to infinity uncut, as the papers do;
    /// z-fail's are then clipped by the camera's far plane where the scene has one (ours:
    /// cut to where a count reaches, z-fail closed beyond the scene).
    #[arg(long)]
    no_sight_cuts: bool,
    /// Crow and stencil-volume with z-fail: count each far cap as a shadow polygon of its
    /// own (ours: the far caps counted as the outline of their union).
    #[arg(long)]
    no_far_outline: bool,
    /// Crow and stencil-volume with z-fail: count each front cap as a shadow polygon with
    /// its depth (ours: the front caps counted with the far caps, as the outline of their
    /// union).
    #[arg(long)]
    no_front_outline: bool,
    /// Williams: texels along each side of a shadow map.
    #[arg(long, default_value_t = 2048)]
    map_size: u32,
    /// Williams: constant depth bias in world units (default: one texel of depth at each
    /// point, which follows the map's resolution).
    #[arg(long)]
    bias: Option<f64>,
    /// Williams: slope-scaled bias, times the receiver's own depth change over the texels a
    /// lookup reaches in the map (the factor of glPolygonOffset; 0, the default, is off:
    /// the normal offset does its work without detaching shadows at grazing angles).
    #[arg(long, default_value_t = 0.0)]
    slope_bias: f64,
    /// Williams: move each lookup along the receiver's normal by this many texels of the map
    /// (normal-offset shadows; 0 is off).
    #[arg(long, default_value_t = 1.0)]
    normal_offset: f64,
    /// Williams: receiver-plane depth bias: compare each PCF texel with the receiver's plane
    /// extrapolated to it.
    #[arg(long)]
    receiver_plane: bool,
    /// Williams: nearest (one texel; the default), pcf (percentage-closer filtering over a
    /// regular box of --pcf-size² texels; the default when --pcf-size is given), stochastic
    /// (Reeves, Salesin & Cook's: --pcf-size² jittered samples over the box), or soft-edge
    /// (Shastry's "Soft-Edged Shadows": PCF into a screen buffer, then a 15-tap Gaussian blur).
    #[arg(long, value_enum)]
    shadow_filter: Option<FilterArg>,
    /// Williams: the PCF kernel's side in texels (odd; 3, Shastry's kernel, when not given).
    #[arg(long)]
    pcf_size: Option<u32>,
    /// Williams: leave polygons facing the light out of the depth map (the "Special Effect" notes).
    #[arg(long)]
    cull_front: bool,
    /// Williams: fit each map to the whole scene, not to the points the camera sees.
    #[arg(long)]
    no_fit: bool,
    /// Planar: project shadows onto this object too (its name, or its index in the file;
    /// repeat for several), or `auto`: every flat object at least a tenth the area of the
    /// largest (the ground, the walls). Objects marked `receiver = true` in the file stay.
    #[arg(long, value_name = "NAME|auto")]
    receiver: Vec<String>,
}

impl ShadowArgs {
    /// Loads the scene and marks the receivers asked for with `--receiver`.
    fn load(&self, path: &std::path::Path) -> umbra::Result<Scene> {
        let mut scene = with_spinner(format!("loading {}", path.display()), || Scene::load(path))?;
        for name in &self.receiver {
            if name == "auto" {
                if scene.mark_planar_receivers().is_empty() {
                    return Err(Error::InvalidOption(format!(
                        "{}: --receiver auto found no flat object",
                        path.display()
                    )));
                }
                continue;
            }
            let object = scene.object_named(name).or_else(|| name.parse().ok()).ok_or_else(|| {
                Error::InvalidOption(format!("{}: --receiver {name}: no object of that name", path.display()))
            })?;
            scene.set_receiver(object, true).map_err(|e| Error::InvalidOption(format!("--receiver {name}: {e}")))?;
        }
        Ok(scene)
    }

    /// `method` with the settings these flags give it (each flag sets its own method's), as
    /// published with `--paper`.
    fn configure(&self, method: ShadowMethod) -> ShadowMethod {
        let method = self.engineered(method);
        if self.paper {
            method.as_published()
        } else {
            method
        }
    }

    /// `method` with the settings these flags give it, `--paper` aside.
    fn engineered(&self, method: ShadowMethod) -> ShadowMethod {
        let kernel = self.pcf_size.unwrap_or(3);
        let named =
            self.shadow_filter.unwrap_or(if self.pcf_size.is_some() { FilterArg::Pcf } else { FilterArg::Nearest });
        let filter = match named {
            FilterArg::Nearest => ShadowFilter::Nearest,
            FilterArg::Pcf => ShadowFilter::Pcf(kernel),
            FilterArg::Stochastic => ShadowFilter::Stochastic(kernel),
            FilterArg::SoftEdge => ShadowFilter::SoftEdge(kernel),
        };
        let construction = if self.no_silhouettes { Construction::PerPolygon } else { self.volumes };
        let settings = StageSettings {
            bouknight_kelley: BouknightKelleyOptions {
                prefilter: !self.no_prefilter,
                sphere_grid: !self.no_sphere_grid,
                seen_receivers: !self.all_receivers,
                drop_behind: !self.no_drop_behind,
                wedge: !self.no_wedge,
                slab: !self.no_slab,
                solid_cull: !self.no_solid_cull,
                solid_outlines: !self.no_solid_outlines,
                own_solid: !self.no_own_solid,
            },
            atherton_weiler_greenberg: self.awg.options(!self.no_solid_cull),
            volumes: VolumeOptions {
                counting: self.crow_count,
                construction,
                sight_cuts: !self.no_sight_cuts,
                far_outline: !self.no_far_outline,
                front_outline: !self.no_front_outline,
            },
            williams: WilliamsOptions {
                map_size: self.map_size,
                bias: self.bias,
                slope_bias: self.slope_bias,
                normal_offset: self.normal_offset,
                receiver_plane: self.receiver_plane,
                filter,
                cull_front: self.cull_front,
                fit_to_view: !self.no_fit,
            },
            nishita_nakamae: NishitaNakamaeOptions {
                hull_cull: !self.no_hull_cull,
                solid_cull: !self.no_solid_cull,
                convex_bodies: !self.no_convex_bodies,
                same_solid: !self.no_same_solid,
                premise_fallback: !self.no_premise_fallback,
                lambert: !self.no_lambert,
            },
        };
        method.with_settings(&settings)
    }

    /// Every method of `methods` configured by these flags; with `--paper`, each stage that
    /// has a paper path twice, engineered and then as published, for the commands that
    /// measure methods side by side.
    fn configure_beside(&self, methods: Vec<ShadowMethod>) -> Vec<ShadowMethod> {
        let mut out = Vec::new();
        for m in methods.into_iter().map(|m| self.engineered(m)) {
            let paper = (self.paper && m.has_paper_path()).then(|| m.as_published());
            out.push(m);
            out.extend(paper);
        }
        out
    }
}

#[derive(clap::Args)]
struct RenderArgs {
    /// The scene file (TOML, see docs/scene-format.md).
    scene: PathBuf,
    /// Where to write the image (PNG).
    #[arg(short, long, default_value = "out.png")]
    output: PathBuf,
    /// Hidden-surface stage: scanline (Watkins), zbuffer, or ray-cast (one ray per pixel).
    #[arg(long, default_value = "scanline", value_parser = parse::<VisibilityMethod>)]
    visibility: VisibilityMethod,
    /// Shadow stage. Exact: bouknight-kelley (projected shadow polygons),
    /// atherton-weiler-greenberg (hidden-surface removal from the light), crow (shadow volumes
    /// counted per span), stencil-volume (the same volumes counted per pixel), ray-cast
    /// (per-pixel reference). Approximate: williams (shadow maps), planar (Blinn's projection
    /// onto receiver planes). Or none. The default is the recommended exact method.
    #[arg(long, default_value = ShadowMethod::DEFAULT.name(), value_parser = parse::<ShadowMethod>)]
    shadows: ShadowMethod,
    /// Keep closed solids' polygons that turn their backs to the eye in the hidden-surface
    /// stage (by default they are left out: they are never seen).
    #[arg(long)]
    no_back_face_cull: bool,
    #[command(flatten)]
    shadow: ShadowArgs,
    /// Write the analysis buffers `id.png` and `light<k>.png` into this folder, with per-pixel
    /// counters in false colour: depth_complexity.png, span_splits.png, shadow_tests.png.
    #[arg(long, value_name = "DIR")]
    aov: Option<PathBuf>,
    /// Print the counters and times as one JSON object on standard output, with the
    /// process's peak resident memory (`peak_rss_mb`, MB of 2^20 bytes); for williams, with
    /// `map_errors`: its wrong interior pixels by cause, against ray-cast (two more renders).
    #[arg(long)]
    stats: bool,
    /// Encode the image with this display gamma (0.1 to 10, for example 2.2); default:
    /// linear values.
    #[arg(long, value_parser = parse_gamma)]
    gamma: Option<f32>,
    /// Draw the shadow stage's own polygons for the first light sample over the image
    /// (shadow polygons, lit detail polygons, shadow-volume polygons).
    #[arg(long, value_enum)]
    debug: Option<Debug>,
    /// Planar mirrors (materials with mirror > 0): reflect the scene and lights (scene,
    /// the "Special Effect" notes' method 2), reflect the eye (eye, method 1), or render mirrors plainly (off).
    #[arg(long, default_value = "scene", value_parser = parse::<ReflectionMethod>)]
    reflection: ReflectionMethod,
    /// Shastry's soft edges on any shadow stage (crow: the article's soft edges on shadow
    /// volumes): each light sample's lit fractions in a screen buffer, blurred by the
    /// article's 15-tap Gaussian or by a 16-tap Poisson disk.
    #[arg(long, value_name = "BLUR", value_parser = parse::<umbra::shadow::Blur>)]
    soft_edges: Option<umbra::shadow::Blur>,
    /// With --soft-edges: the blur's taps this many pixels apart (the article's 1; wider
    /// spacing, wider blur), from 0.25 to 64.
    #[arg(long, default_value_t = 1.0, requires = "soft_edges")]
    tap_spacing: f64,
    /// With --soft-edges: one f32 screen buffer per light sample, all lights shaded in one
    /// pass (per-sample, ours), or the article's one 8-bit buffer shared by every sample, a
    /// shading pass per sample added to the frame (shared; the default with --paper).
    #[arg(long, value_name = "BUFFERS", value_parser = parse::<umbra::shadow::Buffers>, requires = "soft_edges")]
    soft_edge_buffers: Option<umbra::shadow::Buffers>,
}

#[derive(clap::Args)]
struct CompareArgs {
    /// The scene file.
    scene: PathBuf,
    /// Comma-separated visibility stages (default: all).
    #[arg(long, value_delimiter = ',', value_parser = parse::<VisibilityMethod>)]
    visibility: Vec<VisibilityMethod>,
    /// Comma-separated shadow stages (default: all).
    #[arg(long, value_delimiter = ',', value_parser = parse::<ShadowMethod>)]
    shadows: Vec<ShadowMethod>,
    /// Output folder.
    #[arg(long, default_value = "compare")]
    out: PathBuf,
    /// Untimed renders per method first (page faults, caches).
    #[arg(long, default_value_t = 1)]
    warmup: usize,
    /// Timed runs per method; the median, least and greatest are reported.
    #[arg(long, default_value_t = 3)]
    runs: usize,
    #[command(flatten)]
    shadow: ShadowArgs,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// The scene file.
    scene: PathBuf,
    /// Comma-separated visibility stages (one row per visibility × shadow pair).
    #[arg(long, value_delimiter = ',', value_parser = parse::<VisibilityMethod>, default_value = "scanline")]
    visibility: Vec<VisibilityMethod>,
    /// Comma-separated shadow stages.
    #[arg(long, value_delimiter = ',', value_parser = parse::<ShadowMethod>, default_value = ShadowMethod::DEFAULT.name())]
    shadows: Vec<ShadowMethod>,
    /// Timed frames per method.
    #[arg(long, default_value_t = 7)]
    runs: usize,
    /// Untimed frames first, per method.
    #[arg(long, default_value_t = 2)]
    warmup: usize,
    /// Threads to render with (default: one per core). Several, comma-separated (`1,2`):
    /// each method renders a frame at each count in turn, one row per count, and the rows
    /// after the first count's give their speed-up over it.
    #[arg(long, value_delimiter = ',')]
    threads: Vec<usize>,
    /// One JSON object per row instead of a table.
    #[arg(long)]
    json: bool,
    /// Keep closed solids' polygons that turn their backs to the eye in the hidden-surface
    /// stage (by default they are left out: they are never seen).
    #[arg(long)]
    no_back_face_cull: bool,
    /// On a shared machine: before each row, wait until other processes leave the cores
    /// idle and all cores run a fixed loop at once as fast as one alone; time a row again
    /// (up to three tries) when others took a quarter of a core or more while it ran, or the
    /// cores ran 15% slower together than alone right after it. Every row reports the cores
    /// others used either way.
    #[arg(long)]
    undisturbed: bool,
    #[command(flatten)]
    shadow: ShadowArgs,
}

#[derive(clap::Args)]
struct ScaleArgs {
    /// What to sweep: cubes (N per side), quads (depth complexity), spheres (triangles),
    /// scattered / clustered (triangle count), size (triangle size), resolution (width),
    /// samples (N×N grid of a square light over the cubes; each point's error against the
    /// exact fraction is measured too).
    #[arg(long, value_parser = parse::<Sweep>)]
    sweep: Sweep,
    /// Comma-separated values of the parameter.
    #[arg(long, value_delimiter = ',', required = true)]
    values: Vec<f64>,
    /// Comma-separated methods as visibility:shadows (default: scanline:none,zbuffer:none).
    #[arg(long, value_delimiter = ',', value_parser = parse_method)]
    methods: Vec<(VisibilityMethod, ShadowMethod)>,
    /// Counter to plot besides time: visibility.NAME or shadow.NAME.
    #[arg(long, default_value = "visibility.depth_tests")]
    counter: String,
    /// Output folder.
    #[arg(long, default_value = "scale")]
    out: PathBuf,
    /// Timed runs per point; the median is reported.
    #[arg(long, default_value_t = 3)]
    runs: usize,
    /// Image width.
    #[arg(long, default_value_t = 1920)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 1080)]
    height: u32,
    /// Spheres (spheres sweep) or triangles (size sweep).
    #[arg(long, default_value_t = 100)]
    count: u32,
    /// Triangle size (scattered and clustered sweeps).
    #[arg(long, default_value_t = 0.3)]
    size: f64,
    #[command(flatten)]
    shadow: ShadowArgs,
}

#[derive(clap::Args)]
struct TraceArgs {
    /// The scene file.
    scene: PathBuf,
    /// The scanline (0 at the top).
    #[arg(long)]
    line: u32,
    /// Only the spans, runs and decisions covering this pixel.
    #[arg(long)]
    x: Option<u32>,
    /// Shadow stage whose decisions to show.
    #[arg(long, default_value = ShadowMethod::DEFAULT.name(), value_parser = parse::<ShadowMethod>)]
    shadows: ShadowMethod,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    shadow: ShadowArgs,
}
#[derive(clap::Args)]
struct ExploreArgs {
    /// The scene file.
    scene: PathBuf,
    /// The port on 127.0.0.1 (0: any free port; the address is printed).
    #[arg(long, default_value_t = 8470)]
    port: u16,
    /// Open the page in the default browser.
    #[arg(long)]
    open: bool,
    /// Instead of serving, write the page with every line of every stage precomputed into
    /// this folder (open its index.html from disk or put it on any static host).
    #[arg(long)]
    export: Option<PathBuf>,
    /// The exported page's image size, WIDTHxHEIGHT (at most 640x480: every line of every
    /// stage is stored).
    #[arg(long, default_value = "160x120", value_parser = parse_size)]
    size: (u32, u32),
    /// Write into an --export folder that has files already.
    #[arg(long)]
    force: bool,
    /// Start the page with the stages as their papers publish them (the page's "as
    /// published" box; the live page only).
    #[arg(long)]
    paper: bool,
}
fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("'{s}' is not WIDTHxHEIGHT with each from 1 to 640 and 480");
    let (w, h) = s.split_once('x').ok_or_else(bad)?;
    match (w.parse::<u32>(), h.parse::<u32>()) {
        (Ok(w @ 1..=640), Ok(h @ 1..=480)) => Ok((w, h)),
        _ => Err(bad()),
    }
}
fn explore(a: ExploreArgs) -> umbra::Result<()> {
    use serve::serve;
    use umbra::study::explore::{export, Explorer};
    let scene = Scene::load(&a.scene)?;
    let name = a.scene.file_name().map_or_else(|| a.scene.display().to_string(), |n| n.to_string_lossy().into_owned());
    let explorer = Explorer::new(scene, name).with_paper(a.paper);
    if let Some(dir) = &a.export {
        let used = std::fs::read_dir(dir).map(|mut d| d.next().is_some()).unwrap_or(false);
        if used && !a.force {
            return Err(Error::InvalidOption(format!("{}: has files; pass --force to write into it", dir.display())));
        }
        export(&explorer, dir, a.size.0, a.size.1, &ShadowMethod::ALL)?;
        return say(&format!("wrote {}: open it in a browser", dir.join("index.html").display()));
    }
    serve(explorer, a.port, |address| {
        let _ = say(&format!("umbra explore: {address} (Ctrl-C stops)"));
        if a.open {
            open_browser(address);
        }
    })
}

/// Asks the desktop to open `address`; says so when it cannot.
fn open_browser(address: &str) {
    let opener = if cfg!(target_os = "macos") { "open" } else { "xdg-open" };
    if std::process::Command::new(opener).arg(address).spawn().is_err() {
        let _ = say(&format!("could not run {opener}; open {address} yourself"));
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum FilterArg {
    /// One texel.
    Nearest,
    /// Percentage-closer filtering over a regular box of texels.
    Pcf,
    /// Reeves, Salesin & Cook's percentage-closer filtering: jittered samples over the box.
    Stochastic,
    /// PCF, then Shastry's screen-space blur.
    SoftEdge,
}

#[derive(Clone, Copy, ValueEnum)]
enum Debug {
    /// The polygons the shadow stage walks, tinted and outlined.
    ShadowPolygons,
}

#[derive(Clone, Copy, ValueEnum)]
enum Family {
    /// A floor with an N×N grid of cubes.
    Cubes,
    /// D quads stacked toward the camera (depth complexity D).
    Quads,
    /// Tessellated spheres on a floor.
    Spheres,
}

#[derive(clap::Args)]
struct GenerateArgs {
    /// Scene family.
    family: Family,
    /// Where to write the scene file; meshes go to meshes/ beside it.
    #[arg(short, long)]
    output: PathBuf,
    /// Overwrite files that exist.
    #[arg(long)]
    force: bool,
    /// Cubes per side (cubes).
    #[arg(long, default_value_t = 10)]
    n: u32,
    /// Cubes as 6 quads each instead of 12 triangles (cubes).
    #[arg(long)]
    quads: bool,
    /// Depth complexity (quads).
    #[arg(long, default_value_t = 16)]
    depth: u32,
    /// Triangles in all (spheres): each sphere is the UV sphere nearest `triangles / count`
    /// (4s² − 4s triangles for s stacks); the count written is printed.
    #[arg(long, default_value_t = 10_000)]
    triangles: u32,
    /// Number of spheres (spheres).
    #[arg(long, default_value_t = 1)]
    count: u32,
    /// Image width.
    #[arg(long, default_value_t = 1920)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 1080)]
    height: u32,
}

#[derive(clap::Args)]
struct ExportArgs {
    /// The scene file.
    scene: PathBuf,
    /// Where to write the OBJ file.
    #[arg(short, long)]
    output: PathBuf,
    /// Which light (0-based, in file order).
    #[arg(long, default_value_t = 0)]
    light: usize,
    /// Overwrite the OBJ file if it exists.
    #[arg(long)]
    force: bool,
    /// Keep the polygons of closed solids that face away from the light in the light views,
    /// as the paper does.
    #[arg(long)]
    no_solid_cull: bool,
    #[command(flatten)]
    awg: AwgFlags,
}

fn parse<T: std::str::FromStr<Err = Error>>(s: &str) -> Result<T, String> {
    s.parse().map_err(|e: Error| e.to_string())
}

fn parse_method(s: &str) -> Result<(VisibilityMethod, ShadowMethod), String> {
    let (v, sh) = s.split_once(':').ok_or_else(|| format!("'{s}' is not visibility:shadows"))?;
    Ok((parse(v)?, parse(sh)?))
}

fn scene_name(path: &std::path::Path) -> String {
    path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned())
}

fn run(cli: Cli) -> umbra::Result<()> {
    match cli.command {
        Command::Render(a) => render_command(a),
        Command::Compare(a) => compare_command(a),
        Command::Bench(a) => bench_command(a),
        Command::Scale(a) => scale_command(a),
        Command::Trace(a) => trace_command(a),
        Command::Explore(a) => explore(a),
        Command::ExportShadows(e) => export_shadows_command(e),
        Command::Generate(g) => generate_command(g),
    }
}

/// `umbra render`: one frame, its analysis buffers and its stats.
fn render_command(a: RenderArgs) -> umbra::Result<()> {
    check_png_name(&a.output)?;
    if a.debug.is_some() && !a.shadows.has_outlines() {
        let drawn: Vec<&str> = ShadowMethod::ALL.iter().filter(|m| m.has_outlines()).map(|m| m.name()).collect();
        return Err(Error::InvalidOption(format!(
            "--debug shadow-polygons draws the polygons of {}; {} has none to draw",
            drawn.join(", "),
            a.shadows
        )));
    }
    let scene = a.shadow.load(&a.scene)?;
    let opts = RenderOptions {
        visibility: a.visibility,
        shadows: a.shadow.configure(a.shadows.clone()),
        pixel_counters: a.aov.is_some(),
        reflection: a.reflection,
        outlines: a.debug.is_some(),
        back_face_cull: !a.no_back_face_cull,
        soft_edges: a.soft_edges.map(|blur| umbra::shadow::SoftEdges {
            blur,
            spacing: a.tap_spacing,
            buffers: a.soft_edge_buffers.unwrap_or(if a.shadow.paper {
                umbra::shadow::Buffers::Shared
            } else {
                umbra::shadow::Buffers::PerSample
            }),
        }),
    };
    let bar = Arc::new(TerminalBar::new("{msg:40} {bar:30} {pos}/{len} lines {elapsed}"));
    let shown = bar.clone();
    let mut renderer = Renderer::new().with_progress(move |p| shown.report(p));
    let rendered = renderer.render(&scene, &opts).map(|_| ());
    bar.finish();
    rendered?;
    let outlines = renderer.outlines().to_vec();
    let out = renderer.into_rendered().ok_or_else(|| Error::Internal("the renderer kept no frame".into()))?;
    let mut img = out.frame.color_image(a.gamma);
    if a.debug.is_some() {
        umbra::Frame::draw_outlines(&mut img, &outlines, [255, 40, 200]);
    }
    write_png(img, &a.output)?;
    let mut wrote = a.output.display().to_string();
    if let Some(dir) = &a.aov {
        out.frame.save_aovs(dir)?;
        wrote += &format!(" and the analysis buffers in {}", dir.display());
    }
    say(&format!("wrote {wrote}"))?;
    if a.stats {
        let internal = |e: serde_json::Error| Error::Internal(e.to_string());
        let mut json = serde_json::to_value(&out.stats).map_err(internal)?;
        // The process's high-water mark: the scene, the frame and the stage's working memory
        // at their most (taken before `map_errors` renders more).
        json["peak_rss_mb"] = serde_json::json!(umbra::study::bench::peak_rss_mb());
        if let Some(errors) = map_errors(&scene, &opts, &out.frame)? {
            json["map_errors"] = serde_json::to_value(errors).map_err(internal)?;
        }
        stdout(&format!("{json}\n"))?;
    }
    Ok(())
}

/// For a shadow map's frame, its wrong interior pixels by cause against the ray-cast
/// reference (`umbra::study::map_errors`); `None` for other methods.
fn map_errors(
    scene: &umbra::Scene,
    opts: &RenderOptions,
    frame: &umbra::Frame,
) -> umbra::Result<Option<umbra::study::map_errors::MapErrors>> {
    if umbra::study::map_errors::without_bias(&opts.shadows).is_none() {
        return Ok(None);
    }
    let reference = RenderOptions {
        visibility: umbra::VisibilityMethod::RayCast,
        shadows: ShadowMethod::RayCast,
        ..RenderOptions::default()
    };
    let reference = umbra::render(scene, &reference)?.frame;
    umbra::study::map_errors::measure(scene, opts, frame, &reference)
}

/// `umbra compare`: every method against the ray-cast reference, as a report.
fn compare_command(a: CompareArgs) -> umbra::Result<()> {
    let scene = a.shadow.load(&a.scene)?;
    let d = CompareOptions::default();
    let opts = CompareOptions {
        visibility: if a.visibility.is_empty() { d.visibility } else { a.visibility },
        shadows: a.shadow.configure_beside(if a.shadows.is_empty() { d.shadows } else { a.shadows }),
        warmup: a.warmup,
        runs: a.runs,
        out: a.out.clone(),
    };
    let bar = TerminalBar::new("{msg:32} {bar:40} {pos}/{len} renders {elapsed}");
    let report = compare(&scene, &scene_name(&a.scene), &opts, |p| bar.report(p));
    bar.finish();
    let report = report?;
    let mut table = format!(
        "{:>9}   {:<34} {:>26}  {:>17}  {}\n",
        "visibility", "shadows", "frame ms: median (min–max)", "wrong / interior", "status"
    );
    for r in &report.results {
        if r.status != "ok" {
            table += &format!("{:>9} + {:<34} {:>26}  {:>17}  {}\n", r.visibility, r.shadows, "—", "—", r.status);
            continue;
        }
        let time = format!("{:.1} ({:.1}–{:.1})", r.time.median_ms, r.time.min_ms, r.time.max_ms);
        let wrong = format!("{} / {}", r.wrong_pixels, r.interior_pixels);
        table += &format!("{:>9} + {:<34} {:>26}  {:>17}  {}\n", r.visibility, r.shadows, time, wrong, r.status);
        if let Some(c) = r.map_errors {
            table += &format!(
                "{:>46} acne {}, detached {}, aliasing {}, resolution {}\n",
                "by cause:", c.acne, c.detached, c.aliasing, c.resolution
            );
        }
        if let Some(e) = r.area_error {
            table += &format!(
                "{:>46} mean {:.4}, largest {:.3} over {} pixels\n",
                "area lights against the exact fraction:", e.mean, e.max, e.pixels
            );
        }
    }
    stdout(&table)?;
    say(&format!("wrote {}", a.out.join("report.html").display()))
}

/// `umbra bench`: each method's frame and phases, timed.
fn bench_command(a: BenchArgs) -> umbra::Result<()> {
    let scene = a.shadow.load(&a.scene)?;
    let opts = umbra::study::bench::BenchOptions {
        visibility: a.visibility,
        shadows: a.shadow.configure_beside(a.shadows),
        warmup: a.warmup,
        runs: a.runs,
        back_face_cull: !a.no_back_face_cull,
        undisturbed: a.undisturbed,
        threads: a.threads,
        heap: Some(umbra::study::bench::HeapProbe { count: count_heap, peak_bytes }),
    };
    let rows = umbra::study::bench::bench(&scene, &opts, |what| {
        use std::io::Write;
        let _ = writeln!(std::io::stderr(), "bench: {what}");
    })?;
    if a.json {
        let mut text = String::new();
        for r in &rows {
            text += &serde_json::to_string(r).map_err(|e| Error::Internal(e.to_string()))?;
            text.push('\n');
        }
        stdout(&text)
    } else {
        stdout(&umbra::study::bench::table(&rows))
    }
}

/// `umbra scale`: a sweep of generated scenes.
fn scale_command(a: ScaleArgs) -> umbra::Result<()> {
    if !a.shadow.receiver.is_empty() {
        return Err(Error::InvalidOption(
            "--receiver marks objects of a scene file, and scale generates its scenes: it cannot be used here".into(),
        ));
    }
    let methods = if a.methods.is_empty() {
        vec![(VisibilityMethod::Scanline, ShadowMethod::None), (VisibilityMethod::ZBuffer, ShadowMethod::None)]
    } else {
        a.methods
            .into_iter()
            .flat_map(|(v, s)| a.shadow.configure_beside(vec![s]).into_iter().map(move |s| (v, s)))
            .collect()
    };
    let opts = ScaleOptions {
        sweep: a.sweep,
        values: a.values,
        methods,
        runs: a.runs,
        width: a.width,
        height: a.height,
        count: a.count,
        size: a.size,
        counter: a.counter,
        out: a.out.clone(),
    };
    let mut table = format!(
        "{:>10} {:>9}   {:<34} {:>26}  {}\n",
        opts.sweep.name(),
        "visibility",
        "shadows",
        "frame ms: median (min–max)",
        opts.counter
    );
    if opts.sweep == Sweep::Samples {
        table = table.replace('\n', "  mean |fraction − exact| in the penumbra\n");
    }
    for p in scale(&opts)? {
        if let Some(why) = &p.refused {
            table += &format!("{:>10} {:>9} + {:<34} refused: {why}\n", p.value, p.visibility, p.shadows);
            continue;
        }
        let time = format!("{:.1} ({:.1}–{:.1})", p.time.median_ms, p.time.min_ms, p.time.max_ms);
        let error = p.area_error.map_or(String::new(), |e| format!("  {e:.4}"));
        table +=
            &format!("{:>10} {:>9} + {:<34} {:>26}  {}{error}\n", p.value, p.visibility, p.shadows, time, p.counter);
    }
    stdout(&table)?;
    say(&format!("wrote {}", a.out.display()))
}

/// `umbra trace`: one line, step by step.
fn trace_command(a: TraceArgs) -> umbra::Result<()> {
    let scene = a.shadow.load(&a.scene)?;
    let t = umbra::study::trace::trace(&scene, a.line, &a.shadow.configure(a.shadows.clone()))?;
    if let Some(x) = a.x.filter(|&x| x >= scene.camera().width) {
        return Err(Error::InvalidOption(format!("--x {x} is outside the image (width {})", scene.camera().width)));
    }
    if a.json {
        let json = serde_json::to_string_pretty(&t).map_err(|e| Error::Internal(e.to_string()))?;
        stdout(&format!("{json}\n"))
    } else {
        stdout(&t.text(&scene, a.x))
    }
}

/// `umbra export-shadows`: a light's Atherton-Weiler-Greenberg database as OBJ.
fn export_shadows_command(e: ExportArgs) -> umbra::Result<()> {
    let scene = Scene::load(&e.scene)?;
    if e.light >= scene.lights().len() {
        return Err(Error::InvalidOption(format!(
            "{}: no light {} (the scene has {} light(s), numbered from 0)",
            e.scene.display(),
            e.light,
            scene.lights().len()
        )));
    }
    refuse_overwrite(std::slice::from_ref(&e.output), e.force)?;
    let mut counters = umbra::Counters::default();
    let db = umbra::shadow::ShadowDatabase::build(&scene, e.light, e.awg.options(!e.no_solid_cull), &mut counters)?;
    db.write_obj(&scene, &e.output)?;
    let polygons: usize = db.samples.iter().map(Vec::len).sum();
    say(&format!("wrote {}: {polygons} lit detail polygon(s) of light {}", e.output.display(), e.light))
}

/// `umbra generate`: a benchmark scene written as files.
fn generate_command(g: GenerateArgs) -> umbra::Result<()> {
    let scene = match g.family {
        Family::Cubes => generate::cubes(
            g.n,
            if g.quads { generate::Faces::Quads } else { generate::Faces::Triangles },
            g.width,
            g.height,
        )?,
        Family::Quads => generate::stacked_quads(g.depth, g.width, g.height)?,
        Family::Spheres => generate::spheres(g.triangles, g.count, g.width, g.height)?,
    };
    let dir = g.output.parent().unwrap_or(std::path::Path::new("")).join("meshes");
    let stem = g.output.file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let meshes: Vec<PathBuf> = (0..scene.objects().len()).map(|i| dir.join(format!("{stem}_{i}.obj"))).collect();
    refuse_overwrite(&[&[g.output.clone()][..], &meshes].concat(), g.force)?;
    scene.write(&g.output)?;
    let asked = match g.family {
        Family::Spheres if scene.polygons().len() != g.triangles as usize + 1 => {
            format!(", the nearest UV spheres to {} triangles and the floor", g.triangles)
        }
        _ => String::new(),
    };
    say(&format!(
        "wrote {} ({} polygons{asked}) and {} mesh(es) in {}",
        g.output.display(),
        scene.polygons().len(),
        meshes.len(),
        dir.display()
    ))
}

/// Refuses to write over files that exist, unless told to (`--force`).
fn refuse_overwrite(paths: &[PathBuf], force: bool) -> umbra::Result<()> {
    match paths.iter().find(|p| p.exists()) {
        Some(p) if !force => {
            Err(Error::InvalidOption(format!("{}: exists; pass --force to overwrite it", p.display())))
        }
        _ => Ok(()),
    }
}

/// Runs `work` with a spinner saying `what` on standard error when it is a terminal (nothing
/// elsewhere), for work that has no steps to count, such as loading a scene's meshes.
fn with_spinner<T>(what: String, work: impl FnOnce() -> T) -> T {
    use std::io::IsTerminal;
    let spinner = std::io::stderr().is_terminal().then(|| {
        let spinner = indicatif::ProgressBar::new_spinner();
        spinner.set_message(what);
        spinner.enable_steady_tick(std::time::Duration::from_millis(200));
        spinner
    });
    let out = work();
    if let Some(spinner) = spinner {
        spinner.finish_and_clear();
    }
    out
}

/// A line about what was done, on standard error (standard output stays for data).
fn say(line: &str) -> umbra::Result<()> {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{line}");
    Ok(())
}

/// Writes `text` to standard output; a failed write (a closed pipe, a full disk) is an error.
fn stdout(text: &str) -> umbra::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| Error::Write { path: "standard output".into(), source: e })
}

/// Refuses an output name with an extension other than `.png` (only PNG is encoded; a name
/// without one, such as `/dev/stdout`, gets PNG).
fn check_png_name(path: &std::path::Path) -> umbra::Result<()> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    if ext.is_none() || ext.as_deref() == Some("png") {
        return Ok(());
    }
    Err(Error::InvalidOption(format!("{}: umbra writes PNG only; name the output file *.png", path.display())))
}

/// Writes the image as PNG, in one write so that a failed write is an error; missing
/// folders on the way are made first, as `--aov` and `generate` make theirs.
fn write_png(img: umbra::image::RgbImage, path: &std::path::Path) -> umbra::Result<()> {
    check_png_name(path)?;
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), umbra::image::ImageFormat::Png)
        .map_err(|e| Error::Image { path: path.to_owned(), source: e.into() })?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::Write { path: dir.to_owned(), source: e })?;
    }
    std::fs::write(path, bytes).map_err(|e| Error::Write { path: path.to_owned(), source: e })
}

fn parse_gamma(s: &str) -> Result<f32, String> {
    let g: f32 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    umbra::check_gamma(g).map(|()| g).map_err(|e| e.to_string())
}

fn main() -> ExitCode {
    keep_freed_memory();
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            use std::io::Write;
            // Nothing more can be done if standard error is closed too.
            let _ = writeln!(std::io::stderr(), "umbra: {e}");
            ExitCode::FAILURE
        }
    }
}
