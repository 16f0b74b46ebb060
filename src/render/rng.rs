//! The counter-based random numbers shared bit for bit by the CPU and GPU paths.
//!
//! Every number is a pure function of (pixel, sample, bounce, dimension, seed), so any
//! single sample of any pixel can be replayed alone, on either device, and renders of
//! disjoint sample ranges can be merged. The numbers are Owen-scrambled Sobol points,
//! padded two dimensions at a time (Burley, "Practical Hash-based Owen Scrambling", JCGT
//! 2020): each pair of dimensions that a stage draws together (pixel x and y, lens u and v,
//! light u and v, BSDF u and v) takes the first two Sobol dimensions at the sample index
//! shuffled per (pixel, bounce, pair, seed), each component Owen-scrambled by its own seed;
//! the single dimensions (lobe, roulette) take the first. A pixel's samples are
//! thus stratified in every pair, and pixels, bounces and pairs stay independent. The
//! seeds come from `pcg4d` (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT
//! 2020); everything is integer arithmetic and thus exact on every device.

use glam::Vec2;
use std::cell::Cell;
use std::mem::MaybeUninit;

/// Dimensions used by the camera at bounce 0.
pub const DIM_PIXEL_X: u32 = 0;
pub const DIM_PIXEL_Y: u32 = 1;
pub const DIM_LENS_U: u32 = 2;
pub const DIM_LENS_V: u32 = 3;
/// Whether the sample traces a light subpath (`render::caustics`), at bounce 0. (The light
/// pick, which had this dimension once, comes from the light pair's first number.)
pub const DIM_LIGHT_SUBPATH: u32 = 4;
/// Dimensions used at each path vertex (bounce b counts from 0 at the first hit).
pub const DIM_LIGHT_U: u32 = 5;
pub const DIM_LIGHT_V: u32 = 6;
pub const DIM_BSDF_LOBE: u32 = 7;
pub const DIM_BSDF_U: u32 = 8;
pub const DIM_BSDF_V: u32 = 9;
pub const DIM_ROULETTE: u32 = 10;
/// Dimensions of a camera sample's light subpath (`render::caustics`), whose vertex j draws
/// at bounce j: the light point (bounce 0), the direction leaving vertex j (the emitted one
/// at bounce 0, the BSDF's at a non-delta vertex) and the lobe there. The lens point
/// through which non-delta vertex j is seen is the pair `DIM_LENS_U` of bounce j (at least
/// 2; the camera's own is bounce 0's).
pub const DIM_CAUSTIC_LIGHT_U: u32 = 11;
pub const DIM_CAUSTIC_LIGHT_V: u32 = 12;
pub const DIM_CAUSTIC_DIR_U: u32 = 13;
pub const DIM_CAUSTIC_DIR_V: u32 = 14;
pub const DIM_CAUSTIC_LOBE: u32 = 15;
/// Dimensions per bounce; the hash's third key word is `bounce * DIMS_PER_BOUNCE + dim`.
pub const DIMS_PER_BOUNCE: u32 = 16;

/// The 4D PCG hash. mirror: shaders/rng.wgsl `pcg4d`
pub fn pcg4d(v: [u32; 4]) -> [u32; 4] {
    let mut v = v.map(|x| x.wrapping_mul(1664525).wrapping_add(1013904223));
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
    v = v.map(|x| x ^ (x >> 16));
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
    v
}

/// The generator matrix of the second Sobol dimension, by bit of the index (the first is
/// the bit reversal of the index).
const SOBOL_1: [u32; 32] = [
    0x80000000, 0xc0000000, 0xa0000000, 0xf0000000, 0x88000000, 0xcc000000, 0xaa000000, 0xff000000,
    0x80800000, 0xc0c00000, 0xa0a00000, 0xf0f00000, 0x88880000, 0xcccc0000, 0xaaaa0000, 0xffff0000,
    0x80008000, 0xc000c000, 0xa000a000, 0xf000f000, 0x88008800, 0xcc00cc00, 0xaa00aa00, 0xff00ff00,
    0x80808080, 0xc0c0c0c0, 0xa0a0a0a0, 0xf0f0f0f0, 0x88888888, 0xcccccccc, 0xaaaaaaaa, 0xffffffff,
];

