//! Memory kept between frames. A renderer (`Renderer`) hands these pools down the pipeline; a
//! stage takes a buffer for a frame-sized array (a depth buffer, a face-id buffer, a shadow
//! map) and gives it back when done, so that the next frame writes into pages the process
//! already has instead of having the system hand out and zero fresh ones (which, for a
//! 1920x1080 frame, costs more than drawing a simple scene).

use rayon::prelude::*;
use std::any::Any;
use std::sync::{Arc, Mutex};

/// Things kept for reuse (buffers, whole frames); clones share them.
pub(crate) struct Kept<B>(Arc<Mutex<Vec<B>>>);

impl<B> Default for Kept<B> {
    fn default() -> Self {
        Kept(Arc::new(Mutex::new(Vec::new())))
    }
}

impl<B> Clone for Kept<B> {
    fn clone(&self) -> Self {
        Kept(self.0.clone())
    }
}

impl<B> Kept<B> {
    /// Keeps `item` for a later frame.
    fn keep(&self, item: B) {
        if let Ok(mut kept) = self.0.lock() {
            kept.push(item);
        }
    }

    /// The kept item with the most `room`, if any.
    fn take_roomiest(&self, room: impl Fn(&B) -> usize) -> Option<B> {
        let mut kept = self.0.lock().ok()?;
        let best = (0..kept.len()).max_by_key(|&i| room(&kept[i]))?;
        Some(kept.swap_remove(best))
    }

    /// The sum of `bytes` over what is kept.
    fn sum(&self, bytes: impl Fn(&B) -> usize) -> usize {
        self.0.lock().map_or(0, |kept| kept.iter().map(bytes).sum())
    }
}

/// Buffers of `T` kept for reuse.
pub(crate) type Pool<T> = Kept<Vec<T>>;

impl<T> Kept<Vec<T>> {
    /// A buffer of `len` copies of `value`, in kept memory where there is some, written by
    /// all threads (a frame's buffer is millions of entries).
    pub(crate) fn filled(&self, len: usize, value: T) -> Vec<T>
    where
        T: Clone + Send,
    {
        let mut v = self.take();
        v.clear();
        v.par_extend(rayon::iter::repeat_n(value, len));
        v
    }

    /// A kept buffer (any length, any contents), the one with the most room; empty if none.
    pub(crate) fn take(&self) -> Vec<T> {
        self.take_roomiest(Vec::capacity).unwrap_or_default()
    }

    /// Keeps `buffer` for a later frame.
    pub(crate) fn give(&self, buffer: Vec<T>) {
        if buffer.capacity() > 0 {
            self.keep(buffer);
        }
    }

    /// Bytes kept.
    pub(crate) fn bytes(&self) -> usize {
        self.sum(|b| b.capacity() * std::mem::size_of::<T>())
    }
}

/// A buffer taken from a [`Pool`] and given back when dropped: scratch for one piece of a
/// parallel loop (rayon's `map_init`), so that the many pieces a loop is split into share
/// the few buffers that are in use at once.
pub(crate) struct Lease<'a, T> {
    buffer: Vec<T>,
    pool: &'a Pool<T>,
}

impl<T> Pool<T> {
    /// A kept buffer (or a new, empty one), given back when the lease is dropped.
    pub(crate) fn lease(&self) -> Lease<'_, T> {
        Lease { buffer: self.take(), pool: self }
    }
}

impl<T> std::ops::Deref for Lease<'_, T> {
    type Target = Vec<T>;
    fn deref(&self) -> &Vec<T> {
        &self.buffer
    }
}

impl<T> std::ops::DerefMut for Lease<'_, T> {
    fn deref_mut(&mut self) -> &mut Vec<T> {
        &mut self.buffer
    }
}

impl<T> Drop for Lease<'_, T> {
    fn drop(&mut self) {
        self.pool.give(std::mem::take(&mut self.buffer));
    }
}

/// Whole frames kept for reuse (what each mirror shows).
pub(crate) type Frames = Kept<crate::frame::Frame>;

impl Kept<crate::frame::Frame> {
    /// A kept frame, if any (the largest).
    pub(crate) fn take(&self) -> Option<crate::frame::Frame> {
        self.take_roomiest(|f| f.id.capacity())
    }

    /// Keeps `frame` for a later pass.
    pub(crate) fn give(&self, frame: crate::frame::Frame) {
        self.keep(frame);
    }

    /// Bytes kept: colour, ids and lit fractions.
    pub(crate) fn bytes(&self) -> usize {
        self.sum(|f| {
            f.color.capacity() * std::mem::size_of::<glam::Vec3>()
                + f.id.capacity() * 4
                + f.light.iter().map(|l| l.capacity() * 4).sum::<usize>()
        })
    }
}

