#!/usr/bin/env python3
"""Compare meshtrace's CPU ray throughput with Embree 4, per thread.

`meshtrace bench SCENE --device cpu --threads 1 --json --rays-out DIR` measures its own
rates and writes the triangles it traces (DIR/NAME.triangles.f32) and its ray sets: two
primary views (DIR/NAME.primary.rays.f32: the scene's camera;
DIR/NAME.primary_fill.rays.f32: a narrower view that the mesh fills), a cosine bounce from
each primary hit (DIR/NAME.incoherent.rays.f32) and a shadow ray from each primary hit
towards a light (DIR/NAME.shadow.rays.f32). This script runs that command, builds an
Embree scene of the same triangles, traces the same rays through it with the `embreex`
bindings (single-threaded: one `rtcIntersect1` per ray, `rtcOccluded1` for the shadow
rays) and prints both rates and their ratio for each set, with the BVH build rates, and a
brute-force check of a sample of the rays.

Needs numpy and embreex (`pip install embreex`) and a release build of meshtrace
(`cargo build --release`). See bench/README.md.
"""

import argparse
import importlib.metadata
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
DEFAULT_SCENE = REPO.parent / "shared" / "meshes" / "stanford-bunny.obj"
VIEWS = ("primary", "primary_fill", "incoherent", "shadow")
# The ray sets meshtrace reports the share of rays on the mesh for (`VIEW_hits`).
HIT_VIEWS = ("primary", "primary_fill")
# The sets traced as any-hit queries (occlusion up to t_max) rather than closest hit.
ANY_HIT_VIEWS = ("shadow",)
F = np.float32
MAX_MISMATCH = 0.01  # hit/miss disagreements with the brute force that fail the run


# --- meshtrace's files (little-endian float32) -------------------------------------------


def read_f32(path, per_row):
    """The float32 rows of `path`, `per_row` values each."""
    if not path.is_file():
        raise SystemExit(f"{path} is missing (does this meshtrace's bench have --rays-out?)")
    data = np.fromfile(path, dtype="<f4")
    if data.size == 0 or data.size % per_row:
        raise SystemExit(f"{path}: {data.size} floats, not a positive multiple of {per_row}")
    return data.reshape(-1, per_row)


def load_triangles(path):
    """The triangle soup as Embree takes it: corners (3n x 3) and indices 0..3n (n x 3)."""
    verts = np.ascontiguousarray(read_f32(path, 9).reshape(-1, 3), dtype=F)
    if not np.isfinite(verts).all():
        raise SystemExit(f"{path}: non-finite vertex coordinates")
    return verts, np.arange(len(verts), dtype=np.int32).reshape(-1, 3)


def load_rays(path):
    """Origins, unit directions (n x 3) and t_max (n) of a ray file (8 floats a ray)."""
    r = read_f32(path, 8)
    origins = np.ascontiguousarray(r[:, 0:3], dtype=F)
    t_max = np.ascontiguousarray(r[:, 3], dtype=F)
    dirs = np.ascontiguousarray(r[:, 4:7], dtype=F)
    length = np.sqrt((dirs.astype(np.float64) ** 2).sum(axis=1))
    if not (np.isfinite(r).all() and np.abs(length - 1).max() < 1e-5 and (t_max > 0).all()
            and (r[:, 7] == 0).all()):
        raise SystemExit(f"{path}: not rays of the expected layout (origin, t_max, unit "
                         "direction, 0)")
    return origins, dirs, t_max


def run_meshtrace(binary, scene, rays_dir, width, height, repeats, spp):
    """Runs `meshtrace bench`: returns the command, the scene's name (the rows' `scene`,
    which names the files) and its rows by (device, measure)."""
    cmd = [str(binary), "bench", str(scene), "--device", "cpu", "--threads", "1", "--json",
           "--rays-out", str(rays_dir), "--width", str(width), "--height", str(height),
           "--repeats", str(repeats), "--spp", str(spp)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stderr}")
    rows = json.loads(r.stdout)
    names = {row["scene"] for row in rows}
    if len(names) != 1:
        raise SystemExit(f"expected the rows of one scene from meshtrace, got {sorted(names)}")
    got = {(row["device"], row["measure"]): row for row in rows}
    need = [("cpu", f"{v}_rays") for v in VIEWS] + [("host", f"{v}_hits") for v in HIT_VIEWS]
    missing = [f"{d}/{m}" for d, m in need + [("host", "bvh_build")] if (d, m) not in got]
    if missing:
        raise SystemExit(f"meshtrace's bench reported no {', '.join(missing)}")
    return cmd, names.pop(), got