/// [`SOBOL_1`] applied to each byte of an index, its columns bit-reversed: entry
/// `256 k + b` is the XOR of the reversed columns for the set bits of byte value `b` in
/// byte `k`, so that the product takes four lookups instead of a branch per bit (which
/// random indices mispredict), and comes out in the bit order Owen scrambling works in.
const SOBOL_1_REVERSED_BYTES: [u32; 1024] = {
    let mut table = [0u32; 1024];
    let mut i = 0;
    while i < 1024 {
        let (byte, value) = (i / 256, i % 256);
        let mut x = 0u32;
        let mut bit = 0;
        while bit < 8 {
            if (value >> bit) & 1 != 0 {
                x ^= SOBOL_1[8 * byte + bit].reverse_bits();
            }
            bit += 1;
        }
        table[i] = x;
        i += 1;
    }
    table
};

/// Point `index` of Sobol dimension `dim` (0 or 1), as 32 bits of a fraction.
/// mirror: shaders/rng.wgsl `sobol`
pub fn sobol(index: u32, dim: u32) -> u32 {
    sobol_reversed(index, dim).reverse_bits()
}

/// [`sobol`] with its bits reversed, the order [`owen_hash`] takes: the index itself in
/// dimension 0, four table lookups in dimension 1.
/// mirror: shaders/rng.wgsl `sobol_reversed`
#[inline]
pub fn sobol_reversed(index: u32, dim: u32) -> u32 {
    if dim == 0 {
        return index;
    }
    let byte = |k: u32| SOBOL_1_REVERSED_BYTES[(256 * k + ((index >> (8 * k)) & 255)) as usize];
    byte(0) ^ byte(1) ^ byte(2) ^ byte(3)
}

/// Owen scrambling of the bits of `x` from the top (a nested uniform scramble), keyed by
/// `seed`: Laine and Karras's permutation on the reversed bits, in Burley's 2020 form.
/// mirror: shaders/rng.wgsl `owen_scramble`
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    owen_hash(x.reverse_bits(), seed).reverse_bits()
}

/// [`owen_scramble`] in reversed bit order: `owen_scramble(x, seed)` is
/// `owen_hash(x.reverse_bits(), seed).reverse_bits()`, so a caller that holds reversed
/// bits (as [`sobol_reversed`] gives them) saves a reversal.
/// mirror: shaders/rng.wgsl `owen_hash`
#[inline]
pub fn owen_hash(x: u32, seed: u32) -> u32 {
    let mut x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50b47c);
    x ^= x.wrapping_mul(0xb82f1e52);
    x ^= x.wrapping_mul(0xc7afe638);
    x ^= x.wrapping_mul(0x8d22f6e6);
    x
}

/// The pair of dimensions `dim` draws from (numbered within a bounce), and which of its
/// two components it is: the stages' pairs are (pixel x, y), (lens u, v), (light u, v),
/// (BSDF u, v) and the light subpath's (light u, v) and (direction u, v); every other
/// dimension is a pair of its own, component 0.
/// mirror: shaders/rng.wgsl `dim_pair`
pub fn dim_pair(dim: u32) -> (u32, u32) {
    match dim {
        DIM_PIXEL_Y | DIM_LENS_V | DIM_LIGHT_V | DIM_BSDF_V | DIM_CAUSTIC_LIGHT_V
        | DIM_CAUSTIC_DIR_V => (dim - 1, 1),
        _ => (dim, 0),
    }
}

/// Maps 32 random bits to a float in [0, 1) with 24 bits of precision (exact in f32).
/// mirror: shaders/rng.wgsl `u32_to_unit`
pub fn u32_to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// `x.reverse_bits()` in three instructions where the CPU has GFNI (x86 has no bit
/// reversal of its own): an affine transform over GF(2) that reverses the bits of each byte,
/// then a byte swap.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "gfni")]
#[inline]
fn reverse_bits_gfni(x: u32) -> u32 {
    use std::arch::x86_64::*;
    // The 8x8 bit matrix whose row k picks bit 7 - k: each byte's bits reversed.
    const REVERSE_BYTE: u64 = 0x8040_2010_0804_0201;
    let v = _mm_cvtsi32_si128(x as i32);
    let r = _mm_gf2p8affine_epi64_epi8::<0>(v, _mm_set1_epi64x(REVERSE_BYTE as i64));
    (_mm_cvtsi128_si32(r) as u32).swap_bytes()
}

/// The (bounce, pair) keys whose seeds a [`SeedTable`] keeps: those of bounces below
/// `CACHED_KEYS / DIMS_PER_BOUNCE` (8), where nearly every path's draws fall.
const CACHED_KEYS: usize = 128;

