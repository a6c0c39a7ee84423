//! Shadow stages. Each is prepared once per render from the scene and the light samples
//! (projections, detail polygons, volumes, depth maps, a BVH), then asked, run by run in
//! scanline order, which pixels of a visible run each light sample reaches.
//!
//! The same-side rule of section 3 (a polygon whose seen side faces away from a light sample
//! is in shadow from it — Bouknight and Kelley's self-shadowing test) is applied once by the
//! pipeline (`render::walk_line`), before any stage is asked; stages only answer for runs the
//! rule leaves lit.

mod atherton_weiler_greenberg;
mod bouknight_kelley;
mod crow;
mod far_outline;
mod nishita_nakamae;
mod overlay;
mod own_solid;
mod planar;
mod projection;
mod ray_cast;
pub(crate) mod soft_edges;
mod solid_outlines;
mod stencil_volume;
pub(crate) mod volumes;
mod williams;

use atherton_weiler_greenberg::AthertonWeilerGreenberg;
pub use atherton_weiler_greenberg::{DetailPolygon, ShadowDatabase};
use bouknight_kelley::BouknightKelley;
pub use bouknight_kelley::Pairs;
use crow::Crow;
pub(crate) use nishita_nakamae::AreaLight;
use nishita_nakamae::NishitaNakamae;
use planar::Planar;
pub(crate) use ray_cast::blocked;
use ray_cast::RayCastShadows;
pub use soft_edges::{Blur, Buffers, SoftEdges};

/// A light's projection target for [`crate::reference::exact_fraction`]: the plane and the
/// rectangle `rect` of it, seen from the point `from` (projection from a point, as from a
/// point light).
pub(crate) fn projection_target(
    plane: crate::geometry::Plane,
    rect: [glam::DVec3; 4],
    from: glam::DVec3,
) -> projection::Target {
    projection::Target::new(plane, rect, LightSample::Point(from))
}
pub(crate) use projection::Projector;
use stencil_volume::StencilVolume;
pub use volumes::Counting;
use williams::Williams;
pub use williams::{ShadowFilter, WilliamsOptions};

use crate::error::Result;
use crate::scene::{LightSample, Scene};
use crate::stats::Counters;
use crate::view::View;
use crate::visibility::{FrameRuns, Run};

/// Bouknight-Kelley's settings. [`BouknightKelleyOptions::PAPER`] is the paper's method as
/// the "Árnyékolás" notes give it; every other switch turns on a step of ours
/// (`docs/algorithms/bouknight-kelley.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BouknightKelleyOptions {
    /// Use the sphere prefilter (default true; the paper's): pairs whose extents on a sphere
    /// around the light do not overlap are dropped before any projection.
    pub prefilter: bool,
    /// Find the prefilter's overlapping pairs in a grid over the sphere (default true; ours):
    /// each receiver meets only the casters binned in its cells. `false` compares the
    /// extents of every ordered pair, n(n−1) tests a light sample, as the paper does.
    pub sphere_grid: bool,
    /// Make only the polygons seen at some pixel receivers (default true; ours): the others
    /// are never asked. `false` projects onto every polygon whose plane the light sample
    /// lights on the eye's side, as the paper does before the scan.
    pub seen_receivers: bool,
    /// Drop, without projecting, the casters wholly behind the receiver as the light sees
    /// it (default true; ours): their projection is empty. `false` projects them and finds
    /// it empty, as the paper does.
    pub drop_behind: bool,
    /// Drop, without projecting, the casters wholly outside the wedge a triangle receiver
    /// cuts from the light (default true; ours): their shadow falls beside the receiver.
    /// `false` projects them, as the paper does.
    pub wedge: bool,
    /// Drop, without projecting, the casters whose corners' slab across their plane lies
    /// apart from the hull of the light and the receiver (default true; ours): nothing of
    /// them lies between the light and the receiver. `false` projects them, as the paper
    /// does, and finds the projection empty or beside the receiver.
    pub slab: bool,
    /// Drop, before the prefilter, the polygons of closed solids that face away from the
    /// light (default true; ours, not the paper's): on a closed mesh every shadow they cast
    /// is cast by the solid's polygons that face the light. `false` keeps the paper's
    /// casters, to measure the saving.
    pub solid_cull: bool,
    /// Count the shadow polygons a closed solid casts on a receiver under many of them as
    /// the outline of their union (default true; ours): the solid's silhouette from the
    /// light, projected corner by corner, in place of one shadow polygon per polygon facing
    /// the light. `false` projects each, as the paper does. Traces keep each polygon; it
    /// works with the prefilter, whose candidates it counts.
    pub solid_outlines: bool,
    /// Take, of the casters on a receiver's own closed solid, only its front set: those with
    /// a corner in front of the receiver's plane, found once for the polygons (default true;
    /// ours, with `drop_behind`, which drops every other). `false` gathers each from the
    /// prefilter and finds it behind the receiver, one pair at a time.
    pub own_solid: bool,
}

impl BouknightKelleyOptions {
    /// The paper's method with its prefilter, and every step of ours.
    pub const DEFAULT: BouknightKelleyOptions = BouknightKelleyOptions {
        prefilter: true,
        sphere_grid: true,
        seen_receivers: true,
        drop_behind: true,
        wedge: true,
        slab: true,
        solid_cull: true,
        solid_outlines: true,
        own_solid: true,
    };

    /// The paper's method as published: every ordered pair through the sphere prefilter,
    /// every polygon the light faces a receiver, no step of ours.
    pub const PAPER: BouknightKelleyOptions = BouknightKelleyOptions {
        prefilter: true,
        sphere_grid: false,
        seen_receivers: false,
        drop_behind: false,
        wedge: false,
        slab: false,
        solid_cull: false,
        solid_outlines: false,
        own_solid: false,
    };
}

