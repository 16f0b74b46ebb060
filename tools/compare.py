#!/usr/bin/env python3
"""Relative MSE of a test EXR against a reference EXR.

    relMSE = mean over pixels and RGB channels of (x - ref)^2 / (ref^2 + 1e-2)

Usage:
  python3 tools/compare.py REF.exr TEST.exr [--mitsuba-at-same-spp M.exr [M2.exr ...]]
                                            [--mitsuba-relmse VALUE] [--json]

With --mitsuba-at-same-spp (one or more Mitsuba renders at the test's sample count,
different seeds) or --mitsuba-relmse (a stored value, e.g. from
tests/references/<scene>.json) it also prints the ratio ours / Mitsuba: about 1 for
an unbiased renderer with the same variance, well above 1 for a bias or more noise.

EXRs are read with mitsuba.Bitmap (scalar_rgb variant), so no other dependency.
"""
import argparse
import json
import sys

import numpy as np

EPS = 1e-2


def read_exr(path):
    import mitsuba as mi
    if mi.variant() is None:
        mi.set_variant("scalar_rgb")
    bmp = mi.Bitmap(path)
    if bmp.pixel_format() not in (mi.Bitmap.PixelFormat.RGB, mi.Bitmap.PixelFormat.RGBA):
        bmp = bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)
    a = np.array(bmp, dtype=np.float64)
    if a.ndim == 2:
        a = a[:, :, None]
    return a[:, :, :3]


def relmse(test, ref):
    if test.shape != ref.shape:
        raise SystemExit("compare: size mismatch: test %s vs reference %s"
                         % (test.shape, ref.shape))
    return float(np.mean((test - ref) ** 2 / (ref ** 2 + EPS)))


def main():
    ap = argparse.ArgumentParser(description="relative MSE of TEST against REF")
    ap.add_argument("ref")
    ap.add_argument("test")
    ap.add_argument("--mitsuba-at-same-spp", nargs="+", metavar="M.exr",
                    help="Mitsuba render(s) at the test's spp; their mean relMSE is the baseline")
    ap.add_argument("--mitsuba-relmse", type=float, help="baseline relMSE value instead")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args()

    ref = read_exr(args.ref)
    test = read_exr(args.test)
    out = {"relmse": relmse(test, ref)}
    if not np.all(np.isfinite(test)):
        out["nonfinite_pixels"] = int(np.sum(~np.isfinite(test)))
    base = None
    if args.mitsuba_at_same_spp:
        per = [relmse(read_exr(p), ref) for p in args.mitsuba_at_same_spp]
        out["mitsuba_relmse_per_file"] = per
        base = float(np.mean(per))
    elif args.mitsuba_relmse is not None:
        base = args.mitsuba_relmse
    if base is not None:
        out["mitsuba_relmse"] = base
        out["ratio"] = out["relmse"] / base
    if args.json:
        print(json.dumps(out))
    else:
        print("relMSE %.6g" % out["relmse"])
        if base is not None:
            print("mitsuba relMSE %.6g" % base)
            print("ratio ours/mitsuba %.4f" % out["ratio"])
        if "nonfinite_pixels" in out:
            print("non-finite values: %d" % out["nonfinite_pixels"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
