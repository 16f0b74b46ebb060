#!/usr/bin/env python3
"""Generate the textures of tests/scenes/textured.toml procedurally, so that their
provenance is ours.

Writes 8-bit sRGB PNGs (no colour-space chunk: PNGs are sRGB by the scene format) with a
small PNG encoder of our own (numpy + zlib; Pillow is not needed):

  tests/scenes/textured_checker.png  64x64 RGB: an 8x8 checker whose light squares carry
                                     a colour gradient (red grows to the right, blue
                                     upwards) and whose bottom-left square is marked
                                     green, so that orientation errors show; the floor's
                                     map_Kd (tiled 3x3 by `-s 3 3` in textured_floor.mtl)
  tests/scenes/textured_wall.png     32x32 RGB: horizontal bands of three colours with a
                                     vertical gradient, a dark diagonal and an orange
                                     top-left corner; the back wall's and the short
                                     block's albedo
  tests/scenes/textured_light.png    16x8 RGB: a warm left half and a cold right half,
                                     with a white vertical stripe and a magenta block in
                                     the top-right corner; the ceiling light's emission

The images are deterministic (no random numbers); rerunning rewrites identical files.

Usage: python3 tools/gen_test_textures.py [--out-dir tests/scenes]
"""
import argparse
import os
import struct
import zlib

import numpy as np


def write_png(path, img):
    """Writes an HxWx3 (or HxW) uint8 array as an 8-bit RGB (or grey) PNG, rows top
    to bottom, filter type 0 on every row, zlib level 9."""
    img = np.ascontiguousarray(img, dtype=np.uint8)
    if img.ndim == 2:
        colour_type, channels = 0, 1
    elif img.ndim == 3 and img.shape[2] == 3:
        colour_type, channels = 2, 3
    else:
        raise ValueError("write_png: need HxW or HxWx3, got %s" % (img.shape,))
    h, w = img.shape[:2]
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(h))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour_type, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 9))
           + chunk(b"IEND", b""))
    assert channels in (1, 3)
    with open(path, "wb") as fh:
        fh.write(png)


def checker():
    """64x64, 8x8 squares of 8 texels. Row 0 is the top of the image."""
    n, sq = 64, 8
    y, x = np.mgrid[0:n, 0:n]
    fx = (x + 0.5) / n                    # 0 left .. 1 right
    fy = 1.0 - (y + 0.5) / n              # 0 bottom .. 1 top
    light = ((x // sq) + (y // sq)) % 2 == 0
    img = np.empty((n, n, 3))
    img[..., 0] = 0.55 + 0.4 * fx
    img[..., 1] = 0.6
    img[..., 2] = 0.5 + 0.45 * fy
    img[~light] = [0.12, 0.1, 0.09]
    # bottom-left square: green marker
    img[n - sq:, :sq] = [0.15, 0.7, 0.2]
    return np.round(img * 255).astype(np.uint8)


def wall():
    """32x32: three horizontal bands (blue-grey, sand, teal) bottom to top, darker at
    the bottom of each band, a dark diagonal from bottom-left to top-right and an orange
    4x4 block in the top-left corner."""
    n = 32
    y, x = np.mgrid[0:n, 0:n]
    fy = 1.0 - (y + 0.5) / n
    band = np.minimum((fy * 3).astype(int), 2)
    colours = np.array([[0.45, 0.5, 0.65], [0.8, 0.7, 0.5], [0.3, 0.65, 0.6]])
    shade = 0.7 + 0.3 * ((fy * 3) % 1.0)
    img = colours[band] * shade[..., None]
    diag = np.abs((n - 1 - y) - x) <= 1
    img[diag] = [0.08, 0.08, 0.1]
    img[:4, :4] = [0.95, 0.45, 0.1]
    return np.round(img * 255).astype(np.uint8)


def light():
    """16x8: warm left half, cold right half, a white stripe at columns 7-8, a magenta
    3x2 block in the top-right corner."""
    w, h = 16, 8
    img = np.empty((h, w, 3))
    img[:, : w // 2] = [1.0, 0.62, 0.25]
    img[:, w // 2:] = [0.35, 0.6, 1.0]
    img[:, 7:9] = [1.0, 1.0, 1.0]
    img[:2, w - 3:] = [1.0, 0.2, 0.85]
    return np.round(img * 255).astype(np.uint8)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--out-dir", default=os.path.join(here, "..", "tests", "scenes"))
    args = ap.parse_args()
    for name, img in (("textured_checker.png", checker()), ("textured_wall.png", wall()),
                      ("textured_light.png", light())):
        path = os.path.join(args.out_dir, name)
        write_png(path, img)
        print("wrote %s (%dx%d, %d bytes)" % (os.path.relpath(path), img.shape[1],
                                             img.shape[0], os.path.getsize(path)))


if __name__ == "__main__":
    main()
