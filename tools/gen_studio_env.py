#!/usr/bin/env python3
"""Generate assets/env/studio.hdr: a procedural photo-studio environment (256x128 RGBE,
CC0 by construction: nothing but the numbers below) for looking at bare meshes.

Made for a Y-up scene seen from the front-right, above (a three-quarter view from +Z/+X,
camera azimuth 45 degrees) with `rotate = 0`. Directions are given by azimuth a (in the
XZ plane: (sin a, 0, cos a), so a = 0 is +Z and a = 90 is +X) and elevation e:

  light  azimuth  elevation  size (w x h)  radiance (RGB)         where, seen from the camera
  key      -20       40       70 x 45 deg  10.0 x (1.00 .97 .92)   upper front-left, large
  fill     115       20       55 x 35 deg   2.5 x (0.92 .96 1.00)  right, low, cool
  rim      215       35       22 x 60 deg   5.0 x (1.00 1.00 1.00) behind, a tall strip

Each light is a rectangular panel (its outline in the gnomonic projection around its
centre, so edges are straight lines on the panel) with soft edges (a smoothstep over 6 %
of its size), added on top of the background:
  above the horizon a dim gradient, 0.30 at the horizon to 0.20 at the zenith (neutral);
  below it a darker neutral ground, 0.10, joined to the sky over +-2 degrees.
So the brightest softbox is at most 10 / 0.2 = 50 times the background, and there is no
sun: a few spp give little noise. Each texel is the mean of 8x8 samples over its solid
angle's (u, v) square (a box filter), so the edges are antialiased.

The image follows the scene format's mapping ([sky] environment): u = atan2(x, -z) / 2 pi
(u = 0 the left edge, the centre +Z), v = acos(y) / pi (row 0 the top).

Usage: python3 tools/gen_studio_env.py [-o assets/env/studio.hdr] [--width 256 --height 128]
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rgbe  # noqa: E402

# name, azimuth, elevation, width, height (degrees), radiance, tint
LIGHTS = [
    ("key", -20.0, 40.0, 70.0, 45.0, 10.0, (1.00, 0.97, 0.92)),
    ("fill", 115.0, 20.0, 55.0, 35.0, 2.5, (0.92, 0.96, 1.00)),
    ("rim", 215.0, 35.0, 22.0, 60.0, 5.0, (1.00, 1.00, 1.00)),
]
SKY_HORIZON = 0.30
SKY_ZENITH = 0.20
GROUND = 0.10
HORIZON_BLEND_DEG = 2.0
EDGE = 0.06            # soft edge, fraction of the panel's half-size
SUPERSAMPLE = 8


def direction(az_deg, el_deg):
    a, e = math.radians(az_deg), math.radians(el_deg)
    return np.array([math.sin(a) * math.cos(e), math.sin(e), math.cos(a) * math.cos(e)])


def smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def panel(d, az, el, w_deg, h_deg):
    """Coverage (0..1) of a soft-edged rectangular panel centred at (az, el), w x h degrees
    wide (angles subtended at its centre lines), for directions d (..., 3)."""
    c = direction(az, el)
    t = np.cross([0.0, 1.0, 0.0], c)
    t /= np.linalg.norm(t)                   # horizontal, towards the panel's left edge
    b = np.cross(c, t)                       # up along the panel
    dc = d @ c
    front = dc > 1e-3
    safe = np.where(front, dc, 1.0)
    x = (d @ t) / safe / math.tan(math.radians(w_deg / 2))
    y = (d @ b) / safe / math.tan(math.radians(h_deg / 2))
    cov = smoothstep((1 - np.abs(x)) / EDGE) * smoothstep((1 - np.abs(y)) / EDGE)
    return np.where(front, cov, 0.0)


def radiance(d):
    """RGB radiance for unit directions d (..., 3)."""
    y = d[..., 1]
    el = np.degrees(np.arcsin(np.clip(y, -1, 1)))
    sky = SKY_HORIZON + (SKY_ZENITH - SKY_HORIZON) * np.clip(y, 0, 1)
    s = smoothstep((el + HORIZON_BLEND_DEG) / (2 * HORIZON_BLEND_DEG))
    bg = GROUND + (sky - GROUND) * s
    out = np.repeat(bg[..., None], 3, axis=-1)
    for _, az, el0, w, h, power, tint in LIGHTS:
        out += panel(d, az, el0, w, h)[..., None] * power * np.array(tint)
    return out


def render(width, height):
    n = SUPERSAMPLE
    acc = np.zeros((height, width, 3))
    wsum = np.zeros((height, width, 1))
    for sy in range(n):
        v = (np.arange(height)[:, None] + (sy + 0.5) / n) / height
        theta = math.pi * v
        for sx in range(n):
            u = (np.arange(width)[None, :] + (sx + 0.5) / n) / width
            phi = 2 * math.pi * u
            st = np.sin(theta)
            d = np.stack(np.broadcast_arrays(st * np.sin(phi), np.cos(theta),
                                             -st * np.cos(phi)), axis=-1)
            wgt = np.broadcast_to(st, (height, width))[..., None]   # solid angle
            acc += radiance(d) * wgt
            wsum += wgt
    return acc / wsum


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("-o", "--output", default="assets/env/studio.hdr")
    ap.add_argument("--width", type=int, default=256)
    ap.add_argument("--height", type=int, default=128)
    args = ap.parse_args()
    img = render(args.width, args.height)
    os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
    out = rgbe.write_hdr(args.output, img,
                         "meshtrace procedural studio environment, tools/gen_studio_env.py "
                         "(CC0)")
    L = out @ np.array([0.2126, 0.7152, 0.0722])
    h = L.shape[0]
    upper = L[: h // 2]
    print("wrote %s (%dx%d): luminance max %.3f, sky background median %.3f (ratio %.1f), "
          "ground median %.3f" % (args.output, args.width, args.height, L.max(),
                                  np.median(upper), L.max() / np.median(upper),
                                  np.median(L[h // 2 + 4:])))
    sin = np.sin((np.arange(h) + 0.5) / h * math.pi)[:, None]
    tot = (L * sin).sum()
    for name, az, el, w, hh, power, tint in LIGHTS:
        print("  %-4s share of sum(L sin theta): %.1f%%" % (name, 100 * (
            (panel(np.stack(np.broadcast_arrays(*_dirs(args.width, h)), axis=-1), az, el, w, hh)
             * power * np.dot(tint, [0.2126, 0.7152, 0.0722]) * sin).sum() / tot)))


def _dirs(width, height):
    v = (np.arange(height)[:, None] + 0.5) / height
    u = (np.arange(width)[None, :] + 0.5) / width
    th, ph = math.pi * v, 2 * math.pi * u
    return np.sin(th) * np.sin(ph), np.cos(th) * np.ones_like(ph), -np.sin(th) * np.cos(ph)


if __name__ == "__main__":
    main()
