//! The z-buffer (Catmull 1974): polygons are rasterised one at a time into a full-frame depth
//! buffer, keeping at each pixel centre the polygon with the largest inverse depth. The frame
//! is cut into bands of lines that are rasterised in parallel, each with every polygon that
//! reaches it. Then its rows are read out as runs, like every visibility stage.

use super::{runs_of_row, Run, Visibility};
use crate::scan::{for_each_span, EdgeTable};
use crate::stats::Counters;
use crate::view::{ScreenPolygon, View};
use rayon::prelude::*;
use std::ops::Range;

/// The prepared z-buffer stage: the filled polygon-index and depth buffers.
pub struct ZBufferVisibility {
    width: u32,
    /// Scene polygon index per pixel, `u32::MAX` for none.
    ids: Vec<u32>,
}

impl ZBufferVisibility {
    /// Rasterises every screen polygon into the buffers.
    pub fn new(screen: &[ScreenPolygon], view: &View, counters: &mut Counters) -> Self {
        let (w, h) = (view.width as usize, view.height);
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
        let mut ids = vec![u32::MAX; w * h as usize];
        let mut depth = vec![0.0f64; w * h as usize];
        let band = crate::render::band_height(h);
        let counts: Vec<(u64, u64)> = ids
            .par_chunks_mut(w * band as usize)
            .zip(depth.par_chunks_mut(w * band as usize))
            .enumerate()
            .map(|(bi, (ids, depth))| {
                let y0 = bi as u32 * band;
                let lines = y0..(y0 + band).min(h);
                let mut table = EdgeTable::new(h);
                let (mut tests, mut writes) = (0u64, 0u64);
                for (p, r) in screen.iter().zip(&spans) {
                    if r.end <= lines.start || r.start >= lines.end {
                        continue;
                    }
                    for_each_span(&mut table, &[&p.ring], view.width, h, lines.clone(), |y, x0, x1| {
                        let yc = y as f64 + 0.5;
                        let row = (y - y0) as usize * w;
                        tests += (x1 - x0) as u64;
                        for x in x0..x1 {
                            let z = p.depth.inv_z(x as f64 + 0.5, yc);
                            let k = row + x as usize;
                            if z > depth[k] {
                                depth[k] = z;
                                ids[k] = p.poly;
                                writes += 1;
                            }
                        }
                    });
                }
                (tests, writes)
            })
            .collect();
        counters.add("depth_tests", counts.iter().map(|c| c.0).sum());
        counters.add("depth_writes", counts.iter().map(|c| c.1).sum());
        counters.add("buffer_bytes", (ids.len() * 4 + depth.len() * 8) as u64);
        ZBufferVisibility { width: view.width, ids }
    }
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
