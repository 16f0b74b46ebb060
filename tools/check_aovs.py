#!/usr/bin/env python3
"""Check meshtrace's AOVs (depth, normal, albedo, alpha) against Mitsuba 3's intersector.

Mitsuba renders the scene (translated by mitsuba_render.build_scene_dict, so through
meshtrace's exact camera) with its `aov` integrator (`depth`, `position`, `sh_normal`,
`albedo`) on an `rgba` film (A unused, see below), one sample per pixel per pass, `--spp`
passes with their own seeds. With a box filter and one sample per pixel a pass holds each pixel's one camera
sample exactly, so the script forms meshtrace's semantics (docs/scene-format.md, section 11)
sample by sample, not from Mitsuba's filtered averages:

  hit      t > 0 (the `aov` integrator alone leaves the film's A at 0 everywhere; a miss has
           t = 0 and all other AOVs 0, which the script checks on every pass)
  alpha    hits / spp
  depth    dot(mean over hits of position - camera position, unit forward); +inf without hits
  normal   sh_normal turned to face the ray (negated where dot(n, p - camera) > 0, as
           meshtrace's `si.ns.dot(ray.dir) > 0`), summed over hits, normalised; 0 without hits
  albedo   Mitsuba's `albedo` AOV (BSDF::eval_diffuse_reflectance) summed over all samples / spp

Mitsuba's `albedo` AOV is meshtrace's only for `diffuse` (twosided(diffuse) reflectance):
for `conductor` and `dielectric` (delta BSDFs) it is 0 and for `roughconductor` it is the
GGX lobe evaluated at normal incidence, not the albedo. So for the AOV render each shape's
BSDF is replaced by its *albedo twin*, a twosided `diffuse` whose reflectance is the
material's albedo (the same constant or texture: diffuse reflectance, conductor
specular_reflectance, the pbr twin's reflectance), 1 for `dielectric`; normal maps are
dropped (Mitsuba's `sh_normal` is the interpolated normal without the map, so scenes with
normal maps are refused). Geometry, transforms, UVs and camera are untouched.

Two Mitsuba renders (seeds 0 and 1 of the pass sequence) give the reference and the
sampling noise; meshtrace renders on each --device with seed 0 (its random sub-pixel
positions are its own). Per AOV and pixel an error e is computed:

  depth    |z - z_ref| / z_ref where both are finite; 1 where one is finite and the other not
  normal   angle in degrees between the normals; 180 where one is 0 and the other not
  albedo   max over RGB of |a - a_ref|
  alpha    |a - a_ref|

and two statistics over all pixels: MAE = mean(e) and FRAC = fraction of pixels with
e > TOL (TOL per AOV, below). meshtrace passes an AOV when each of its statistics is at
most 1.5 x Mitsuba's seed-to-seed statistic plus a small floor (FLOOR, for noiseless
images). --self-test also applies wrong variants to a copy of meshtrace's arrays (normal
negated, depth x 1.01, alpha read one pixel to the right, albedo x 1.03) and prints their
verdicts, which must be FAIL.

Usage:
  python3 tools/check_aovs.py SCENE [--spp 128] [--device cpu gpu] [--width W --height H]
      [--meshtrace target/release/meshtrace]
      [--spheres mesh|analytic] [--raw-albedo] [--self-test] [--keep DIR] [--json OUT]

Exit status 1 when an AOV fails on a device (or a --self-test variant passes).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_render as mr  # noqa: E402

AOVS = ("depth", "normal", "albedo", "alpha")
TOL = {"depth": 1e-3, "normal": 2.0, "albedo": 0.01, "alpha": 0.1}
FLOOR_MAE = {"depth": 1e-5, "normal": 0.01, "albedo": 1e-4, "alpha": 1e-4}
FLOOR_FRAC = 2e-3
RATIO = 1.5


# ---------------------------------------------------------------- Mitsuba side

def albedo_twin(b, where):
    """The twosided diffuse BSDF whose eval_diffuse_reflectance is meshtrace's albedo AOV
    for the Mitsuba BSDF dict `b` made by mitsuba_render.mitsuba_bsdf."""
    t = b["type"]
    if t == "twosided":
        return albedo_twin(b["bsdf"], where)
    if t == "normalmap":
        raise SystemExit("check_aovs: %s: a normal map: Mitsuba's sh_normal AOV does not "
                         "apply it; not checkable" % where)
    if t == "diffuse":
        refl = b.get("reflectance", {"type": "rgb", "value": [0.5, 0.5, 0.5]})
    elif t in ("conductor", "roughconductor"):
        refl = b.get("specular_reflectance", {"type": "rgb", "value": [1.0, 1.0, 1.0]})
    elif t == "dielectric":
        refl = {"type": "rgb", "value": [1.0, 1.0, 1.0]}
    else:
        raise SystemExit("check_aovs: %s: BSDF type %s has no albedo twin" % (where, t))
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": refl}}


def aov_scene_dict(mi, scene_path, args, tmp):
    class A:  # overrides for build_scene_dict
        pass
    A.width, A.height, A.max_depth = args.width, args.height, None
    A.spp, A.seed, A.spheres = None, None, args.spheres
    d, o = mr.build_scene_dict(mi, scene_path, A, tmp)
    d["integrator"] = {"type": "aov", "aovs": "t:depth,p:position,n:sh_normal,a:albedo"}
    sensor = d["sensor"]
    sensor["film"]["pixel_format"] = "rgba"
    sensor["sampler"] = {"type": "independent", "sample_count": 1}
    if sensor["type"] != "perspective":
        print("check_aovs: note: %s camera: the normal is faced towards p - camera position, "
              "not the sampled lens point" % sensor["type"], file=sys.stderr)
    for k, v in d.items():
        if isinstance(v, dict) and "bsdf" in v and not args.raw_albedo:
            v["bsdf"] = albedo_twin(v["bsdf"], k)
    m = np.array(sensor["to_world"].matrix, dtype=np.float64)
    cam = m[:3, 3]
    fwd = m[:3, 2] / np.linalg.norm(m[:3, 2])
    return d, o, cam, fwd


def mitsuba_aovs(mi, scene, w, h, spp, seed, cam, fwd):
    """meshtrace's four AOVs from `spp` one-sample passes (see the module doc)."""
    n_hit = np.zeros((h, w))
    s_p = np.zeros((h, w, 3))
    s_n = np.zeros((h, w, 3))
    s_a = np.zeros((h, w, 3))
    film = scene.sensors()[0].film()
    names = None
    for k in range(spp):
        mi.render(scene, spp=1, seed=mr.pass_seed(seed, k))
        bmp = film.bitmap()
        if names is None:
            names = [f.name for f in bmp.struct_()]
            ix = {n: i for i, n in enumerate(names)}
            ip = [ix["p.X"], ix["p.Y"], ix["p.Z"]]
            inn = [ix["n.X"], ix["n.Y"], ix["n.Z"]]
            ial = [ix["a.R"], ix["a.G"], ix["a.B"]]
            it = ix["t.T"] if "t.T" in ix else ix["t.Y"]
        a = np.array(bmp, dtype=np.float64)
        # A is 0 everywhere (the aov integrator alone returns no `valid`); a miss has t = 0
        # and every other AOV 0 too (checked on each pass), a hit t > near_clip > 0
        hit = a[:, :, it] > 0.0
        if np.any(a[~hit][:, ip + inn + ial] != 0.0):
            raise SystemExit("check_aovs: Mitsuba's misses are not what this script assumes")
        p = a[:, :, ip]
        n = a[:, :, inn]
        flip = np.einsum("ijk,ijk->ij", n, p - cam) > 0.0
        n = np.where(flip[:, :, None], -n, n)
        n_hit += hit
        s_p += np.where(hit[:, :, None], p, 0.0)
        s_n += np.where(hit[:, :, None], n, 0.0)
        s_a += a[:, :, ial]          # a miss counts 0
    alpha = n_hit / spp
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_p = s_p / n_hit[:, :, None]
        depth = np.where(n_hit > 0, np.einsum("ijk,k->ij", mean_p - cam, fwd), np.inf)
        nl = np.linalg.norm(s_n, axis=2, keepdims=True)
        normal = np.where((n_hit > 0)[:, :, None] & (nl > 0), s_n / nl, 0.0)
    return {"depth": depth, "normal": normal, "albedo": s_a / spp, "alpha": alpha}


