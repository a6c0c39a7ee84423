//! Stencil shadow volumes (Heidmann 1991; Everitt & Kilgard 2002): the z-buffer twin of
//! Crow's per-span counting. The same shadow polygons ([`super::volumes`]) are rasterised one
//! at a time, pixel by pixel, into a stencil count against the depth of the visible surface,
//! as a GPU does with the stencil buffer: z-pass adds each polygon's sign where it lies in
//! front of the visible surface, z-fail subtracts it where it lies behind. A pixel is in
//! shadow where its count is above zero.

use super::far_outline;
use super::volumes::{Adjacency, ScreenVolumes};
use super::{Construction, Decision, ShadowContext, ShadowStage, ShadowWalker, VolumeOptions};
use crate::geometry::RingList;
use crate::scan::{boundary, for_each_span, ring_bins, ActiveEdges, EdgeTable};
use crate::stats::Counters;
use crate::view::DepthPlane;
use crate::visibility::Run;
use rayon::prelude::*;

/// The prepared stage: every sample's lit mask.
pub struct StencilVolume<'a> {
    ctx: &'a ShadowContext<'a>,
    /// `lit[sample][pixel]`.
    lit: Vec<Vec<bool>>,
}

impl<'a> StencilVolume<'a> {
    /// Rasterises every light sample's shadow polygons into a stencil count.
    pub fn new(
        ctx: &'a ShadowContext<'a>,
        options: VolumeOptions,
        counters: &mut Counters,
    ) -> crate::error::Result<Self> {
        let view = ctx.view;
        let (w, h) = (view.width as usize, view.height);
        let pixels = w as u64 * h as u64;
        let samples = ctx.all_samples().count() as u64;
        // A lit mask per sample, the stencil counts and the surface ids.
        let bytes = crate::budget::mul(samples, pixels).saturating_add(8 * pixels);
        crate::budget::check(format_args!("stencil-volume: {samples} lit mask(s) of {w}x{h}"), bytes)?;
        let scene = ctx.scene;
        // The depth buffer of the visible surfaces, from the visibility stage's runs, a line
        // each (ours: by all threads, as every per-frame list below).
        let mut surface = ctx.pools.u32.filled(w * h as usize, u32::MAX);
        surface.par_chunks_mut(w).zip(&ctx.runs.lines).for_each(|(line, runs)| {
            for r in runs {
                line[r.x0 as usize..r.x1 as usize].fill(r.poly);
            }
        });
        // The depth planes of the polygons seen at some pixel, the only ones asked for.
        let planes: Vec<Option<DepthPlane>> = (scene.polygons.par_iter().zip(&ctx.visible))
            .map(|(p, &seen)| seen.then(|| view.depth_plane(&p.plane)).flatten())
            .collect();
        let adjacency = Adjacency::kept(scene, options.construction != Construction::PerPolygon, &ctx.pools.stash);
        let counting = options.counting;
        let band = crate::scan::band_height(h);
        let mut writes = 0u64;
        let lit = ctx
            .all_samples()
            .map(|(_, _, sample)| {
                let vols = ScreenVolumes::new(ctx, &adjacency, sample, options, counters);
                let far = far_outline::table(h, &vols.far);
                // Each band's shadow polygons, those whose lines reach it, so that a band draws
                // only its own (ours: a tiled rasteriser's binning; z-fail puts a million caps
                // on s3).
                let bins = ring_bins(&vols.rings, band, h);
                let mut stencil = ctx.pools.i32.filled(w * h as usize, 0);
                let written: u64 = stencil
                    .par_chunks_mut(w * band as usize)
                    .enumerate()
                    .map(|(bi, rows)| {
                        let y0 = bi as u32 * band;
                        let lines = y0..(y0 + band).min(h);
                        let mut table = EdgeTable::new(h);
                        let mut n = 0u64;
                        for &i in &bins[bi] {
                            let (sp, ring) = (&vols.polys[i as usize], vols.rings.ring(i as usize));
                            for_each_span(&mut table, &[ring], view.width, h, lines.clone(), |y, x0, x1| {
                                let yc = y as f64 + 0.5;
                                // The visible polygon's depth plane and face, looked up again
                                // only where the polygon changes along the span (ours).
                                let mut seen: (u32, Option<(DepthPlane, u32)>) = (u32::MAX, None);
                                for x in x0..x1 {
                                    let k = y as usize * w + x as usize;
                                    let poly = surface[k];
                                    if poly != seen.0 {
                                        let plane = planes.get(poly as usize).copied().flatten();
                                        seen = (poly, plane.map(|d| (d, scene.polygons[poly as usize].face)));
                                    }
                                    let Some((d, face)) = seen.1 else { continue };
                                    let xc = x as f64 + 0.5;
                                    let c = sp.count_at(counting, poly, face, xc, yc, d.inv_z(xc, yc));
                                    rows[k - y0 as usize * w] += c;
                                    n += (c != 0) as u64;
                                }
                            });
                        }
                        // The far caps together (ours, the far outline): each pixel where a
                        // polygon is seen adds the winding number of their outline.
                        let mut walk = ActiveEdges::new(&far, lines.clone());
                        while let Some((y, xs)) = walk.next_line() {
                            let row = (y - y0) as usize * w;
                            let (mut winding, mut from) = (0i32, 0usize);
                            for c in xs {
                                let at = boundary(c.x, view.width) as usize;
                                if winding != 0 {
                                    for x in from..at {
                                        let poly = surface[y as usize * w + x] as usize;
                                        if planes.get(poly).is_some_and(Option::is_some) {
                                            rows[row + x] += winding;
                                            n += 1;
                                        }
                                    }
                                }
                                (winding, from) = (winding + c.tag as i32, at);
                            }
                        }
                        n
                    })
                    .sum();
                writes += written;
                let mut lit = ctx.pools.masks.take();
                lit.clear();
                lit.par_extend(stencil.par_iter().map(|&c| c <= 0));
                ctx.pools.i32.give(stencil);
                lit
            })
            .collect();
        ctx.pools.u32.give(surface);
        counters.add(crate::stats::Counter::StencilWrites, writes);
        Ok(StencilVolume { ctx, lit })
    }
}

impl Drop for StencilVolume<'_> {
    fn drop(&mut self) {
        for mask in self.lit.drain(..) {
            self.ctx.pools.masks.give(mask);
        }
    }
}

impl ShadowStage for StencilVolume<'_> {
    fn walker(&self) -> Box<dyn ShadowWalker + '_> {
        Box::new(Walker { stage: self })
    }

    /// The lit masks (the shadow volumes are let go once drawn).
    fn bytes(&self) -> usize {
        self.lit.iter().map(crate::pool::held).sum()
    }
}

struct Walker<'s> {
    stage: &'s StencilVolume<'s>,
}

impl ShadowWalker for Walker<'_> {
    fn lit(&mut self, light: usize, sample: usize, line: u32, run: &Run, lit: &mut [f32]) {
        let st = self.stage;
        let row = line as usize * st.ctx.view.width as usize;
        let mask = &st.lit[st.ctx.sample_index(light, sample)][row + run.x0 as usize..row + run.x1 as usize];
        for (o, &m) in lit.iter_mut().zip(mask) {
            *o = if m { 1.0 } else { 0.0 };
        }
    }

    fn decision(&self) -> Decision {
        Decision {
            tested: Vec::new(),
            note: "read from the stencil count rasterised in preparation".into(),
            detail: super::Detail::None,
        }
    }
}
