//! Crow's shadow volumes (F. C. Crow, "Shadow algorithms for computer graphics", SIGGRAPH
//! 1977), counted per span as a scanline renderer does it.
//!
//! The shadow polygons that bound each light sample's volumes ([`super::volumes`]) are put
//! into screen space and walked along the scanlines with the shared edge and active-edge
//! tables as invisible surfaces. Crow's rule: along the line of sight, +1 for a shadow polygon
//! facing the viewer, −1 for one facing away; a point is in shadow when the count is above
//! zero.
//!
//! For a visible run on polygon B, the count can change only at an *event*: where a shadow
//! polygon's edge crosses the scanline (it starts or stops covering the run), or where a
//! shadow polygon's plane crosses B's plane (it passes from in front of the visible surface
//! to behind it; both inverse depths are linear along the line, so the crossing is found
//! exactly). The run is split at its events and the count taken once per piece.
//!
//! - **z-pass**: the shadow polygons between the eye and the visible point, starting from
//!   the eye's own count — the near caps put that in, pixel by pixel, as polygons at the near
//!   plane that every visible point lies behind.
//! - **z-fail**: the shadow polygons behind the visible point, signs reversed (counting from
//!   infinity toward the eye), with the volumes capped. Where a far plane closes them, the
//!   far caps count together, as the winding number of their union's outline, walked from an
//!   edge table of its own ([`super::far_outline`], ours).
//! - **naive z-pass**: z-pass from zero. Wrong wherever the near plane is inside a volume
//!   (the "Rendering 6: Shadow" notes' failure), on purpose.
//!
//! A front cap that is the visible polygon itself lies exactly at the visible point: z-pass
//! takes it as not in front, z-fail as behind, as a depth test `<` would. A per-polygon
//! volume never counts for its own face.

use super::volumes::{Adjacency, Counting, ScreenVolumes};
use super::{
    Construction, CountAdd, Decision, Detail, ShadowContext, ShadowStage, ShadowWalker, VolumeOptions, FAR_CAPS,
};
use crate::scan::{boundary, ActiveEdges, EdgeTable, OpenSet};
use crate::stats::Counters;
use crate::visibility::Run;
use glam::DVec2;

/// One light sample's shadow polygons, ready to walk.
struct SampleVolumes {
    table: EdgeTable,
    volumes: ScreenVolumes,
    /// Z-fail's far outline (ours, [`super::far_outline`]): its edges, each tagged with the
    /// weight its crossing adds to the count (an `i32`'s bits); empty without it.
    far: EdgeTable,
}

/// The prepared stage.
pub struct Crow<'a> {
    ctx: &'a ShadowContext<'a>,
    counting: Counting,
    samples: Vec<SampleVolumes>,
}

impl<'a> Crow<'a> {
    /// Builds every light sample's shadow polygons and their edge tables.
    pub fn new(ctx: &'a ShadowContext<'a>, options: VolumeOptions, counters: &mut Counters) -> Self {
        let counting = options.counting;
        let view = ctx.view;
        let adjacency = Adjacency::kept(ctx.scene, options.construction != Construction::PerPolygon, &ctx.pools.stash);
        let samples = ctx
            .all_samples()
            .map(|(_, _, sample)| {
                let mut volumes = ScreenVolumes::new(ctx, &adjacency, sample, options, counters);
                // Sorted as it is made, with no unsorted list beside it (ours; z-fail puts
                // more than two million edges into s3's table).
                let table = EdgeTable::of_rings(view.height, &volumes.rings);
                let far = super::far_outline::table(view.height, &volumes.far);
                // The walk reads the tables and the polygons' planes: the outlines are kept
                // for a study alone (ours).
                if !ctx.keep_outlines {
                    volumes.rings = Default::default();
                    volumes.far = Vec::new();
                }
                SampleVolumes { table, volumes, far }
            })
            .collect();
        Crow { ctx, counting, samples }
    }
}

