//! Parallel loops cut into pieces that two threads can share evenly.
//!
//! Rayon cuts a loop into a few long pieces, one or two per thread, and a thread that has
//! finished its own waits while the other works through its last. Where items differ in
//! cost (a receiver under a sphere's shadow and one on its lit side, a culled polygon and a
//! kept one), the loops of the shadow stages cap their pieces with `with_max_len`. Where
//! each piece writes a list whose length only the piece knows, it counts first, and then
//! fills its own stretch of one list ([`stretches`]); the list is the one a serial loop
//! would make, with no pass that joins the pieces' lists on one thread.
//! Where each piece has already made its own list, [`joined`] copies them into their
//! stretches of one list, in parallel.

use rayon::prelude::*;

/// `list` cut, from its start, into consecutive stretches of the given lengths (which sum
/// to at most its length).
pub(crate) fn stretches<T>(mut list: &mut [T], lengths: impl IntoIterator<Item = usize>) -> Vec<&mut [T]> {
    let lengths = lengths.into_iter();
    let mut out = Vec::with_capacity(lengths.size_hint().0);
    for n in lengths {
        let (stretch, rest) = std::mem::take(&mut list).split_at_mut(n);
        out.push(stretch);
        list = rest;
    }
    out
}

/// Where each of consecutive stretches of the given lengths starts, the first at 0.
pub(crate) fn starts(lengths: impl IntoIterator<Item = usize>) -> Vec<usize> {
    let mut at = 0;
    lengths
        .into_iter()
        .map(|n| {
            at += n;
            at - n
        })
        .collect()
}

/// The `parts` one after another in one list, item `x` of part `k` written as `f(k, x)`:
/// each part fills its own stretch, in parallel (the list a serial loop over the parts would
/// make).
pub(crate) fn joined<S: Sync, T: Copy + Send + Sync>(parts: &[&[S]], f: impl Fn(usize, &S) -> T + Sync) -> Vec<T> {
    let lengths = || parts.iter().map(|p| p.len());
    let Some(fill) = parts.iter().enumerate().find_map(|(k, p)| Some(f(k, p.first()?))) else { return Vec::new() };
    let mut list = filled(lengths().sum(), fill);
    stretches(&mut list, lengths()).into_par_iter().zip(parts).enumerate().for_each(|(k, (to, from))| {
        to.iter_mut().zip(from.iter()).for_each(|(t, x)| *t = f(k, x));
    });
    list
}

/// The `(key, item)` pairs grouped by key, by all threads: each key beside its items in
/// increasing order, the keys in increasing order (found by sorting, where a hash map would
/// be filled on one thread).
pub(crate) fn grouped(mut pairs: Vec<(u32, u32)>) -> Vec<(u32, Vec<u32>)> {
    pairs.par_sort_unstable();
    let starts: Vec<usize> =
        (0..pairs.len()).into_par_iter().filter(|&j| j == 0 || pairs[j].0 != pairs[j - 1].0).collect();
    starts
        .par_iter()
        .enumerate()
        .map(|(g, &a)| {
            let b = starts.get(g + 1).copied().unwrap_or(pairs.len());
            (pairs[a].0, pairs[a..b].iter().map(|&(_, i)| i).collect())
        })
        .collect()
}

/// `n` copies of `v`, written by all threads: the first writes to a list's fresh pages are
/// most of the cost of making it (a 1080p frame's colour and ids, 33 MB, made on one thread
/// were the largest serial step of a one-frame render).
pub(crate) fn filled<T: Copy + Send + Sync>(n: usize, v: T) -> Vec<T> {
    let mut list = Vec::new();
    list.par_extend(rayon::iter::repeat_n(v, n));
    list
}

/// `marked[i]`: whether `i` is among `indices` (each below `n`), marked by all threads. A
/// flag is read before it is written: where an index comes many times, threads that all
/// wrote it would pass its cache line between their cores each time.
pub(crate) fn marked(n: usize, indices: impl ParallelIterator<Item = usize>) -> Vec<bool> {
    use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
    let mut flags = Vec::new();
    flags.par_extend((0..n).into_par_iter().map(|_| AtomicBool::new(false)));
    indices.for_each(|i| {
        if !flags[i].load(Relaxed) {
            flags[i].store(true, Relaxed);
        }
    });
    flags.into_par_iter().map(AtomicBool::into_inner).collect()
}

/// Lets go of `list` by all threads: a list of many small allocations (a shadow database's
/// million outlines) takes a thread tens of milliseconds to free, while the others wait.
pub(crate) fn let_go<T: Send>(list: Vec<T>) {
    list.into_par_iter().with_min_len(1024).for_each(drop);
}

