//! Property tests (proptest): the BVH over random triangle soups (degenerate, huge and
//! tiny triangles included) against brute force, and scene files generated from the
//! format's grammar, which must parse or fail with a one-line error naming the file.

use crate::common;

use glam::Vec3;
use meshtrace::bvh::{BuildParams, Bvh, solid, traverse_any, traverse_closest, validate};
use meshtrace::geometry::{
    ShearedRay, T_INF, TriVerts, intersect_aabb, intersect_triangle, safe_inverse,
};
use meshtrace::math::{Aabb, Ray};
use meshtrace::scene::parse_scene;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use std::fmt::Write as _;
use std::path::Path;

// ---------------------------------------------------------------------------------------
// Triangle soups and rays
// ---------------------------------------------------------------------------------------

/// A coordinate in about [-4, 4]: often a small integer, so that shared edges, axis-aligned
/// triangles and exactly coplanar faces are common.
fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => -4.0f32..4.0,
        1 => (-4i32..=4).prop_map(|i| i as f32),
        1 => (-8i32..=8).prop_map(|i| i as f32 * 0.5),
    ]
}

fn point() -> impl Strategy<Value = Vec3> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// A triangle, often degenerate: repeated corners, one point, collinear corners, or tiny.
fn triangle() -> impl Strategy<Value = [Vec3; 3]> {
    prop_oneof![
        6 => [point(), point(), point()],
        1 => (point(), point()).prop_map(|(a, b)| [a, a, b]),
        1 => (point(), point()).prop_map(|(a, b)| [a, b, b]),
        1 => point().prop_map(|a| [a, a, a]),
        1 => (point(), point(), -2.0f32..3.0).prop_map(|(a, b, s)| [a, b, a + s * (b - a)]),
        1 => (point(), point(), -2i32..=3).prop_map(|(a, b, s)| [a, a + s as f32 * (b - a), b]),
        // Axis-aligned and flat: a zero-thickness box.
        1 => (point(), coord(), coord()).prop_map(|(a, dx, dy)| {
            [a, a + Vec3::new(dx, 0.0, 0.0), a + Vec3::new(0.0, dy, 0.0)]
        }),
        1 => (point(), point(), point()).prop_map(|(a, b, c)| [a, a + 1e-4 * b, a + 1e-4 * c]),
    ]
}

/// Whether a triangle is far from degenerate: its smallest angle's sine is at least 1e-3.
/// Only such triangles get exact agreement between the triangle and box tests; see
/// `bvh_with_degenerate_triangles_matches_brute_force`.
fn well_shaped([a, b, c]: &[Vec3; 3]) -> bool {
    let (e1, e2, e3) = (*b - *a, *c - *a, *c - *b);
    let area2 = e1.cross(e2).length();
    let longest = e1.length().max(e2.length()).max(e3.length());
    area2.is_finite() && area2 > 1e-3 * longest * longest
}

#[derive(Clone)]
struct Soup {
    tris: Vec<[Vec3; 3]>,
}

/// One triangle a line, as arrays, so that a failing case can be pasted into a test.
impl std::fmt::Debug for Soup {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        writeln!(f, "Soup {{ {} triangles:", self.tris.len())?;
        for t in &self.tris {
            writeln!(f, "    {:?},", t.map(|p| p.to_array()))?;
        }
        write!(f, "}}")
    }
}

/// 1–300 triangles, the whole soup scaled to unit, huge (1e6) or tiny (1e-6) size and
/// possibly moved far (1e6) from the origin (tiny soups moved far collapse to a point).
/// With `degenerate` false, triangles that are not [`well_shaped`] are left out.
fn soup(degenerate: bool) -> impl Strategy<Value = Soup> {
    let scale = prop_oneof![Just(1.0f32), Just(1e6), Just(1e-6)];
    let offset = prop_oneof![
        3 => Just(Vec3::ZERO),
        1 => Just(Vec3::new(1e6, -1e6, 1e6)),
    ];
    (prop::collection::vec(triangle(), 1..=300), scale, offset).prop_map(move |(tris, s, o)| {
        let mut tris: Vec<[Vec3; 3]> = tris
            .into_iter()
            .map(|t| t.map(|p| p * s + o))
            .filter(|t| degenerate || well_shaped(t))
            .collect();
        if tris.is_empty() {
            tris.push([Vec3::ZERO, Vec3::X, Vec3::Y].map(|p| p * s));
        }
        Soup { tris }
    })
}

