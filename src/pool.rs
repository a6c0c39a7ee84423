//! Memory kept between frames. A renderer (`Renderer`) hands these pools down the pipeline; a
//! stage takes a buffer for a frame-sized array (a depth buffer, a face-id buffer, a shadow
//! map) and gives it back when done, so that the next frame writes into pages the process
//! already has instead of having the system hand out and zero fresh ones (which, for a
//! 1920x1080 frame, costs more than drawing a simple scene).

use std::sync::{Arc, Mutex};

/// Buffers of `T` kept for reuse; clones share them.
#[derive(Clone)]
pub(crate) struct Pool<T>(Arc<Mutex<Vec<Vec<T>>>>);

impl<T> Default for Pool<T> {
    fn default() -> Self {
        Pool(Arc::new(Mutex::new(Vec::new())))
    }
}

impl<T> Pool<T> {
    /// A buffer of `len` copies of `value`, in kept memory where there is some.
    pub(crate) fn filled(&self, len: usize, value: T) -> Vec<T>
    where
        T: Clone,
    {
        let mut v = self.take();
        v.clear();
        v.resize(len, value);
        v
    }

    /// A kept buffer (any length, any contents), the one with the most room; empty if none.
    pub(crate) fn take(&self) -> Vec<T> {
        let Ok(mut kept) = self.0.lock() else { return Vec::new() };
        let best = (0..kept.len()).max_by_key(|&i| kept[i].capacity());
        best.map(|i| kept.swap_remove(i)).unwrap_or_default()
    }

    /// Keeps `buffer` for a later frame.
    pub(crate) fn give(&self, buffer: Vec<T>) {
        if buffer.capacity() == 0 {
            return;
        }
        if let Ok(mut kept) = self.0.lock() {
            kept.push(buffer);
        }
    }

    /// Bytes kept.
    pub(crate) fn bytes(&self) -> usize {
        self.0.lock().map_or(0, |kept| kept.iter().map(|b| b.capacity() * std::mem::size_of::<T>()).sum())
    }
}

/// The pools of every element type the pipeline's frame-sized buffers use.
#[derive(Clone, Default)]
pub(crate) struct Pools {
    /// Shadow maps (Williams).
    pub(crate) f32: Pool<f32>,
    /// Depth buffers (z-buffer visibility).
    pub(crate) f64: Pool<f64>,
    /// Face-id buffers (z-buffer visibility).
    pub(crate) u32: Pool<u32>,
    /// Stencil counts (stencil shadow volumes).
    pub(crate) i32: Pool<i32>,
    /// Lit masks (stencil shadow volumes).
    pub(crate) masks: Pool<bool>,
    /// Points (the seen points Williams' maps are fitted to: two a visible run).
    pub(crate) points: Pool<glam::DVec3>,
    /// Whole frames (what each mirror shows).
    pub(crate) frames: Frames,
}

/// Whole frames kept for reuse; clones share them.
#[derive(Clone, Default)]
pub(crate) struct Frames(Arc<Mutex<Vec<crate::frame::Frame>>>);

impl Frames {
    /// A kept frame, if any.
    pub(crate) fn take(&self) -> Option<crate::frame::Frame> {
        self.0.lock().ok()?.pop()
    }

    /// Keeps `frame` for a later pass.
    pub(crate) fn give(&self, frame: crate::frame::Frame) {
        if let Ok(mut kept) = self.0.lock() {
            kept.push(frame);
        }
    }
}

impl Pools {
    /// Bytes kept in all of them.
    pub(crate) fn bytes(&self) -> usize {
        self.f32.bytes()
            + self.f64.bytes()
            + self.u32.bytes()
            + self.i32.bytes()
            + self.masks.bytes()
            + self.points.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_buffer_given_back_is_taken_again_with_its_memory() {
        let pool = Pool::<u32>::default();
        assert!(pool.take().is_empty());
        let mut v = vec![7u32; 1000];
        let at = v.as_ptr();
        v.clear();
        pool.give(v);
        pool.give(vec![1u32; 10]);
        assert_eq!(pool.bytes(), 4 * (1000 + 10));
        let again = pool.take();
        assert_eq!((again.as_ptr(), again.capacity()), (at, 1000), "the roomiest buffer comes first");
        assert_eq!(pool.take().capacity(), 10);
        assert!(pool.take().is_empty());
    }
}