impl Default for BouknightKelleyOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Atherton-Weiler-Greenberg's settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AthertonWeilerGreenbergOptions {
    /// Split two convex pieces of the light view by each other's edges (default true; ours,
    /// not the paper's): the same inside and outside parts as Weiler and Atherton's clipper
    /// gives, the outside as convex pieces, from a walk a tenth as long. `false` clips every
    /// pair with Weiler and Atherton's clipper, as the paper does, to measure the saving.
    pub convex_split: bool,
    /// Leave out of the area sort the polygons that lie behind everything they overlap in
    /// the light view (a floor under a crowd; default true; ours): they hide nothing, and are
    /// lit where no visible piece covers them, the visible pieces over them cut out as holes
    /// without clipping. `false` sorts them with the rest, as the paper does.
    pub backgrounds: bool,
    /// Take out of the area sort, before the light view is cut into regions, the polygons
    /// that no other polygon in the view meets (default true; ours): they are found sheet by
    /// sheet (the side of a closed mesh facing the light, whose polygons never overlap one
    /// another) on a grid, without testing pairs, and are wholly lit. `false` sorts them with
    /// the rest, as the paper does.
    pub lone_sheets: bool,
    /// With `lone_sheets`, settle a closed solid's side facing the light at once where it
    /// lies in one light view (default true; ours): only its corners are mapped, its outline
    /// there is found from the edges it turns to the light, and its polygons whose boxes
    /// meet nothing else are wholly lit without being mapped one by one. `false` takes every
    /// polygon through the lone-sheet step alone.
    pub whole_solids: bool,
    /// Leave out of each light view the polygons of closed solids that cast shadows and turn
    /// away from the light (default true; ours, the solid cull of
    /// `docs/algorithms/bouknight-kelley.md`): they are unlit and hide nothing the solid's
    /// polygons turned to the light do not. `false` puts every polygon in the view, as the
    /// paper does.
    pub solid_cull: bool,
    /// Cut each light view into regions of at most 1,024 casters and sort them apart (default
    /// true; ours): what hides what inside a region depends only on what lies in it. `false`
    /// sorts the whole view at once, as the paper does.
    pub tiling: bool,
    /// Map a polygon that lies wholly inside one face of the cube around a point light into
    /// that face's view alone (default true; ours). `false` maps every polygon into all six
    /// views, each clipping it to its own frustum.
    pub face_binning: bool,
    /// Find the pieces a front polygon may overlap in a grid over their boxes (default true;
    /// ours). `false` hands the front polygon every piece still in the sort, as the paper's
    /// clipper takes the whole list (a piece whose box misses the front polygon's is put
    /// outside without clipping, the clipper's own first test).
    pub sort_grid: bool,
}

impl AthertonWeilerGreenbergOptions {
    /// The paper's two passes, and every step of ours.
    pub const DEFAULT: AthertonWeilerGreenbergOptions = AthertonWeilerGreenbergOptions {
        convex_split: true,
        backgrounds: true,
        lone_sheets: true,
        whole_solids: true,
        solid_cull: true,
        tiling: true,
        face_binning: true,
        sort_grid: true,
    };

    /// The paper as published: one area sort of each whole light view, every polygon in it,
    /// Weiler and Atherton's clipper for every cut, no step of ours.
    pub const PAPER: AthertonWeilerGreenbergOptions = AthertonWeilerGreenbergOptions {
        convex_split: false,
        backgrounds: false,
        lone_sheets: false,
        whole_solids: false,
        solid_cull: false,
        tiling: false,
        face_binning: false,
        sort_grid: false,
    };
}

impl Default for AthertonWeilerGreenbergOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// How the shadow volumes are built from the casting polygons.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum Construction {
    /// Bergeron's 1986 general volumes: every casting polygon bounds a volume, and the sides
    /// that neighbouring polygons share are merged, so that only silhouette and boundary
    /// edges keep sides; closed solids' polygons turned away from the light are left out
    /// (ours). Exact for any meshes and any light (the default).
    #[default]
    Merged,
    /// Every casting polygon its own volume, nothing merged (to measure what merging saves).
    PerPolygon,
    /// Crow's 1977 construction, as published: one volume per object, its sides on the
    /// object's contour edges (between a polygon turned to the light and one turned away),
    /// its caps on the polygons turned to the light, and z-pass's count starting from the
    /// number of volumes that hold the eye, one count for the whole image. Exact for closed,
    /// outward-wound objects with the light outside them and no volume crossing the near
    /// plane; wrong elsewhere, on purpose (`docs/algorithms/crow.md`).
    Crow1977,
}

impl Construction {
    /// The construction's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Construction::Merged => "merged",
            Construction::PerPolygon => "per-polygon",
            Construction::Crow1977 => "crow-1977",
        }
    }

    /// Every construction.
    pub const ALL: [Construction; 3] = [Construction::Merged, Construction::PerPolygon, Construction::Crow1977];
}

crate::error::named!(Construction, "volume construction");

/// The settings of shadow volumes, counted per span (Crow) or per pixel (stencil).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct VolumeOptions {
    /// How the volumes are counted along the line of sight (default z-pass).
    pub counting: volumes::Counting,
    /// How the volumes are built (default: Bergeron's merged volumes).
    pub construction: Construction,
    /// Cut the volumes to where a count can reach (default true; ours): z-pass's sides to
    /// the hull of the eye and the scene's bounds, and z-fail's volumes closed at a plane
    /// beyond the scene. `false` extrudes every volume to infinity, as the papers do, and
    /// z-fail's volumes are then clipped by the camera's far plane where the scene has one
    /// (the failure Everitt and Kilgard's infinite far plane removes).
    pub sight_cuts: bool,
    /// Count z-fail's far caps as the outline of their union (default true; ours; where the
    /// sight cuts close the volumes at a far plane): the caps' edges that two casters share
    /// cancel, and Crow's walk (or the stencil's drawing) adds the winding number of what is
    /// left instead of each cap (`docs/algorithms/crow.md`). `false` counts each far cap as a
    /// shadow polygon of its own.
    pub far_outline: bool,
    /// Count z-fail's front caps as the outline of their union too (default true; ours;
    /// with the far outline): a front cap is a scene polygon, never in front of the visible
    /// point, so z-fail counts it wherever it covers the pixel, whatever the depth, and the
    /// caps' shared edges cancel (`docs/algorithms/crow.md`). `false` counts each front cap
    /// as a shadow polygon with its depth.
    pub front_outline: bool,
}

