//! Counters: what each stage did (after pbrt-v4's `util/stats.h`). Stages count into plain
//! local variables in their hot loops and add them here once per line or band.

use serde::Serialize;
use std::collections::BTreeMap;

/// What a stage counted, by [`Counter`]: only the counters it keeps, printed by name in name
/// order. A `_max` counter keeps the largest value added, the others the sum.
///
/// ```
/// use umbra::{generate, render, Counter, RenderOptions};
/// let out = render(&generate::cubes(2, generate::Faces::Quads, 64, 48)?, &RenderOptions::default())?;
/// assert!(out.stats.visibility_counters.get(Counter::Spans) > 0);
/// assert_eq!(out.stats.visibility_counters.get_named("spans"), Some(out.stats.visibility_counters.get(Counter::Spans)));
/// # Ok::<(), umbra::Error>(())
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Counters(BTreeMap<&'static str, u64>);

impl Counters {
    /// Adds `n` to `counter` (or raises it to `n` for a `_max` counter).
    pub fn add(&mut self, counter: Counter, n: u64) {
        self.add_named(counter.name(), n);
    }

    fn add_named(&mut self, name: &'static str, n: u64) {
        let v = self.0.entry(name).or_insert(0);
        if name.ends_with("_max") {
            *v = (*v).max(n);
        } else {
            *v += n;
        }
    }

    /// Adds every counter of `other`.
    pub fn merge(&mut self, other: &Counters) {
        for (&k, &v) in &other.0 {
            self.add_named(k, v);
        }
    }

    /// The value of `counter` (0 when never counted).
    pub fn get(&self, counter: Counter) -> u64 {
        self.0.get(counter.name()).copied().unwrap_or(0)
    }

    /// The value of the counter named `name`, if this record holds it (what `scale
    /// --counter` asks with a name from the command line).
    pub fn get_named(&self, name: &str) -> Option<u64> {
        self.0.get(name).copied()
    }

    /// All counters in name order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, u64)> + '_ {
        self.0.iter().map(|(&k, &v)| (k, v))
    }
}

