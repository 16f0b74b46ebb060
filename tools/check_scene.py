#!/usr/bin/env python3
"""Check meshtrace against Mitsuba 3 on any scene, as the test suite does for its own.

Renders a Mitsuba reference (--ref-spp), then at each --spp level Mitsuba and meshtrace
(through its command line, on each --device) with seeds 0..seeds-1, and prints
relMSE(meshtrace) / relMSE(Mitsuba), both means over the seeds and both against that
reference: about 1 for an unbiased renderer with Mitsuba's variance; the suite's bound
is 1.3.

Usage:
  python3 tools/check_scene.py SCENE [--ref-spp 8192] [--spp 64 512] [--seeds 4]
      [--device cpu gpu] [--width W --height H] [--max-depth D]
      [--meshtrace target/release/meshtrace] [--keep DIR] [--json OUT]

SCENE is anything both tools read: a scene TOML, a bare .obj, or a bare .gltf/.glb
(whose size and spp then come from --width/--height, as for meshtrace).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_render as mr  # noqa: E402
from compare import read_exr, relmse  # noqa: E402
from make_references import REF_SEED  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--ref-spp", type=int, default=8192)
    ap.add_argument("--spp", type=int, nargs="+", default=[64, 512])
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--device", nargs="+", default=["cpu", "gpu"], choices=("cpu", "gpu"))
    ap.add_argument("--width", type=int)
    ap.add_argument("--height", type=int)
    ap.add_argument("--max-depth", type=int)
    ap.add_argument("--variant")
    ap.add_argument("--lanes", type=int, default=1 << 23)
    ap.add_argument("--meshtrace", default="target/release/meshtrace")
    ap.add_argument("--keep", help="write the reference and the renders here")
    ap.add_argument("--json", help="write the results here")
    args = ap.parse_args()

    mi = mr.setup_mitsuba(args.variant)

    class A:  # overrides for build_scene_dict
        pass
    A.width, A.height, A.max_depth = args.width, args.height, args.max_depth
    A.spp, A.seed, A.spheres = None, None, "analytic"

    out = args.keep or tempfile.mkdtemp(prefix="check_scene_")
    os.makedirs(out, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="check_scene_mi_") as tmp:
        d, o = mr.build_scene_dict(mi, args.scene, A, tmp)
        scene = mi.load_dict(d)
    w, h, depth = o["width"], o["height"], o["max_depth"]
    print("%s: %dx%d, max_depth %d, reference %d spp" % (args.scene, w, h, depth, args.ref_spp))
    ref, t = mr.render(mi, scene, w, h, args.ref_spp, REF_SEED, args.lanes, verbose=False)
    mr.write_exr(mi, ref, os.path.join(out, "ref.exr"))
    ref = ref.astype("float64")
    print("reference: %.1f s" % t)

    results = {"scene": args.scene, "width": w, "height": h, "max_depth": depth,
               "reference_spp": args.ref_spp, "seeds": args.seeds, "spp": {}}
    for spp in args.spp:
        row = {}
        per = []
        for s in range(args.seeds):
            img, _ = mr.render(mi, scene, w, h, spp, s, args.lanes, verbose=False)
            per.append(relmse(img.astype("float64"), ref))
        row["mitsuba"] = sum(per) / len(per)
        for device in args.device:
            per = []
            for s in range(args.seeds):
                path = os.path.join(out, "%s_%d_%d.exr" % (device, spp, s))
                cmd = [args.meshtrace, "render", args.scene, "-o", path, "--spp", str(spp),
                       "--seed", str(s), "--width", str(w), "--height", str(h),
                       "--max-depth", str(depth), "--device", device, "--quiet"]
                subprocess.run(cmd, check=True)
                per.append(relmse(read_exr(path), ref))
            row[device] = sum(per) / len(per)
            row[device + "_ratio"] = row[device] / row["mitsuba"]
        results["spp"][str(spp)] = row
        print("%4d spp: Mitsuba relMSE %.4g; %s" % (
            spp, row["mitsuba"],
            "; ".join("%s %.4g (ratio %.3f)" % (dv, row[dv], row[dv + "_ratio"])
                      for dv in args.device)))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=2)
            fh.write("\n")


if __name__ == "__main__":
    main()
