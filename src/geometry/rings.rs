//! Many small screen outlines kept one after another in one list.
//!
//! A shadow stage can put a million polygons on screen in a frame (Crow's volumes on s3). Kept
//! as a list of lists, each outline is an allocation of its own, made on one thread and freed
//! one by one, often on another. [`Rings`] keeps them all in one list of points and where
//! each ends: the parallel loops that make them fill one list a piece, and the pieces' lists
//! are joined in parallel ([`Rings::joined`]).

use crate::pieces::{joined, starts};
use glam::DVec2;

/// A list of rings read by index: a list of lists or [`Rings`].
pub(crate) trait RingList: Sync {
    /// The number of rings.
    fn count(&self) -> usize;
    /// Ring `i`.
    fn ring(&self, i: usize) -> &[DVec2];
}

impl RingList for [Vec<DVec2>] {
    fn count(&self) -> usize {
        self.len()
    }

    fn ring(&self, i: usize) -> &[DVec2] {
        &self[i]
    }
}

/// Rings kept one after another: ring `i` is `points[ends[i - 1]..ends[i]]`.
#[derive(Debug, Clone, Default)]
pub(crate) struct Rings {
    points: Vec<DVec2>,
    ends: Vec<usize>,
}

impl RingList for Rings {
    fn count(&self) -> usize {
        self.ends.len()
    }

    fn ring(&self, i: usize) -> &[DVec2] {
        let start = if i == 0 { 0 } else { self.ends[i - 1] };
        &self.points[start..self.ends[i]]
    }
}

impl Rings {
    /// Adds a ring at the end.
    pub fn push(&mut self, ring: &[DVec2]) {
        self.points.extend_from_slice(ring);
        self.ends.push(self.points.len());
    }

    /// The rings in order.
    pub fn iter(&self) -> impl Iterator<Item = &[DVec2]> + '_ {
        (0..self.count()).map(|i| self.ring(i))
    }

    /// The rings of every part, in order, in one list: each part is copied into its own
    /// stretch of the list in parallel.
    pub fn joined(parts: &[Rings]) -> Rings {
        let offsets = starts(parts.iter().map(|p| p.points.len()));
        let points: Vec<&[DVec2]> = parts.iter().map(|p| p.points.as_slice()).collect();
        let ends: Vec<&[usize]> = parts.iter().map(|p| p.ends.as_slice()).collect();
        Rings { points: joined(&points, |_, &p| p), ends: joined(&ends, |k, &end| end + offsets[k]) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(k: usize, n: usize) -> Vec<DVec2> {
        (0..n).map(|i| DVec2::new(k as f64, i as f64)).collect()
    }

    #[test]
    fn rings_joined_from_parts_are_the_rings_pushed_in_order() {
        let sizes = [[3, 4, 0, 5].as_slice(), &[], &[7], &[3, 3]];
        let mut all = Rings::default();
        let mut k = 0;
        let parts: Vec<Rings> = sizes
            .iter()
            .map(|part| {
                let mut rings = Rings::default();
                for &n in part.iter() {
                    rings.push(&ring(k, n));
                    all.push(&ring(k, n));
                    k += 1;
                }
                rings
            })
            .collect();
        let joined = Rings::joined(&parts);
        assert_eq!(joined.count(), 7);
        assert!(joined.iter().eq(all.iter()));
        assert_eq!(joined.ring(4), ring(4, 7).as_slice());
        assert!(joined.ring(2).is_empty());
    }
}