/// The bytes a list holds (its capacity, not its length).
pub(crate) fn held<T>(list: &Vec<T>) -> usize {
    list.capacity() * std::mem::size_of::<T>()
}

/// Things of any type kept for reuse, found by their type: what a stage keeps for its next
/// frame in types of its own (a band's edge table, the screen polygons, an edge adjacency),
/// which this module need not know.
#[derive(Clone, Default)]
pub(crate) struct Stash(Arc<Mutex<Vec<Box<dyn Any + Send>>>>);

impl Stash {
    /// A kept `T` (the last kept), or a new one when none is.
    pub(crate) fn take<T: Any + Send + Default>(&self) -> T {
        let Ok(mut kept) = self.0.lock() else { return T::default() };
        match kept.iter().rposition(|b| b.is::<T>()) {
            Some(at) => kept.remove(at).downcast::<T>().map_or_else(|_| T::default(), |b| *b),
            None => T::default(),
        }
    }

    /// Lets go of every kept `T` (working memory a stage has done with for this frame).
    pub(crate) fn discard<T: Any + Send>(&self) {
        let gone: Vec<Box<dyn Any + Send>> = match self.0.lock() {
            Ok(mut kept) => kept.extract_if(.., |b| b.is::<T>()).collect(),
            Err(_) => Vec::new(),
        };
        drop(gone);
    }

    /// Keeps `item` for a later frame.
    pub(crate) fn put<T: Any + Send>(&self, item: T) {
        if let Ok(mut kept) = self.0.lock() {
            kept.push(Box::new(item));
        }
    }

    /// The kept `T` that `is` picks, or (when none is) `make`'s, kept from now on in place of
    /// the least recently used `T` when `limit` are kept already.
    pub(crate) fn find_or_make<T: Any + Send + Clone>(
        &self,
        is: impl Fn(&T) -> bool,
        make: impl FnOnce() -> T,
        limit: usize,
    ) -> T {
        if let Ok(mut kept) = self.0.lock() {
            if let Some(at) = kept.iter().position(|b| b.downcast_ref::<T>().is_some_and(&is)) {
                // The most recently used last.
                let found = kept.remove(at);
                let copy = found.downcast_ref::<T>().cloned();
                kept.push(found);
                if let Some(copy) = copy {
                    return copy;
                }
            }
        }
        let made = make();
        if let Ok(mut kept) = self.0.lock() {
            let of_type: Vec<usize> = (0..kept.len()).filter(|&i| kept[i].is::<T>()).collect();
            if of_type.len() >= limit.max(1) {
                kept.remove(of_type[0]);
            }
            kept.push(Box::new(made.clone()));
        }
        made
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
    /// What stages keep in types of their own.
    pub(crate) stash: Stash,
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
            + self.frames.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stash_discards_every_kept_item_of_one_type() {
        let stash = Stash::default();
        stash.put(vec![1u8]);
        stash.put(String::from("kept"));
        stash.put(vec![2u8]);
        stash.discard::<Vec<u8>>();
        assert_eq!(stash.take::<Vec<u8>>(), Vec::<u8>::new(), "both let go");
        assert_eq!(stash.take::<String>(), "kept", "other types stay");
    }

    #[test]
    fn a_leased_buffer_comes_back_when_dropped() {
        let pool = Pool::<u32>::default();
        {
            let mut lease = pool.lease();
            lease.resize(100, 7);
        }
        let again = pool.lease();
        assert_eq!(again.len(), 100);
        assert!(pool.take().is_empty(), "the lease holds the only buffer");
    }

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

    #[test]
    fn a_stash_gives_back_by_type_and_keeps_the_most_recently_used() {
        let stash = Stash::default();
        assert_eq!(stash.take::<Vec<u8>>(), Vec::<u8>::new());
        stash.put(vec![1u8, 2]);
        stash.put(String::from("kept"));
        assert_eq!(stash.take::<String>(), "kept");
        assert_eq!(stash.take::<String>(), "", "taken once");
        assert_eq!(stash.take::<Vec<u8>>(), vec![1, 2]);
        // At most two (u32, &str) kept: the least recently used one goes.
        let made = std::cell::Cell::new(0);
        let get = |k: u32| {
            stash.find_or_make(
                |e: &(u32, &str)| e.0 == k,
                || {
                    made.set(made.get() + 1);
                    (k, "made")
                },
                2,
            )
        };
        for k in [1, 2, 1, 3] {
            get(k);
        }
        assert_eq!(made.get(), 3, "1 was found again");
        get(1);
        assert_eq!(made.get(), 3, "1 was used more recently than 2, which went");
        get(2);
        assert_eq!(made.get(), 4);
    }
}
