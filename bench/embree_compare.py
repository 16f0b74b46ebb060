#!/usr/bin/env python3
"""Compare meshtrace's CPU primary-ray closest-hit throughput with Embree 4, per thread.

The mesh, the camera (`Camera::framing`) and the rays (`RaySets::primary` of
src/bench.rs: one jittered camera ray per pixel, pcg4d keys (pixel, 0, dim, 0x0bec))
are rebuilt here bit for bit in numpy float32/uint32 arithmetic, traced with Embree
through the `embreex` bindings (single-threaded: one `rtcIntersect1` per ray), and
compared with `meshtrace bench MESH --device cpu --threads 1 --json`.

Needs numpy and embreex (`pip install embreex`) and a release build of meshtrace
(`cargo build --release`). See bench/README.md.
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
DEFAULT_MESH = REPO.parent / "shared" / "meshes" / "stanford-bunny.obj"
BENCH_SEED = 0x0BEC
DIM_PIXEL_X = 0
DIM_PIXEL_Y = 1
DIMS_PER_BOUNCE = 16
F = np.float32


# --- mesh ------------------------------------------------------------------------------


def load_obj(path):
    """Positions (float32, n x 3) and fan-triangulated faces (int64, m x 3) of an OBJ.

    Like meshtrace's loader (tobj, triangulate): points and lines are ignored, indices may
    be negative (relative), and only vertices some face uses are kept (for the bounds).
    """
    positions = []
    faces = []
    with open(path, "r", encoding="utf-8", errors="replace") as f:
        for line in f:
            if line.startswith("v "):
                p = line.split()
                positions.append((float(p[1]), float(p[2]), float(p[3])))
            elif line.startswith("f "):
                n = len(positions)
                idx = []
                for tok in line.split()[1:]:
                    i = int(tok.split("/", 1)[0])
                    idx.append(i - 1 if i > 0 else n + i)
                for k in range(1, len(idx) - 1):
                    faces.append((idx[0], idx[k], idx[k + 1]))
    if not faces:
        raise SystemExit(f"{path}: the mesh has no faces")
    verts = np.array(positions, dtype=F)
    tris = np.array(faces, dtype=np.int64)
    used = np.unique(tris)
    # Drop zero-area triangles as meshtrace's scene builder does (|(b-a)x(c-a)| > 0).
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    area2 = np.sqrt(dot(cross(b - a, c - a), cross(b - a, c - a)))
    keep = (area2 > 0) & np.isfinite(area2)
    return verts, tris[keep], verts[used], int((~keep).sum())


# --- float32 vector helpers, in glam's operation order ----------------------------------


def dot(a, b):
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def cross(a, b):
    return np.stack(
        [
            a[..., 1] * b[..., 2] - b[..., 1] * a[..., 2],
            a[..., 2] * b[..., 0] - b[..., 2] * a[..., 0],
            a[..., 0] * b[..., 1] - b[..., 0] * a[..., 1],
        ],
        axis=-1,
    )


def normalize(v):
    """glam `normalize`: v * (1 / |v|)."""
    length = np.sqrt(dot(v, v))
    return v * (F(1.0) / length)[..., None]


def f32_sin(x):
    # Correctly rounded, as glibc's sinf/tanf are in practice (computed in f64, rounded).
    return F(math.sin(float(x)))


def f32_tan(x):
    return F(math.tan(float(x)))


# --- camera and rays (src/scene/camera.rs, src/render/rng.rs, src/bench.rs) ------------

RADS_PER_DEG = F(math.pi) / F(180.0)  # Rust's f32::to_radians constant, in f32


class Camera:
    def __init__(self, used_verts):
        """`Camera::framing` of the bounds of `used_verts`."""
        vfov = F(40.0)
        lo = used_verts.min(axis=0)
        hi = used_verts.max(axis=0)
        center = F(0.5) * (lo + hi)
        ext = hi - lo
        radius = max(F(F(0.5) * np.sqrt(dot(ext, ext))), F(1e-6))
        half = F(F(0.5) * F(vfov * RADS_PER_DEG))
        distance = F(F(F(1.1) * radius) / f32_sin(half))
        view = normalize(np.array([0.0, 0.25, 1.0], dtype=F))
        position = center + distance * view
        forward = normalize(center - position)
        right = normalize(cross(forward, np.array([0.0, 1.0, 0.0], dtype=F)))
        up = cross(right, forward)
        self.position, self.forward, self.right, self.up = position, forward, right, up
        self.tan_half = f32_tan(half)
        self.center, self.radius, self.distance = center, radius, distance


def pcg4d(v0, v1, v2, v3):
    """The 4D PCG hash on uint32 arrays; returns the four words."""
    with np.errstate(over="ignore"):
        v = [np.asarray(x, dtype=np.uint32) * np.uint32(1664525) + np.uint32(1013904223)
             for x in (v0, v1, v2, v3)]
        v[0] = v[0] + v[1] * v[3]
        v[1] = v[1] + v[2] * v[0]
        v[2] = v[2] + v[0] * v[1]
        v[3] = v[3] + v[1] * v[2]
        v = [x ^ (x >> np.uint32(16)) for x in v]
        v[0] = v[0] + v[1] * v[3]
        v[1] = v[1] + v[2] * v[0]
        v[2] = v[2] + v[0] * v[1]
        v[3] = v[3] + v[1] * v[2]
    return v


def rng_1d(pixel, sample, bounce, dim, seed):
    """`Rng::new(pixel, sample, seed).rng_1d(bounce, dim)` for a uint32 array of pixels."""
    n = pixel.shape[0]
    key = np.full(n, bounce * DIMS_PER_BOUNCE + dim, dtype=np.uint32)
    x = pcg4d(pixel, np.full(n, sample, np.uint32), key, np.full(n, seed, np.uint32))[0]
    return (x >> np.uint32(8)).astype(F) * F(1.0 / 16_777_216.0)


def primary_rays(cam, width, height):
    """meshtrace's bench primary rays: origins and unit directions, float32 (n x 3)."""
    i = np.arange(width * height, dtype=np.uint32)
    px = (i % np.uint32(width)).astype(F)
    py = (i // np.uint32(width)).astype(F)
    jx = rng_1d(i, 0, 0, DIM_PIXEL_X, BENCH_SEED)
    jy = rng_1d(i, 0, 0, DIM_PIXEL_Y, BENCH_SEED)
    w, h = F(width), F(height)
    aspect = F(w / h)
    sx = (F(2.0) * (px + jx) / w - F(1.0)) * cam.tan_half * aspect
    sy = (F(1.0) - F(2.0) * (py + jy) / h) * cam.tan_half
    d = cam.forward + sx[:, None] * cam.right
    d = d + sy[:, None] * cam.up
    dirs = np.ascontiguousarray(normalize(d), dtype=F)
    origins = np.ascontiguousarray(np.broadcast_to(cam.position, dirs.shape), dtype=F)
    return origins, dirs


# --- a brute-force check of a sample of rays ----------------------------------------------


def brute_force_t(verts, tris, origins, dirs, chunk=16):
    """Closest hit distance (inf for a miss) by Moller-Trumbore against every triangle, f64."""
    v = verts.astype(np.float64)
    a, b, c = v[tris[:, 0]], v[tris[:, 1]], v[tris[:, 2]]
    e1, e2 = b - a, c - a
    out = np.full(len(dirs), np.inf)
    for s in range(0, len(dirs), chunk):
        o = origins[s:s + chunk, None, :].astype(np.float64)
        d = dirs[s:s + chunk, None, :].astype(np.float64)
        p = np.cross(d, e2)
        det = np.sum(e1 * p, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            tv = o - a
            u = np.sum(tv * p, axis=-1) * inv
            q = np.cross(tv, e1)
            w = np.sum(d * q, axis=-1) * inv
            t = np.sum(e2 * q, axis=-1) * inv
        ok = (det != 0) & (u >= 0) & (w >= 0) & (u + w <= 1) & (t > 0)
        out[s:s + chunk] = np.where(ok, t, np.inf).min(axis=1)
    return out


# --- Embree ------------------------------------------------------------------------------


def init_embree(build_threads):
    """Imports embreex. Embree's builder runs on TBB with one thread per CPU it may use;
    for `build_threads` > 0 the process is confined to that many CPUs while TBB starts
    (its thread count is fixed then), and set free again afterwards."""
    try:
        from embreex import mesh_construction, rtcore, rtcore_scene
    except ImportError as e:
        raise SystemExit(f"embreex is not installed ({e}); run: pip install embreex")
    saved = os.sched_getaffinity(0)
    if build_threads > 0:
        os.sched_setaffinity(0, sorted(saved)[:build_threads])
    try:
        device = rtcore.EmbreeDevice()
        # Start TBB's pool now: a small scene built with the confined affinity.
        s = rtcore_scene.EmbreeScene(device)
        g = np.random.default_rng(0).random((3 * 20000, 3), dtype=F)
        mesh_construction.TriangleMesh(s, g, np.arange(3 * 20000, dtype=np.int32).reshape(-1, 3))
        s.run(np.zeros((1, 3), F), np.ones((1, 3), F))
    finally:
        os.sched_setaffinity(0, saved)
    return device, rtcore_scene, mesh_construction


def embree_scene(emb, verts, tris):
    device, rtcore_scene, mesh_construction = emb
    scene = rtcore_scene.EmbreeScene(device)
    mesh_construction.TriangleMesh(scene, verts, tris.astype(np.int32))
    return scene


def embree_build_seconds(emb, verts, tris, repeats):
    """Times the BVH build: the first `run` commits the scene (`rtcCommitScene`); one ray.
    Creating the scene and copying the buffers into Embree are excluded."""
    o = np.zeros((1, 3), F)
    d = np.array([[0.0, 0.0, 1.0]], F)
    times = []
    for _ in range(repeats + 1):
        scene = embree_scene(emb, verts, tris)
        start = time.perf_counter()
        scene.run(o, d)
        times.append(time.perf_counter() - start)
        del scene
    return times[1:]


def timed(repeats, f):
    f()
    out = []
    for _ in range(repeats):
        start = time.perf_counter()
        f()
        out.append(time.perf_counter() - start)
    return out


# --- meshtrace ---------------------------------------------------------------------------


def run_meshtrace(binary, mesh, width, height, repeats, spp):
    cmd = [str(binary), "bench", str(mesh), "--device", "cpu", "--threads", "1", "--json",
           "--width", str(width), "--height", str(height), "--repeats", str(repeats),
           "--spp", str(spp)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stderr}")
    rows = json.loads(r.stdout)
    got = {}
    for row in rows:
        if row["measure"] in ("primary_rays", "bvh_build") and row["device"] in ("cpu", "host"):
            got[row["measure"]] = row
    return cmd, got


# --- main --------------------------------------------------------------------------------


def parse_size(text):
    parts = text.lower().split("x")
    if len(parts) == 1:
        parts = parts * 2
    try:
        w, h = (int(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"bad size `{text}`: use N or WxH")
    if w < 1 or h < 1:
        raise argparse.ArgumentTypeError("the size must be at least 1x1")
    return w, h


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mesh", type=Path, default=DEFAULT_MESH, help="an .obj (default: %(default)s)")
    ap.add_argument("--size", type=parse_size, default=(512, 512), help="N or WxH (default 512)")
    ap.add_argument("--repeats", type=int, default=5, help="timed runs after one warm-up (median)")
    ap.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "meshtrace")
    ap.add_argument("--spp", type=int, default=1,
                    help="meshtrace bench's path-tracing spp (not compared; kept small to save time)")
    ap.add_argument("--embree-build-threads", type=int, default=1,
                    help="CPUs Embree's BVH builder may use (0: all; default 1, like --threads 1)")
    ap.add_argument("--verify", type=int, default=256,
                    help="rays checked against a brute-force intersection (0: none)")
    ap.add_argument("--skip-meshtrace", action="store_true", help="time Embree only")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args()
    width, height = args.size
    say = (lambda *a: print(*a, file=sys.stderr)) if args.json else print

    verts, tris, used, dropped = load_obj(args.mesh)
    cam = Camera(used)
    origins, dirs = primary_rays(cam, width, height)
    n = len(dirs)
    say(f"mesh {args.mesh} : {len(tris)} triangles ({dropped} degenerate dropped); "
        f"{width}x{height} = {n} primary rays")

    emb = init_embree(args.embree_build_threads)
    build = embree_build_seconds(emb, verts, tris, args.repeats)
    scene = embree_scene(emb, verts, tris)
    scene.run(origins[:1], dirs[:1])  # commit: the build is not timed below

    t_hit = scene.run(origins, dirs, query="DISTANCE")
    hit = t_hit < 1e30
    hits = int(hit.sum())
    mean_t = float(t_hit[hit].astype(np.float64).mean()) if hits else float("nan")

    # The measure: closest hit of every ray, primID only (the cheapest result embreex gives).
    prim = timed(args.repeats, lambda: scene.run(origins, dirs))
    # For reference: with output=1 embreex also returns u, v, Ng, t, geomID, through
    # untyped numpy stores that add Python-level cost per ray.
    full = timed(args.repeats, lambda: scene.run(origins, dirs, output=1))
    # The loop's own cost, without geometry: an empty committed scene.
    empty = rtcore_scene_empty(emb)
    loop = timed(args.repeats, lambda: empty.run(origins, dirs))

    verify = None
    if args.verify > 0:
        sel = np.linspace(0, n - 1, min(args.verify, n)).astype(np.int64)
        bf = brute_force_t(verts, tris, origins[sel], dirs[sel])
        bf_hit = np.isfinite(bf)
        agree = int((bf_hit == hit[sel]).sum())
        both = bf_hit & hit[sel]
        rel = np.abs(t_hit[sel][both] - bf[both]) / bf[both]
        verify = {"rays": int(len(sel)), "hit_agree": agree, "brute_hits": int(bf_hit.sum()),
                  "max_rel_t_diff": float(rel.max()) if both.any() else 0.0}

    med = statistics.median
    emb_mrays = n / med(prim) / 1e6
    result = {
        "mesh": str(args.mesh), "triangles": int(len(tris)), "width": width, "height": height,
        "rays": n,
        "camera": {"position": cam.position.tolist(), "forward": cam.forward.tolist()},
        "embree": {
            "version": repr(emb[0]),
            "primary_rays_mrays": emb_mrays,
            "primary_rays_mrays_all": [n / t / 1e6 for t in prim],
            "primary_rays_output1_mrays": n / med(full) / 1e6,
            "empty_scene_loop_mrays": n / med(loop) / 1e6,
            "bvh_build_s": med(build),
            "bvh_build_mtris": len(tris) / med(build) / 1e6,
            "bvh_build_threads": args.embree_build_threads or os.cpu_count(),
            "hits": hits, "mean_t": mean_t,
        },
        "verify": verify,
    }
    if not args.skip_meshtrace:
        cmd, mt = run_meshtrace(args.binary, args.mesh, width, height, args.repeats, args.spp)
        result["meshtrace"] = {
            "command": " ".join(cmd),
            "primary_rays_mrays": mt["primary_rays"]["median"],
            "primary_rays_min_max": [mt["primary_rays"]["min"], mt["primary_rays"]["max"]],
            "bvh_build_mtris": mt["bvh_build"]["median"],
            "bvh_build_s": len(tris) / mt["bvh_build"]["median"] / 1e6,
        }
        result["ratio_primary"] = result["meshtrace"]["primary_rays_mrays"] / emb_mrays
        result["ratio_build"] = result["meshtrace"]["bvh_build_mtris"] / result["embree"]["bvh_build_mtris"]

    if args.json:
        print(json.dumps(result, indent=2))
        return
    e = result["embree"]
    m = result.get("meshtrace")
    say(f"camera position {np.array2string(cam.position, precision=5)}, "
        f"Embree: {hits} hits ({100 * hits / n:.2f}%), mean t {mean_t:.6f}")
    if verify:
        say(f"brute-force check of {verify['rays']} rays: {verify['hit_agree']} agree on hit/miss "
            f"({verify['brute_hits']} hits), max relative t difference {verify['max_rel_t_diff']:.2e}")
    say("")
    row = "{:<34} {:>12} {:>12} {:>10}"
    say(row.format("measure (1 thread)", "meshtrace", "embree", "mt/embree"))
    fmt = lambda x: f"{x:.3f}" if x is not None else "-"
    say(row.format("primary closest hit  Mrays/s", fmt(m and m["primary_rays_mrays"]),
                   fmt(e["primary_rays_mrays"]), fmt(m and result["ratio_primary"])))
    say(row.format("BVH build            Mtris/s", fmt(m and m["bvh_build_mtris"]),
                   fmt(e["bvh_build_mtris"]), fmt(m and result["ratio_build"])))
    say(row.format("BVH build            ms", fmt(m and 1e3 * m["bvh_build_s"]),
                   fmt(1e3 * e["bvh_build_s"]), ""))
    say("")
    say(f"embree, output=1 (u, v, Ng, t, ids): {e['primary_rays_output1_mrays']:.3f} Mrays/s; "
        f"embreex loop on an empty scene: {e['empty_scene_loop_mrays']:.3f} Mrays/s")
    if m:
        say(f"meshtrace primary min..max {m['primary_rays_min_max'][0]:.3f}.."
            f"{m['primary_rays_min_max'][1]:.3f}; embree build threads: {e['bvh_build_threads']}")


def rtcore_scene_empty(emb):
    device, rtcore_scene, _ = emb
    s = rtcore_scene.EmbreeScene(device)
    s.run(np.zeros((1, 3), F), np.ones((1, 3), F))
    return s


if __name__ == "__main__":
    main()