impl ShadowStage for Crow<'_> {
    fn bytes(&self) -> usize {
        self.samples.iter().map(|s| s.table.bytes() + s.volumes.bytes() + s.far.bytes()).sum()
    }

    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        let h = self.ctx.view.height;
        Box::new(Walker {
            stage: self,
            lines: self
                .samples
                .iter()
                .map(|s| LineState {
                    aet: ActiveEdges::new(&s.table, 0..h),
                    xs: Vec::new(),
                    cursor: 0,
                    open: OpenSet::new(s.volumes.polys.len()),
                    far: FarLine { aet: ActiveEdges::new(&s.far, 0..h), xs: Vec::new(), cursor: 0, winding: 0 },
                })
                .collect(),
            events: Vec::new(),
            sweep: Sweep::default(),
            last_pieces: Vec::new(),
            last_counts: Vec::new(),
            last_adds: Vec::new(),
            yc: 0.0,
            runs: 0,
            events_total: 0,
            split: 0,
        })
    }

    /// The first sample's shadow polygons, then its far outline's edges, each as a ring of
    /// two points.
    fn outlines(&self) -> Vec<Vec<DVec2>> {
        if !self.ctx.keep_outlines {
            return Vec::new();
        }
        let Some(s) = self.samples.first() else { return Vec::new() };
        let polys = s.volumes.rings.iter().map(<[DVec2]>::to_vec);
        polys.chain(s.volumes.far.iter().map(|e| vec![e.lo, e.hi])).collect()
    }
}

/// One sample's walk along the current line: its crossings as (first pixel, polygon), and
/// which polygons cover the pixel the walk has reached.
struct LineState<'a> {
    aet: ActiveEdges<'a>,
    xs: Vec<(u32, u32)>,
    cursor: usize,
    open: OpenSet,
    far: FarLine<'a>,
}

/// One sample's walk along its far outline on the current line: the crossings as (first
/// pixel, weight), and the winding number at the pixel the walk has reached.
struct FarLine<'a> {
    aet: ActiveEdges<'a>,
    xs: Vec<(u32, i32)>,
    cursor: usize,
    winding: i32,
}

impl FarLine<'_> {
    /// What the far caps add along `run` (ours), onto `events`: the winding number at its
    /// first pixel, then the weight of each crossing inside it.
    fn events_in(&mut self, run: &Run, events: &mut Vec<(u32, i32)>) {
        while self.cursor < self.xs.len() && self.xs[self.cursor].0 <= run.x0 {
            self.winding += self.xs[self.cursor].1;
            self.cursor += 1;
        }
        if self.winding != 0 {
            events.push((run.x0, self.winding));
        }
        while self.cursor < self.xs.len() && self.xs[self.cursor].0 < run.x1 {
            let (at, w) = self.xs[self.cursor];
            events.push((at, w));
            self.winding += w;
            self.cursor += 1;
        }
    }
}

impl LineState<'_> {
    /// Step 1, the pairing: the pieces of `run` each shadow polygon covers, as (polygon,
    /// first pixel, end), by walking the line's crossings to the run's end.
    fn pieces_in(&mut self, run: &Run, pieces: &mut Vec<(u32, u32, u32)>) {
        // Bring the walk to the run's first pixel: the open polygons then cover it.
        while self.cursor < self.xs.len() && self.xs[self.cursor].0 <= run.x0 {
            let (_, t) = self.xs[self.cursor];
            self.open.toggle(t, run.x0);
            self.cursor += 1;
        }
        self.open.restart_at(run.x0);
        pieces.clear();
        while self.cursor < self.xs.len() && self.xs[self.cursor].0 < run.x1 {
            let (at, t) = self.xs[self.cursor];
            if let Some(start) = self.open.toggle(t, at) {
                pieces.push((t, start, at));
            }
            self.cursor += 1;
        }
        pieces.extend(self.open.open().map(|(t, s)| (t, s, run.x1)));
    }
}

/// The sweep's scratch, all zero between runs: each pixel's change of count, and a bit per
/// pixel where an event falls.
#[derive(Default)]
struct Sweep {
    changes: Vec<i32>,
    marks: Vec<u64>,
}

