#!/usr/bin/env python3
"""Render a Mitsuba reference for one of our scenes and Mitsuba's own noise level.

Writes tests/references/<name>_ref.exr (the reference, --ref-spp samples per pixel) and
tests/references/<name>.json with Mitsuba's relMSE against that reference at each of
--spp: "mitsuba_relmse": {"64": mean over seeds 0..seeds-1, ...} and
"mitsuba_relmse_per_seed": {"64": [...], ...}; the reference passes use seeds far from
those, see mitsuba_render.pass_seed).

Usage:
  python3 tools/make_references.py assets/cornell/cornell.toml --name cornell \
      --ref-spp 16384 --spp 16 64 --seeds 4 [--width 256 --height 256]
"""
import argparse
import json
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_render as mr  # noqa: E402
from compare import relmse  # noqa: E402

REF_SEED = 1_000_000_007 % (1 << 32)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--name", required=True)
    ap.add_argument("--out-dir", default="tests/references")
    ap.add_argument("--ref-spp", type=int, default=16384)
    ap.add_argument("--spp", type=int, nargs="+", default=[16, 64])
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--width", type=int)
    ap.add_argument("--height", type=int)
    ap.add_argument("--max-depth", type=int)
    ap.add_argument("--variant")
    ap.add_argument("--lanes", type=int, default=1 << 23)
    args = ap.parse_args()

    mi = mr.setup_mitsuba(args.variant)
    class A:  # overrides for build_scene_dict
        width, height, max_depth = args.width, args.height, args.max_depth
        spp, seed = None, None

    with tempfile.TemporaryDirectory(prefix="mitsuba_ref_") as tmp:
        d, o = mr.build_scene_dict(mi, args.scene, A, tmp)
        scene = mi.load_dict(d)
    w, h = o["width"], o["height"]
    print("variant %s, %dx%d, max_depth %d" % (mi.variant(), w, h, o["max_depth"]))

    ref, t_ref = mr.render(mi, scene, w, h, args.ref_spp, REF_SEED, args.lanes)
    print("reference %d spp: %.1f s" % (args.ref_spp, t_ref))
    os.makedirs(args.out_dir, exist_ok=True)
    ref_path = os.path.join(args.out_dir, "%s_ref.exr" % args.name)
    mr.write_exr(mi, ref, ref_path)
    ref = ref.astype("float64")

    result = {
        "scene": os.path.relpath(os.path.abspath(args.scene)),
        "reference": os.path.relpath(os.path.abspath(ref_path)),
        "width": w, "height": h,
        "reference_spp": args.ref_spp,
        "spp": o["spp"],
        "max_depth": o["max_depth"],
        "renderer": "Mitsuba %s (%s), path integrator rr_depth 5, box filter, "
                    "tools/mitsuba_render.py" % (mi.__version__, mi.variant()),
        "metric": "mean((x-ref)^2/(ref^2+1e-2))",
        "mitsuba_relmse": {},
        "mitsuba_relmse_per_seed": {},
        "seeds": list(range(args.seeds)),
        "timings_s": {"reference": round(t_ref, 1)},
    }
    for spp in args.spp:
        per, ts = [], []
        for s in range(args.seeds):
            img, t = mr.render(mi, scene, w, h, spp, s, args.lanes, verbose=False)
            per.append(relmse(img.astype("float64"), ref))
            ts.append(t)
        mean = sum(per) / len(per)
        result["mitsuba_relmse"][str(spp)] = mean
        result["mitsuba_relmse_per_seed"][str(spp)] = per
        result["timings_s"]["%d_spp" % spp] = round(sum(ts) / len(ts), 2)
        print("%d spp: relMSE mean %.6g per seed %s (%.2f s each)"
              % (spp, mean, ["%.6g" % p for p in per], sum(ts) / len(ts)))
    json_path = os.path.join(args.out_dir, "%s.json" % args.name)
    with open(json_path, "w") as fh:
        json.dump(result, fh, indent=2)
        fh.write("\n")
    print("wrote", ref_path, json_path)


if __name__ == "__main__":
    main()
