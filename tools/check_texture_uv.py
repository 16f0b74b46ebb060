#!/usr/bin/env python3
"""Check mitsuba_render.py's texture translation against the scene format's lookup rule.

scene-format.md: the value of a texture at UV (u, v) with `scale = [su, sv]` is the
bilinear, repeat-wrapped lookup at (su u, sv v), where UV (0, 0) is the image's
bottom-left corner for OBJ `vt` and texel centres sit at half-integers
(x = u' width - 0.5, y_from_bottom = v' height - 0.5); 8-bit images are sRGB.

This script builds an emitting quad through mitsuba_render's own functions (split_obj
writes its triangle OBJ with `vt`, resolve_toml_material + bitmap_texture build the
texture, shapes get flip_tex_coords = false as in build_scene_dict), renders it with an
orthographic camera (max_depth 1: the image is the emitted radiance), and compares it
with a numpy evaluation of the rule above averaged over each pixel. The texture is a
random 5x3 image (odd, non-square, so that a half-texel or row-order error shows),
written once as an 8-bit PNG (sRGB path) and once as an EXR (linear path). As a control
it also renders Mitsuba's default convention (flip_tex_coords = true, image rows as
they are), which agrees at integer scales and must disagree at non-integer ones.

Result with Mitsuba 3.9.1 (llvm_ad_rgb), 1024 spp, 24x24 pixels, PNG and EXR alike: the
script's translation agrees to < 0.01 max abs (noise of the pixel integral; mean abs
~1e-3) at scales (1, 1), (3, 3), (2, 1.5), (0.7, 1.3); the default-flip control agrees
at the integer scales and is off by 0.57 to 0.74 at the other two.

Also checks parse_map's reading of MTL map options.

Usage: python3 tools/check_texture_uv.py [--spp 1024] [--variant V]
Exits with status 1 if a check fails.
"""
import argparse
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_render as mr  # noqa: E402
from gen_test_textures import write_png  # noqa: E402

N = 24            # pixels per side
TOL_MAX = 0.03    # max abs error allowed per pixel (noise at 1024 spp is ~0.01)


def spec_lookup(T, u, v, su, sv):
    """The format's rule on a linear image T (row 0 = top): bilinear, repeat wrapping,
    texel centres at half-integers, (0, 0) at the bottom-left."""
    H, W = T.shape[:2]
    x = u * su * W - 0.5
    yb = v * sv * H - 0.5                       # from the bottom row
    x0, y0 = np.floor(x).astype(int), np.floor(yb).astype(int)
    fx, fy = (x - x0)[..., None], (yb - y0)[..., None]

    def tex(ix, iyb):
        return T[H - 1 - (iyb % H), ix % W]
    return ((1 - fx) * (1 - fy) * tex(x0, y0) + fx * (1 - fy) * tex(x0 + 1, y0)
            + (1 - fx) * fy * tex(x0, y0 + 1) + fx * fy * tex(x0 + 1, y0 + 1))


def expected(T, su, sv, k=16):
    """Mean of the rule over a k x k grid in each of N x N pixels of the quad [-1, 1]^2
    seen head-on (pixel row 0 at the top, y = 1), u = (x + 1) / 2, v = (y + 1) / 2."""
    o = (np.arange(N * k) + 0.5) / (N * k)
    u = np.broadcast_to(o[None, :], (N * k, N * k))
    v = np.broadcast_to(1.0 - o[:, None], (N * k, N * k))
    return spec_lookup(T, u, v, su, sv).reshape(N, k, N, k, 3).mean(axis=(1, 3))


def render(mi, obj_file, radiance, flip, spp):
    sc = mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 1},
        "sensor": {"type": "orthographic",
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": N, "height": N,
                            "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "quad": {"type": "obj", "filename": obj_file, "face_normals": True,
                 "flip_tex_coords": flip,
                 "emitter": {"type": "area", "radiance": radiance},
                 "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}}}})
    return np.array(mi.render(sc, spp=spp), dtype=np.float64)[..., :3]


def check_parse_map():
    ok = True
    cases = [("tex.png", ("tex.png", (1.0, 1.0))),
             ("-s 3 3 tex.png", ("tex.png", (3.0, 3.0))),
             ("-s 2 tex.png", ("tex.png", (2.0, 1.0))),
             ("-s 2 0.5 1 -o 0.1 0.2 -clamp on my tex.png", ("my tex.png", (2.0, 0.5))),
             ("-bm 0.5 -o -0.25 0 0 a.png", ("a.png", (1.0, 1.0)))]
    for rest, want in cases:
        got = mr.parse_map(rest, "check")
        good = got == want
        ok &= good
        print("parse_map(%r) -> %r %s" % (rest, got, "ok" if good else "FAIL (want %r)" % (want,)))
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--variant")
    args = ap.parse_args()
    mi = mr.setup_mitsuba(args.variant)
    ok = check_parse_map()
    rng = np.random.default_rng(1)
    with tempfile.TemporaryDirectory(prefix="check_uv_") as tmp:
        # the quad [-1, 1]^2 at z = 0 facing +z; vt (0, 0) at its bottom-left corner
        # (as seen from +z, +y up), vt (1, 1) at the top-right
        src = os.path.join(tmp, "quad.obj")
        with open(src, "w") as fh:
            fh.write("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n")
        (obj_file, _, _, has_vt, _), = mr.split_obj(src, tmp, "q")
        assert has_vt
        # 5x3 test image, row 0 = top: as an 8-bit PNG (sRGB) and as a linear EXR
        png8 = (rng.random((3, 5, 3)) * 255).round().astype(np.uint8)
        write_png(os.path.join(tmp, "t.png"), png8)
        lin_png = mr.srgb_to_linear(png8 / 255.0)
        lin_exr = rng.random((3, 5, 3)).astype(np.float32)
        mi.Bitmap(lin_exr, mi.Bitmap.PixelFormat.RGB).write(os.path.join(tmp, "t.exr"))
        for fname, T in (("t.png", lin_png), ("t.exr", lin_exr.astype(np.float64))):
            for su, sv in ((1, 1), (3, 3), (2, 1.5), (0.7, 1.3)):
                mat = mr.resolve_toml_material(
                    {"type": "diffuse",
                     "emission": {"texture": fname, "scale": [su, sv], "strength": 1.0}},
                    tmp, "[materials.check]")
                ref = mat["emission"]
                exp = expected(T, su, sv)
                ours = render(mi, obj_file, mr.bitmap_texture(mi, ref), False, args.spp)
                # control: Mitsuba's default v flip with the image rows as they are
                default = dict(mr.bitmap_texture(mi, ref))
                img = mr.load_texture(mi, ref.path, "check").astype(np.float32)
                default["bitmap"] = mi.Bitmap(np.ascontiguousarray(img),
                                              mi.Bitmap.PixelFormat.RGB)
                ctrl = render(mi, obj_file, default, True, args.spp)
                e_ours, e_ctrl = abs(ours - exp), abs(ctrl - exp)
                good = e_ours.max() <= TOL_MAX
                ok &= good
                print("%s scale (%g, %g): script max|d| %.4f mean %.4f %s | Mitsuba default "
                      "flip max|d| %.4f" % (fname, su, sv, e_ours.max(), e_ours.mean(),
                                            "ok" if good else "FAIL", e_ctrl.max()))
    print("all checks passed" if ok else "SOME CHECKS FAILED")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