struct Walker<'s> {
    stage: &'s Crow<'s>,
    lines: Vec<LineState<'s>>,
    events: Vec<(u32, i32)>,
    /// Scratch for the sweep.
    sweep: Sweep,
    /// The last run's coverage pieces (polygon, start, end) and its counted pieces.
    last_pieces: Vec<(u32, u32, u32)>,
    last_counts: Vec<(u32, u32, i32)>,
    /// What each piece added to the count over the last run.
    last_adds: Vec<CountAdd>,
    yc: f64,
    runs: u64,
    events_total: u64,
    split: u64,
}

impl Walker<'_> {
    /// Step 2, the plane crossings: where each covering piece starts and stops adding to the
    /// count along the run (`events`), a piece whose shadow polygon crosses the run's plane
    /// inside it being cut at the first pixel that counts differently.
    /// The run's depth plane is worked out only when a piece covers it (ours: most runs have
    /// none).
    fn count_events(&mut self, k: usize, run: &Run, pieces: &[(u32, u32, u32)]) {
        self.events.clear();
        self.last_adds.clear();
        let polys = &self.stage.samples[k].volumes.polys;
        let (b, poly) = (run.poly, &self.stage.ctx.scene.polygons[run.poly as usize]);
        if pieces.is_empty() {
            return;
        }
        let Some(bd) = self.stage.ctx.view.depth_plane(&poly.plane) else { return };
        let face = poly.face;
        let (counting, yc, record) = (self.stage.counting, self.yc, self.stage.ctx.keep_outlines);
        for &(t, s, e) in pieces.iter().filter(|p| p.1 < p.2) {
            let p = &polys[t as usize];
            // What polygon p adds to the count at pixel x (see `count_at`).
            let counts = |x: u32| {
                let xc = x as f64 + 0.5;
                p.count_at(counting, b, face, xc, yc, bd.inv_z(xc, yc))
            };
            let (first, last) = (counts(s), counts(e - 1));
            let (events, adds) = (&mut self.events, &mut self.last_adds);
            let mut add = |a: u32, z: u32, c: i32| {
                if a < z && c != 0 {
                    events.push((a, c));
                    events.push((z, -c));
                    // Kept for traces only: a render never asks for them.
                    if record {
                        let near_cap = p.near_cap;
                        adds.push(CountAdd { polygon: t, start: a, end: z, add: c, near_cap, far_caps: false });
                    }
                }
            };
            if first == last {
                add(s, e, first);
                continue;
            }
            // The planes cross inside [s, e): find the first pixel that counts differently.
            let (l, r) = (p.depth, bd);
            let x_star = ((r.b - l.b) * yc + (r.c - l.c)) / (l.a - r.a);
            let mut m = if x_star.is_finite() { boundary(x_star, u32::MAX).clamp(s + 1, e - 1) } else { s + 1 };
            while m > s + 1 && counts(m - 1) != first {
                m -= 1;
            }
            while m < e - 1 && counts(m) == first {
                m += 1;
            }
            add(s, m, first);
            add(m, e, last);
        }
    }

    /// For traces: what the far caps add along `run`, from their events (`self.events[from..]`,
    /// in order), as one [`CountAdd`] per stretch where it is constant and not zero.
    fn record_far(&mut self, run: &Run, from: usize) {
        let mut add = 0;
        let mut start = run.x0;
        for i in from..=self.events.len() {
            let (at, change) = self.events.get(i).copied().unwrap_or((run.x1, 0));
            if at > start && add != 0 {
                self.last_adds.push(CountAdd {
                    polygon: FAR_CAPS,
                    start,
                    end: at,
                    add,
                    near_cap: false,
                    far_caps: true,
                });
            }
            (add, start) = (add + change, start.max(at));
        }
    }

    /// Step 3, the count: swept along the run, constant between events; a pixel is in
    /// shadow where it is above zero. The events are summed into the pixels where they fall
    /// and those pixels marked in a bit set, which is then read in order: no sorting, and
    /// time in the number of events, not of pixels.
    fn sweep(&mut self, run: &Run, lit: &mut [f32]) {
        self.runs += 1;
        self.events_total += self.events.len() as u64;
        self.last_counts.clear();
        let len = (run.x1 - run.x0) as usize;
        let Sweep { changes, marks } = &mut self.sweep;
        if changes.len() <= len {
            changes.resize(len + 1, 0);
            marks.resize((len + 1).div_ceil(64), 0);
        }
        for &(x, c) in &self.events {
            let at = ((x - run.x0) as usize).min(len);
            changes[at] += c;
            marks[at / 64] |= 1 << (at % 64);
        }
        let (mut count, mut start) = (0i32, 0usize);
        for (word, bits) in marks[..(len + 1).div_ceil(64)].iter_mut().enumerate() {
            while *bits != 0 {
                let at = word * 64 + bits.trailing_zeros() as usize;
                *bits &= *bits - 1;
                let change = std::mem::take(&mut changes[at]);
                // An event at the run's end changes nothing in it.
                if at == len {
                    continue;
                }
                if at > start {
                    lit[start..at].fill(if count > 0 { 0.0 } else { 1.0 });
                    self.last_counts.push((run.x0 + start as u32, run.x0 + at as u32, count));
                    start = at;
                }
                count += change;
            }
        }
        lit[start..len].fill(if count > 0 { 0.0 } else { 1.0 });
        self.last_counts.push((run.x0 + start as u32, run.x1, count));
        if self.last_counts.len() > 1 {
            self.split += 1;
        }
    }
}

