//! Many small screen outlines kept one after another in one list.
//!
//! A shadow stage can put a million polygons on screen in a frame (Crow's volumes on s3). Kept
//! as a list of lists, each outline is an allocation of its own, made on one thread and freed
//! one by one, often on another. [`Rings`] keeps them all in one list of points and where
//! each ends: the parallel loops that make them fill one list a piece, and the pieces are
//! read as one list where they lie ([`RingPieces`]).

use crate::pieces::starts;
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
    /// The bytes it holds.
    pub fn bytes(&self) -> usize {
        crate::pool::held(&self.points) + crate::pool::held(&self.ends)
    }

    /// Adds a ring at the end.
    pub fn push(&mut self, ring: &[DVec2]) {
        self.points.extend_from_slice(ring);
        self.ends.push(self.points.len());
    }

    /// The rings in order.
    pub fn iter(&self) -> impl Iterator<Item = &[DVec2]> + '_ {
        (0..self.count()).map(|i| self.ring(i))
    }
}

/// Rings kept in the pieces a parallel loop made them in, read as one list: ring `i` is
/// found through the number of the piece that holds it, four bytes a ring (a bisection over
/// the pieces' first indices, three times a ring as z-fail's edge table is built, was a
/// twentieth of Crow's z-fail frame on s3). Joining the pieces into one [`Rings`] would hold
/// every point twice while it copies (z-fail's million caps on s3: 72 MB more at the
/// frame's peak).
#[derive(Debug, Clone, Default)]
pub(crate) struct RingPieces {
    parts: Vec<Rings>,
    /// `first[k]`: the index of part `k`'s first ring; one more entry, the count.
    first: Vec<usize>,
    /// `part[i]`: the part that holds ring `i`.
    part: Vec<u32>,
}

impl RingPieces {
    /// The bytes its parts hold.
    pub fn bytes(&self) -> usize {
        self.parts.iter().map(Rings::bytes).sum::<usize>()
            + crate::pool::held(&self.first)
            + crate::pool::held(&self.part)
    }

    /// The rings of every part, in order.
    pub fn new(parts: Vec<Rings>) -> RingPieces {
        let first = starts(parts.iter().map(|p| p.count()));
        let parts_and_first = parts.into_iter().zip(first).filter(|(p, _)| p.count() > 0);
        let (parts, mut first): (Vec<Rings>, Vec<usize>) = parts_and_first.unzip();
        first.push(parts.iter().map(|p| p.count()).sum());
        let part = parts.iter().enumerate().flat_map(|(k, p)| std::iter::repeat_n(k as u32, p.count())).collect();
        RingPieces { parts, first, part }
    }

    /// The rings in order.
    pub fn iter(&self) -> impl Iterator<Item = &[DVec2]> + '_ {
        self.parts.iter().flat_map(|p| p.iter())
    }
}

impl RingList for RingPieces {
    fn count(&self) -> usize {
        self.first.last().copied().unwrap_or(0)
    }

    fn ring(&self, i: usize) -> &[DVec2] {
        let k = self.part[i] as usize;
        self.parts[k].ring(i - self.first[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(k: usize, n: usize) -> Vec<DVec2> {
        (0..n).map(|i| DVec2::new(k as f64, i as f64)).collect()
    }

    #[test]
    fn rings_read_from_their_pieces_are_the_rings_pushed_in_order() {
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
        let pieces = RingPieces::new(parts.clone());
        assert_eq!(pieces.count(), 7);
        assert!(pieces.iter().eq(all.iter()));
        assert!((0..7).all(|i| pieces.ring(i) == all.ring(i)));
        assert!(RingPieces::new(Vec::new()).iter().next().is_none());
        assert_eq!(pieces.ring(4), ring(4, 7).as_slice());
        assert!(pieces.ring(2).is_empty());
    }
}
