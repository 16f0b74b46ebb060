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

glTF (--gltf runs these alone): the same comparison for a glTF emissive quad read and
translated by the script itself (gltf_read + mitsuba_render.gltf_geometry: an embedded
buffer and an embedded PNG, emissiveTexture with KHR_texture_transform), against meshtrace's
rule for glTF: UV (0, 0) at the image's top-left, v running down, the lookup at
M (u, v) + offset with M = [[cos r su, sin r sv], [-sin r su, cos r sv]] (src/scene/
texture.rs UvTransform::matrix), bilinear, repeat, texel centres at half-integers; at the
identity, a scale, a rotation and offset + rotation + scale. Result (3.9.1, llvm_ad_rgb,
1024 spp): max error < 0.01 in every case; the control (image rows reversed, as for OBJ)
is off by 0.52 to 0.59. And the rotation's direction against Khronos's TextureTransformTest
(tests/data/gltf/TextureTransformTest): with the script's matrix, the arrow texture of the
"Rotation" and "All" quads ends nearest their "Correct" markers (0.13 and 0.08 away;
"Rotation"'s "Error" marker 0.67), the opposite rotation far from them (0.67, 0.45).

Also checks parse_map's reading of MTL map options.

Usage: python3 tools/check_texture_uv.py [--spp 1024] [--variant V] [--gltf]
Exits with status 1 if a check fails.
"""
import argparse
import base64
import json
import math
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


def gltf_lookup(T, u, v, M):
    """meshtrace's glTF lookup on a linear image T (row 0 = top): s = M . (u, v, 1),
    repeat, bilinear, texel centres at half-integers, v running down from the top."""
    H, W = T.shape[:2]
    su = M[0, 0] * u + M[0, 1] * v + M[0, 2]
    sv = M[1, 0] * u + M[1, 1] * v + M[1, 2]
    x = (su - np.floor(su)) * W - 0.5
    y = (sv - np.floor(sv)) * H - 0.5
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]

    def tex(ix, iy):
        return T[iy % H, ix % W]
    return ((1 - fx) * (1 - fy) * tex(x0, y0) + fx * (1 - fy) * tex(x0 + 1, y0)
            + (1 - fx) * fy * tex(x0, y0 + 1) + fx * fy * tex(x0 + 1, y0 + 1))


def gltf_expected(T, M, k=16):
    """The rule averaged over each of N x N pixels of the quad [-1, 1]^2 seen head-on: u =
    (x + 1) / 2 grows to the right, v = (1 - y) / 2 downwards (glTF UVs of the quad)."""
    o = (np.arange(N * k) + 0.5) / (N * k)
    u = np.broadcast_to(o[None, :], (N * k, N * k))
    v = np.broadcast_to(o[:, None], (N * k, N * k))
    return gltf_lookup(T, u, v, M).reshape(N, k, N, k, 3).mean(axis=(1, 3))


def gltf_quad(path, png_bytes, transform):
    """A glTF file: the quad [-1, 1]^2 at z = 0 facing +z, its UVs (u right, v down), an
    emissive material (black Lambertian base: specularFactor 0) whose emissiveTexture (the
    PNG, embedded as a data URI) has KHR_texture_transform `transform`; the buffer is
    embedded too."""
    pos = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype="<f4")
    uv = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], dtype="<f4")
    idx = np.array([0, 1, 2, 0, 2, 3], dtype="<u2")
    data = pos.tobytes() + uv.tobytes() + idx.tobytes()
    info = {"index": 0}
    if transform:
        info["extensions"] = {"KHR_texture_transform": transform}
    doc = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_texture_transform", "KHR_materials_specular"],
        "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1},
                                    "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1],
                                                "metallicFactor": 0},
                       "emissiveFactor": [1, 1, 1], "emissiveTexture": info,
                       "extensions": {"KHR_materials_specular": {"specularFactor": 0}}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "data:image/png;base64," + base64.b64encode(png_bytes).decode()}],
        "buffers": [{"uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(data).decode(), "byteLength": len(data)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                        {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [-1, -1, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                      {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}],
    }
    with open(path, "w") as fh:
        json.dump(doc, fh)


def render_shape(mi, shape, spp):
    sc = mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 1},
        "sensor": {"type": "orthographic",
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": N, "height": N,
                            "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "quad": shape})
    return np.array(mi.render(sc, spp=spp), dtype=np.float64)[..., :3]


def check_gltf(mi, spp, tmp, rng):
    """The glTF texture translation against meshtrace's glTF rule; see the docstring."""
    ok = True
    png8 = (rng.random((3, 5, 3)) * 255).round().astype(np.uint8)
    write_png(os.path.join(tmp, "g.png"), png8)
    with open(os.path.join(tmp, "g.png"), "rb") as fh:
        png_bytes = fh.read()
    T = mr.srgb_to_linear(png8 / 255.0)
    cases = [("identity", None), ("scale (2, 1.5)", {"scale": [2, 1.5]}),
             ("rotation 1.1", {"rotation": 1.1}),
             ("offset + rotation + scale", {"offset": [0.2, -0.35], "rotation": 0.6,
                                            "scale": [0.7, 1.3]})]
    for k, (name, tt) in enumerate(cases):
        path = os.path.join(tmp, "quad%d.gltf" % k)
        gltf_quad(path, png_bytes, tt)
        shapes, _, _ = mr.gltf_geometry(mi, path, np.eye(4), None, tmp, "gq%d" % k, None)
        (shape,) = shapes
        tt = tt or {}
        r, (sx, sy), (ox, oy) = tt.get("rotation", 0.0), tt.get("scale", [1, 1]), \
            tt.get("offset", [0, 0])
        c, sn = math.cos(r), math.sin(r)
        M = np.array([[c * sx, sn * sy, ox], [-sn * sx, c * sy, oy], [0, 0, 1]])
        exp = gltf_expected(T, M)
        ours = render_shape(mi, shape, spp)
        # control: the image rows reversed (the OBJ convention)
        ctrl_shape = dict(shape)
        em = dict(shape["emitter"])
        rad = dict(em["radiance"])
        img = np.ascontiguousarray(np.array(rad["bitmap"])[::-1], dtype=np.float32)
        rad["bitmap"] = mi.Bitmap(img, mi.Bitmap.PixelFormat.RGB)
        em["radiance"] = rad
        ctrl_shape["emitter"] = em
        ctrl = render_shape(mi, ctrl_shape, spp)
        e_ours, e_ctrl = abs(ours - exp), abs(ctrl - exp)
        good = e_ours.max() <= TOL_MAX
        ok &= good
        print("glTF %s: script max|d| %.4f mean %.4f %s | rows reversed max|d| %.4f"
              % (name, e_ours.max(), e_ours.mean(), "ok" if good else "FAIL", e_ctrl.max()))
    return ok & check_texture_transform_test(mi, tmp)


def check_texture_transform_test(mi, tmp):
    """KHR_texture_transform's rotation direction, against Khronos's TextureTransformTest:
    on the "Rotation" and "All" quads the arrow texture, mapped by the script's matrix
    (GltfMaterials.texture), must come nearest the "Correct" marker, and nearer to it than
    with the opposite rotation."""
    here = os.path.dirname(os.path.abspath(__file__))
    path = os.path.join(here, "..", "tests", "data", "gltf", "TextureTransformTest",
                        "TextureTransformTest.gltf")
    doc = mr.gr.Doc(path)
    sc = mr.gr.read_scene(doc)
    mats = mr.GltfMaterials(mi, doc, tmp, "ttt")
    arrow = np.array(mi.Bitmap(os.path.join(os.path.dirname(path), "Arrow.png")), dtype=float)
    dark = (arrow[..., 3] > 128) & (arrow[..., 0] < 128)
    H, W = dark.shape
    ok = True
    for name in ("Rotation", "All"):
        mat = [i for i, m in enumerate(doc.json["materials"]) if m.get("name") == name][0]
        part = [p for p in sc.parts if p.material == mat][0]
        info = doc.json["materials"][mat]["pbrMetallicRoughness"]["baseColorTexture"]
        ref = mats.texture(info, "check", [1, 1, 1])
        # the quad's UVs are affine in its local x, y
        P = np.c_[part.positions[:, :2], np.ones(len(part.positions))]
        A = np.linalg.lstsq(P, part.uvs, rcond=None)[0]
        g = (np.arange(200) + 0.5) / 200 - 0.5
        X, Y = np.meshgrid(g, g)
        uv = np.c_[X.ravel(), Y.ravel(), np.ones(X.size)] @ A
        node = [n for n in doc.json["nodes"] if n.get("name") == name][0]
        markers = {doc.json["nodes"][ch]["name"].split(" - ")[-1]:
                   np.array(doc.json["nodes"][ch]["translation"][:2]) for ch in node["children"]}
        dists = {}
        for label, M in (("script", ref.matrix),
                         ("opposite", ref.matrix * [[1, -1, 1], [-1, 1, 1], [1, 1, 1]])):
            st = np.c_[uv, np.ones(len(uv))] @ np.asarray(M).T
            st = np.clip(st[:, :2], 0, 0.99999)     # the file's sampler clamps
            pts = np.c_[X.ravel(), Y.ravel()][dark[(st[:, 1] * H).astype(int),
                                                   (st[:, 0] * W).astype(int)]]
            dists[label] = {k: float(np.min(np.linalg.norm(pts - v, axis=1)))
                            for k, v in markers.items()}
        d = dists["script"]
        good = min(d, key=d.get) == "Correct" and d["Correct"] < dists["opposite"]["Correct"]
        ok &= good
        print("TextureTransformTest %s: arrow to markers with the script's rotation: %s; with "
              "the opposite rotation: %s %s" % (
                  name, ", ".join("%s %.3f" % kv for kv in d.items()),
                  ", ".join("%s %.3f" % kv for kv in dists["opposite"].items()),
                  "ok" if good else "FAIL"))
    return ok


def check_parse_map():
    ok = True
    cases = [("tex.png", ("tex.png", (1.0, 1.0), "repeat")),
             ("-s 3 3 tex.png", ("tex.png", (3.0, 3.0), "repeat")),
             ("-s 2 tex.png", ("tex.png", (2.0, 1.0), "repeat")),
             ("-s 2 0.5 1 -o 0.1 0.2 -clamp on my tex.png", ("my tex.png", (2.0, 0.5), "clamp")),
             ("-clamp off a.png", ("a.png", (1.0, 1.0), "repeat")),
             ("-bm 0.5 -o -0.25 0 0 a.png", ("a.png", (1.0, 1.0), "repeat"))]
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
    ap.add_argument("--gltf", action="store_true", help="only the glTF checks")
    args = ap.parse_args()
    mi = mr.setup_mitsuba(args.variant)
    rng = np.random.default_rng(1)
    if args.gltf:
        with tempfile.TemporaryDirectory(prefix="check_uv_") as tmp:
            ok = check_gltf(mi, args.spp, tmp, rng)
        print("all checks passed" if ok else "SOME CHECKS FAILED")
        sys.exit(0 if ok else 1)
    ok = check_parse_map()
    with tempfile.TemporaryDirectory(prefix="check_uv_") as tmp:
        # the quad [-1, 1]^2 at z = 0 facing +z; vt (0, 0) at its bottom-left corner
        # (as seen from +z, +y up), vt (1, 1) at the top-right
        src = os.path.join(tmp, "quad.obj")
        with open(src, "w") as fh:
            fh.write("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n")
        (obj_file, _, _, has_vt, _, _), = mr.split_obj(src, tmp, "q")
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
        ok &= check_gltf(mi, args.spp, tmp, rng)
    print("all checks passed" if ok else "SOME CHECKS FAILED")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