impl VolumeOptions {
    /// Z-pass with the eye's own count, on merged volumes, cut to sight.
    pub const DEFAULT: VolumeOptions = VolumeOptions {
        counting: volumes::Counting::ZPass,
        construction: Construction::Merged,
        sight_cuts: true,
        far_outline: true,
        front_outline: true,
    };

    /// Crow's 1977 construction counted by z-pass, uncut: the paper as published.
    pub const PAPER: VolumeOptions = VolumeOptions {
        counting: volumes::Counting::ZPass,
        construction: Construction::Crow1977,
        sight_cuts: false,
        far_outline: false,
        front_outline: false,
    };
}

impl Default for VolumeOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Nishita and Nakamae's steps of ours, each with its switch (`docs/algorithms/nishita-nakamae.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct NishitaNakamaeOptions {
    /// Leave out the casters outside the convex hull of a receiver and the light (a BVH
    /// query), instead of taking every polygon as a possible occluder of every receiver.
    pub hull_cull: bool,
    /// Drop the polygons of closed solids that turn their back on the whole light.
    pub solid_cull: bool,
    /// Hide with one hull what a convex closed solid hides at a penumbra pixel, instead of
    /// one shadow per polygon.
    pub convex_bodies: bool,
    /// Take no caster of a receiver's own convex solid (seen from outside, none can come
    /// between it and the light).
    pub same_solid: bool,
    /// Where the papers' premise fails for a pair (the caster reaches as near the light as
    /// its nearest corner, or the light is cut by the receiver's plane), take the caster as
    /// an occluder of every pixel of the receiver. Off, the pair is left out as the premise
    /// assumes it never arises: its shadow is missing (not exact).
    pub premise_fallback: bool,
    /// Shade an area light's diffuse term from the irradiance of the part of the light each
    /// pixel sees, by Lambert's contour formula (the papers'). Off, the diffuse term is the
    /// grid's samples' (`docs/shading.md`), each weighted by the exact fraction, as the
    /// sampling stages shade it. The lit fraction is the same either way.
    pub lambert: bool,
}

impl NishitaNakamaeOptions {
    /// Every step of ours on.
    pub const DEFAULT: NishitaNakamaeOptions = NishitaNakamaeOptions {
        hull_cull: true,
        solid_cull: true,
        convex_bodies: true,
        same_solid: true,
        premise_fallback: true,
        lambert: true,
    };

    /// The papers as published: every polygon a possible occluder of every receiver, each
    /// hiding on its own, the premise taken for granted.
    pub const PAPER: NishitaNakamaeOptions = NishitaNakamaeOptions {
        hull_cull: false,
        solid_cull: false,
        convex_bodies: false,
        same_solid: false,
        premise_fallback: false,
        lambert: true,
    };
}

impl Default for NishitaNakamaeOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Every stage's settings at once, as a command line or a notebook holds them;
/// [`ShadowMethod::with_settings`] gives a method those of its own stage.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageSettings {
    /// Bouknight-Kelley's.
    pub bouknight_kelley: BouknightKelleyOptions,
    /// Atherton-Weiler-Greenberg's.
    pub atherton_weiler_greenberg: AthertonWeilerGreenbergOptions,
    /// The shadow volumes', counted per span (Crow) or in a stencil.
    pub volumes: VolumeOptions,
    /// Williams' shadow maps'.
    pub williams: WilliamsOptions,
    /// Nishita and Nakamae's.
    pub nishita_nakamae: NishitaNakamaeOptions,
}

/// What every shadow stage is prepared from.
pub(crate) struct ShadowContext<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The view.
    pub view: &'a View,
    /// The visible runs of every line.
    pub runs: &'a FrameRuns,
    /// `visible[i]`: whether scene polygon `i` is seen at some pixel (the receivers that
    /// matter).
    pub visible: Vec<bool>,
    /// Keep the screen outlines of the stage's polygons (shadow polygons, detail polygons)
    /// for drawing them over the image, and what traces show of them (Bouknight-Kelley:
    /// what became of each receiver's pairs).
    pub keep_outlines: bool,
    /// Atherton-Weiler-Greenberg's shadow databases (one per light), built beforehand to
    /// render many views of them; `None` builds them.
    pub(crate) awg_database: Option<std::sync::Arc<Vec<ShadowDatabase>>>,
    /// Each light's samples (`samples[light][sample]`).
    pub samples: Vec<Vec<LightSample>>,
    /// Every `(light, sample, sample's position)`, in order ([`ShadowContext::all_samples`]),
    /// listed once for the frame: a line's walk reads it for every run.
    flat: Vec<(usize, usize, LightSample)>,
    /// The scene's size (diagonal of its bounds), for tolerances.
    pub extent: f64,
    /// Where frame-sized buffers (shadow maps) come from and go back to.
    pub(crate) pools: crate::pool::Pools,
}

impl<'a> ShadowContext<'a> {
    /// The context for rendering `scene` from `view`, whose visible runs are `runs`.
    pub fn new(scene: &'a Scene, view: &'a View, runs: &'a FrameRuns, keep_outlines: bool) -> Self {
        let samples: Vec<Vec<LightSample>> = scene.lights.iter().map(|l| l.samples()).collect();
        let flat = samples.iter().enumerate().flat_map(|(l, ss)| ss.iter().enumerate().map(move |(s, &x)| (l, s, x)));
        let flat = flat.collect();
        let extent = scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length().max(1e-300));
        let visible = runs.visible(scene.polygons.len());
        let pools = Default::default();
        ShadowContext { scene, view, runs, visible, keep_outlines, awg_database: None, samples, flat, extent, pools }
    }

    /// The same context, with Atherton-Weiler-Greenberg's databases built beforehand.
    pub(crate) fn with_awg_database(self, db: Option<std::sync::Arc<Vec<ShadowDatabase>>>) -> Self {
        ShadowContext { awg_database: db, ..self }
    }

    /// The same context, taking its frame-sized buffers from `pools` (a renderer's).
    pub(crate) fn with_pools(self, pools: &crate::pool::Pools) -> Self {
        ShadowContext { pools: pools.clone(), ..self }
    }

    /// Every (light, sample) pair, in order: the flat index of sample `s` of light `l` is
    /// `sample_index(l, s)`.
    pub fn all_samples(&self) -> impl Iterator<Item = (usize, usize, LightSample)> + '_ {
        self.flat.iter().copied()
    }

    /// How many rows of lit values a line's walk fills (`render::walk_line`): one per light
    /// sample, then three per light for the irradiance vector of a stage that gives it
    /// ([`ShadowWalker::irradiance`]; from [`ShadowContext::vector_row`]).
    pub fn lit_rows(&self) -> usize {
        self.samples.iter().map(Vec::len).sum::<usize>() + 3 * self.samples.len()
    }

    /// The first of light `l`'s three rows of its irradiance vector's components.
    pub fn vector_row(&self, l: usize) -> usize {
        self.samples.iter().map(Vec::len).sum::<usize>() + 3 * l
    }

    /// The flat index of sample `s` of light `l`.
    pub fn sample_index(&self, l: usize, s: usize) -> usize {
        self.samples[..l].iter().map(Vec::len).sum::<usize>() + s
    }
}

