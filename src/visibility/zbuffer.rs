//! The z-buffer (Catmull 1974): polygons are rasterised one at a time into a full-frame depth
//! buffer, keeping at each pixel centre the polygon with the largest inverse depth. The frame
//! is cut into bands of lines that are rasterised in parallel, each with every polygon that
//! reaches it. Then its rows are read out as runs, like every visibility stage.

use super::{runs_of_row, Run, Visibility};
use crate::pool::Pools;
use crate::scan::{for_each_span, EdgeTable};
use crate::stats::Counters;
use crate::view::{ScreenPolygon, View};
use rayon::prelude::*;
use std::ops::Range;

/// The prepared z-buffer stage: the filled polygon-index buffer (the depth buffer goes back
/// to the renderer's pool once drawn, and the ids when the stage is dropped).
pub struct ZBufferVisibility {
    width: u32,
    /// Scene polygon index per pixel, `u32::MAX` for none.
    ids: Vec<u32>,
    pools: Pools,
}

impl ZBufferVisibility {
    /// Rasterises every screen polygon into buffers taken from `pools`.
    pub(crate) fn new(screen: &[ScreenPolygon], view: &View, pools: &Pools, counters: &mut Counters) -> Self {
        let buffers = rasterize::<f64>(screen, view.width, view.height, Some(pools.u32.take()), pools.f64.take());
        counters.add("depth_tests", buffers.tests);
        counters.add("depth_writes", buffers.writes);
        counters.add("buffer_bytes", (buffers.ids.len() * 4 + buffers.depth.len() * 8) as u64);
        pools.f64.give(buffers.depth);
        ZBufferVisibility { width: view.width, ids: buffers.ids, pools: pools.clone() }
    }
}

impl Drop for ZBufferVisibility {
    fn drop(&mut self) {
        self.pools.u32.give(std::mem::take(&mut self.ids));
    }
}

/// A depth value a buffer can hold: `f64` for visibility, `f32` for shadow maps.
pub trait Depth: Copy + PartialOrd + Send + Sync {
    /// Nothing drawn (farther than anything).
    const FAR: Self;
    /// Zero, which a fresh buffer can be allocated as without being written.
    const ZERO: Self;
    /// From a depth-plane value.
    fn from_f64(v: f64) -> Self;
    /// The value `i` pixels along a span that starts at `z0` and changes by `a` per pixel,
    /// in the buffer's own precision (from the start, not accumulated).
    fn along(z0: Self, a: Self, i: i32) -> Self;
}

impl Depth for f64 {
    const FAR: Self = f64::NEG_INFINITY;
    const ZERO: Self = 0.0;
    fn from_f64(v: f64) -> Self {
        v
    }
    fn along(z0: Self, a: Self, i: i32) -> Self {
        z0 + a * i as f64
    }
}

impl Depth for f32 {
    const FAR: Self = f32::NEG_INFINITY;
    const ZERO: Self = 0.0;
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    fn along(z0: Self, a: Self, i: i32) -> Self {
        z0 + a * i as f32
    }
}

/// A filled depth buffer: the nearest polygon and its nearness (a [`DepthPlane`] value, larger
/// is nearer; [`Depth::FAR`] where nothing was drawn) at each pixel centre.
///
/// [`DepthPlane`]: crate::view::DepthPlane
pub struct DepthBuffer<D> {
    /// `ScreenPolygon::poly` of the nearest polygon per pixel, `u32::MAX` for none; empty
    /// when ids were not asked for.
    pub ids: Vec<u32>,
    /// Its nearness per pixel.
    pub depth: Vec<D>,
    /// Pixels tested.
    pub tests: u64,
    /// Pixels written.
    pub writes: u64,
}