/// Sorts `keys` by their high halves (`key >> 32`, each below `2^bits`), keeping the order of
/// keys with equal high halves: a radix sort, least significant digit first, of at most
/// eleven bits a pass, all by all threads. Each chunk of the keys puts its own keys in digit
/// order in its stretch of a second list, and then each digit's stretch of the result
/// gathers them from the chunks, in chunk order. Where the low halves are in increasing
/// order to start with, the result is `keys` sorted (in place of a comparison sort's
/// log₂ n passes, two on a million cells).
pub(crate) fn sort_by_high_half(keys: &mut [u64], bits: u32) {
    const DIGIT: u32 = 11;
    const CHUNK: usize = 1 << 16;
    if keys.len() < 2 || bits == 0 {
        return;
    }
    let passes = bits.div_ceil(DIGIT);
    let width = bits.div_ceil(passes);
    let buckets = 1usize << width;
    let mut other = filled(keys.len(), 0u64);
    for pass in 0..passes {
        let shift = 32 + pass * width;
        let digit = |k: u64| (k >> shift) as usize & (buckets - 1);
        // Each chunk in digit order, in its own stretch of `other`; its count of each digit.
        let counts: Vec<Vec<usize>> = keys
            .par_chunks(CHUNK)
            .zip(other.par_chunks_mut(CHUNK))
            .map(|(from, to)| {
                let mut count = vec![0; buckets];
                from.iter().for_each(|&k| count[digit(k)] += 1);
                let mut at = starts(count.iter().copied());
                for &k in from {
                    let d = digit(k);
                    to[at[d]] = k;
                    at[d] += 1;
                }
                count
            })
            .collect();
        let within: Vec<Vec<usize>> = counts.iter().map(|c| starts(c.iter().copied())).collect();
        let totals = (0..buckets).map(|d| counts.iter().map(|c| c[d]).sum::<usize>());
        let chunks: Vec<&[u64]> = other.chunks(CHUNK).collect();
        stretches(keys, totals).into_par_iter().enumerate().for_each(|(d, mut to)| {
            for (j, chunk) in chunks.iter().enumerate() {
                let (from, n) = (&chunk[within[j][d]..], counts[j][d]);
                let (head, rest) = std::mem::take(&mut to).split_at_mut(n);
                head.copy_from_slice(&from[..n]);
                to = rest;
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grouped_lists_each_keys_items_in_order_the_keys_in_order() {
        // Enough pairs for the parallel sort to cut them, in scrambled order.
        let pairs: Vec<(u32, u32)> = (0..5_000u32).rev().map(|i| ((i * 7919) % 13, i)).collect();
        let groups = grouped(pairs);
        assert_eq!(groups.iter().map(|g| g.0).collect::<Vec<_>>(), (0..13).collect::<Vec<_>>());
        for (key, items) in &groups {
            assert!(items.windows(2).all(|w| w[0] < w[1]));
            assert!(items.iter().all(|&i| (i * 7919) % 13 == *key));
        }
        assert_eq!(groups.iter().map(|g| g.1.len()).sum::<usize>(), 5_000);
        assert!(grouped(Vec::new()).is_empty());
    }

    #[test]
    fn marked_flags_each_index_given_once_or_many_times() {
        let indices = vec![7usize, 3, 7, 7, 0];
        let flags = marked(9, indices.into_par_iter());
        let on: Vec<usize> = (0..9).filter(|&i| flags[i]).collect();
        assert_eq!((flags.len(), on), (9, vec![0, 3, 7]));
    }

    #[test]
    fn stretches_follow_one_another() {
        let mut list: Vec<u32> = (0..10).collect();
        let cut = stretches(&mut list, [3, 0, 5]);
        let lens: Vec<usize> = cut.iter().map(|s| s.len()).collect();
        assert_eq!(lens, [3, 0, 5]);
        assert_eq!((cut[0][0], cut[2][0], cut[2][4]), (0, 3, 7));
    }

    #[test]
    fn stretches_start_where_the_ones_before_end() {
        assert_eq!(starts([3, 0, 5, 1]), [0, 3, 3, 8]);
        assert!(starts([]).is_empty());
    }

    #[test]
    fn parts_joined_follow_one_another() {
        let parts: [&[u32]; 4] = [&[], &[1, 2], &[], &[3, 4, 5]];
        assert_eq!(joined(&parts, |k, &x| 10 * k as u32 + x), [11, 12, 33, 34, 35]);
        assert!(joined::<u32, u32>(&[&[], &[]], |_, &x| x).is_empty());
    }

    #[test]
    fn sorted_by_high_half_is_sorted_and_keeps_equal_halves_in_order() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for (n, bits) in [(0, 5), (1, 3), (10, 1), (1000, 4), (70_000, 11), (200_003, 20), (150_000, 23)] {
            // High halves at random below 2^bits, low halves the keys' places.
            let keys: Vec<u64> = (0..n).map(|i| (rng.gen_range(0..1u64 << bits) << 32) | i as u64).collect();
            let mut radix = keys.clone();
            sort_by_high_half(&mut radix, bits);
            let mut want = keys.clone();
            want.sort_unstable();
            assert_eq!(radix, want, "n = {n}, bits = {bits}");
        }
        // Stable: keys with the same high half keep their order, whatever their low halves.
        let mut keys = vec![(2 << 32) | 9, (1 << 32) | 5, (2 << 32) | 1, (1 << 32) | 7, 3];
        sort_by_high_half(&mut keys, 2);
        assert_eq!(keys, [3, (1 << 32) | 5, (1 << 32) | 7, (2 << 32) | 9, (2 << 32) | 1]);
    }
}
