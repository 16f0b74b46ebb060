//! What every comparison draws on: a small random stream, the meshes (the real ones beside
//! the checkout where present, else generated or shipped ones), closedness and inside tests
//! for the escape counts, and the rays the traversal measures trace.

use glam::{DVec3, Vec3};
use meshtrace::geometry::TriVerts;
use meshtrace::math::{Aabb, Ray};
use meshtrace::scene::obj::load_obj;
use meshtrace::scene::source::Fs;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// SplitMix64 (Steele, Lea and Flood 2014): one add and three mixes a draw, so the
/// samplers' timings are mostly their own work, and the same seed always gives the same
/// numbers.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    #[inline(always)]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 24 random bits, as meshtrace's samplers take their inputs.
    #[inline(always)]
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform in [-1, 1) with 53 random bits: the seed's `Random{-1, 1}.getDouble()`
    /// (`std::uniform_real_distribution<double>`).
    #[inline(always)]
    pub fn signed_f64(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)) * 2.0 - 1.0
    }

    /// Uniform index below `n`.
    pub fn below(&mut self, n: usize) -> usize {
        (((self.next_u64() >> 32) * n as u64) >> 32) as usize
    }

    /// A uniform direction (by rejection from the cube, in f64).
    pub fn direction(&mut self) -> Vec3 {
        loop {
            let v = DVec3::new(self.signed_f64(), self.signed_f64(), self.signed_f64());
            let l = v.length_squared();
            if l > 1e-6 && l < 1.0 {
                return (v / l.sqrt()).as_vec3();
            }
        }
    }

    /// Uniform barycentrics (b1, b2) of a point inside a triangle, away from its edges
    /// when `margin > 0` (every barycentric at least `margin`).
    pub fn barycentrics(&mut self, margin: f32) -> (f32, f32) {
        loop {
            let (a, b) = (self.f32(), self.f32());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            if a >= margin && b >= margin && 1.0 - a - b >= margin {
                return (a, b);
            }
        }
    }
}

/// A source of uniform doubles in [-1, 1), as the seed's samplers draw them.
pub trait SignedUniform {
    fn signed_f64(&mut self) -> f64;
}

impl SignedUniform for Rng {
    #[inline(always)]
    fn signed_f64(&mut self) -> f64 {
        Rng::signed_f64(self)
    }
}

/// The seed's own generator (`Random` in `Step 2/include/util/std.h`): `std::mt19937`
/// (Matsumoto and Nishimura 1998) behind libstdc++'s
/// `std::uniform_real_distribution<double>{-1, 1}`, which makes each double of two 32-bit
/// outputs (`generate_canonical`: `(a + b 2^32) / 2^64`). A draw costs several times one of
/// [`Rng`], which changes how much the rejection method's extra draws weigh.
#[derive(Clone)]
pub struct Mt19937 {
    state: [u32; 624],
    index: usize,
}

impl Mt19937 {
    pub fn new(seed: u32) -> Self {
        let mut state = [0u32; 624];
        state[0] = seed;
        for i in 1..624 {
            let prev = state[i - 1];
            state[i] = 1_812_433_253u32
                .wrapping_mul(prev ^ (prev >> 30))
                .wrapping_add(i as u32);
        }
        Self { state, index: 624 }
    }

    /// The next 32-bit output.
    #[inline(always)]
    pub fn next_u32(&mut self) -> u32 {
        if self.index >= 624 {
            self.twist();
        }
        let mut y = self.state[self.index];
        self.index += 1;
        y ^= y >> 11;
        y ^= (y << 7) & 0x9d2c_5680;
        y ^= (y << 15) & 0xefc6_0000;
        y ^ (y >> 18)
    }

    fn twist(&mut self) {
        for i in 0..624 {
            let y = (self.state[i] & 0x8000_0000) | (self.state[(i + 1) % 624] & 0x7fff_ffff);
            let mag = if y & 1 == 0 { 0 } else { 0x9908_b0df };
            self.state[i] = self.state[(i + 397) % 624] ^ (y >> 1) ^ mag;
        }
        self.index = 0;
    }
}

impl SignedUniform for Mt19937 {
    #[inline(always)]
    fn signed_f64(&mut self) -> f64 {
        let low = f64::from(self.next_u32());
        let high = f64::from(self.next_u32());
        let canonical = ((low + high * 4_294_967_296.0) / 18_446_744_073_709_551_616.0)
            .min(1.0 - f64::EPSILON / 2.0);
        2.0 * canonical - 1.0
    }
}