/// The seeds (`pcg4d` of pixel, bounce, pair and seed) that one pixel's draws have
/// computed, for its next samples: they do not depend on the sample. The CPU renderer
/// gives one to the streams of a pixel's samples in a pass ([`Rng::with_table`]), so that
/// each key is hashed once per pixel and pass instead of once per sample; the numbers are
/// the same bits. The GPU, one sample per invocation, keeps no such table.
pub struct SeedTable {
    /// Bit `key` set where `seeds[key]` holds the seeds of key `key`; the others are
    /// uninitialised, so that a new table writes nothing but this mask.
    cached: Cell<u128>,
    seeds: [Cell<MaybeUninit<[u32; 4]>>; CACHED_KEYS],
}

impl SeedTable {
    /// An empty table.
    pub fn new() -> Self {
        Self {
            cached: Cell::new(0),
            seeds: [const { Cell::new(MaybeUninit::uninit()) }; CACHED_KEYS],
        }
    }
}

impl Default for SeedTable {
    fn default() -> Self {
        Self::new()
    }
}

impl std::fmt::Debug for SeedTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "SeedTable({:#x})", self.cached.get())
    }
}

/// The random stream of one camera sample: the key that, with a bounce and a
/// dimension, names every number the path uses. mirror: shaders/rng.wgsl `Rng`
#[derive(Clone, Copy, Debug)]
pub struct Rng<'a> {
    pixel: u32,
    sample: u32,
    seed: u32,
    /// `sample` with its bits reversed, as the index shuffle of every draw takes it: kept
    /// so that draws do not reverse it again (x86 has no bit-reversal instruction; the WGSL
    /// twin, whose `reverseBits` is one, keeps no such copy).
    sample_reversed: u32,
    /// Where the pixel's seeds are kept, if anywhere.
    table: Option<&'a SeedTable>,
}

impl Rng<'static> {
    /// The stream of one sample.
    pub fn new(pixel: u32, sample: u32, seed: u32) -> Self {
        Self {
            pixel,
            sample,
            seed,
            sample_reversed: sample.reverse_bits(),
            table: None,
        }
    }
}

impl<'a> Rng<'a> {
    /// The stream of `sample`, keeping its seeds in `table` (emptied first) for the
    /// pixel's further samples, which [`Self::set_sample`] moves it through.
    pub fn with_table(pixel: u32, sample: u32, seed: u32, table: &'a SeedTable) -> Self {
        table.cached.set(0);
        Self {
            table: Some(table),
            ..Rng::new(pixel, sample, seed)
        }
    }

    /// The sample index.
    pub fn sample(&self) -> u32 {
        self.sample
    }

    /// The stream of another sample of the same pixel and seed.
    pub fn set_sample(&mut self, sample: u32) {
        self.sample = sample;
        self.sample_reversed = sample.reverse_bits();
    }

    /// The uniform number in [0, 1) for (bounce, dimension). mirror: shaders/rng.wgsl `rng_1d`
    pub fn rng_1d(&self, bounce: u32, dim: u32) -> f32 {
        u32_to_unit(self.rng_u32(bounce, dim))
    }

    /// The raw 32 bits for (bounce, dimension): component `c` of the pair of `dim`, at the
    /// sample index shuffled for (pixel, bounce, pair, seed), Owen-scrambled for the
    /// component. mirror: shaders/rng.wgsl `rng_u32`
    pub fn rng_u32(&self, bounce: u32, dim: u32) -> u32 {
        let (pair, c) = dim_pair(dim);
        let (seeds, index) = self.pair_index(bounce, pair, u32::reverse_bits);
        owen_hash(sobol_reversed(index, c), seeds[1 + c as usize]).reverse_bits()
    }

    /// Both numbers of the pair that starts at dimension `dim` (pixel, lens, light or BSDF
    /// u): `(rng_1d(bounce, dim), rng_1d(bounce, dim + 1))`, with the pair's seeds and
    /// shuffled index computed once. mirror: shaders/rng.wgsl `rng_2d`
    pub fn rng_2d(&self, bounce: u32, dim: u32) -> Vec2 {
        debug_assert_eq!(
            dim_pair(dim + 1),
            (dim, 1),
            "dimension {dim} starts no pair"
        );
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("gfni") {
            // SAFETY: the CPU has GFNI, the only requirement of `rng_2d_gfni`.
            return unsafe { self.rng_2d_gfni(bounce, dim) };
        }
        self.rng_2d_with(bounce, dim, u32::reverse_bits)
    }

    /// [`Self::rng_2d`] with its three bit reversals done by [`reverse_bits_gfni`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "gfni")]
    fn rng_2d_gfni(&self, bounce: u32, dim: u32) -> Vec2 {
        // A closure inside a GFNI function may call GFNI functions safely.
        self.rng_2d_with(bounce, dim, |x| reverse_bits_gfni(x))
    }