/// A prepared shadow stage.
pub(crate) trait ShadowStage: Sync {
    /// A walker for one band of lines; it is called in increasing line order.
    fn walker(&self) -> Box<dyn ShadowWalker + '_>;

    /// Pictures of what the stage built, for study (Williams: its depth maps).
    fn pictures(&self) -> Vec<Picture> {
        Vec::new()
    }

    /// The screen outlines of the polygons the stage walks for the first sample of the first
    /// light (shadow polygons, detail polygons, shadow-volume polygons), when the options
    /// asked to keep them; for drawing over the image.
    fn outlines(&self) -> Vec<Vec<glam::DVec2>> {
        Vec::new()
    }

    /// The bytes the prepared stage holds through the walk (`--stats`' `stage_bytes`).
    fn bytes(&self) -> usize;
}

/// Answers, line by line, which pixels of each visible run a light sample reaches.
pub(crate) trait ShadowWalker {
    /// Called once for each line, in increasing order, before its runs.
    fn start_line(&mut self, _line: u32) {}

    /// Writes into `lit[i]` how much of sample `sample` of light `light` reaches pixel
    /// `run.x0 + i` of `line`: 0 or 1 for exact stages, a fraction for filtered ones. Only
    /// called for runs whose polygon faces the sample on its seen side.
    fn lit(&mut self, light: usize, sample: usize, line: u32, run: &Run, lit: &mut [f32]);

    /// Whether the stage answers for light `light` as a whole (an area light's exact
    /// fraction): [`ShadowWalker::lit`] is then asked for its sample 0 only, whichever side of
    /// the run's plane the samples lie, and its answer stands for every sample.
    fn whole_light(&self, _light: usize) -> bool {
        false
    }

    /// Whether, for a light it answers for as a whole, the stage also gives each pixel the
    /// irradiance vector of the part of the light it sees ([`ShadowWalker::light_vector`]),
    /// from which the shading takes the light's diffuse term (`crate::geometry::lambert`).
    fn irradiance(&self, _light: usize) -> bool {
        false
    }

    /// The irradiance vectors of the pixels of the last [`ShadowWalker::lit`] call (for
    /// light `light`, where [`ShadowWalker::irradiance`] says so), component by component;
    /// zero where the pixel sees none of the light.
    fn light_vector(&self, _light: usize, _out: [&mut [f32]; 3]) {}

    /// Adds the walker's counters.
    fn finish(&mut self, _counters: &mut Counters) {}

    /// What the last [`ShadowWalker::lit`] call did, for traces and per-pixel counter images.
    fn decision(&self) -> Decision {
        Decision::default()
    }
}

/// What a shadow walker did for one run: how much it tested at each pixel, and a note.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Decision {
    /// Pixel ranges `start..end` and how many of the stage's polygons (shadow polygons,
    /// detail polygons, volume polygons), texels or rays were tested at each of their pixels.
    pub tested: Vec<(u32, u32, u32)>,
    /// The stage's own account, in a line.
    pub note: String,
    /// The same account as data, for drawing it (`umbra explore`).
    pub detail: Detail,
}

/// What a stage looked at for one run, in the terms of its paper.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Detail {
    /// Nothing beyond the note.
    #[default]
    None,
    /// Bouknight-Kelley: the shadow polygons on the run's polygon that touch the run, and
    /// the scan segments examined, in the order of the recursion.
    Segments {
        /// Shadow polygons touching the run.
        covers: Vec<Cover>,
        /// Every segment examined.
        segments: Vec<Segment>,
        /// What became of the run's polygon's pairs (steps 1-3), when the stage kept them.
        pairs: Option<bouknight_kelley::Pairs>,
    },
    /// Atherton-Weiler-Greenberg: the lit detail polygons on the run's polygon that cover
    /// pixels of the run.
    Covers {
        /// Detail polygons over the run.
        covers: Vec<Cover>,
    },
    /// Williams: where each pixel of the run falls in its shadow map, the nearness the map
    /// holds there and the point's threshold.
    Texels {
        /// Texels along each side of the map.
        size: u32,
        /// The side of the filter's kernel in texels (1: nearest).
        kernel: u32,
        /// Each pixel's lookup.
        texels: Vec<Texel>,
    },
    /// Crow: what each shadow polygon over the run adds to the count, and the count.
    Counts {
        /// Each shadow polygon's contribution over the pixels where it holds.
        adds: Vec<CountAdd>,
        /// The count along the run: `(start, end, count)`; lit where it is zero.
        counts: Vec<(u32, u32, i32)>,
    },
}

/// An overlay polygon (shadow polygon, detail polygon) covering pixels `start..end`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Cover {
    /// The polygon, an index into the stage's outlines.
    pub polygon: u32,
    /// First pixel covered.
    pub start: u32,
    /// One past the last.
    pub end: u32,
}

/// A picture of something a stage built for one light sample (a shadow map, a cube face).
#[derive(Debug, Clone)]
pub struct Picture {
    /// The light.
    pub light: usize,
    /// Its sample.
    pub sample: usize,
    /// The cube face (0 for a single map).
    pub face: usize,
    /// The map's texels along each side (the picture may be smaller).
    pub size: u32,
    /// The picture.
    pub image: image::GrayImage,
}