/// An indexed triangle mesh, as the comparisons need it: positions and corner indices.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// Each triangle's box, in input order (what the builders take).
    pub fn bounds(&self) -> Vec<Aabb> {
        (0..self.triangles.len())
            .map(|t| Aabb::from_points(&self.corners(t)))
            .collect()
    }

    /// The triangles in the order `order` names them (a tree's leaf order).
    pub fn tri_verts(&self, order: &[u32]) -> Vec<TriVerts> {
        order
            .iter()
            .map(|&i| TriVerts::new(self.corners(i as usize)))
            .collect()
    }

    /// The box of the whole mesh.
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }

    /// Every undirected edge once, with how many triangles use it in each direction.
    fn edge_uses(&self) -> HashMap<(u32, u32), (u32, u32)> {
        let mut uses: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
        for t in &self.triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let e = uses.entry((a.min(b), a.max(b))).or_default();
                if a < b {
                    e.0 += 1;
                } else {
                    e.1 += 1;
                }
            }
        }
        uses
    }

    /// The undirected edges, each once, in a fixed order.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut edges: Vec<[u32; 2]> = self.edge_uses().keys().map(|&(a, b)| [a, b]).collect();
        edges.sort_unstable();
        edges
    }

    /// Whether the mesh is closed and consistently wound: every edge is used by exactly two
    /// triangles, once in each direction. A ray from inside such a mesh must cross it, so
    /// a test that reports no hit for one has let it through a crack.
    pub fn is_closed(&self) -> bool {
        self.edge_uses().values().all(|&uses| uses == (1, 1))
    }

    /// The generalised winding number of point `p` (Jacobson et al. 2013): the triangles'
    /// signed solid angles (Van Oosterom and Strackee 1983) over 4 pi. 1 inside a closed
    /// mesh wound outwards, 0 outside.
    pub fn winding_number(&self, p: DVec3) -> f64 {
        let mut sum = 0.0;
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.positions[i as usize].as_dvec3() - p);
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let num = a.dot(b.cross(c));
            let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
            sum += 2.0 * num.atan2(den);
        }
        sum / (4.0 * std::f64::consts::PI)
    }

    /// `n` points inside the (closed) mesh: random points of its box whose winding number
    /// is near 1 and that lie at least 2% of the box's diagonal from every vertex.
    pub fn interior_points(&self, n: usize, rng: &mut Rng) -> Vec<Vec3> {
        let b = self.aabb();
        let clearance = 0.02 * b.extent().length();
        let mut out = Vec::with_capacity(n);
        for _ in 0..100_000 {
            if out.len() == n {
                break;
            }
            let p = b.min + b.extent() * Vec3::new(rng.f32(), rng.f32(), rng.f32());
            let near = self.positions.iter().any(|&v| v.distance(p) < clearance);
            if !near && (self.winding_number(p.as_dvec3()) - 1.0).abs() < 1e-3 {
                out.push(p);
            }
        }
        assert_eq!(out.len(), n, "{}: too few interior points found", self.name);
        out
    }
}

/// The unit icosphere of `level` (`meshtrace::scene::sphere`): closed by construction, as
/// subdivision shares every midpoint between the two triangles of its edge.
pub fn icosphere(level: u32) -> Mesh {
    let (positions, triangles) = meshtrace::scene::sphere::icosphere(level);
    Mesh {
        name: format!("icosphere-{level}"),
        positions,
        triangles,
    }
}

/// The checkout's root.
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Where the bench writes its measurements and the plot script reads them: criterion's
/// own rule for its folder (`$CARGO_TARGET_DIR`, else `target/`), `algorithms/` in it.
pub fn results_dir() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"));
    target.join("algorithms")
}

/// An OBJ file as a [`Mesh`] (its name without the extension).
pub fn load(path: &Path) -> Mesh {
    let part = load_obj(path, &Fs).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Mesh {
        name: path
            .file_stem()
            .map_or("mesh".into(), |s| s.to_string_lossy().into_owned()),
        positions: part.positions,
        triangles: part.triangles.iter().map(|t| t.p).collect(),
    }
}

/// A mesh of `../shared/meshes` beside the checkout, or `None` after saying why not.
pub fn shared_mesh(file: &str) -> Option<Mesh> {
    let path = root().join("../shared/meshes").join(file);
    if path.exists() {
        Some(load(&path))
    } else {
        eprintln!("algorithms: {} absent; skipping it", path.display());
        None
    }
}

/// The mesh the speed measures trace and the builders build over: the Stanford bunny
/// (69,451 triangles) where `../shared` has it, else an icosphere of 81,920.
pub fn speed_mesh() -> Mesh {
    shared_mesh("stanford-bunny.obj").unwrap_or_else(|| {
        eprintln!("algorithms: using icosphere-6 for the speed measures instead");
        icosphere(6)
    })
}

/// The closed meshes of the escape counts: an icosphere always, and spot and homer (both
/// closed, consistently wound) where `../shared` has them.
pub fn closed_meshes() -> Vec<Mesh> {
    let mut meshes = vec![icosphere(4)];
    meshes.extend(
        ["spot.obj", "homer.obj"]
            .into_iter()
            .filter_map(shared_mesh),
    );
    for m in &meshes {
        assert!(m.is_closed(), "{} is not closed", m.name);
    }
    meshes
}

/// The built-in Cornell box's shapes as one mesh (shipped in `assets/cornell/`): walls,
/// floor, ceiling and box tops lie in axis planes, so their triangles' boxes are flat.
pub fn cornell_box() -> Mesh {
    let mut mesh = Mesh {
        name: "cornell".into(),
        positions: Vec::new(),
        triangles: Vec::new(),
    };
    for shape in [
        "floor",
        "ceiling",
        "back",
        "green_wall",
        "red_wall",
        "light",
        "small_box",
        "large_box",
    ] {
        let part = load(&root().join("assets/cornell").join(format!("{shape}.obj")));
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(part.positions);
        mesh.triangles
            .extend(part.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    mesh
}

/// `n` rays that hit `mesh`: from random points of a sphere twice the size of the mesh's
/// bounding sphere, towards a random point of a random triangle. What a renderer's rays
/// that find something cost, without the empty space around the mesh.
pub fn aimed_rays(mesh: &Mesh, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    let b = mesh.aabb();
    let (centre, radius) = (b.center(), b.extent().length());
    (0..n)
        .map(|_| {
            let origin = centre + radius * rng.direction();
            let [a, p, q] = mesh.corners(rng.below(mesh.triangles.len()));
            let (u, v) = rng.barycentrics(0.0);
            let target = a + u * (p - a) + v * (q - a);
            Ray::new(origin, (target - origin).normalize())
        })
        .collect()
}
