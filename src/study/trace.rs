//! `umbra trace`: what Watkins' algorithm and the shadow stage did on one scanline — the
//! edges entering and leaving, the active edge table in order, each span with the polygons
//! covering it, their depths at its ends and where it was split, the runs, and for every run
//! and light sample the shadow stage's decision.

use crate::error::{Error, Result};
use crate::scan::ActiveEdges;
use crate::scene::Scene;
use crate::shadow::{Decision, Picture, ShadowContext, ShadowMethod, ShadowStage, ShadowWalker};
use crate::stats::Counters;
use crate::view::{Screen, View};
use crate::visibility::{resolve, Run, ScanlineVisibility, SpanRecord, Visibility};
use serde::Serialize;
use std::fmt::Write as _;
use std::ops::Range;

/// An edge of the edge table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EdgeTrace {
    /// Scene polygon.
    pub polygon: u32,
    /// Its face id.
    pub face: u32,
    /// First line it is active on.
    pub first_line: u32,
    /// First line it is no longer active on.
    pub end_line: u32,
    /// Its top vertex.
    pub top: (f64, f64),
    /// dx/dy.
    pub dxdy: f64,
}

/// One run's shadow decision for one light sample.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShadowTrace {
    /// Light.
    pub light: usize,
    /// Sample.
    pub sample: usize,
    /// The run.
    pub x0: u32,
    /// The run.
    pub x1: u32,
    /// The run's polygon.
    pub polygon: u32,
    /// The lit value over the run, as pieces `(start, end, value)`.
    pub lit: Vec<(u32, u32, f32)>,
    /// `false` when the same-side rule settled it (light behind the seen side).
    pub asked_stage: bool,
    /// The stage's decision.
    pub decision: Decision,
}

/// Everything done on one line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LineTrace {
    /// The line.
    pub line: u32,
    /// Shadow stage traced.
    pub shadows: String,
    /// Edges whose first line this is.
    pub entering: Vec<EdgeTrace>,
    /// Edges active on the line before and not on this one.
    pub leaving: Vec<EdgeTrace>,
    /// The active edge table in order: (x of the crossing, scene polygon).
    pub active: Vec<(f64, u32)>,
    /// The spans as resolved.
    pub spans: Vec<SpanRecord>,
    /// The runs handed on.
    pub runs: Vec<Run>,
    /// The shadow stage's decisions.
    pub decisions: Vec<ShadowTrace>,
}

/// Traces line `line` of `scene` with scanline visibility and the shadow stage `shadows`
/// (which keeps its polygons' outlines and what became of them, for the trace to show).
pub fn trace(scene: &Scene, line: u32, shadows: &ShadowMethod) -> Result<LineTrace> {
    let mut out = None;
    trace_lines(scene, line..line + 1, shadows, |t| {
        out = Some(t);
        Ok(())
    })?;
    out.ok_or_else(|| Error::Internal(format!("line {line} was not traced")))
}

/// Traces every line of `lines` in order, handing each to `emit`; the shadow stage is
/// prepared once.
pub fn trace_lines(
    scene: &Scene,
    lines: Range<u32>,
    shadows: &ShadowMethod,
    mut emit: impl FnMut(LineTrace) -> Result<()>,
) -> Result<()> {
    let view = View::new(&scene.camera);
    if lines.end > view.height || lines.is_empty() {
        let line = lines.end.saturating_sub(1).max(lines.start);
        return Err(Error::out_of_range("line", line, format!("inside the image (height {})", view.height)));
    }
    with_stage(scene, &view, shadows, |screen, vis, ctx, stage| {
        let edge = |e: (u32, u32, u32, f64, f64, f64)| {
            let poly = screen[e.0].poly;
            EdgeTrace {
                polygon: poly,
                face: scene.polygons[poly as usize].face,
                first_line: e.1,
                end_line: e.2,
                top: (e.3, e.4),
                dxdy: e.5,
            }
        };
        let (mut entering, mut leaving) = (vec![Vec::new(); lines.len()], vec![Vec::new(); lines.len()]);
        let table = vis.whole_table();
        for e in table.edges() {
            for (at, list) in [(e.1, &mut entering), (e.2, &mut leaving)] {
                if lines.contains(&at) {
                    list[(at - lines.start) as usize].push(edge(e));
                }
            }
        }
        let mut visible = Vec::with_capacity(lines.len());
        vis.walk_recorded(lines.clone(), &mut |_, r, s| visible.push((r.to_vec(), s.to_vec())));
        let mut walker = stage.walker();
        for y in 0..lines.start {
            walker.start_line(y);
        }
        let mut aet = ActiveEdges::new(&table, lines.clone());
        let rows = visible.into_iter().zip(entering).zip(leaving);
        for (line, (((runs, spans), entering), leaving)) in lines.clone().zip(rows) {
            walker.start_line(line);
            let active = aet.advance_to(line).iter().map(|c| (c.x, screen[c.tag].poly)).collect();
            let decisions = decide(ctx, walker.as_mut(), line, &runs);
            let shadows = shadows.label();
            emit(LineTrace { line, shadows, entering, leaving, active, spans, runs, decisions })?;
        }
        Ok(())
    })
}