/// Where one pixel's point falls in a shadow map (Williams).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Texel {
    /// The pixel.
    pub x: u32,
    /// The cube face it falls in (0 for a single map).
    pub face: u8,
    /// Its texel coordinates in the map (a cube map: in the face it falls in).
    pub u: f32,
    /// Its texel coordinates in the map.
    pub v: f32,
    /// The nearness the map holds at that texel (`1/z` from the light, or minus the depth
    /// for a directional light's map); `None` outside the map or where nothing was drawn.
    pub map: Option<f32>,
    /// The point's own nearness with the bias: a texel hides the point when it holds more.
    pub threshold: f32,
}

/// One scan segment Bouknight-Kelley examined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Segment {
    /// First pixel.
    pub start: u32,
    /// One past the last.
    pub end: u32,
    /// Depth of the recursion (0: the whole run).
    pub depth: u32,
    /// What was decided.
    pub outcome: Outcome,
}

/// What became of a scan segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Outcome {
    /// No shadow polygon touches it: lit.
    Lit,
    /// One covers it fully: in shadow.
    Shadow,
    /// One covers it partly: split at that polygon's edges.
    Split,
}

/// What one shadow-volume polygon adds to Crow's count over pixels `start..end`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CountAdd {
    /// The shadow polygon, an index into the stage's outlines.
    pub polygon: u32,
    /// First pixel.
    pub start: u32,
    /// One past the last.
    pub end: u32,
    /// +1 entering a volume, -1 leaving one (z-pass); the opposite behind the point (z-fail).
    pub add: i32,
    /// A near cap: part of the eye's own count.
    pub near_cap: bool,
    /// Z-fail's far caps, counted together as the outline of their union (their `polygon`
    /// is [`FAR_CAPS`]; ours, `VolumeOptions::far_outline`).
    pub far_caps: bool,
}

/// The `polygon` of a [`CountAdd`] that the far caps make together.
pub const FAR_CAPS: u32 = u32::MAX;

/// The shadow methods, each with its own settings. Chosen by name on the command line
/// (`"crow".parse()` gives Crow with its defaults).
///
/// ```
/// use umbra::shadow::{Counting, VolumeOptions, WilliamsOptions};
/// use umbra::{generate, render, RenderOptions, ShadowMethod};
///
/// let scene = generate::cubes(2, generate::Faces::Quads, 64, 48)?;
/// let z_fail = ShadowMethod::Crow(VolumeOptions { counting: Counting::ZFail, ..Default::default() });
/// let small_map = ShadowMethod::Williams(WilliamsOptions { map_size: 512, ..Default::default() });
/// for shadows in [z_fail, small_map, "bouknight-kelley".parse()?] {
///     let exact = shadows.is_exact();
///     let out = render(&scene, &RenderOptions { shadows, ..Default::default() })?;
///     println!("{} exact: {exact}", out.stats.shadows);
/// }
/// # Ok::<(), umbra::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum ShadowMethod {
    /// No shadows: every sample reaches every point on its seen side.
    None,
    /// One shadow ray per pixel and light sample (the exact reference).
    RayCast,
    /// Appel / Bouknight-Kelley projected shadow polygons, scan segment by scan segment.
    BouknightKelley(BouknightKelleyOptions),
    /// Crow's shadow volumes counted per span.
    Crow(VolumeOptions),
    /// Atherton-Weiler-Greenberg: hidden-surface removal from the light, lit detail polygons.
    AthertonWeilerGreenberg(AthertonWeilerGreenbergOptions),
    /// Williams' two-pass z-buffer shadow maps (approximate).
    Williams(WilliamsOptions),
    /// Shadow volumes counted per pixel in a stencil buffer.
    StencilVolume(VolumeOptions),
    /// Blinn's shadows projected onto marked receiver planes (approximate).
    Planar,
    /// Nishita & Nakamae's umbra and penumbra polygons from the light's corners, the
    /// penumbra's pixels by clipping the light: area lights' exact fraction.
    NishitaNakamae(NishitaNakamaeOptions),
}

impl ShadowMethod {
    /// The engine's recommended exact method (the default of `--shadows`): Bouknight-Kelley,
    /// exact, the fastest exact stage on the benchmark scenes, and the oldest.
    pub const DEFAULT: ShadowMethod = ShadowMethod::BouknightKelley(BouknightKelleyOptions::DEFAULT);

    /// Every method, with its default settings.
    pub const ALL: [ShadowMethod; 9] = [
        ShadowMethod::None,
        ShadowMethod::BouknightKelley(BouknightKelleyOptions::DEFAULT),
        ShadowMethod::AthertonWeilerGreenberg(AthertonWeilerGreenbergOptions::DEFAULT),
        ShadowMethod::Crow(VolumeOptions::DEFAULT),
        ShadowMethod::Williams(WilliamsOptions::DEFAULT),
        ShadowMethod::StencilVolume(VolumeOptions::DEFAULT),
        ShadowMethod::Planar,
        ShadowMethod::NishitaNakamae(NishitaNakamaeOptions::DEFAULT),
        ShadowMethod::RayCast,
    ];