    /// [`Self::rng_2d`]'s arithmetic, reversing bits with `reverse`.
    #[inline(always)]
    fn rng_2d_with(&self, bounce: u32, dim: u32, reverse: impl Fn(u32) -> u32) -> Vec2 {
        let (seeds, index) = self.pair_index(bounce, dim, &reverse);
        let component = |c: u32| {
            u32_to_unit(reverse(owen_hash(
                sobol_reversed(index, c),
                seeds[1 + c as usize],
            )))
        };
        Vec2::new(component(0), component(1))
    }

    /// The seeds of (pixel, bounce, pair, seed) and the sample index shuffled by the first.
    #[inline(always)]
    fn pair_index(&self, bounce: u32, pair: u32, reverse: impl Fn(u32) -> u32) -> ([u32; 4], u32) {
        let key = bounce.wrapping_mul(DIMS_PER_BOUNCE).wrapping_add(pair);
        let seeds = self.key_seeds(key);
        (seeds, reverse(owen_hash(self.sample_reversed, seeds[0])))
    }

    /// `pcg4d` of (pixel, key, seed), from the table where it is kept.
    #[inline(always)]
    fn key_seeds(&self, key: u32) -> [u32; 4] {
        let hash = || pcg4d([self.pixel, key, self.seed, 0x5eed]);
        let Some((table, slot)) = self
            .table
            .and_then(|table| Some((table, table.seeds.get(key as usize)?)))
        else {
            return hash();
        };
        let bit = 1u128 << key;
        let cached = table.cached.get();
        if cached & bit != 0 {
            // SAFETY: the slot was written when its bit was set.
            return unsafe { slot.get().assume_init() };
        }
        let seeds = hash();
        slot.set(MaybeUninit::new(seeds));
        table.cached.set(cached | bit);
        seeds
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_floats_are_in_range_and_uniform() {
        let rng = Rng::new(7, 3, 11);
        let n = 100_000u32;
        let mut buckets = [0u32; 10];
        for d in 0..n {
            let x = rng.rng_1d(d / DIMS_PER_BOUNCE, d % DIMS_PER_BOUNCE);
            assert!((0.0..1.0).contains(&x));
            buckets[(x * 10.0) as usize] += 1;
        }
        // Chi-square with 9 degrees of freedom; 27.9 is the 0.999 quantile.
        let expect = n as f64 / 10.0;
        let chi2: f64 = buckets
            .iter()
            .map(|&b| (b as f64 - expect).powi(2) / expect)
            .sum();
        assert!(chi2 < 27.9, "chi2 = {chi2}, buckets {buckets:?}");
    }

    /// The first 256 samples of a pixel, in each pair of dimensions that a stage draws
    /// together, form a (0, 8, 2)-net: one point in each of the 16 × 16 squares, and in
    /// each of the 256 × 1 and 1 × 256 strips; a single dimension alone puts one point in
    /// each 1/256 of [0, 1). Independent numbers would leave many cells empty.
    #[test]
    fn a_pixels_samples_are_stratified_in_every_pair() {
        for (pixel, bounce, seed) in [(0, 0, 0), (12345, 3, 7), (u32::MAX, 9, 1)] {
            for (du, dv) in [
                (DIM_PIXEL_X, DIM_PIXEL_Y),
                (DIM_LENS_U, DIM_LENS_V),
                (DIM_LIGHT_U, DIM_LIGHT_V),
                (DIM_BSDF_U, DIM_BSDF_V),
                (DIM_CAUSTIC_LIGHT_U, DIM_CAUSTIC_LIGHT_V),
                (DIM_CAUSTIC_DIR_U, DIM_CAUSTIC_DIR_V),
            ] {
                for (nx, ny) in [(16, 16), (256, 1), (1, 256)] {
                    let mut cells = vec![0u32; 256];
                    for sample in 0..256 {
                        let rng = Rng::new(pixel, sample, seed);
                        let x = (rng.rng_1d(bounce, du) * nx as f32) as usize;
                        let y = (rng.rng_1d(bounce, dv) * ny as f32) as usize;
                        cells[y * nx + x] += 1;
                    }
                    assert!(
                        cells.iter().all(|&c| c == 1),
                        "pixel {pixel}, dims ({du}, {dv}), {nx}x{ny}: {cells:?}"
                    );
                }
            }
            for dim in [
                DIM_BSDF_LOBE,
                DIM_ROULETTE,
                DIM_LIGHT_SUBPATH,
                DIM_CAUSTIC_LOBE,
            ] {
                let mut cells = vec![0u32; 256];
                for sample in 0..256 {
                    let x = Rng::new(pixel, sample, seed).rng_1d(bounce, dim);
                    cells[(x * 256.0) as usize] += 1;
                }
                assert!(cells.iter().all(|&c| c == 1), "dim {dim}: {cells:?}");
            }
        }
    }

    #[test]
    fn a_seed_table_changes_no_number() {
        let table = SeedTable::new();
        for (pixel, seed) in [(3, 0), (3, 1), (40_000, 1)] {
            let mut kept = Rng::with_table(pixel, 0, seed, &table);
            for sample in [0, 1, 7, 63, 1 << 20] {
                kept.set_sample(sample);
                let fresh = Rng::new(pixel, sample, seed);
                for bounce in 0..12 {
                    for dim in [DIM_PIXEL_X, DIM_LIGHT_U, DIM_BSDF_U] {
                        assert_eq!(kept.rng_2d(bounce, dim), fresh.rng_2d(bounce, dim));
                    }
                    for dim in [DIM_LIGHT_V, DIM_BSDF_LOBE, DIM_ROULETTE] {
                        assert_eq!(kept.rng_u32(bounce, dim), fresh.rng_u32(bounce, dim));
                    }
                }
            }
        }
    }

    #[test]
    fn streams_differ_by_every_key_word() {
        let base = Rng::new(1, 2, 3).rng_u32(4, 5);
        assert_ne!(base, Rng::new(0, 2, 3).rng_u32(4, 5));
        assert_ne!(base, Rng::new(1, 0, 3).rng_u32(4, 5));
        assert_ne!(base, Rng::new(1, 2, 0).rng_u32(4, 5));
        assert_ne!(base, Rng::new(1, 2, 3).rng_u32(0, 5));
        assert_ne!(base, Rng::new(1, 2, 3).rng_u32(4, 0));
    }

    /// The byte tables give the generator matrix's product, and the pair draw gives what
    /// its two single draws give.
    #[test]
    fn sobol_tables_and_pair_draws_agree_with_their_definitions() {
        let mut x = 0x1234_5678u32;
        for _ in 0..10_000 {
            x = pcg4d([x, 1, 2, 3])[0];
            let by_bits = (0..32)
                .filter(|b| (x >> b) & 1 != 0)
                .fold(0, |acc, b| acc ^ SOBOL_1[b]);
            assert_eq!(sobol(x, 1), by_bits, "index {x:#x}");
            assert_eq!(sobol(x, 0), x.reverse_bits());
            assert_eq!(
                owen_scramble(x, 77),
                owen_hash(x.reverse_bits(), 77).reverse_bits()
            );
        }
        for (pixel, sample, seed) in [(0, 0, 0), (9, 1234, 5), (u32::MAX, u32::MAX, 1)] {
            let rng = Rng::new(pixel, sample, seed);
            for bounce in [0, 1, 7] {
                for dim in [DIM_PIXEL_X, DIM_LENS_U, DIM_LIGHT_U, DIM_BSDF_U] {
                    let pair = rng.rng_2d(bounce, dim);
                    assert_eq!(pair.x.to_bits(), rng.rng_1d(bounce, dim).to_bits());
                    assert_eq!(pair.y.to_bits(), rng.rng_1d(bounce, dim + 1).to_bits());
                }
            }
        }
    }

    /// The GFNI reversal is `reverse_bits` (where the CPU has GFNI; elsewhere there is
    /// nothing to compare), on every single bit and on hashed words.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_gfni_bit_reversal_is_reverse_bits() {
        if !std::arch::is_x86_feature_detected!("gfni") {
            eprintln!("skipped: this CPU has no GFNI");
            return;
        }
        let words = (0..32)
            .map(|b| 1u32 << b)
            .chain((0..100_000).map(|i| pcg4d([i, 9, 8, 7])[1]));
        for x in words.chain([0, u32::MAX]) {
            // SAFETY: the CPU has GFNI.
            assert_eq!(
                unsafe { reverse_bits_gfni(x) },
                x.reverse_bits(),
                "{x:#010x}"
            );
        }
    }

    #[test]
    fn pcg4d_known_values() {
        // Pinned against an independent implementation (Python, wrapping u32 arithmetic):
        // a change to the hash would silently break replaying renders and GPU/CPU agreement.
        assert_eq!(
            pcg4d([0, 0, 0, 0]),
            [251852841, 760645481, 850445371, 3542436074]
        );
        assert_eq!(
            pcg4d([1, 2, 3, 4]),
            [908250390, 4044648920, 3775961919, 45698095]
        );
    }
}