/// The pictures the shadow stage `shadows` builds for `scene` (Williams: its depth maps).
pub fn pictures(scene: &Scene, shadows: &ShadowMethod) -> Result<Vec<Picture>> {
    let view = View::new(&scene.camera);
    with_stage(scene, &view, shadows, |_, _, _, stage| Ok(stage.pictures()))
}

/// Prepares what a render prepares before its walk (the screen polygons, Watkins'
/// visibility, the runs, the shadow stage) and hands it to `f`.
fn with_stage<T>(
    scene: &Scene,
    view: &View,
    shadows: &ShadowMethod,
    f: impl FnOnce(&Screen, &ScanlineVisibility, &ShadowContext, &dyn ShadowStage) -> Result<T>,
) -> Result<T> {
    let screen = view.screen_polygons(scene);
    let mut counters = Counters::default();
    let vis = ScanlineVisibility::new(scene, &screen, view, &Default::default(), &mut counters);
    let frame_runs = resolve(&vis as &dyn Visibility, view.height, &mut counters);
    let ctx = ShadowContext::new(scene, view, &frame_runs, true);
    let stage = shadows.prepare(&ctx, &mut counters)?;
    f(&screen, &vis, &ctx, stage.as_ref())
}

/// The shadow stage's decision for every run of `line` and every light sample, through the
/// render's own walk.
fn decide(ctx: &ShadowContext, walker: &mut dyn ShadowWalker, line: u32, runs: &[Run]) -> Vec<ShadowTrace> {
    let mut decisions = Vec::new();
    let mut lit = vec![0.0f32; ctx.view.width as usize * ctx.lit_rows()];
    crate::render::walk_line(ctx, walker, line, runs, &mut lit, |run, l, s, asked, walker, lit| {
        let decision = if asked {
            walker.decision()
        } else {
            let note = "the light is behind the seen side: in shadow".into();
            Decision { tested: Vec::new(), note, detail: Default::default() }
        };
        let mut pieces: Vec<(u32, u32, f32)> = Vec::new();
        for (i, &v) in lit.iter().enumerate() {
            let x = run.x0 + i as u32;
            match pieces.last_mut() {
                Some(p) if p.2 == v && p.1 == x => p.1 = x + 1,
                _ => pieces.push((x, x + 1, v)),
            }
        }
        let (x0, x1, polygon) = (run.x0, run.x1, run.poly);
        decisions.push(ShadowTrace { light: l, sample: s, x0, x1, polygon, lit: pieces, asked_stage: asked, decision });
    });
    decisions
}

impl LineTrace {
    /// The trace as readable text; `x` restricts spans, runs and decisions to that pixel.
    pub fn text(&self, scene: &Scene, x: Option<u32>) -> String {
        let face = |p: u32| scene.polygons[p as usize].face;
        let keep = |a: u32, b: u32| x.is_none_or(|x| a <= x && x < b);
        let mut t = String::new();
        let _ = writeln!(t, "line {} (sampled at y = {}.5), shadows: {}", self.line, self.line, self.shadows);
        let _ = writeln!(t, "\nedge table: {} edge(s) enter, {} leave", self.entering.len(), self.leaving.len());
        for (what, list) in [("enters", &self.entering), ("leaves", &self.leaving)] {
            for e in list {
                let _ = writeln!(
                    t,
                    "  {what}: polygon {} (face {}), lines {}..{}, top ({:.3}, {:.3}), dx/dy {:.4}",
                    e.polygon, e.face, e.first_line, e.end_line, e.top.0, e.top.1, e.dxdy
                );
            }
        }
        let _ = writeln!(t, "\nactive edge table ({} crossings, by x):", self.active.len());
        for (cx, p) in &self.active {
            let _ = writeln!(t, "  x = {cx:.4}  polygon {p} (face {})", face(*p));
        }
        let _ = writeln!(t, "\nspans:");
        for s in self.spans.iter().filter(|s| keep(s.x0, s.x1)) {
            let cover: Vec<String> =
                s.covering.iter().map(|c| format!("face {} (1/z {:.4} .. {:.4})", c.1, c.2, c.3)).collect();
            let verdict = match s.split_at {
                Some(m) => format!(
                    "nearest differs at the ends (faces {} and {}): split at {m}",
                    face(s.nearest.0),
                    face(s.nearest.1)
                ),
                None => format!("face {} nearest at both ends: wins", face(s.nearest.0)),
            };
            let _ = writeln!(
                t,
                "  {}{}..{}: [{}] -> {verdict}",
                "  ".repeat(s.depth as usize),
                s.x0,
                s.x1,
                cover.join(", ")
            );
        }
        let _ = writeln!(t, "\nruns:");
        for r in self.runs.iter().filter(|r| keep(r.x0, r.x1)) {
            let _ = writeln!(t, "  {}..{}: polygon {} (face {})", r.x0, r.x1, r.poly, face(r.poly));
        }
        let _ = writeln!(t, "\nshadow decisions:");
        for d in self.decisions.iter().filter(|d| keep(d.x0, d.x1)) {
            let pieces: Vec<String> = d.lit.iter().map(|(a, b, v)| format!("{a}..{b}: {v}")).collect();
            let _ = writeln!(
                t,
                "  run {}..{} light {} sample {}: lit [{}]; {}",
                d.x0,
                d.x1,
                d.light,
                d.sample,
                pieces.join(", "),
                d.decision.note
            );
        }
        t
    }
}
