//! The z-buffer's rasteriser (Catmull 1974, "A Subdivision Algorithm for Computer Display
//! of Curved Surfaces"): polygons are drawn one at a time into a full-frame depth buffer,
//! keeping at each pixel centre the nearest. Written once and used from the eye by z-buffer
//! visibility (in f64, with polygon ids) and from the light by Williams' shadow maps (in f32,
//! depth only). The frame is cut into bands of lines drawn in parallel, each with every
//! polygon that reaches it.

use crate::scan::{for_each_span, EdgeTable};
use crate::view::{Screen, ScreenPolygon};
use glam::DVec2;
use rayon::prelude::*;
use std::ops::Range;

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
    screen: &Screen,
    width: u32,
    height: u32,
    ids: Option<Vec<u32>>,
    storage: Vec<D>,
) -> DepthBuffer<D> {
    let (w, h) = (width as usize, height);
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
    let band = crate::scan::band_height(h);
    let chunk = w * band as usize;
    let members = screen.band_members(h, band);
    let mut id_chunks: Vec<&mut [u32]> = ids.chunks_mut(chunk).collect();
    id_chunks.resize_with(depth.len().div_ceil(chunk), || &mut []);
    let counts: Vec<(u64, u64)> = depth
        .par_chunks_mut(chunk)
        .zip(id_chunks.into_par_iter())
        .enumerate()
        .map(|(bi, (depth, ids))| {
            let y0 = bi as u32 * band;
            let rows = BandRows { y0, lines: y0..(y0 + band).min(h), width, height: h, depth, ids };
            draw_band(members[bi].iter().map(|&i| screen.get(i)), rows)
        })
        .collect();
    DepthBuffer { ids, depth, tests: counts.iter().map(|c| c.0).sum(), writes: counts.iter().map(|c| c.1).sum() }
}

/// One band's rows of the depth and id buffers (`ids` empty for depth only).
struct BandRows<'a, D> {
    y0: u32,
    lines: Range<u32>,
    width: u32,
    height: u32,
    depth: &'a mut [D],
    ids: &'a mut [u32],
}

/// The z-buffer loop over one band: clears its rows, then draws `polygons` into them in
/// order, span by span. Returns the pixels tested and written.
fn draw_band<'p, D: Depth>(
    polygons: impl Iterator<Item = (&'p ScreenPolygon, &'p [DVec2])>,
    rows: BandRows<D>,
) -> (u64, u64) {
    let BandRows { y0, lines, width, height, depth, ids } = rows;
    let w = width as usize;
    depth.fill(D::FAR);
    ids.fill(u32::MAX);
    let mut table = EdgeTable::new(height);
    let (mut tests, mut writes) = (0u64, 0u64);
    for (p, ring) in polygons {
        for_each_span(&mut table, &[ring], width, height, lines.clone(), |y, x0, x1| {
            let z0 = D::from_f64(p.depth.inv_z(x0 as f64 + 0.5, y as f64 + 0.5));
            let a = D::from_f64(p.depth.a);
            let (start, end) = ((y - y0) as usize * w + x0 as usize, (y - y0) as usize * w + x1 as usize);
            tests += (x1 - x0) as u64;
            // Counted locally: a counter outside the closure would be read and written
            // through memory at every pixel.
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
}