/// The z-buffer loop: rasterises `screen` one polygon at a time, keeping at each pixel
/// centre the polygon whose depth plane is largest (nearest), in parallel bands of lines.
/// Used for visibility (with ids, in f64) and, from the light, for Williams' shadow maps
/// (depth only, in f32).
///
/// The depth buffer is built in `storage`, and the polygon ids (when asked for) in `ids`
/// (any contents; reallocated if too small), so that a caller drawing many frames can hand
/// back the last frame's buffers instead of having fresh pages zeroed by the system each time.
pub fn rasterize<D: Depth>(
    screen: &[ScreenPolygon],
    width: u32,
    height: u32,
    ids: Option<Vec<u32>>,
    storage: Vec<D>,
) -> DepthBuffer<D> {
    let (w, h) = (width as usize, height);
    let spans: Vec<Range<u32>> = screen
        .iter()
        .map(|p| {
            let (lo, hi) =
                p.ring.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| (lo.min(q.y), hi.max(q.y)));
            let first = (lo - 0.5).ceil().clamp(0.0, h as f64) as u32;
            let end = (hi - 0.5).ceil().clamp(0.0, h as f64) as u32;
            first..end
        })
        .collect();
    // Zeroed allocations cost nothing until written: each band clears its own rows, in
    // parallel and just before drawing them.
    let reuse = |mut v: Vec<u32>| {
        if v.capacity() < w * h as usize {
            v = vec![0; w * h as usize];
        }
        v.resize(w * h as usize, 0);
        v
    };
    let mut ids = ids.map_or_else(Vec::new, reuse);
    let mut depth = if storage.capacity() >= w * h as usize { storage } else { vec![D::ZERO; w * h as usize] };
    depth.resize(w * h as usize, D::ZERO);
    let band = crate::render::band_height(h);
    let chunk = w * band as usize;
    // The polygons each band meets, in drawing order.
    let mut members = vec![Vec::new(); h.div_ceil(band) as usize];
    for (i, r) in spans.iter().enumerate() {
        for b in r.start / band..r.end.div_ceil(band) {
            members[b as usize].push(i);
        }
    }
    let mut id_chunks: Vec<&mut [u32]> = ids.chunks_mut(chunk).collect();
    id_chunks.resize_with(depth.len().div_ceil(chunk), || &mut []);
    let counts: Vec<(u64, u64)> = depth
        .par_chunks_mut(chunk)
        .zip(id_chunks.into_par_iter())
        .enumerate()
        .map(|(bi, (depth, ids))| {
            let y0 = bi as u32 * band;
            let lines = y0..(y0 + band).min(h);
            depth.fill(D::FAR);
            ids.fill(u32::MAX);
            let mut table = EdgeTable::new(h);
            let (mut tests, mut writes) = (0u64, 0u64);
            for p in members[bi].iter().map(|&i| &screen[i]) {
                for_each_span(&mut table, &[&p.ring], width, h, lines.clone(), |y, x0, x1| {
                    let z0 = D::from_f64(p.depth.inv_z(x0 as f64 + 0.5, y as f64 + 0.5));
                    let a = D::from_f64(p.depth.a);
                    let (start, end) = ((y - y0) as usize * w + x0 as usize, (y - y0) as usize * w + x1 as usize);
                    tests += (x1 - x0) as u64;
                    // Counted locally: a counter outside the closure would be read and
                    // written through memory at every pixel.
                    let mut span_writes = 0;
                    if ids.is_empty() {
                        // Depth only (a shadow map): branch-free, so it vectorises.
                        for (d, i) in depth[start..end].iter_mut().zip(0..) {
                            let z = D::along(z0, a, i);
                            let nearer = z > *d;
                            span_writes += u32::from(nearer);
                            *d = if nearer { z } else { *d };
                        }
                    } else {
                        for ((d, id), i) in depth[start..end].iter_mut().zip(&mut ids[start..end]).zip(0..) {
                            let z = D::along(z0, a, i);
                            if z > *d {
                                (*d, *id) = (z, p.poly);
                                span_writes += 1;
                            }
                        }
                    }
                    writes += u64::from(span_writes);
                });
            }
            (tests, writes)
        })
        .collect();
    DepthBuffer { ids, depth, tests: counts.iter().map(|c| c.0).sum(), writes: counts.iter().map(|c| c.1).sum() }
}

impl Visibility for ZBufferVisibility {
    fn walk(&self, lines: Range<u32>, _counters: &mut Counters, f: &mut dyn FnMut(u32, &[Run])) {
        let w = self.width as usize;
        let mut runs = Vec::new();
        for y in lines {
            runs_of_row(&self.ids[y as usize * w..(y as usize + 1) * w], &mut runs);
            f(y, &runs);
        }
    }
}