/// A ray in units of the soup's bounds: from anywhere around them, aimed at a point on a
/// triangle (most hit), in a random direction, or along an axis (zero direction
/// components, which the slab test must survive).
#[derive(Clone, Debug)]
struct RaySpec {
    origin: [f32; 3],
    aim: Aim,
}

#[derive(Clone, Debug)]
enum Aim {
    Triangle { index: usize, u: f32, v: f32 },
    Direction([f32; 3]),
    Axis { axis: usize, negative: bool },
}

fn ray_spec() -> impl Strategy<Value = RaySpec> {
    let aim = prop_oneof![
        4 => (any::<usize>(), 0.0f32..=1.0, 0.0f32..=1.0)
            .prop_map(|(index, u, v)| Aim::Triangle { index, u, v }),
        2 => [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0].prop_map(Aim::Direction),
        1 => (0usize..3, any::<bool>())
            .prop_map(|(axis, negative)| Aim::Axis { axis, negative }),
    ];
    ([-0.5f32..1.5, -0.5f32..1.5, -0.5f32..1.5], aim)
        .prop_map(|(origin, aim)| RaySpec { origin, aim })
}

fn rays() -> impl Strategy<Value = Vec<RaySpec>> {
    prop::collection::vec(ray_spec(), 1..48)
}

fn make_ray(spec: &RaySpec, bounds: &Aabb, tris: &[[Vec3; 3]]) -> Option<Ray> {
    let origin = bounds.min + bounds.extent() * Vec3::from(spec.origin);
    let dir = match spec.aim {
        Aim::Triangle { index, u, v } => {
            let [a, b, c] = tris[index % tris.len()];
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            (a + u * (b - a) + v * (c - a)) - origin
        }
        Aim::Direction(d) => Vec3::from(d),
        Aim::Axis { axis, negative } => {
            let mut d = Vec3::ZERO;
            d[axis] = if negative { -1.0 } else { 1.0 };
            d
        }
    };
    let dir = dir.try_normalize()?;
    origin.is_finite().then_some(Ray::new(origin, dir))
}

/// The closest hit over every triangle (leaf order), as (t, leaf index).
fn brute_force(tris: &[TriVerts], ray: &Ray) -> Option<(f32, u32)> {
    let mut best: Option<(f32, u32)> = None;
    for (k, t) in tris.iter().enumerate() {
        if let Some(h) = intersect_triangle(&ShearedRay::new(ray), t, best.map_or(T_INF, |b| b.0)) {
            best = Some((h.t, k as u32));
        }
    }
    best
}

/// The next larger float of a positive finite `x`.
fn next_float(x: f32) -> f32 {
    f32::from_bits(x.to_bits() + 1)
}

/// The distance to the triangle's plane in `f64`, rounded up to an `f32`.
fn exact_plane_distance(ray: &Ray, tri: &TriVerts) -> f32 {
    let [a, b, c] = tri.corners().map(|p| p.as_dvec3());
    let n = (b - a).cross(c - a);
    let t = n.dot(a - ray.origin.as_dvec3()) / n.dot(ray.dir.as_dvec3());
    let t32 = t as f32;
    if (t32 as f64) < t {
        next_float(t32)
    } else {
        t32
    }
}

/// Where the closest triangle's own box is entered, for failure messages.
fn explain(tris: &[TriVerts], ray: &Ray, best: Option<(f32, u32)>) -> String {
    let Some((t, k)) = best else {
        return String::new();
    };
    let tri = &tris[k as usize];
    let b = Aabb::from_points(&tri.corners());
    let entry = intersect_aabb(ray.origin, safe_inverse(ray.dir), b.min, b.max, T_INF);
    let h = intersect_triangle(&ShearedRay::new(ray), tri, T_INF);
    format!(
        "hit triangle {:?} at {} (u, v = {:?}); its box {b:?} is entered at t = {entry:e}, the hit is at t = {t:e}",
        tri.corners().map(|p| p.to_array()),
        ray.at(t),
        h.map(|h| (h.u, h.v))
    )
}

/// What to check of a soup besides the tree's invariants.
#[derive(Clone, Copy)]
struct Checks {
    /// `traverse_closest` against brute force.
    closest: bool,
    /// `traverse_any` against the closest hit, for `t_max` at least 0.1% from it.
    any: bool,
    /// `traverse_any` with `t_max` one ulp beyond both the computed and the exact hit.
    any_beyond_hit: bool,
}