# ---------------------------------------------------------------- meshtrace side

def read_meshtrace(mi, path):
    bmp = mi.Bitmap(path)
    names = [f.name for f in bmp.struct_()]
    a = np.array(bmp, dtype=np.float64)
    ix = {n: i for i, n in enumerate(names)}
    g = lambda *ns: a[:, :, [ix[n] for n in ns]]  # noqa: E731
    return {"depth": a[:, :, ix["Z"]],
            "normal": g("normal.X", "normal.Y", "normal.Z"),
            "albedo": g("albedo.R", "albedo.G", "albedo.B"),
            "alpha": a[:, :, ix["A"]]}


# ---------------------------------------------------------------- comparison

def per_pixel_error(name, x, ref):
    if name == "depth":
        fx, fr = np.isfinite(x), np.isfinite(ref)
        e = np.where(fx != fr, 1.0, 0.0)
        both = fx & fr
        e[both] = np.abs(x[both] - ref[both]) / np.maximum(np.abs(ref[both]), 1e-12)
        return e
    if name == "normal":
        zx = np.linalg.norm(x, axis=2) == 0
        zr = np.linalg.norm(ref, axis=2) == 0
        c = np.clip(np.einsum("ijk,ijk->ij", x, ref)
                    / np.maximum(np.linalg.norm(x, axis=2) * np.linalg.norm(ref, axis=2),
                                 1e-30), -1.0, 1.0)
        e = np.degrees(np.arccos(c))
        e[zx & zr] = 0.0
        e[zx != zr] = 180.0
        return e
    if name == "albedo":
        return np.abs(x - ref).max(axis=2)
    return np.abs(x - ref)


