//! Answers of [`shading::light_spot_surely_outside`] kept per thread, keyed by the bits of
//! every input.
//!
//! The fur stage asks, once a triangle, layer and tile, whether a light spot surely misses a
//! triangle ([`super::fragment::Spot::surely_misses`]). The test reads the triangle's vertex
//! normals alone, which every shell of a mesh triangle shares, so the same question comes
//! back on each of a frame's layers and tiles; its f64 square roots and divisions wait on
//! each other for about a thousand cycles (perf: 14 % of the CPU of the default scene at
//! 128×72, where triangles are small and many batches test). A hit costs a hash and a compare
//! of 13 words.
//!
//! A memo of a pure function changes no answer: a hit returns what the function returned
//! for the same bits, a miss computes it, so the image does not depend on which thread asked
//! first or what else its memo holds (no order, thread count or tile size shows in a byte).

use crate::shading;
use glam::Vec3;
use std::cell::RefCell;

/// Entries of a thread's memo (each a 64-byte line, 256 KiB in all): about the triangles a
/// tile meets on one layer of a small image (the default scene at 128×72: about 4 in 5 of the
/// questions hit, 9 in 10 with four times the entries, whose misses in the caches cost more).
const ENTRIES: usize = 4096;

/// The inputs as bits: the three normals, the direction, the cosine.
type Key = [u32; 13];

/// One entry: the key, and the answer (bit 0) with bit 1 set once the entry holds one.
#[derive(Clone, Copy)]
#[repr(C, align(64))]
struct Entry {
    key: Key,
    answer: u32,
}

/// A direct-mapped table: a key has one slot, and a new key there replaces the old.
struct Memo {
    entries: Vec<Entry>,
}

thread_local! {
    static MEMO: RefCell<Memo> = const { RefCell::new(Memo { entries: Vec::new() }) };
}

/// Bit 1 of [`Entry::answer`]: the entry holds an answer.
const HELD: u32 = 2;

/// [`shading::light_spot_surely_outside`]`(normals, direction, below)`, the same answer for
/// the same bits, from this thread's memo where it asked the same question before.
pub fn light_spot_surely_outside(normals: [Vec3; 3], direction: Vec3, below: f32) -> bool {
    let key = key_of(normals, direction, below);
    let slot = slot_of(&key);
    let held = MEMO.with_borrow(|memo| {
        memo.entries
            .get(slot)
            .filter(|e| e.answer & HELD != 0 && e.key == key)
            .map(|e| e.answer & 1 != 0)
    });
    if let Some(answer) = held {
        #[cfg(test)]
        tests::HITS.set(tests::HITS.get() + 1);
        return answer;
    }
    let answer = shading::light_spot_surely_outside(normals, direction, below);
    MEMO.with_borrow_mut(|memo| {
        if memo.entries.is_empty() {
            memo.entries = vec![
                Entry {
                    key: [0; 13],
                    answer: 0,
                };
                ENTRIES
            ];
        }
        memo.entries[slot] = Entry {
            key,
            answer: HELD | u32::from(answer),
        };
    });
    answer
}

/// The bits of the test's inputs.
fn key_of(normals: [Vec3; 3], direction: Vec3, below: f32) -> Key {
    let mut key = [0u32; 13];
    for (k, v) in normals.iter().chain([&direction]).enumerate() {
        key[3 * k..3 * k + 3].copy_from_slice(&v.to_array().map(f32::to_bits));
    }
    key[12] = below.to_bits();
    key
}

/// The slot of `key`: a multiplicative hash of its words, its top bits.
fn slot_of(key: &Key) -> usize {
    let hash = key.iter().fold(0u64, |h, &w| {
        (h.rotate_left(5) ^ u64::from(w)).wrapping_mul(0x517c_c1b7_2722_0a95)
    });
    (hash >> (64 - ENTRIES.trailing_zeros())) as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::Lcg;

    thread_local! {
        /// Questions this thread's memo answered from an entry.
        pub(super) static HITS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
    }

    #[test]
    fn the_memo_answers_as_the_test_when_it_hits_misses_and_replaces() {
        // Triangles near a spot's edge (both answers occur). A few asked twice: the second
        // time they hit. Then three times as many as the memo has slots, twice over: entries
        // are replaced, and every answer must still be the test's.
        let mut rng = Lcg::new(7);
        let direction = Vec3::new(0.6, 0.5, 0.8);
        let below = 0.7f32;
        let mut triangle = || -> [Vec3; 3] {
            let centre = (direction.normalize() + 0.8 * rng.direction()).normalize();
            [0, 1, 2].map(|_| (centre + 0.05 * rng.direction()).normalize())
        };
        let few: Vec<[Vec3; 3]> = (0..ENTRIES / 8).map(|_| triangle()).collect();
        let many: Vec<[Vec3; 3]> = (0..3 * ENTRIES).map(|_| triangle()).collect();
        let (mut outside, mut inside) = (0, 0);
        let mut ask = |normals: &[Vec3; 3]| {
            let expected = shading::light_spot_surely_outside(*normals, direction, below);
            assert_eq!(
                light_spot_surely_outside(*normals, direction, below),
                expected
            );
            if expected {
                outside += 1;
            } else {
                inside += 1;
            }
        };
        let hits_before = HITS.get();
        few.iter().for_each(&mut ask);
        few.iter().for_each(&mut ask);
        let hits = HITS.get() - hits_before;
        // Two of the few may share a slot and replace each other: with random slots about
        // n²/2m pairs of n keys in m slots do (32 here), each costing up to two hits.
        assert!(
            hits >= few.len() as u64 * 3 / 4,
            "{hits} hits of {}",
            few.len()
        );
        many.iter().for_each(&mut ask);
        many.iter().for_each(&mut ask);
        assert!(
            outside > 1000 && inside > 1000,
            "{outside} outside, {inside} inside"
        );
    }

    #[test]
    fn any_input_bit_is_part_of_the_key() {
        // One triangle surely outside; flipping the cosine's or the direction's bits to values
        // that put it inside must not be answered from the memo.
        let normals = [
            Vec3::Z,
            Vec3::new(0.0, 0.05, 1.0).normalize(),
            Vec3::new(0.05, 0.0, 1.0).normalize(),
        ];
        let away = Vec3::X;
        assert!(light_spot_surely_outside(normals, away, 0.5));
        assert!(!light_spot_surely_outside(normals, Vec3::Z, 0.5));
        assert!(light_spot_surely_outside(normals, away, 0.5));
        assert!(!light_spot_surely_outside(normals, away, -0.5));
        let moved = [Vec3::X, normals[1], normals[2]];
        assert_eq!(
            light_spot_surely_outside(moved, away, 0.5),
            shading::light_spot_surely_outside(moved, away, 0.5)
        );
        assert!(!light_spot_surely_outside(moved, away, 0.5));
    }

    #[test]
    fn keys_spread_over_the_slots() {
        // Normals of a smooth mesh differ in low bits: their slots must not pile up.
        let mut used = vec![0u32; ENTRIES];
        for i in 0..ENTRIES {
            let a = i as f32 * 1e-3;
            let n = Vec3::new(a.sin(), a.cos(), 0.3).normalize();
            used[slot_of(&key_of([n, n, n], Vec3::Z, 0.5))] += 1;
        }
        let filled = used.iter().filter(|&&c| c > 0).count();
        assert!(filled > ENTRIES / 2, "{filled} of {ENTRIES} slots used");
    }
}