fn check_soup(soup: &Soup, rays: &[RaySpec], checks: Checks) -> Result<(), TestCaseError> {
    let bounds: Vec<Aabb> = soup.tris.iter().map(|c| Aabb::from_points(c)).collect();
    let bvh = Bvh::build(&bounds, &BuildParams::default())
        .map_err(|e| TestCaseError::fail(format!("build: {e}")))?;
    if let Err(e) = validate(&bvh, &bounds) {
        return Err(TestCaseError::fail(format!("invalid BVH: {e}")));
    }
    let tris: Vec<TriVerts> = bvh
        .order
        .iter()
        .map(|&i| TriVerts::new(soup.tris[i as usize]))
        .collect();
    let all = bounds.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
    for (r, spec) in rays.iter().enumerate() {
        let Some(ray) = make_ray(spec, &all, &soup.tris) else {
            continue;
        };
        let best = brute_force(&tris, &ray);
        let hit = traverse_closest(&bvh.nodes, &tris, &ray, T_INF, solid);
        if checks.closest {
            let same = match (best, hit) {
                (None, None) => true,
                // The same distance from another triangle: a ray through a shared edge or
                // coincident faces.
                (Some((t, k)), Some(h)) => h.tri == k || h.t == t,
                _ => false,
            };
            prop_assert!(
                same,
                "ray {r} {ray:?}: brute force {best:?}, traverse_closest {hit:?}; {}",
                explain(&tris, &ray, best)
            );
        }
        let closest = best.map(|(t, _)| t);
        let mut limits = Vec::new();
        if checks.any {
            limits.extend([T_INF, 1.0, all.extent().length()]);
            if let Some(t) = closest {
                limits.extend([t, 0.5 * t, t * 0.999, t * 1.001]);
            }
        }
        if let (true, Some((t, k))) = (checks.any_beyond_hit, best) {
            // Beyond both the computed hit and the exact one: the box test's slack covers
            // its own rounding, and a box is entered before the exact hit inside it.
            let exact = exact_plane_distance(&ray, &tris[k as usize]);
            limits.push(next_float(t.max(exact)));
        }
        for t_max in limits {
            let expected = closest.is_some_and(|t| t < t_max);
            let any = traverse_any(&bvh.nodes, &tris, &ray, t_max, solid);
            prop_assert!(
                any == expected,
                "ray {r} {ray:?}: traverse_any(t_max = {t_max:e}) is {any}, closest hit {best:?}; {}",
                explain(&tris, &ray, best)
            );
        }
    }
    Ok(())
}

const ALL: Checks = Checks {
    closest: true,
    any: true,
    any_beyond_hit: false,
};

/// Every property: 256 cases from a fixed seed, so a run is reproducible and CI never
/// meets a case no one has seen.
fn config() -> Config {
    Config {
        cases: 256,
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(1),
        ..Config::default()
    }
}

proptest! {
    #![proptest_config(config())]

    /// Degenerate, huge and tiny triangles: the tree is valid.
    #[test]
    fn bvh_validates(soup in soup(true)) {
        check_soup(&soup, &[], ALL)?;
    }

    /// Well-shaped triangles, huge and tiny included: the tree's closest hit is brute
    /// force's, and any-hit agrees with it.
    #[test]
    fn bvh_matches_brute_force(soup in soup(false), rays in rays()) {
        check_soup(&soup, &rays, ALL)?;
    }

    #[test]
    fn bvh_with_degenerate_triangles_matches_brute_force(soup in soup(true), rays in rays()) {
        check_soup(&soup, &rays, ALL)?;
    }

    #[test]
    fn any_hit_just_beyond_the_closest_hit(soup in soup(false), rays in rays()) {
        check_soup(&soup, &rays, Checks { closest: false, any: false, any_beyond_hit: true })?;
    }
}

/// Many copies of the same triangle and of one point: no split plane separates them, so
/// the builder must still make a tree the traversal can walk.
#[test]
fn coincident_triangles() {
    let a = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let p = [Vec3::ONE; 3];
    for n in [1, 2, 16, 17, 300] {
        let soup = Soup {
            tris: std::iter::repeat_n(a, n)
                .chain(std::iter::repeat_n(p, n))
                .collect(),
        };
        let rays: Vec<RaySpec> = (0..8)
            .map(|i| RaySpec {
                origin: [0.1 * i as f32, 0.2, 1.5],
                aim: Aim::Triangle {
                    index: 0,
                    u: 0.25,
                    v: 0.25,
                },
            })
            .collect();
        check_soup(&soup, &rays, ALL).unwrap_or_else(|e| panic!("{n} copies: {e}"));
    }
}

