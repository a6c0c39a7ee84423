//! The z-buffer (Catmull 1974): polygons are rasterised one at a time into a full-frame depth
//! buffer, keeping at each pixel centre the polygon with the largest inverse depth. The frame
//! is cut into bands of lines that are rasterised in parallel, each with every polygon that
//! reaches it. Then its rows are read out as runs, like every visibility stage.

use super::{runs_of_row, Run, Visibility};
use crate::pool::Pools;
use crate::raster::rasterize;
use crate::stats::Counters;
use crate::view::{Screen, View};
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
    pub(crate) fn new(screen: &Screen, view: &View, pools: &Pools, counters: &mut Counters) -> Self {
        let buffers = rasterize::<f64>(screen, view.width, view.height, Some(pools.u32.take()), pools.f64.take());
        counters.add(crate::stats::Counter::DepthTests, buffers.tests);
        counters.add(crate::stats::Counter::DepthWrites, buffers.writes);
        counters.add(crate::stats::Counter::BufferBytes, (buffers.ids.len() * 4 + buffers.depth.len() * 8) as u64);
        pools.f64.give(buffers.depth);
        ZBufferVisibility { width: view.width, ids: buffers.ids, pools: pools.clone() }
    }
}

impl Drop for ZBufferVisibility {
    fn drop(&mut self) {
        self.pools.u32.give(std::mem::take(&mut self.ids));
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
