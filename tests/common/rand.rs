//! Deterministic random test inputs, the same in every run and on every machine:
//!
//! - [`SplitMix`]: the sequential generator, with the draws tests need (unit floats, ranges,
//!   `below(n)`, chances, vectors, unit vectors).
//! - [`stream`] and [`hashed_unit`]: random access, for tests that address each number by
//!   (stream, index, dimension) so that any case can be recomputed alone (a CPU replaying
//!   a GPU case) and no two tests share numbers. They use the renderer's own counter-based
//!   hash, `pcg4d`.

use glam::Vec3;
use meshtrace::render::rng::{pcg4d, u32_to_unit};

/// SplitMix64: a tiny deterministic generator for test inputs.
#[derive(Clone, Debug)]
pub struct SplitMix(u64);

impl SplitMix {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    pub fn u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }

    /// Uniform in [0, 1), 24 bits.
    pub fn unit(&mut self) -> f32 {
        u32_to_unit(self.u32())
    }

    /// Uniform in [a, b).
    pub fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.unit()
    }

    /// Uniform in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        ((self.u32() as u64 * n as u64) >> 32) as usize
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f32) -> bool {
        self.unit() < p
    }

    /// Each component uniform in [a, b).
    pub fn vec3(&mut self, a: f32, b: f32) -> Vec3 {
        Vec3::new(self.range(a, b), self.range(a, b), self.range(a, b))
    }

    /// A uniformly random unit vector (by rejection from the cube).
    pub fn unit_vector(&mut self) -> Vec3 {
        loop {
            let v = self.vec3(-1.0, 1.0);
            let l2 = v.length_squared();
            if l2 > 1e-4 && l2 <= 1.0 {
                return v / l2.sqrt();
            }
        }
    }
}

/// A stream id per label and number (FNV-1a of the label, mixed with `k`), so that each use
/// of [`hashed_unit`] gets numbers of its own.
pub fn stream(label: &str, k: u32) -> u32 {
    let mut h = 0x811c_9dc5u32;
    for b in label.bytes() {
        h = (h ^ b as u32).wrapping_mul(0x0100_0193);
    }
    h ^ k.wrapping_mul(0x9e37_79b9)
}

/// The uniform number in [0, 1) at (`seed`, `stream`, `index`, `dim`): the renderer's hash
/// of the four words (`Rng::new(index, stream, seed).rng_1d(0, dim)` for `dim` below
/// `DIMS_PER_BOUNCE`), 24 bits.
pub fn hashed_unit(seed: u32, stream: u32, index: u32, dim: u32) -> f32 {
    u32_to_unit(pcg4d([index, stream, dim, seed])[0])
}

/// The `index`-th triple of uniform numbers in [0, 1) of `stream` (dimensions 0, 1, 2).
pub fn hashed_u3(seed: u32, stream: u32, index: u32) -> [f32; 3] {
    [0, 1, 2].map(|dim| hashed_unit(seed, stream, index, dim))
}