/// A collinear triangle as an OBJ writes it (decimal coordinates, so its corners are only
/// nearly collinear in `f32` and the loader keeps it), and a ray aimed at its segment:
/// the triangle test reports a hit 0.027 away from the segment, outside the triangle's box.
#[test]
fn no_hit_outside_a_nearly_collinear_triangle() {
    let (a, c, b) = (
        Vec3::new(1.3, -0.6, -1.7),
        Vec3::new(0.7, -0.7, 0.1),
        Vec3::new(0.1, -0.8, 1.9),
    );
    let tri = TriVerts::new([a, c, b]);
    let ray = Ray::new(
        Vec3::new(-0.013272762, 2.2080655, 1.6160536),
        Vec3::new(0.25485438, -0.7587521, -0.59945357),
    );
    if let Some(h) = intersect_triangle(&ShearedRay::new(&ray), &tri, T_INF) {
        let p = ray.at(h.t);
        let b = Aabb::from_points(&tri.corners());
        let outside = (p - p.clamp(b.min, b.max)).length();
        assert!(
            outside < 1e-5,
            "hit at t = {} ({p}) lies {outside} outside the triangle's box {b:?}",
            h.t
        );
    }
}

// ---------------------------------------------------------------------------------------
// Scene files from the format's grammar
// ---------------------------------------------------------------------------------------

/// A float as TOML writes it; mostly in range, sometimes not (negative, zero, huge, tiny,
/// NaN, infinite), so that both outcomes occur.
fn float() -> impl Strategy<Value = String> {
    prop_oneof![
        8 => (-10.0f32..10.0).prop_map(|x| format!("{x:?}")),
        4 => (-3i32..=3).prop_map(|i| i.to_string()),
        1 => prop::sample::select(vec![
            "0.0", "-0.0", "1e30", "-1e30", "3e38", "1e39", "1e-30", "1e-45", "nan", "inf",
            "-inf", "+inf", "1_000.5", "6.02e23",
        ])
        .prop_map(str::to_string),
    ]
}

fn vec3() -> impl Strategy<Value = String> {
    [float(), float(), float()].prop_map(|[x, y, z]| format!("[{x}, {y}, {z}]"))
}

/// An unsigned setting: mostly sensible, sometimes zero, huge or negative (a type error).
fn uint() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => (1u32..64).prop_map(|i| i.to_string()),
        1 => prop::sample::select(vec!["0", "4294967295", "4294967296", "-1", "100000", "0x10"])
            .prop_map(str::to_string),
    ]
}

/// Optional `key = value` line.
fn opt_line(key: &'static str, value: BoxedStrategy<String>) -> impl Strategy<Value = String> {
    prop::option::weighted(0.5, value).prop_map(move |v| match v {
        Some(v) => format!("{key} = {v}\n"),
        None => String::new(),
    })
}

fn camera() -> impl Strategy<Value = String> {
    let position = prop_oneof![
        3 => Just("[0, 1, 5]".to_string()),
        1 => vec3(),
    ];
    (
        position,
        vec3(),
        opt_line("up", vec3().boxed()),
        opt_line(
            "vfov",
            (-10.0f32..200.0).prop_map(|x| format!("{x:?}")).boxed(),
        ),
        opt_line("aperture", float().boxed()),
        opt_line("focus_distance", float().boxed()),
    )
        .prop_map(|(p, l, up, vfov, ap, fd)| {
            format!("[camera]\nposition = {p}\nlook_at = {l}\n{up}{vfov}{ap}{fd}\n")
        })
}

fn render() -> impl Strategy<Value = String> {
    prop::option::of(
        (
            opt_line("width", uint().boxed()),
            opt_line("height", uint().boxed()),
            opt_line("spp", uint().boxed()),
            opt_line("max_depth", uint().boxed()),
            opt_line("seed", uint().boxed()),
        )
            .prop_map(|(w, h, s, d, seed)| format!("[render]\n{w}{h}{s}{d}{seed}\n")),
    )
    .prop_map(Option::unwrap_or_default)
}

