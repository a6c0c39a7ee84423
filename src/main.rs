//! The `umbra` command line: a thin layer over the library.

use clap::{Parser, Subcommand, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;
use umbra::shadow::volumes::Counting;
use umbra::shadow::{ShadowFilter, ShadowOptions, WilliamsOptions};
use umbra::{generate, render, RenderOptions, Scene, ShadowMethod, VisibilityMethod};

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
    /// Write a generated benchmark scene (scene file plus OBJ meshes).
    Generate(GenerateArgs),
    /// Build the Atherton-Weiler-Greenberg shadow database of a light (its lit detail
    /// polygons, independent of the camera) and write it as an OBJ file.
    ExportShadows(ExportArgs),
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
}

#[derive(clap::Args)]
struct RenderArgs {
    /// The scene file (TOML, see SCENE_FORMAT.md).
    scene: PathBuf,
    /// Where to write the image (PNG).
    #[arg(short, long, default_value = "out.png")]
    output: PathBuf,
    /// Hidden-surface stage: scanline (Watkins), zbuffer, or ray-cast (one ray per pixel).
    #[arg(long, default_value = "scanline", value_parser = parse_visibility)]
    visibility: VisibilityMethod,
    /// Shadow stage. Exact: bouknight-kelley (projected shadow polygons), crow (shadow
    /// volumes counted per span), stencil-volume (the same volumes counted per pixel),
    /// ray-cast (per-pixel reference). Approximate: williams (shadow maps), planar (Blinn's
    /// projection onto receiver planes). Or none. The default is the recommended exact method.
    #[arg(long, default_value = ShadowMethod::DEFAULT.name(), value_parser = parse_shadows)]
    shadows: ShadowMethod,
    /// Write the analysis buffers id.png and light<k>.png into this folder.
    #[arg(long, value_name = "DIR")]
    aov: Option<PathBuf>,
    /// Print the counters and times as one JSON object on standard output.
    #[arg(long)]
    stats: bool,
    /// Encode the image with this display gamma (for example 2.2); default: linear values.
    #[arg(long)]
    gamma: Option<f32>,
    /// Bouknight-Kelley: project every pair, without the sphere prefilter (to measure it).
    #[arg(long)]
    no_prefilter: bool,
    /// Crow: count shadow volumes from the eye with the eye's own count (zpass), from
    /// infinity (zfail), or from zero at the eye (naive-zpass, wrong when the eye is in shadow).
    #[arg(long, default_value = "zpass", value_parser = parse_count)]
    crow_count: Counting,
    /// Williams: texels along each side of a shadow map.
    #[arg(long, default_value_t = 2048)]
    map_size: u32,
    /// Williams: constant depth bias in world units (default: 0.1% of the scene's size).
    #[arg(long)]
    bias: Option<f64>,
    /// Williams: slope-scaled bias, in texels times the tangent of the angle of incidence.
    #[arg(long, default_value_t = 1.5)]
    slope_bias: f64,
    /// Williams: nearest (one texel), pcf (percentage-closer filtering over --pcf-size²
    /// texels), or soft-edge (seed 002: PCF into a screen buffer, then a 15-tap Gaussian blur).
    #[arg(long, value_enum, default_value = "pcf")]
    shadow_filter: FilterArg,
    /// Williams: the PCF kernel's side in texels (odd; 3 is seed 002's kernel).
    #[arg(long, default_value_t = 3)]
    pcf_size: u32,
    /// Williams: leave polygons facing the light out of the depth map (seed 003).
    #[arg(long)]
    cull_front: bool,
    /// Draw the shadow stage's own polygons for the first light sample over the image
    /// (shadow-polygons: Bouknight-Kelley's projections on their receivers).
    #[arg(long, value_enum)]
    debug: Option<Debug>,
}

#[derive(Clone, Copy, ValueEnum)]
enum FilterArg {
    /// One texel.
    Nearest,
    /// Percentage-closer filtering.
    Pcf,
    /// PCF, then seed 002's screen-space blur.
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
    /// Cubes per side (cubes).
    #[arg(long, default_value_t = 10)]
    n: u32,
    /// Cubes as 6 quads each instead of 12 triangles (cubes).
    #[arg(long)]
    quads: bool,
    /// Depth complexity (quads).
    #[arg(long, default_value_t = 16)]
    depth: u32,
    /// Triangles in all (spheres).
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

fn parse_visibility(s: &str) -> Result<VisibilityMethod, String> {
    s.parse().map_err(|e: umbra::Error| e.to_string())
}

fn parse_count(s: &str) -> Result<Counting, String> {
    s.parse().map_err(|e: umbra::Error| e.to_string())
}

fn parse_shadows(s: &str) -> Result<ShadowMethod, String> {
    s.parse().map_err(|e: umbra::Error| e.to_string())
}

fn run(cli: Cli) -> umbra::Result<()> {
    match cli.command {
        Command::Render(a) => {
            let scene = Scene::load(&a.scene)?;
            let filter = match a.shadow_filter {
                FilterArg::Nearest => ShadowFilter::Nearest,
                FilterArg::Pcf => ShadowFilter::Pcf(a.pcf_size),
                FilterArg::SoftEdge => ShadowFilter::SoftEdge(a.pcf_size),
            };
            if a.map_size == 0 || a.map_size > 16384 || a.pcf_size % 2 == 0 {
                return Err(umbra::Error::Invalid("--map-size must be 1..=16384 and --pcf-size odd".into()));
            }
            let williams = WilliamsOptions {
                map_size: a.map_size,
                bias: a.bias,
                slope_bias: a.slope_bias,
                filter,
                cull_front: a.cull_front,
            };
            let shadow_options = ShadowOptions {
                prefilter: !a.no_prefilter,
                crow_count: a.crow_count,
                williams,
                awg_database: None,
                keep_outlines: a.debug.is_some(),
            };
            let opts = RenderOptions { visibility: a.visibility, shadows: a.shadows, shadow_options, progress: true };
            let out = render(&scene, &opts)?;
            let mut img = out.frame.color_image(a.gamma);
            if a.debug.is_some() {
                umbra::Frame::draw_outlines(&mut img, &out.outlines, [255, 40, 200]);
            }
            img.save_with_format(&a.output, image::ImageFormat::Png)
                .map_err(|e| umbra::Error::Image { path: a.output.clone(), source: e })?;
            if let Some(dir) = &a.aov {
                out.frame.save_aovs(dir)?;
            }
            if a.stats {
                println!("{}", serde_json::to_string(&out.stats).map_err(|e| umbra::Error::Invalid(e.to_string()))?);
            }
            Ok(())
        }
        Command::ExportShadows(e) => {
            let scene = Scene::load(&e.scene)?;
            let mut counters = umbra::Counters::default();
            let db = umbra::shadow::ShadowDatabase::build(&scene, e.light, &mut counters)?;
            db.write_obj(&scene, &e.output)
        }
        Command::Generate(g) => {
            let scene = match g.family {
                Family::Cubes => generate::cubes(g.n, !g.quads, g.width, g.height)?,
                Family::Quads => generate::stacked_quads(g.depth, g.width, g.height)?,
                Family::Spheres => generate::spheres(g.triangles, g.count, g.width, g.height)?,
            };
            scene.write(&g.output)
        }
    }
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("umbra: {e}");
            ExitCode::FAILURE
        }
    }
}