/// Declares [`Counter`]: each counter once, with its name in reports and what it counts.
macro_rules! counters {
    ($($(#[doc = $doc:literal])+ $variant:ident = $name:literal,)+) => {
        /// Every counter a stage keeps, by what it counts. The stages that keep each are
        /// named in its description; `--stats`, `bench` and `scale --counter` print it by
        /// its name ([`Counter::name`]). A name ending in `_max` keeps the largest value
        /// instead of the sum.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[non_exhaustive]
        pub enum Counter {
            $($(#[doc = $doc])+ $variant,)+
        }

        impl Counter {
            /// Every counter.
            pub const ALL: &'static [Counter] = &[$(Counter::$variant,)+];

            /// Its name in reports (`depth_tests`).
            pub fn name(&self) -> &'static str {
                match self {
                    $(Counter::$variant => $name,)+
                }
            }
        }
    };
}

counters! {
    /// Visibility, all stages: the polygons left after clipping and projecting to the screen.
    ScreenPolygons = "screen_polygons",
    /// Visibility, all stages: the visible runs handed to the shadow stage.
    Runs = "runs",
    /// Watkins: the polygons entered in the bands' edge tables, summed over bands.
    BandMembers = "band_members",
    /// Watkins: the edges in the bands' edge tables.
    Edges = "edges",
    /// Watkins: the edges that entered the active edge table.
    EdgesEntered = "edges_entered",
    /// Watkins: the spans the active edges cut the lines into.
    Spans = "spans",
    /// Watkins: the spans split where the nearest polygon differs at their two ends.
    SpanSplits = "span_splits",
    /// Watkins and the z-buffer: depth comparisons.
    DepthTests = "depth_tests",
    /// Watkins: the most active edges on one line.
    ActiveEdgesMax = "active_edges_max",
    /// Watkins: the most working memory of one band (its table, active edges, spans, runs), bytes.
    BandBytesMax = "band_bytes_max",
    /// Z-buffer: depth writes.
    DepthWrites = "depth_writes",
    /// Every shadow stage: the bytes its prepared stage holds through the walk (shadow
    /// polygons' edge tables, planes and outlines, detail polygons, depth maps, masks and
    /// buffers, a ray-caster's hierarchy), the walkers' per-band scratch not included.
    StageBytes = "stage_bytes",
    /// Z-buffer: the bytes of its depth and id buffers.
    BufferBytes = "buffer_bytes",
    /// Bouknight-Kelley: the bytes of the front sets and solids' trees kept for the scene's
    /// polygons (`own_solid`).
    OwnSolidBytes = "own_solid_bytes",
    /// Ray-cast visibility: the rays cast, one per pixel.
    Rays = "rays",
    /// Bouknight-Kelley: ordered pairs of polygons, n(n − 1), per light sample; Nishita-Nakamae:
    /// the receiver-caster pairs its candidate search found.
    Pairs = "pairs",
    /// Bouknight-Kelley: casters dropped because they face away from the light on a closed solid.
    CastersDroppedFacingAway = "casters_dropped_facing_away",
    /// Bouknight-Kelley, planar and Nishita-Nakamae: the receivers, per light (sample).
    Receivers = "receivers",
    /// Bouknight-Kelley and ray-cast: the polygons that cast shadows.
    Casters = "casters",
    /// Bouknight-Kelley: receivers times casters, the pairs the prefilter starts from.
    PairsWithRoles = "pairs_with_roles",
    /// Bouknight-Kelley: microseconds spent building the prefilter's sphere grid.
    PrefilterGridUs = "prefilter_grid_us",
    /// Bouknight-Kelley: the pairs the sphere prefilter kept.
    PairsKeptByPrefilter = "pairs_kept_by_prefilter",
    /// Bouknight-Kelley: the pairs the prefilter tested (without its sphere grid).
    PairsTestedByPrefilter = "pairs_tested_by_prefilter",
    /// Bouknight-Kelley: receivers that took only their front set of their own closed
    /// solid's casters (`own_solid`).
    ReceiversOnOwnSolid = "receivers_on_own_solid",
    /// Bouknight-Kelley: the polygons of those front sets, summed over the receivers.
    OwnSolidFront = "own_solid_front",
    /// Bouknight-Kelley: kept pairs whose caster lies wholly behind the receiver from the light.
    PairsDroppedBehind = "pairs_dropped_behind",
    /// Bouknight-Kelley: kept pairs whose caster's shadow misses the receiver (the wedge test).
    PairsOutsideReceiver = "pairs_outside_receiver",
    /// Bouknight-Kelley: kept pairs whose caster lies apart from the hull of the light and
    /// the receiver (the slab test).
    PairsApart = "pairs_apart",
    /// Bouknight-Kelley: the (receiver, closed solid) pairs whose shadow polygons were counted
    /// as the outline of their union.
    SolidOutlines = "solid_outlines",
    /// Bouknight-Kelley: kept pairs whose caster was counted in its solid's outline, not
    /// projected on its own.
    PairsOutlined = "pairs_outlined",
    /// Bouknight-Kelley: projections that left no shadow polygon on the receiver.
    ProjectionsEmpty = "projections_empty",
    /// Bouknight-Kelley and planar: the shadow polygons made.
    ShadowPolygons = "shadow_polygons",
    /// Bouknight-Kelley: CPU microseconds in the prefilter, summed over threads.
    PrefilterCpuUs = "prefilter_cpu_us",
    /// Bouknight-Kelley: CPU microseconds projecting shadows, summed over threads.
    ProjectionCpuUs = "projection_cpu_us",
    /// Bouknight-Kelley: the scan segments examined.
    SegmentsExamined = "segments_examined",
    /// Bouknight-Kelley: the segments split at a shadow polygon's edge.
    SegmentSplits = "segment_splits",
    /// Bouknight-Kelley: the deepest recursion of a segment's splits.
    RecursionDepthMax = "recursion_depth_max",
    /// Crow: the runs whose count was taken.
    RunsCounted = "runs_counted",
    /// Crow: the additions to the count along the runs (a shadow polygon entering or leaving).
    Events = "events",
    /// Crow: the runs split where the count changes.
    RunsSplit = "runs_split",
    /// Crow's 1977 construction by z-pass: the volumes that hold the eye.
    EyeCount = "eye_count",
    /// Shadow volumes: the edges the merged (Bergeron) volumes share between polygons.
    MergedEdges = "merged_edges",
    /// Shadow volumes: the polygons whose volumes stand apart (no shared edge).
    PolygonsApart = "polygons_apart",
    /// Shadow volumes: the sides of weight 1.
    SidesWeight1 = "sides_weight_1",
    /// Shadow volumes: the sides of weight 2 (an edge that two volumes share, counted once twice).
    SidesWeight2 = "sides_weight_2",
    /// Shadow volumes: the volume polygons on the screen.
    ScreenShadowPolygons = "screen_shadow_polygons",
    /// Shadow volumes: the sides made, on edges pushed away from the light.
    ShadowPolygonsSide = "shadow_polygons_side",
    /// Shadow volumes: the front caps made (polygons facing the light).
    ShadowPolygonsFrontCap = "shadow_polygons_front_cap",
    /// Shadow volumes: the back caps made (front caps pushed to infinity away from the light).
    ShadowPolygonsBackCap = "shadow_polygons_back_cap",
    /// Shadow volumes: the volumes' cross-sections with the near plane.
    ShadowPolygonsNearCap = "shadow_polygons_near_cap",
    /// Shadow volumes: the cross-sections with the far plane that closes z-fail's volumes.
    ShadowPolygonsFarCap = "shadow_polygons_far_cap",
    /// Shadow volumes: the screen edges left of the far caps once those two casters share
    /// cancel (z-fail's far outline, ours).
    FarOutlineEdges = "far_outline_edges",
    /// Shadow volumes: the sides cut away where no line of sight can reach them.
    SidesOutsideSight = "sides_outside_sight",
    /// Stencil volumes: writes to the stencil buffer.
    StencilWrites = "stencil_writes",
    /// Ray-cast shadows: the shadow rays cast.
    ShadowRays = "shadow_rays",
    /// Williams: orthographic maps (directional lights).
    MapsOrtho = "maps_ortho",
    /// Williams: perspective maps (a light whose scene fits one frustum).
    MapsPerspective = "maps_perspective",
    /// Williams: cube faces (six per light sample that needs a cube).
    MapsCubeFaces = "maps_cube_faces",
    /// Williams: the texels of one map.
    MapTexels = "map_texels",
    /// Williams: lookups in the maps.
    MapLookups = "map_lookups",
    /// Atherton-Weiler-Greenberg: the fragments of pass 1's sort in light space.
    LightSpaceFragments = "light_space_fragments",
    /// Atherton-Weiler-Greenberg: Weiler-Atherton clip operations.
    ClipOperations = "clip_operations",
    /// Atherton-Weiler-Greenberg: polygons split where they interpenetrate.
    InterpenetrationSplits = "interpenetration_splits",
    /// Atherton-Weiler-Greenberg: the deepest recursion of the area sort.
    AreaSortDepthMax = "area_sort_depth_max",
    /// Atherton-Weiler-Greenberg: the tiles the light view was cut into.
    LightViewTiles = "light_view_tiles",
    /// Atherton-Weiler-Greenberg: backgrounds found in the light view (a polygon behind all others).
    LightViewBackgrounds = "light_view_backgrounds",
    /// Atherton-Weiler-Greenberg: lone polygons in the light view (overlapping none).
    LightViewLone = "light_view_lone",
    /// Atherton-Weiler-Greenberg: closed solids whose side facing the light was found lone
    /// whole, without its polygons being mapped one by one (ours).
    LightViewWholeSolids = "light_view_whole_solids",
    /// Atherton-Weiler-Greenberg: lit detail polygons.
    DetailPolygons = "detail_polygons",
    /// Atherton-Weiler-Greenberg: their vertices.
    DetailVertices = "detail_vertices",
    /// Atherton-Weiler-Greenberg: microseconds of pass 1.
    Pass1Us = "pass1_us",
    /// Atherton-Weiler-Greenberg: detail polygons on the screen.
    DetailPolygonsInView = "detail_polygons_in_view",
    /// Nishita-Nakamae: umbra polygons on the receivers.
    UmbraPolygons = "umbra_polygons",
    /// Nishita-Nakamae: penumbra polygons on the receivers.
    PenumbraPolygons = "penumbra_polygons",
    /// Nishita-Nakamae: receivers whose every pixel is clipped (a premise fails there).
    ReceiversSearchedEverywhere = "receivers_searched_everywhere",
    /// Nishita-Nakamae: pixels dark a span at a time (inside an umbra polygon).
    UmbraPixelsAtOnce = "umbra_pixels_at_once",
    /// Nishita-Nakamae: pixels lit a span at a time (outside every penumbra polygon).
    LitPixelsAtOnce = "lit_pixels_at_once",
    /// Nishita-Nakamae: pixels whose visible part of the light was clipped out and measured.
    PenumbraPixelsClipped = "penumbra_pixels_clipped",
    /// Nishita-Nakamae: the parts hidden from the light at those pixels (shadows and cuts).
    LightPartsHidden = "light_parts_hidden",
    /// Nishita-Nakamae: convex solids' shadows taken as one hull.
    ConvexSolidShadows = "convex_solid_shadows",
    /// Every stage: runs the same-side rule settled before the stage was asked (the light
    /// behind the seen side).
    SelfShadowedRuns = "self_shadowed_runs",
    /// Every stage: runs no light reaches at any pixel (in shadow, or turned from every
    /// light), shaded as their ambient term alone (ours).
    DarkRuns = "dark_runs",
    /// Every stage, area lights: pixels in the umbra (seed 000's, of the grid or exact).
    UmbraPixels = "umbra_pixels",
    /// Every stage, area lights: pixels in the penumbra.
    PenumbraPixels = "penumbra_pixels",
}

crate::error::named!(Counter, "counter");

/// What a render did: the methods, the counters of each stage and the time of each step.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Stats {
    /// Visibility method name.
    pub visibility: String,
    /// Shadow method name.
    pub shadows: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// World polygons in the scene.
    pub polygons: usize,
    /// Light samples over all lights.
    pub light_samples: usize,
    /// Visibility counters.
    pub visibility_counters: Counters,
    /// Shadow counters.
    pub shadow_counters: Counters,
    /// Milliseconds per step (wall clock).
    pub time_ms: Times,
}

/// Milliseconds per step of a render (wall clock). The walk and the shading run line by line
/// in the same parallel pass; that pass's wall-clock time is split between them in the
/// proportion of their summed per-band times.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Times {
    /// Clipping and projecting the polygons.
    pub view: f64,
    /// Preparing the visibility stage and resolving every line into runs.
    pub visibility: f64,
    /// Preparing the shadow stage.
    pub shadow_prepare: f64,
    /// The shadow stage's per-line walk: which pixels of each run every light sample reaches.
    pub shadow_walk: f64,
    /// Shading every run.
    pub shading: f64,
    /// Rendering what the mirrors show, when a mirror is seen.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reflections: Option<f64>,
    /// The whole frame.
    pub total: f64,
}

impl Times {
    /// Each step but the total, by name, in the pipeline's order (`reflections` when there
    /// was one).
    pub fn steps(&self) -> impl Iterator<Item = (&'static str, f64)> {
        let steps = [
            ("view", Some(self.view)),
            ("visibility", Some(self.visibility)),
            ("shadow_prepare", Some(self.shadow_prepare)),
            ("shadow_walk", Some(self.shadow_walk)),
            ("shading", Some(self.shading)),
            ("reflections", self.reflections),
        ];
        steps.into_iter().filter_map(|(k, v)| Some((k, v?)))
    }
}