def stats(name, x, ref):
    e = per_pixel_error(name, x, ref)
    return {"mae": float(e.mean()), "frac": float((e > TOL[name]).mean())}


def verdict(name, s, noise):
    return (s["mae"] <= RATIO * noise["mae"] + FLOOR_MAE[name]
            and s["frac"] <= RATIO * noise["frac"] + FLOOR_FRAC)


def tampered(x):
    """Wrong variants of meshtrace's arrays: each must fail."""
    out = {}
    y = dict(x)
    y["normal"] = -x["normal"]
    out["normal negated"] = ("normal", y)
    y = dict(x)
    y["depth"] = x["depth"] * 1.01
    out["depth x 1.01"] = ("depth", y)
    y = dict(x)
    y["alpha"] = np.concatenate([x["alpha"][:, 1:], x["alpha"][:, -1:]], axis=1)
    out["alpha one pixel right"] = ("alpha", y)
    y = dict(x)
    y["albedo"] = x["albedo"] * 1.03
    out["albedo x 1.03"] = ("albedo", y)
    return out


def fmt(s):
    return "MAE %.3g, >tol %.4f" % (s["mae"], s["frac"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--spp", type=int, default=128)
    ap.add_argument("--device", nargs="+", default=["cpu", "gpu"], choices=("cpu", "gpu"))
    ap.add_argument("--width", type=int)
    ap.add_argument("--height", type=int)
    ap.add_argument("--variant")
    ap.add_argument("--spheres", choices=("analytic", "mesh"), default="mesh",
                    help="spheres as meshtrace's icosphere (default: the geometry is then "
                         "the same) or Mitsuba's analytic sphere")
    ap.add_argument("--meshtrace", default="target/release/meshtrace")
    ap.add_argument("--raw-albedo", action="store_true",
                    help="keep the scene's BSDFs (Mitsuba's own albedo AOV; to show why the "
                         "albedo twins are needed)")
    ap.add_argument("--self-test", action="store_true",
                    help="also check that wrong variants of meshtrace's AOVs fail")
    ap.add_argument("--keep", help="write meshtrace's EXRs and Mitsuba's arrays (.npz) here")
    ap.add_argument("--json", help="write the results here")
    args = ap.parse_args()

    mi = mr.setup_mitsuba(args.variant)
    out = args.keep or tempfile.mkdtemp(prefix="check_aovs_")
    os.makedirs(out, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="check_aovs_mi_") as tmp:
        d, o, cam, fwd = aov_scene_dict(mi, args.scene, args, tmp)
        scene = mi.load_dict(d)
    w, h = o["width"], o["height"]
    print("%s: %dx%d, %d spp, Mitsuba %s" % (args.scene, w, h, args.spp, mi.variant()))
    t0 = time.time()
    ref = mitsuba_aovs(mi, scene, w, h, args.spp, 0, cam, fwd)
    other = mitsuba_aovs(mi, scene, w, h, args.spp, 1, cam, fwd)
    print("Mitsuba: 2 x %d passes, %.1f s" % (args.spp, time.time() - t0))
    np.savez(os.path.join(out, "mitsuba.npz"), **{k: ref[k] for k in AOVS})
    noise = {k: stats(k, other[k], ref[k]) for k in AOVS}
    results = {"scene": args.scene, "width": w, "height": h, "spp": args.spp,
               "tol": TOL, "ratio": RATIO, "floor_mae": FLOOR_MAE, "floor_frac": FLOOR_FRAC,
               "mitsuba_seed_to_seed": noise, "devices": {}, "self_test": {}}
    print("%-7s %-32s" % ("aov", "Mitsuba seed 1 vs seed 0") + "".join(
        "  %-40s" % ("meshtrace " + dv) for dv in args.device))
    ok = True
    mts = {}
    for dv in args.device:
        path = os.path.join(out, "meshtrace_%s.exr" % dv)
        cmd = [args.meshtrace, "render", args.scene, "-o", path, "--spp", str(args.spp),
               "--seed", "0", "--width", str(w), "--height", str(h), "--device", dv,
               "--aov", ",".join(AOVS), "--quiet"]
        t0 = time.time()
        subprocess.run(cmd, check=True)
        print("meshtrace %s: %.1f s" % (dv, time.time() - t0))
        mts[dv] = read_meshtrace(mi, path)
    for k in AOVS:
        line = "%-7s %-32s" % (k, fmt(noise[k]))
        for dv in args.device:
            s = stats(k, mts[dv][k], ref[k])
            v = verdict(k, s, noise[k])
            ok &= v
            results["devices"].setdefault(dv, {})[k] = dict(s, ok=v)
            line += "  %-40s" % ("%s %s" % (fmt(s), "pass" if v else "FAIL"))
        print(line)
    if args.self_test:
        dv = args.device[0]
        print("self-test on meshtrace %s's arrays (each must FAIL):" % dv)
        for label, (k, y) in tampered(mts[dv]).items():
            s = stats(k, y[k], ref[k])
            v = verdict(k, s, noise[k])
            ok &= not v
            results["self_test"][label] = dict(s, aov=k, ok=v)
            print("  %-24s %-7s %s  %s" % (label, k, fmt(s), "pass (BAD)" if v else "FAIL (good)"))
    print("overall: %s" % ("pass" if ok else "FAIL"))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=2)
            fh.write("\n")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