impl ShadowWalker for Walker<'_> {
    fn start_line(&mut self, line: u32) {
        self.yc = line as f64 + 0.5;
        let width = self.stage.ctx.view.width;
        for st in &mut self.lines {
            let xs = st.aet.advance_to(line);
            st.xs.clear();
            st.xs.extend(xs.iter().map(|c| (boundary(c.x, width), c.tag)));
            st.cursor = 0;
            st.open.clear();
            let far = &mut st.far;
            let xs = far.aet.advance_to(line);
            far.xs.clear();
            far.xs.extend(xs.iter().map(|c| (boundary(c.x, width), c.tag as i32)));
            (far.cursor, far.winding) = (0, 0);
        }
    }

    fn lit(&mut self, light: usize, sample: usize, _line: u32, run: &Run, lit: &mut [f32]) {
        let k = self.stage.ctx.sample_index(light, sample);
        let ctx = self.stage.ctx;
        if ctx.view.edge_on(&ctx.scene.polygons[run.poly as usize].plane) {
            lit.fill(1.0);
            return;
        }
        let mut pieces = std::mem::take(&mut self.last_pieces);
        self.lines[k].pieces_in(run, &mut pieces);
        self.count_events(k, run, &pieces);
        let from = self.events.len();
        self.lines[k].far.events_in(run, &mut self.events);
        if self.stage.ctx.keep_outlines {
            self.record_far(run, from);
        }
        self.last_pieces = pieces;
        self.sweep(run, lit);
    }

    fn decision(&self) -> Decision {
        let counts: Vec<String> = self.last_counts.iter().map(|(a, b, c)| format!("{a}..{b}: {c}")).collect();
        let far: Vec<String> = self
            .last_adds
            .iter()
            .filter(|a| a.far_caps)
            .map(|a| format!("{}..{}: {}", a.start, a.end, a.add))
            .collect();
        let far = if far.is_empty() { String::new() } else { format!("; the far caps add [{}]", far.join(", ")) };
        Decision {
            tested: self.last_pieces.iter().map(|&(_, s, e)| (s, e, 1)).collect(),
            note: format!(
                "{} shadow polygon piece(s) cover the run, {} event(s){far}; counts [{}]",
                self.last_pieces.len(),
                self.events.len(),
                counts.join(", ")
            ),
            detail: Detail::Counts { adds: self.last_adds.clone(), counts: self.last_counts.clone() },
        }
    }

    fn finish(&mut self, counters: &mut Counters) {
        counters.add(crate::stats::Counter::RunsCounted, self.runs);
        counters.add(crate::stats::Counter::Events, self.events_total);
        counters.add(crate::stats::Counter::RunsSplit, self.split);
    }
}