def saved_scene_name(rays_dir, scene):
    """The scene whose files an earlier run left in `rays_dir`: the only one there, or else
    the one named like `scene` (its file stem, or the name after `builtin:`)."""
    names = sorted(p.name[: -len(".triangles.f32")] for p in rays_dir.glob("*.triangles.f32"))
    guess = str(scene).split(":", 1)[1] if str(scene).startswith("builtin:") else Path(scene).stem
    if len(names) == 1:
        return names[0]
    if guess in names:
        return guess
    raise SystemExit(f"{rays_dir}: no files of scene `{guess}` (there: {names or 'none'})")


def meshtrace_version(binary):
    r = subprocess.run([str(binary), "--version"], capture_output=True, text=True)
    return r.stdout.strip() if r.returncode == 0 else None


# --- a brute-force check of a sample of rays ----------------------------------------------


def brute_force_t(verts, origins, dirs, t_max):
    """Closest hit distance in (0, t_max) (inf for a miss) by Moller-Trumbore against
    every triangle of the soup, in float64."""
    v = verts.astype(np.float64).reshape(-1, 3, 3)
    a, e1, e2 = v[:, 0], v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    chunk = max(1, 2_000_000 // len(v))  # rays per step: ~2M ray-triangle pairs
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
        ok &= t < t_max[s:s + chunk, None].astype(np.float64)
        out[s:s + chunk] = np.where(ok, t, np.inf).min(axis=1)
    return out


def verify(verts, origins, dirs, t_max, t_embree, hit, count):
    """Compares Embree's hits of `count` rays spread over the set with the brute force."""
    n = len(dirs)
    sel = np.unique(np.linspace(0, n - 1, min(count, n)).astype(np.int64))
    bf = brute_force_t(verts, origins[sel], dirs[sel], t_max[sel])
    bf_hit = np.isfinite(bf)
    both = bf_hit & hit[sel]
    rel = np.abs(t_embree[sel][both] - bf[both]) / bf[both]
    return {"rays": int(len(sel)), "hit_disagree": int((bf_hit != hit[sel]).sum()),
            "brute_hits": int(bf_hit.sum()),
            "max_rel_t_diff": float(rel.max()) if both.any() else 0.0}


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


def embree_scene(emb, verts=None, indices=None):
    """An uncommitted scene of one triangle mesh, or of none without `verts`."""
    device, rtcore_scene, mesh_construction = emb
    scene = rtcore_scene.EmbreeScene(device)
    if verts is not None:
        mesh_construction.TriangleMesh(scene, verts, indices)
    return scene


def commit(scene):
    """Builds the scene's BVH (`rtcCommitScene`): embreex commits on the first `run`."""
    scene.run(np.zeros((1, 3), F), np.array([[0.0, 0.0, 1.0]], F))
    return scene


def embree_build_seconds(emb, verts, indices, repeats):
    """Times the BVH build (the commit, with one ray); creating the scene and copying the
    buffers into Embree are excluded. One warm-up build, then `repeats` timed ones."""
    times = []
    for _ in range(repeats + 1):
        scene = embree_scene(emb, verts, indices)
        start = time.perf_counter()
        commit(scene)
        times.append(time.perf_counter() - start)
        del scene
    return times[1:]


def timed(repeats, f):
    """Seconds of `repeats` calls of `f` after one warm-up call."""
    f()
    out = []
    for _ in range(repeats):
        start = time.perf_counter()
        f()
        out.append(time.perf_counter() - start)
    return out


def trace_view(scene, empty, verts, rays, repeats, verify_count, any_hit=False):
    """Embree's rates and hits for one ray set: closest hits, or with `any_hit` occlusion
    within each ray's t_max (`rtcOccluded1`)."""
    origins, dirs, t_max = rays
    n = len(dirs)
    t_hit = scene.run(origins, dirs, dists=t_max.copy(), query="DISTANCE")  # in place
    hit = t_hit < t_max
    hits = int(hit.sum())
    if any_hit:
        occluded = scene.run(origins, dirs, dists=t_max.copy(), query="OCCLUDED") >= 0
        if (occluded != hit).sum() > MAX_MISMATCH * n:
            raise SystemExit(f"Embree's occlusion and closest-hit queries disagree on "
                             f"{int((occluded != hit).sum())} of {n} rays")
        # The measure: occlusion of every ray within its t_max.
        prim = timed(repeats, lambda: scene.run(origins, dirs, dists=t_max, query="OCCLUDED"))
    else:
        # The measure: closest hit of every ray, primID only (the cheapest result embreex
        # gives).
        prim = timed(repeats, lambda: scene.run(origins, dirs, dists=t_max))
    # For reference: with output=1 embreex also returns u, v, Ng, t, geomID, through
    # untyped numpy stores that add Python-level cost per ray. It writes t into `dists`.
    full = timed(repeats, lambda: scene.run(origins, dirs, dists=t_max.copy(), output=1))
    # The loop's own cost, without geometry: an empty committed scene.
    loop = timed(repeats, lambda: empty.run(origins, dirs, dists=t_max))
    med = statistics.median
    return {
        "rays": n,
        "mrays": n / med(prim) / 1e6,
        "mrays_all": [n / t / 1e6 for t in prim],
        "output1_mrays": n / med(full) / 1e6,
        "empty_scene_loop_mrays": n / med(loop) / 1e6,
        "hits": hits,
        "hit_fraction": hits / n,
        "mean_t": float(t_hit[hit].astype(np.float64).mean()) if hits else None,
        "verify": (verify(verts, origins, dirs, t_max, t_hit, hit, verify_count)
                   if verify_count > 0 else None),
    }


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


def fmt(x, spec=".3f"):
    return "-" if x is None else format(x, spec)


def print_table(result):
    m = result["meshtrace"]
    row = "{:<22} {:>9} {:>10} {:>10} {:>10} {:>10} {:>10}"
    print(row.format("", "", "meshtrace", "embree", "", "mesh hits", "any hit"))
    print(row.format("view (1 thread)", "rays", "Mrays/s", "Mrays/s", "mt/embree",
                     "meshtrace", "embree"))
    for view, v in result["views"].items():
        e = v["embree"]
        mt = v["meshtrace"] or {}
        print(row.format(view, e["rays"], fmt(mt.get("mrays")), fmt(e["mrays"]),
                         fmt(v["ratio"]), fmt(mt.get("mesh_hit_fraction"), ".1%"),
                         fmt(e["hit_fraction"], ".1%")))
    e = result["embree"]
    print(row.format("BVH build   Mtris/s", result["triangles"],
                     fmt(m and m["bvh_build_mtris"]), fmt(e["bvh_build_mtris"]),
                     fmt(result["ratio_build"]), "", ""))
    print(row.format("BVH build   ms", "", fmt(m and 1e3 * m["bvh_build_s"]),
                     fmt(1e3 * e["bvh_build_s"]), "", "", ""))
    print()
    for view, v in result["views"].items():
        e = v["embree"]
        line = (f"{view}: embree {e['hits']} of {e['rays']} rays hit "
                f"({e['hit_fraction']:.2%}), mean t {fmt(e['mean_t'], '.6g')}; "
                f"output=1 {e['output1_mrays']:.3f} Mrays/s, empty-scene loop "
                f"{e['empty_scene_loop_mrays']:.3f} Mrays/s")
        if v["meshtrace"]:
            lo, hi = v["meshtrace"]["min_max"]
            line += f"; meshtrace min..max {lo:.3f}..{hi:.3f}"
        print(line)
        c = e["verify"]
        if c:
            print(f"  brute force, {c['rays']} rays: {c['hit_disagree']} disagree on hit/miss "
                  f"({c['brute_hits']} hits), max relative t difference "
                  f"{c['max_rel_t_diff']:.2e}")
    print(f"embree build threads: {result['embree']['bvh_build_threads']}; "
          + "; ".join(f"{k} {v}" for k, v in result["versions"].items() if v))
    if m:
        print(f"meshtrace: {m['command']}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", "--mesh", default=str(DEFAULT_SCENE),
                    help="any scene `meshtrace bench` takes: a mesh file, a scene file, "
                         "builtin:NAME (default: %(default)s)")
    ap.add_argument("--size", type=parse_size, default=(512, 512), help="N or WxH (default 512)")
    ap.add_argument("--repeats", type=int, default=5, help="timed runs after one warm-up (median)")
    ap.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "meshtrace")
    ap.add_argument("--spp", type=int, default=1,
                    help="meshtrace bench's path-tracing spp (not compared; kept small to save time)")
    ap.add_argument("--embree-build-threads", type=int, default=1,
                    help="CPUs Embree's BVH builder may use (0: all; default 1, like --threads 1)")
    ap.add_argument("--verify", type=int, default=256,
                    help="rays of each view checked against a brute-force intersection (0: none)")
    ap.add_argument("--rays-dir", type=Path,
                    help="where meshtrace writes the triangles and rays, kept afterwards "
                         "(default: a temporary directory)")
    ap.add_argument("--skip-meshtrace", action="store_true",
                    help="don't run meshtrace: trace the files an earlier run left in "
                         "--rays-dir (Embree numbers only)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args()
    width, height = args.size
    say = (lambda *a: print(*a, file=sys.stderr)) if args.json else print

    with tempfile.TemporaryDirectory(prefix="embree_compare.") as tmp:
        rays_dir = args.rays_dir or Path(tmp)
        if args.skip_meshtrace:
            if not args.rays_dir:
                raise SystemExit("--skip-meshtrace needs --rays-dir")
            cmd, mt = None, None
            name = saved_scene_name(rays_dir, args.scene)
        else:
            rays_dir.mkdir(parents=True, exist_ok=True)
            say(f"running meshtrace bench on {args.scene} ...")
            cmd, name, mt = run_meshtrace(args.binary, args.scene, rays_dir, width, height,
                                          args.repeats, args.spp)
        tri_path = rays_dir / f"{name}.triangles.f32"
        verts, indices = load_triangles(tri_path)
        rays = {v: load_rays(rays_dir / f"{name}.{v}.rays.f32") for v in VIEWS}
    ntris = len(indices)
    say(f"{tri_path}: {ntris} triangles; "
        + ", ".join(f"{v} {len(r[1])} rays" for v, r in rays.items()))

    emb = init_embree(args.embree_build_threads)
    build = embree_build_seconds(emb, verts, indices, args.repeats)
    scene = commit(embree_scene(emb, verts, indices))
    empty = commit(embree_scene(emb))

    med = statistics.median
    result = {
        "scene": args.scene, "name": name, "triangles": ntris, "width": width,
        "height": height, "repeats": args.repeats,
        "meshtrace": None,
        "embree": {
            "bvh_build_s": med(build),
            "bvh_build_mtris": ntris / med(build) / 1e6,
            "bvh_build_threads": args.embree_build_threads or os.cpu_count(),
        },
        "views": {},
        "ratio_build": None,
        "versions": {
            "embree": repr(emb[0]).split(":")[-1].strip(),
            "embreex": importlib.metadata.version("embreex"),
            "numpy": np.__version__,
            "python": platform.python_version(),
            "meshtrace": None if args.skip_meshtrace else meshtrace_version(args.binary),
        },
    }
    if mt:
        build_mtris = mt[("host", "bvh_build")]["median"]
        result["meshtrace"] = {"command": " ".join(cmd), "bvh_build_mtris": build_mtris,
                               "bvh_build_s": ntris / build_mtris / 1e6}
        result["ratio_build"] = build_mtris / result["embree"]["bvh_build_mtris"]
    failures = []
    for view, r in rays.items():
        say(f"tracing {view} with embree ...")
        e = trace_view(scene, empty, verts, r, args.repeats, args.verify,
                       any_hit=view in ANY_HIT_VIEWS)
        m = None
        if mt:
            row = mt[("cpu", f"{view}_rays")]
            hits = mt.get(("host", f"{view}_hits"))
            m = {"mrays": row["median"], "min_max": [row["min"], row["max"]],
                 "mesh_hit_fraction": hits["median"] if hits else None}
        result["views"][view] = {"meshtrace": m, "embree": e,
                                 "ratio": m["mrays"] / e["mrays"] if m else None}
        if e["hits"] == 0 and view not in ANY_HIT_VIEWS:
            failures.append(f"{view}: no ray hits any triangle in Embree")
        c = e["verify"]
        if c and c["hit_disagree"] > MAX_MISMATCH * c["rays"]:
            failures.append(f"{view}: Embree and the brute force disagree on hit/miss for "
                            f"{c['hit_disagree']} of {c['rays']} rays")
    result["failures"] = failures

    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print()
        print_table(result)
    if failures:
        raise SystemExit("FAILED: " + "; ".join(failures))


if __name__ == "__main__":
    main()
