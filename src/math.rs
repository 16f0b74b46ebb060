//! Rays, axis-aligned boxes and frames: the geometric primitives every other module
//! speaks. The ray and the frame have WGSL twins in `shaders/math.wgsl`.

use glam::Vec3;

/// A ray `origin + t * dir` for `t` in `[0, t_max)`; `dir` need not be normalised.
/// mirror: shaders/math.wgsl `Ray`
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// An axis-aligned bounding box; the empty box has `min > max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| b.grow(p))
    }

    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn union(self, o: Aabb) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }

    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Corner `k` of 8: bits 0, 1 and 2 of `k` pick `max` over `min` in x, y and z.
    pub fn corner(&self, k: usize) -> Vec3 {
        Vec3::select(
            glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
            self.max,
            self.min,
        )
    }

    /// Surface area, the SAH's measure of how likely a random ray is to hit the box.
    pub fn area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    pub fn contains(&self, o: &Aabb) -> bool {
        o.is_empty() || (self.min.cmple(o.min).all() && self.max.cmpge(o.max).all())
    }
}

/// Orthonormal basis around a unit normal (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
/// mirror: shaders/math.wgsl `onb_from_normal`
pub fn onb_from_normal(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    (t, bt)
}

/// Rec. 709 luminance, used to weigh emitters by power and for Russian roulette.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// A number uniform in [0, 1) for object `uid`, view `view` and dimension `dim`: a pure
/// function of the three (FNV-1a of the uid, mixed with the view and dimension by
/// SplitMix64's finaliser). The dataset scripts draw from unseeded generators; a batch
/// preset (and a lighting preset's suns) draws from the same distributions, reproducibly
/// and independently per object and view.
pub fn uniform(uid: &str, view: u32, dim: u32) -> f64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for b in uid.bytes() {
        h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
    }
    let mut x = h ^ ((view as u64) << 32 | dim as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^= x >> 31;
    (x >> 11) as f64 / (1u64 << 53) as f64
}
