#!/usr/bin/env python3
"""Check mitsuba_render.py's normal-map translation on Mitsuba's side alone.

A flat quad (facing +Z) with a diffuse albedo rho carries a constant tangent-space normal map
that tilts the shading normal by 30 degrees, towards +u or towards image-up (OpenGL
convention: +Y = up the image), and is lit by a directional light of irradiance E from
l = normalize(0.6, 0.3, 1) under a black sky; the camera looks at it head-on. Every pixel
on the quad then has the radiance rho / pi * E * dot(n', l), where n' is the tilted normal
in world space: +u and image-up are known from the quad's UVs. The scenes go through the
script's whole path (build_scene_dict: a TOML scene with an OBJ quad and `normal_map`, and
a bare glTF file with normalTexture and a KHR_lights_punctual directional light, also with
a TANGENT attribute that agrees with the UVs), with UVs as authored and mirrored (u running to -X: the script flips the map's green channel for
such triangles, see normal_map_bsdf); a control renders the mirrored quad without the
flip. The map is an 8-bit PNG, decoded as data (n = 2 c / 255 - 1, normalised).

Result (Mitsuba 3.9.1, llvm_ad_rgb): every case, TOML and glTF, plain and mirrored UVs,
equals the expected radiance to 0.01% (the 8-bit encoding included in the expectation);
the control is off by 29.5% for the tilt towards image-up (its y goes the wrong way; 0.4%
for the tilt towards +u, whose 8-bit y is not quite 0). The refusals are checked too: a TOML
normal_map strength other than 1, a glTF normalTexture scale other than 1, and TANGENT
attributes that disagree with the UVs' frame (rotated, or of the wrong handedness) are errors.

Usage: python3 tools/check_normal_map.py [--variant V]
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

RHO = 0.5
E = 1.0
L_DIR = np.array([0.6, 0.3, 1.0]) / np.linalg.norm([0.6, 0.3, 1.0])
THETA = math.radians(30.0)
TOL = 0.003   # relative


class Args:
    width = height = None
    spp = 16
    seed = 0
    max_depth = 2
    spheres = "analytic"


def encode(n):
    """8-bit RGB of a unit tangent-space normal, and the normal it decodes to."""
    c = np.round((np.asarray(n) + 1.0) / 2.0 * 255.0).astype(np.uint8)
    d = c / 255.0 * 2.0 - 1.0
    return c, d / np.linalg.norm(d)


def render(mi, scene_dict):
    sc = mi.load_dict(scene_dict)
    img = np.array(mi.render(sc, spp=16), dtype=np.float64)[..., :3]
    h, w = img.shape[:2]
    return img[h // 4: 3 * h // 4, w // 4: 3 * w // 4].mean()


def toml_scene(tmp, png, mirrored, strength=1.0):
    """A TOML scene: the OBJ quad [-1, 1]^2 facing +Z, vt (0, 0) bottom-left (u along +X,
    or along -X when mirrored; vt's v, image-up, along +Y)."""
    u0, u1 = (1, 0) if mirrored else (0, 1)
    with open(os.path.join(tmp, "q.obj"), "w") as fh:
        fh.write("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                 "vt %d 0\nvt %d 0\nvt %d 1\nvt %d 1\nf 1/1 2/2 3/3 4/4\n" % (u0, u1, u1, u0))
    path = os.path.join(tmp, "nm.toml")
    d = -L_DIR
    with open(path, "w") as fh:
        fh.write("""[camera]
position = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]
vfov = 30.0
[render]
width = 16
height = 16
max_depth = 2
[materials.m]
type = "diffuse"
albedo = [%g, %g, %g]
normal_map = { texture = "%s", strength = %g }
[[objects]]
mesh = "q.obj"
material = "m"
[[lights]]
type = "directional"
direction = [%r, %r, %r]
irradiance = [%g, %g, %g]
""" % (RHO, RHO, RHO, png, strength, float(d[0]), float(d[1]), float(d[2]), E, E, E))
    return path


def gltf_scene(tmp, png_path, mirrored, scale=1.0, tangent=None):
    """A bare glTF: the quad [-1, 1]^2 facing +Z with glTF UVs (v down: image-up along +Y;
    u along +X, or -X when mirrored), a specular-0 diffuse material with the normal map,
    a directional light (lux = E x 683) travelling along -l, a camera at z = 3; with
    `tangent` (4 numbers), a TANGENT attribute holding it at every vertex."""
    pos = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype="<f4")
    us = [1, 0, 0, 1] if mirrored else [0, 1, 1, 0]
    uv = np.array([[us[0], 1], [us[1], 1], [us[2], 0], [us[3], 0]], dtype="<f4")
    nrm = np.tile(np.array([0, 0, 1], dtype="<f4"), (4, 1))
    idx = np.array([0, 1, 2, 0, 2, 3], dtype="<u2")
    data = pos.tobytes() + nrm.tobytes() + uv.tobytes() + idx.tobytes()
    tan = np.tile(np.array(tangent or [1, 0, 0, 1], dtype="<f4"), (4, 1)).tobytes()
    # the light's node turns -Z onto -l
    z = np.array([0.0, 0.0, -1.0])
    axis = np.cross(z, -L_DIR)
    ang = math.acos(np.dot(z, -L_DIR))
    q = list(axis / np.linalg.norm(axis) * math.sin(ang / 2)) + [math.cos(ang / 2)]
    with open(png_path, "rb") as fh:
        png = fh.read()
    doc = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_specular"],
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]},
                  {"rotation": q, "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(30),
                                                            "znear": 0.1}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "intensity": E * 683.0}]}},
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1,
                                                   "TEXCOORD_0": 2},
                                    "indices": 3, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [RHO, RHO, RHO, 1],
                                                "metallicFactor": 0},
                       "normalTexture": {"index": 0, "scale": scale},
                       "extensions": {"KHR_materials_specular": {"specularFactor": 0}}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "data:image/png;base64," + base64.b64encode(png).decode()}],
        "buffers": [{"uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(data + tan).decode(), "byteLength": len(data) + 64}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 96, "byteLength": 32},
                        {"buffer": 0, "byteOffset": 128, "byteLength": 12},
                        {"buffer": 0, "byteOffset": 140, "byteLength": 64}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [-1, -1, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
                      {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
                      {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"},
                      {"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC4"}],
    }
    if tangent is not None:
        doc["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] = 4
    path = os.path.join(tmp, "nm.gltf")
    with open(path, "w") as fh:
        json.dump(doc, fh)
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--variant")
    args = ap.parse_args()
    mi = mr.setup_mitsuba(args.variant)
    ok = True
    with tempfile.TemporaryDirectory(prefix="check_nm_") as tmp:
        for tilt_name, n_t in (("+u", [math.sin(THETA), 0, math.cos(THETA)]),
                               ("image-up", [0, math.sin(THETA), math.cos(THETA)])):
            c, d = encode(n_t)
            png = "n_%s.png" % ("u" if tilt_name == "+u" else "up")
            write_png(os.path.join(tmp, png), np.tile(c, (4, 4, 1)))
            for fmt in ("TOML", "glTF", "glTF+TANGENT"):
                for mirrored in (False, True):
                    # world: +u along +X (or -X when mirrored), image-up along +Y
                    n_w = np.array([-d[0] if mirrored else d[0], d[1], d[2]])
                    want = RHO / math.pi * E * max(0.0, float(np.dot(n_w, L_DIR)))
                    mr._warned.clear()
                    # the TANGENT that agrees: +X with w = 1 (B = n x T = +Y, image-up);
                    # mirrored: -X, and w = -1 keeps B = +Y
                    tangent = None if fmt != "glTF+TANGENT" else \
                        ([-1, 0, 0, -1] if mirrored else [1, 0, 0, 1])
                    path = toml_scene(tmp, png, mirrored) if fmt == "TOML" else \
                        gltf_scene(tmp, os.path.join(tmp, png), mirrored, tangent=tangent)
                    a = Args()
                    if fmt != "TOML":
                        a.width = a.height = 16
                    scene, _ = mr.build_scene_dict(mi, path, a, tmp)
                    got = render(mi, scene)
                    err = abs(got - want) / want
                    good = err <= TOL
                    ok &= good
                    line = "%s, tilt towards %s, %s UVs: radiance %.5f, expected %.5f (%+.2f%%) %s" % (
                        fmt, tilt_name, "mirrored" if mirrored else "plain", got, want,
                        100 * (got - want) / want, "ok" if good else "FAIL")
                    if mirrored:
                        # control: the mirrored quad without the green flip
                        orig = mr.TexRef.flipped
                        mr.TexRef.flipped = lambda self: self
                        try:
                            scene, _ = mr.build_scene_dict(mi, path, a, tmp)
                        finally:
                            mr.TexRef.flipped = orig
                        ctrl = render(mi, scene)
                        line += " | without the green flip %+.1f%%" % (100 * (ctrl - want) / want)
                    print(line)
        # refusals: tangents that disagree with the UVs' frame
        for tangent in ([0, 1, 0, 1], [1, 0, 0, -1]):
            a = Args()
            a.width = a.height = 16
            try:
                mr.build_scene_dict(mi, gltf_scene(tmp, os.path.join(tmp, "n_u.png"), False,
                                                   tangent=tangent), a, tmp)
                print("glTF: TANGENT %s was translated: FAIL" % tangent)
                ok = False
            except mr.gr.GltfError as e:
                print("glTF: TANGENT %s is refused: ok (%s)" % (tangent, str(e)[:110] + "..."))
        for fmt in ("TOML", "glTF"):
            try:
                if fmt == "TOML":
                    mr.build_scene_dict(mi, toml_scene(tmp, "n_u.png", False, strength=0.5),
                                        Args(), tmp)
                else:
                    a = Args()
                    a.width = a.height = 16
                    mr.build_scene_dict(mi, gltf_scene(tmp, os.path.join(tmp, "n_u.png"),
                                                       False, scale=0.5), a, tmp)
                print("%s: a strength/scale of 0.5 was translated: FAIL" % fmt)
                ok = False
            except (mr.SceneError, mr.gr.GltfError) as e:
                print("%s: a strength/scale of 0.5 is refused: ok (%s)" % (fmt, e))
    print("all checks passed" if ok else "SOME CHECKS FAILED")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