    /// The method's name on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            ShadowMethod::None => "none",
            ShadowMethod::RayCast => "ray-cast",
            ShadowMethod::BouknightKelley(_) => "bouknight-kelley",
            ShadowMethod::Crow(_) => "crow",
            ShadowMethod::AthertonWeilerGreenberg(_) => "atherton-weiler-greenberg",
            ShadowMethod::Williams(_) => "williams",
            ShadowMethod::StencilVolume(_) => "stencil-volume",
            ShadowMethod::Planar => "planar",
            ShadowMethod::NishitaNakamae(_) => "nishita-nakamae",
        }
    }

    /// What the stage does, in a few sentences for a reader of the study tools (`umbra
    /// explore` shows it above the stage's trace).
    pub fn description(&self) -> &'static str {
        match self {
            ShadowMethod::None => "No shadows: every light sample reaches every point on its seen side.",
            ShadowMethod::RayCast => "The reference: one shadow ray per pixel and light sample, through a BVH.",
            ShadowMethod::BouknightKelley(_) => {
                "Appel / Bouknight-Kelley (1970): every polygon's shadow projected from the light onto each \
                 receiver's plane (pairs kept by the sphere prefilter). For each run, the shadow polygons on \
                 its receiver are walked with their own active edges; then a segment no shadow polygon touches \
                 is lit, one a shadow polygon covers fully is in shadow, and one covered partly is split at \
                 that polygon's edges and each part examined again. Below: the segments of the picked run, \
                 one row per depth of the recursion."
            }
            ShadowMethod::Crow(_) => {
                "Crow (1977): shadow volumes bounded by shadow polygons. Along the run, each shadow polygon \
                 in front of the visible point adds +1 (entering a volume) or -1 (leaving one); near caps \
                 carry the eye's own count. Where the count is 0 the point is lit. Below: each polygon's \
                 contribution over the pixels where it holds, and the count along the run."
            }
            ShadowMethod::AthertonWeilerGreenberg(_) => {
                "Atherton, Weiler & Greenberg (1978): hidden-surface removal from the light (Weiler-Atherton \
                 clipping) leaves the lit parts of every polygon as detail polygons, merged into the model. \
                 A pixel is lit where a lit detail polygon of its polygon covers it. Below: the detail \
                 polygons over the picked run."
            }
            ShadowMethod::Williams(_) => {
                "Williams (1978): a depth map rendered from the light; a point is lit where it is no farther \
                 from the light than the map's depth at its texel (with bias and percentage-closer filtering). \
                 Approximate: the red pixels differ from ray-cast."
            }
            ShadowMethod::StencilVolume(_) => {
                "Shadow volumes counted per pixel in a stencil buffer (Heidmann 1991): the z-buffer version \
                 of Crow's count, rasterised before the frame is shaded."
            }
            ShadowMethod::Planar => "Blinn (1988): shadows projected onto marked receiver planes. Approximate.",
            ShadowMethod::NishitaNakamae(_) => {
                "Nishita & Nakamae (1983-85): umbra and penumbra polygons from the light's corners; pixels \
                 in an umbra are dark and outside every penumbra lit, a span at a time; only in the penumbra \
                 is the visible part of an area light clipped out and measured: its exact lit fraction."
            }
        }
    }

    /// The method as its paper publishes it, with none of our engineering (`--paper`):
    /// Bouknight-Kelley, Atherton-Weiler-Greenberg and Crow's volumes (per span or in a
    /// stencil) with every step of ours off ([`BouknightKelleyOptions::PAPER`] keeping the
    /// prefilter's switch, [`AthertonWeilerGreenbergOptions::PAPER`], and Crow's 1977
    /// construction uncut, keeping the count); every other method as it is (it has no steps
    /// of ours to turn off, or is a reference).
    ///
    /// ```
    /// use umbra::shadow::{BouknightKelleyOptions, ShadowMethod};
    /// let bk: ShadowMethod = "bouknight-kelley".parse()?;
    /// assert_eq!(bk.as_published(), ShadowMethod::BouknightKelley(BouknightKelleyOptions::PAPER));
    /// assert!(bk.as_published().is_paper());
    /// # Ok::<(), umbra::Error>(())
    /// ```
    pub fn as_published(&self) -> ShadowMethod {
        match self {
            ShadowMethod::BouknightKelley(o) => ShadowMethod::BouknightKelley(BouknightKelleyOptions {
                prefilter: o.prefilter,
                ..BouknightKelleyOptions::PAPER
            }),
            ShadowMethod::AthertonWeilerGreenberg(_) => {
                ShadowMethod::AthertonWeilerGreenberg(AthertonWeilerGreenbergOptions::PAPER)
            }
            ShadowMethod::Crow(v) => ShadowMethod::Crow(VolumeOptions { counting: v.counting, ..VolumeOptions::PAPER }),
            ShadowMethod::StencilVolume(v) => {
                ShadowMethod::StencilVolume(VolumeOptions { counting: v.counting, ..VolumeOptions::PAPER })
            }
            ShadowMethod::NishitaNakamae(_) => ShadowMethod::NishitaNakamae(NishitaNakamaeOptions::PAPER),
            ShadowMethod::None | ShadowMethod::RayCast | ShadowMethod::Williams(_) | ShadowMethod::Planar => {
                self.clone()
            }
        }
    }

    /// The method with the settings of its own stage from `settings` (a stage without
    /// settings is left as it is): how a command line or a notebook that holds every
    /// stage's settings at once configures whichever method it is given.
    ///
    /// ```
    /// use umbra::shadow::{Counting, ShadowMethod, StageSettings, VolumeOptions};
    /// let mut settings = StageSettings::default();
    /// settings.volumes.counting = Counting::ZFail;
    /// let crow: ShadowMethod = "crow".parse()?;
    /// assert_eq!(crow.with_settings(&settings), ShadowMethod::Crow(settings.volumes));
    /// assert_eq!(ShadowMethod::RayCast.with_settings(&settings), ShadowMethod::RayCast);
    /// # Ok::<(), umbra::Error>(())
    /// ```
    pub fn with_settings(&self, settings: &StageSettings) -> ShadowMethod {
        match self {
            ShadowMethod::BouknightKelley(_) => ShadowMethod::BouknightKelley(settings.bouknight_kelley),
            ShadowMethod::AthertonWeilerGreenberg(_) => {
                ShadowMethod::AthertonWeilerGreenberg(settings.atherton_weiler_greenberg)
            }
            ShadowMethod::Crow(_) => ShadowMethod::Crow(settings.volumes),
            ShadowMethod::StencilVolume(_) => ShadowMethod::StencilVolume(settings.volumes),
            ShadowMethod::Williams(_) => ShadowMethod::Williams(settings.williams.clone()),
            ShadowMethod::NishitaNakamae(_) => ShadowMethod::NishitaNakamae(settings.nishita_nakamae),
            ShadowMethod::None | ShadowMethod::RayCast | ShadowMethod::Planar => self.clone(),
        }
    }

    /// The settings of the method that a study tells apart, each once, the default first:
    /// its paper path; the shadow volumes' other countings (and, for Crow, the count uncut
    /// by the sight hull); Bouknight-Kelley without its prefilter and without its solid cull.
    /// The exactness tests check every one of them that [`ShadowMethod::is_exact`].
    ///
    /// ```
    /// use umbra::ShadowMethod;
    /// let crow: ShadowMethod = "crow".parse()?;
    /// let labels: Vec<String> = crow.variants().iter().map(|m| m.command_line()).collect();
    /// assert_eq!(labels[0], "crow");
    /// assert!(labels.contains(&"crow --crow-count zfail".to_string()));
    /// assert!(labels.contains(&"crow --paper".to_string()));
    /// # Ok::<(), umbra::Error>(())
    /// ```
    pub fn variants(&self) -> Vec<ShadowMethod> {
        let mut out = vec![self.clone()];
        match self {
            ShadowMethod::BouknightKelley(o) => {
                out.push(ShadowMethod::BouknightKelley(BouknightKelleyOptions { prefilter: false, ..*o }));
                out.push(ShadowMethod::BouknightKelley(BouknightKelleyOptions { solid_cull: false, ..*o }));
                out.push(ShadowMethod::BouknightKelley(BouknightKelleyOptions { solid_outlines: false, ..*o }));
            }
            ShadowMethod::Crow(v) => {
                let z_fail = VolumeOptions { counting: volumes::Counting::ZFail, ..*v };
                out.push(ShadowMethod::Crow(z_fail));
                out.push(ShadowMethod::Crow(VolumeOptions { far_outline: false, ..z_fail }));
                out.push(ShadowMethod::Crow(VolumeOptions { front_outline: false, ..z_fail }));
                out.push(ShadowMethod::Crow(VolumeOptions { sight_cuts: false, ..*v }));
                out.push(ShadowMethod::Crow(VolumeOptions { counting: volumes::Counting::NaiveZPass, ..*v }));
            }
            ShadowMethod::StencilVolume(v) => {
                let z_fail = VolumeOptions { counting: volumes::Counting::ZFail, ..*v };
                out.push(ShadowMethod::StencilVolume(z_fail));
                out.push(ShadowMethod::StencilVolume(VolumeOptions { far_outline: false, ..z_fail }));
                out.push(ShadowMethod::StencilVolume(VolumeOptions { front_outline: false, ..z_fail }));
            }
            ShadowMethod::NishitaNakamae(o) => {
                // Each step that buys speed off by itself (the premise's fallback is what
                // keeps the stage exact: it goes with the paper path), and the grid's
                // shading in place of Lambert's irradiance.
                out.push(ShadowMethod::NishitaNakamae(NishitaNakamaeOptions { hull_cull: false, ..*o }));
                out.push(ShadowMethod::NishitaNakamae(NishitaNakamaeOptions { solid_cull: false, ..*o }));
                out.push(ShadowMethod::NishitaNakamae(NishitaNakamaeOptions { convex_bodies: false, ..*o }));
                out.push(ShadowMethod::NishitaNakamae(NishitaNakamaeOptions { same_solid: false, ..*o }));
                out.push(ShadowMethod::NishitaNakamae(NishitaNakamaeOptions { lambert: false, ..*o }));
            }
            ShadowMethod::AthertonWeilerGreenberg(_)
            | ShadowMethod::None
            | ShadowMethod::RayCast
            | ShadowMethod::Williams(_)
            | ShadowMethod::Planar => {}
        }
        let paper = self.as_published();
        if self.has_paper_path() && !out.contains(&paper) {
            out.push(paper);
        }
        out
    }

    /// Whether the stage keeps polygons of its own to draw over the image
    /// ([`crate::RenderOptions::outlines`], `umbra render --debug shadow-polygons`): the
    /// shadow polygons of Bouknight-Kelley and Crow, Atherton-Weiler-Greenberg's detail
    /// polygons, the planar shadows.
    pub fn has_outlines(&self) -> bool {
        match self {
            ShadowMethod::BouknightKelley(_)
            | ShadowMethod::AthertonWeilerGreenberg(_)
            | ShadowMethod::Crow(_)
            | ShadowMethod::Planar => true,
            ShadowMethod::None
            | ShadowMethod::RayCast
            | ShadowMethod::Williams(_)
            | ShadowMethod::StencilVolume(_)
            | ShadowMethod::NishitaNakamae(_) => false,
        }
    }

    /// Whether the method gives an area light the exact fraction of `docs/scene-format.md`
    /// §3 (the part of the light a point sees), not the fraction of its grid of samples:
    /// such a stage is judged against the exact fraction (`reference::exact_fraction`), the
    /// others against ray-cast.
    pub fn exact_area_fraction(&self) -> bool {
        match self {
            ShadowMethod::NishitaNakamae(_) => true,
            ShadowMethod::None
            | ShadowMethod::RayCast
            | ShadowMethod::BouknightKelley(_)
            | ShadowMethod::Crow(_)
            | ShadowMethod::AthertonWeilerGreenberg(_)
            | ShadowMethod::Williams(_)
            | ShadowMethod::StencilVolume(_)
            | ShadowMethod::Planar => false,
        }
    }

    /// The method as written on the command line: its name, then the flags that set its
    /// options apart from the defaults (`crow --crow-count zfail`, `williams --shadow-filter
    /// pcf --pcf-size 5`; a paper path: `bouknight-kelley --paper`). For reports.
    ///
    /// ```
    /// use umbra::shadow::{Counting, ShadowMethod, VolumeOptions};
    /// let z_fail = ShadowMethod::Crow(VolumeOptions { counting: Counting::ZFail, ..Default::default() });
    /// assert_eq!(z_fail.command_line(), "crow --crow-count zfail");
    /// assert_eq!(z_fail.as_published().command_line(), "crow --paper --crow-count zfail");
    /// ```
    pub fn command_line(&self) -> String {
        let paper = self.is_paper();
        let mut on: Vec<(bool, String)> = vec![(paper, "--paper".into())];
        match self {
            ShadowMethod::BouknightKelley(o) => {
                on.push((!o.prefilter, "--no-prefilter".into()));
                if !paper {
                    on.push((!o.sphere_grid, "--no-sphere-grid".into()));
                    on.push((!o.seen_receivers, "--all-receivers".into()));
                    on.push((!o.drop_behind, "--no-drop-behind".into()));
                    on.push((!o.wedge, "--no-wedge".into()));
                    on.push((!o.slab, "--no-slab".into()));
                    on.push((!o.solid_cull, "--no-solid-cull".into()));
                    on.push((!o.solid_outlines, "--no-solid-outlines".into()));
                    on.push((!o.own_solid, "--no-own-solid".into()));
                }
            }
            ShadowMethod::AthertonWeilerGreenberg(_) if paper => {}
            ShadowMethod::AthertonWeilerGreenberg(o) => {
                on.push((!o.convex_split, "--no-convex-split".into()));
                on.push((!o.backgrounds, "--no-backgrounds".into()));
                on.push((!o.lone_sheets, "--no-lone-sheets".into()));
                on.push((o.lone_sheets && !o.whole_solids, "--no-whole-solids".into()));
                on.push((!o.solid_cull, "--no-solid-cull".into()));
                on.push((!o.tiling, "--no-tiling".into()));
                on.push((!o.face_binning, "--no-face-binning".into()));
                on.push((!o.sort_grid, "--no-sort-grid".into()));
            }
            ShadowMethod::Crow(v) | ShadowMethod::StencilVolume(v) => {
                on.push((v.counting != volumes::Counting::ZPass, format!("--crow-count {}", v.counting.name())));
                if !paper {
                    let construction = v.construction != Construction::Merged;
                    on.push((construction, format!("--volumes {}", v.construction.name())));
                    on.push((!v.sight_cuts, "--no-sight-cuts".into()));
                    on.push((!v.far_outline, "--no-far-outline".into()));
                    on.push((v.far_outline && !v.front_outline, "--no-front-outline".into()));
                }
            }
            ShadowMethod::Williams(o) => on.extend(o.flags().into_iter().map(|f| (true, f))),
            ShadowMethod::NishitaNakamae(_) if paper => {}
            ShadowMethod::NishitaNakamae(o) => {
                on.push((!o.hull_cull, "--no-hull-cull".into()));
                on.push((!o.solid_cull, "--no-solid-cull".into()));
                on.push((!o.convex_bodies, "--no-convex-bodies".into()));
                on.push((!o.same_solid, "--no-same-solid".into()));
                on.push((!o.premise_fallback, "--no-premise-fallback".into()));
                on.push((!o.lambert, "--no-lambert".into()));
            }
            ShadowMethod::None | ShadowMethod::RayCast | ShadowMethod::Planar => {}
        }
        let mut flags = vec![self.name().to_string()];
        flags.extend(on.into_iter().filter(|(set, _)| *set).map(|(_, f)| f));
        flags.join(" ")
    }

    /// Whether the method runs as its paper publishes it: [`ShadowMethod::as_published`]
    /// leaves it unchanged and it has steps of ours to leave out (a paper path).
    pub fn is_paper(&self) -> bool {
        self.has_paper_path() && self.as_published() == *self
    }

    /// Whether the method has a paper path that differs from its engineered default.
    pub fn has_paper_path(&self) -> bool {
        matches!(
            self,
            ShadowMethod::BouknightKelley(_)
                | ShadowMethod::AthertonWeilerGreenberg(_)
                | ShadowMethod::Crow(_)
                | ShadowMethod::StencilVolume(_)
                | ShadowMethod::NishitaNakamae(_)
        )
    }

    /// The method's name in reports: its command-line name, with " (paper)" for a paper
    /// path.
    pub fn label(&self) -> String {
        if self.is_paper() {
            format!("{} (paper)", self.name())
        } else {
            self.name().to_string()
        }
    }

    /// Whether the method gives the exact answer of `docs/scene-format.md` §3 on every
    /// valid scene: every method but the approximate ones, shadow volumes counted by the
    /// naive z-pass, Crow's 1977 construction (exact only where its preconditions hold) and
    /// z-fail uncut (wrong where the camera's far plane cuts a volume).
    pub fn is_exact(&self) -> bool {
        match self {
            ShadowMethod::None | ShadowMethod::Williams(_) | ShadowMethod::Planar => false,
            ShadowMethod::Crow(v) | ShadowMethod::StencilVolume(v) => {
                v.counting != volumes::Counting::NaiveZPass
                    && v.construction != Construction::Crow1977
                    && (v.sight_cuts || v.counting != volumes::Counting::ZFail)
            }
            ShadowMethod::NishitaNakamae(o) => o.premise_fallback,
            ShadowMethod::RayCast | ShadowMethod::BouknightKelley(_) | ShadowMethod::AthertonWeilerGreenberg(_) => true,
        }
    }

    /// Prepares the stage.
    pub(crate) fn prepare<'a>(
        &self,
        ctx: &'a ShadowContext<'a>,
        counters: &mut Counters,
    ) -> Result<Box<dyn ShadowStage + 'a>> {
        Ok(match self {
            ShadowMethod::None => Box::new(NoShadows),
            ShadowMethod::RayCast => Box::new(RayCastShadows::new(ctx, counters)),
            ShadowMethod::BouknightKelley(o) => Box::new(BouknightKelley::new(ctx, *o, counters)),
            ShadowMethod::Crow(o) => Box::new(Crow::new(ctx, *o, counters)),
            ShadowMethod::AthertonWeilerGreenberg(o) => Box::new(AthertonWeilerGreenberg::new(ctx, *o, counters)?),
            ShadowMethod::Williams(o) => Box::new(Williams::new(ctx, o, counters)?),
            ShadowMethod::StencilVolume(o) => Box::new(StencilVolume::new(ctx, *o, counters)?),
            ShadowMethod::Planar => Box::new(Planar::new(ctx, counters)?),
            ShadowMethod::NishitaNakamae(o) => Box::new(NishitaNakamae::new(ctx, *o, counters)),
        })
    }
}

crate::error::named!(ShadowMethod, "shadow method");

/// The `none` stage.
struct NoShadows;

impl ShadowStage for NoShadows {
    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        Box::new(NoShadows)
    }

    fn bytes(&self) -> usize {
        0
    }
}

impl ShadowWalker for NoShadows {
    fn lit(&mut self, _: usize, _: usize, _: u32, _: &Run, lit: &mut [f32]) {
        lit.fill(1.0);
    }
}
