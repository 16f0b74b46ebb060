#!/usr/bin/env python3
"""Regenerate the environment maps of assets/env/ that are not procedural studios:

  assets/env/rooitou_park_256x128.hdr  Poly Haven's "Rooitou Park" (CC0), box-filtered from
                                       its 1024x512 release (rooitou_park_1k.hdr) to 256x128:
                                       each texel the mean of a 4x4 block, so the sun's energy
                                       (its integral over the sphere) is kept
  assets/env/test_16x8.hdr             a synthetic 16x8 map for unit tests (below)
  assets/env/test_16x8.exr             the same values as a float32 OpenEXR (RGB)

The source is not shipped (1.5 MB). It is the file hdri/rooitou_park_1k.hdr of
https://github.com/pmndrs/drei-assets at commit 456060a26bbeb8fdf79326f224b6d99b8bcce736
(git blob d05a54b138f7d6b5a324311d32895c7cbe2b30e5; the same blob is src/hdri/park.hdr of
https://github.com/pmndrs/assets, the CC0 npm package @pmndrs/assets), for example

  curl -LO https://raw.githubusercontent.com/pmndrs/drei-assets/456060a26bbeb8fdf79326f224b6d99b8bcce736/hdri/rooitou_park_1k.hdr

The script checks the file's git blob hash before using it. Without --source only the
synthetic maps are written.

The synthetic map (row 0 = the top = +Y, column 0 starts at u = 0; see
shared/specs/scene-format.md [sky] environment): texel (row i, column j) holds
  (r, g, b) = ((j + 1) / 16, (i + 1) / 8, 0.5)
except texel (row 2, column 11), which holds (8192, 4096, 2048), and texel (row 5,
column 0), which holds (0, 0, 0). Every value is exactly representable in RGBE (and in
float32), so both files decode to exactly these numbers (RGBE decoded as
(r, g, b) 2^(e - 136), as Mitsuba and the `image` crate do).

Usage:
  python3 tools/gen_test_envmaps.py [--source rooitou_park_1k.hdr] [--out-dir assets/env]
"""
import argparse
import hashlib
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rgbe  # noqa: E402

SOURCE_BLOB = "d05a54b138f7d6b5a324311d32895c7cbe2b30e5"
SOURCE_SIZE = (1024, 512)
FACTOR = 4                     # 1024x512 -> 256x128
REAL_NAME = "rooitou_park_256x128.hdr"

BRIGHT = (2, 11, (8192.0, 4096.0, 2048.0))   # row, column, value
BLACK = (5, 0)


def git_blob_sha1(data):
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


def luminance(img):
    return img @ np.array([0.2126, 0.7152, 0.0722])


def synthetic():
    h, w = 8, 16
    img = np.zeros((h, w, 3))
    img[:, :, 0] = (np.arange(w)[None, :] + 1) / w
    img[:, :, 1] = (np.arange(h)[:, None] + 1) / h
    img[:, :, 2] = 0.5
    i, j, v = BRIGHT
    img[i, j] = v
    img[BLACK] = 0.0
    return img


def box_downsample(img, k):
    h, w, c = img.shape
    if h % k or w % k:
        raise SystemExit("image size %dx%d is not a multiple of %d" % (w, h, k))
    return img.reshape(h // k, k, w // k, k, c).mean(axis=(1, 3))


def stats(img):
    """Peak and median luminance, the peak's texel, the sun's share of the irradiance-like
    integral sum(L sin theta) (texels above 100 x the median)."""
    L = luminance(img)
    h = L.shape[0]
    sin = np.sin((np.arange(h) + 0.5) / h * np.pi)[:, None]
    med = float(np.median(L))
    sun = L > 100 * med
    share = float((L * sin)[sun].sum() / (L * sin).sum())
    i, j = np.unravel_index(int(L.argmax()), L.shape)
    return dict(peak=float(L.max()), median=med, ratio=float(L.max()) / med, row=int(i),
                col=int(j), sun_texels=int(sun.sum()), sun_share=share)


def write_exr(path, img):
    """float32 RGB OpenEXR through Mitsuba's Bitmap (scalar variant)."""
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32), mi.Bitmap.PixelFormat.RGB).write(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--source", help="rooitou_park_1k.hdr (see the docstring)")
    ap.add_argument("--out-dir", default="assets/env")
    ap.add_argument("--no-exr", action="store_true", help="skip test_16x8.exr (no Mitsuba)")
    args = ap.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)

    syn = synthetic()
    back = rgbe.write_hdr(os.path.join(args.out_dir, "test_16x8.hdr"), syn,
                          "meshtrace synthetic test map, tools/gen_test_envmaps.py (CC0)")
    assert np.array_equal(back, syn), "test map not exactly representable in RGBE"
    print("wrote test_16x8.hdr (exact)")
    if not args.no_exr:
        write_exr(os.path.join(args.out_dir, "test_16x8.exr"), syn)
        print("wrote test_16x8.exr")

    if args.source:
        with open(args.source, "rb") as fh:
            data = fh.read()
        blob = git_blob_sha1(data)
        if blob != SOURCE_BLOB:
            raise SystemExit("%s: git blob %s, expected %s (rooitou_park_1k.hdr of "
                             "pmndrs/drei-assets)" % (args.source, blob, SOURCE_BLOB))
        src = rgbe.read_hdr(args.source)
        if (src.shape[1], src.shape[0]) != SOURCE_SIZE:
            raise SystemExit("unexpected source size %s" % (src.shape,))
        s0 = stats(src)
        out = box_downsample(src, FACTOR)
        written = rgbe.write_hdr(
            os.path.join(args.out_dir, REAL_NAME), out,
            "Rooitou Park, Poly Haven (CC0), rooitou_park_1k.hdr box-filtered 4x4 to "
            "256x128\nby meshtrace tools/gen_test_envmaps.py")
        s1 = stats(written)
        flux_src = (luminance(src) * np.sin((np.arange(512) + 0.5) / 512 * np.pi)[:, None]).sum() / 4 ** 2
        flux_out = (luminance(written) * np.sin((np.arange(128) + 0.5) / 128 * np.pi)[:, None]).sum()
        for name, s in (("source 1024x512", s0), ("%s" % REAL_NAME, s1)):
            print("%s: peak luminance %.5g, median %.5g, peak/median %.4g, peak at row %d "
                  "column %d; %d texels > 100 x median hold %.1f%% of sum(L sin theta)"
                  % (name, s["peak"], s["median"], s["ratio"], s["row"], s["col"],
                     s["sun_texels"], 100 * s["sun_share"]))
        print("sum(L sin theta) dA: source %.6g, written %.6g (ratio %.5f)"
              % (flux_src, flux_out, flux_out / flux_src))


if __name__ == "__main__":
    main()