fn sky() -> impl Strategy<Value = String> {
    prop_oneof![
        2 => Just(String::new()),
        2 => vec3().prop_map(|c| format!("[sky]\ncolor = {c}\n\n")),
        2 => (vec3(), vec3())
            .prop_map(|(z, h)| format!("[sky]\nzenith = {z}\nhorizon = {h}\n\n")),
        1 => (
            opt_line("color", vec3().boxed()),
            opt_line("zenith", vec3().boxed()),
            opt_line("horizon", vec3().boxed()),
        )
            .prop_map(|(c, z, h)| format!("[sky]\n{c}{z}{h}\n")),
    ]
}

/// A TOML basic string (quoted, escaped) holding `s`.
fn quoted(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => write!(out, "\\u{:04X}", c as u32).unwrap(),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn material(name: String) -> impl Strategy<Value = String> {
    let kind = prop::sample::select(vec![
        "diffuse",
        "conductor",
        "rough_conductor",
        "dielectric",
    ]);
    (
        kind,
        opt_line("albedo", vec3().boxed()),
        opt_line("emission", vec3().boxed()),
        opt_line("roughness", float().boxed()),
        opt_line("ior", float().boxed()),
    )
        .prop_map(move |(kind, albedo, emission, roughness, ior)| {
            format!(
                "[materials.{}]\ntype = \"{kind}\"\n{albedo}{emission}{roughness}{ior}\n",
                quoted(&name)
            )
        })
}

fn transform() -> impl Strategy<Value = String> {
    let matrix = (
        prop::collection::vec(float(), 12),
        prop_oneof![
            3 => Just("0, 0, 0, 1".to_string()),
            1 => [float(), float(), float(), float()].prop_map(|v| v.join(", ")),
        ],
    )
        .prop_map(|(m, last)| format!("matrix = [{}, {last}]\n", m.join(", ")));
    let scale = prop_oneof![float(), vec3()];
    prop_oneof![
        2 => Just(String::new()),
        3 => (
            opt_line("scale", scale.boxed()),
            opt_line("rotate", vec3().boxed()),
            opt_line("translate", vec3().boxed()),
        )
            .prop_map(|(s, r, t)| format!("{s}{r}{t}")),
        1 => matrix,
    ]
}

/// An object: a sphere (meshes are not on disk), its material by name (possibly unknown),
/// and a transform.
fn object(names: Vec<String>) -> impl Strategy<Value = String> {
    let material = prop_oneof![
        2 => Just(None),
        3 => prop::sample::select(if names.is_empty() {
            vec![String::from("x")]
        } else {
            names
        })
        .prop_map(Some),
        1 => Just(Some("unknown".to_string())),
    ];
    let subdivisions = prop_oneof![
        8 => (0u32..=3).prop_map(|s| format!(", subdivisions = {s}")),
        1 => Just(String::new()),
        1 => Just(", subdivisions = 11".to_string()),
    ];
    (vec3(), float(), subdivisions, material, transform()).prop_map(
        |(center, radius, sub, material, transform)| {
            let material = material
                .map(|m| format!("material = {}\n", quoted(&m)))
                .unwrap_or_default();
            format!(
                "[[objects]]\nsphere = {{ center = {center}, radius = {radius}{sub} }}\n{material}{transform}\n"
            )
        },
    )
}

/// A whole scene file; material names come from `name`.
fn scene_text(name: BoxedStrategy<String>) -> impl Strategy<Value = String> {
    prop::collection::btree_set(name, 0..4).prop_flat_map(|names| {
        let names: Vec<String> = names.into_iter().collect();
        let materials: Vec<_> = names.iter().map(|n| material(n.clone())).collect();
        let unknown_key = prop_oneof![
            12 => Just(String::new()),
            1 => Just("[render]\nfps = 3\n".to_string()),
        ];
        (
            camera(),
            render(),
            sky(),
            materials,
            prop::collection::vec(object(names), 0..4),
            unknown_key,
        )
            .prop_map(|(camera, render, sky, materials, objects, extra)| {
                format!(
                    "{camera}{render}{sky}{}{}{extra}",
                    materials.concat(),
                    objects.concat()
                )
            })
    })
}

/// Parses `text` as `scenes/generated.toml`: it must load, or fail with a one-line message
/// naming the file.
fn check_scene_text(text: &str) -> Result<(), TestCaseError> {
    let path = Path::new("scenes/generated.toml");
    if let Err(e) = parse_scene(text, path) {
        let msg = e.to_string();
        prop_assert!(
            !msg.contains(['\n', '\r']),
            "message is not one line: {msg:?}\n--- scene ---\n{text}"
        );
        prop_assert!(
            msg.contains("scenes/generated.toml"),
            "message does not name the file: {msg:?}\n--- scene ---\n{text}"
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    /// Material names as bare keys.
    #[test]
    fn generated_scenes_parse_or_fail_on_one_line(
        text in scene_text("[a-z][a-z0-9_-]{0,7}".boxed()),
    ) {
        check_scene_text(&text)?;
    }

    /// Material names as quoted keys holding any characters, line breaks included.
    #[test]
    fn generated_scenes_with_any_material_names_fail_on_one_line(
        text in scene_text(prop_oneof![
            any::<String>(),
            "[a-z]{0,3}[\n\r\t\"\\\\ .\\[\\]=#é\u{2028}]{1,3}[a-z]{0,3}",
        ].boxed()),
    ) {
        check_scene_text(&text)?;
    }
}

/// A mesh path holding a line break: the I/O error names the path, on one line.
#[test]
fn error_naming_a_mesh_path_with_a_line_break_is_one_line() {
    let text = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\n\
                [[objects]]\nmesh = \"no\\nsuch\\rmesh.obj\"\n";
    let err =
        parse_scene(text, Path::new("scenes/generated.toml")).expect_err("the mesh does not exist");
    let msg = err.to_string();
    assert!(!msg.contains(['\n', '\r']), "not one line: {msg:?}");
}

/// A quoted key holding a carriage return: toml's message quotes it, and the error must
/// still be one line (`Ctx::syntax` replaces only line feeds).
#[test]
fn syntax_error_quoting_a_carriage_return_is_one_line() {
    let text = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\n\"a\\rb\" = 1\n";
    let err = parse_scene(text, Path::new("scenes/generated.toml")).expect_err("an unknown key");
    let msg = err.to_string();
    assert!(!msg.contains(['\n', '\r']), "not one line: {msg:?}");
}

// ---------------------------------------------------------------------------------------
// Watertightness
// ---------------------------------------------------------------------------------------

/// Möller–Trumbore as the triangle test was before it became watertight: here only to show
/// that the rays of `no_ray_escapes_a_closed_mesh` do find the gaps of a test that is not.
fn moller_trumbore_hits(ray: &Ray, [v0, v1, v2]: [Vec3; 3]) -> bool {
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return false;
    }
    let inv = 1.0 / det;
    let s = ray.origin - v0;
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv;
    u >= 0.0 && v >= 0.0 && u + v <= 1.0 && e2.dot(q) * inv > 0.0
}

/// Rays from inside a closed mesh ([`common::scenes::closed_mesh_probe`]) all hit it: no ray slips
/// between two triangles that share an edge.
#[test]
fn no_ray_escapes_a_closed_mesh() {
    let probe = common::scenes::closed_mesh_probe();
    let tris: Vec<[Vec3; 3]> = probe
        .faces
        .iter()
        .map(|t| t.map(|k| probe.positions[k as usize]))
        .collect();
    let bounds: Vec<Aabb> = tris.iter().map(|c| Aabb::from_points(c)).collect();
    let bvh = Bvh::build(&bounds, &BuildParams::default()).unwrap();
    let leaf_tris: Vec<TriVerts> = bvh
        .order
        .iter()
        .map(|&i| TriVerts::new(tris[i as usize]))
        .collect();
    let (mut escapes, mut mt_escapes) = (Vec::new(), 0);
    for &(origin, dir) in &probe.rays {
        let ray = Ray::new(origin, dir);
        if traverse_closest(&bvh.nodes, &leaf_tris, &ray, T_INF, solid).is_none() {
            escapes.push(ray);
        }
        mt_escapes += !tris.iter().any(|&t| moller_trumbore_hits(&ray, t)) as usize;
    }
    eprintln!(
        "{} rays from inside: {} escape (Möller–Trumbore: {mt_escapes})",
        probe.rays.len(),
        escapes.len()
    );
    assert!(
        escapes.is_empty(),
        "{} rays escape, e.g. {:?}",
        escapes.len(),
        &escapes[..escapes.len().min(3)]
    );
    assert!(
        mt_escapes > 0,
        "the rays no longer probe the edges: Möller–Trumbore lets none escape"
    );
}
