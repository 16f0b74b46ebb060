#!/usr/bin/env python3
"""Generate tests/scenes/gltf_room/: a small glTF 2.0 room (room.gltf + room.bin + three
PNG textures), the scene of the glTF Mitsuba references (tests/mitsuba_references.rs,
`gltf_room` as a bare file and `gltf_room_toml` through tests/scenes/gltf_room.toml).

Everything is procedural and deterministic (numpy, struct, json, and the PNG writer of
gen_test_textures.py); rerunning rewrites identical files. The file exercises, on purpose,
much of what a glTF reader must get right:

  * node tree, 3 levels: `room` (rotation + translation) > `shell` (uniform scale) > the
    walls (each a column-major `matrix`), `room` > `furniture` (translation) > the boxes,
    the mirror, the glass block (TRS with non-uniform scale; one box under a mirroring
    scale, whose winding must be swapped) and `lamp` (a mirroring scale: the quad emits
    downwards only if the corners are swapped), `room` > `rig` > `camera`;
  * meshes reused by several nodes (`quad_white`: floor and ceiling; `box_tex`: two boxes)
    and accessors shared between meshes;
  * primitive modes: a triangle strip without indices (floor/ceiling), a fan with unsigned
    byte indices (left wall), lists with unsigned short and unsigned int indices;
  * accessors: an interleaved bufferView (POSITION and NORMAL, byteStride 24), normalized
    UNSIGNED_SHORT texture coordinates (the boxes), a sparse accessor over a bufferView (the
    mirror: two vertices moved) and a sparse accessor without a bufferView (the lamp: every
    vertex from the sparse values);
  * materials (meshtrace's pbr sub-cases with exact Mitsuba twins): KHR_materials_specular
    specularFactor 0 diffuse walls, a base-colour texture with KHR_texture_transform
    (scale on the back wall; offset, rotation and scale on the boxes), a perfect mirror
    (metallic 1, roughness 0), a glass block (KHR_materials_transmission 1 +
    KHR_materials_volume thickness + KHR_materials_ior 1.5; it floats 3 cm above the
    floor: a glass face coplanar with the floor is resolved differently by each renderer,
    which showed as a 10% difference seen through the glass), an emissive quad
    (emissiveFactor x emissiveTexture x KHR_materials_emissive_strength);
  * KHR_lights_punctual: a point light and a spot light (aimed by its node's rotation);
  * its own perspective camera.

Usage: python3 tools/gen_gltf_room.py [--out-dir tests/scenes/gltf_room]
"""
import argparse
import json
import math
import os

import numpy as np

from gen_test_textures import write_png


# ---------------------------------------------------------------- textures

def checker():
    """24x24: a 6x6 checker, warm/cool with a gradient, and a green top-left square and
    a dark-red top-right one (orientation markers)."""
    n, sq = 24, 4
    y, x = np.mgrid[0:n, 0:n]
    light = ((x // sq) + (y // sq)) % 2 == 0
    img = np.empty((n, n, 3))
    img[..., 0] = 0.85 - 0.3 * (y / n)
    img[..., 1] = 0.7
    img[..., 2] = 0.45 + 0.4 * (x / n)
    img[~light] = [0.15, 0.12, 0.1]
    img[:sq, :sq] = [0.15, 0.7, 0.2]
    img[:sq, n - sq:] = [0.5, 0.05, 0.05]
    return np.round(img * 255).astype(np.uint8)


def wall():
    """16x16: three horizontal bands with a dark diagonal from the top-left corner."""
    n = 16
    y, x = np.mgrid[0:n, 0:n]
    band = np.minimum(y * 3 // n, 2)
    colours = np.array([[0.8, 0.72, 0.55], [0.45, 0.55, 0.7], [0.6, 0.62, 0.5]])
    img = colours[band] * (0.75 + 0.25 * (x / n))[..., None]
    img[np.abs(x - y) <= 0] = [0.1, 0.1, 0.12]
    return np.round(img * 255).astype(np.uint8)


def lamp():
    """8x4: warm left, cooler right, a white centre stripe."""
    img = np.empty((4, 8, 3))
    img[:, :4] = [1.0, 0.8, 0.55]
    img[:, 4:] = [0.75, 0.85, 1.0]
    img[:, 3:5] = [1.0, 1.0, 1.0]
    return np.round(img * 255).astype(np.uint8)


# ---------------------------------------------------------------- buffer building

class Builder:
    def __init__(self):
        self.bin = bytearray()
        self.views, self.accessors = [], []

    def view(self, data, stride=None, target=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride:
            v["byteStride"] = stride
        if target:
            v["target"] = target
        self.bin += data
        self.views.append(v)
        return len(self.views) - 1

    def accessor(self, **kw):
        self.accessors.append(kw)
        return len(self.accessors) - 1


def f32(a):
    return np.asarray(a, dtype="<f4").tobytes()


def minmax(a):
    a = np.asarray(a, dtype=np.float32)
    return {"min": a.min(axis=0).tolist(), "max": a.max(axis=0).tolist()}


def quat_axis(axis, deg):
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    h = math.radians(deg) / 2
    return [float(x) for x in np.append(a * math.sin(h), math.cos(h))]


def quat_look(direction):
    """Unit quaternion turning -Z onto `direction` (about the axis orthogonal to both)."""
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    z = np.array([0.0, 0.0, -1.0])
    axis = np.cross(z, d)
    ang = math.degrees(math.acos(np.clip(np.dot(z, d), -1, 1)))
    return quat_axis(axis, ang)


def col_major(M):
    return [float(x) for x in np.asarray(M).T.reshape(-1)]


def rot(axis, deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = np.eye(4)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def trs(t=(0, 0, 0), r=np.eye(4), s=(1, 1, 1)):
    T = np.eye(4)
    T[:3, 3] = t
    return T @ r @ np.diag(list(s) + [1.0])


def build():
    b = Builder()
    ARRAY, ELEMENT = 34962, 34963

    # --- the unit quad in the XZ plane, facing +Y; uv = (x + 0.5, z + 0.5)
    qp = np.array([[-0.5, 0, 0.5], [0.5, 0, 0.5], [-0.5, 0, -0.5], [0.5, 0, -0.5]])
    qn = np.tile([0.0, 1.0, 0.0], (4, 1))
    quv = qp[:, [0, 2]] + 0.5
    a_qp = b.accessor(bufferView=b.view(f32(qp), target=ARRAY), componentType=5126, count=4,
                      type="VEC3", **minmax(qp))
    a_qn = b.accessor(bufferView=b.view(f32(qn), target=ARRAY), componentType=5126, count=4,
                      type="VEC3")
    a_quv = b.accessor(bufferView=b.view(f32(quv), target=ARRAY), componentType=5126, count=4,
                       type="VEC2")
    # strip order 0 1 2 3 needs no indices; fan 0 1 3 2 (u8); lists (u16 and u32)
    a_fan = b.accessor(bufferView=b.view(bytes([0, 1, 3, 2]), target=ELEMENT),
                       componentType=5121, count=4, type="SCALAR")
    a_l16 = b.accessor(bufferView=b.view(np.array([0, 1, 2, 2, 1, 3], "<u2").tobytes(),
                                         target=ELEMENT), componentType=5123, count=6,
                       type="SCALAR")
    a_l32 = b.accessor(bufferView=b.view(np.array([0, 1, 2, 2, 1, 3], "<u4").tobytes(),
                                         target=ELEMENT), componentType=5125, count=6,
                       type="SCALAR")

    # --- the mirror: the quad with vertices 2 and 3 moved by a sparse accessor
    sp_idx = b.view(np.array([2, 3], "<u1").tobytes())
    sp_val = b.view(f32([[-0.5, 0, -1.0], [0.5, 0, -1.0]]))
    mp = qp.copy()
    mp[2:, 2] = -1.0
    a_mp = b.accessor(bufferView=b.accessors[a_qp]["bufferView"], componentType=5126,
                      count=4, type="VEC3", **minmax(mp),
                      sparse={"count": 2, "indices": {"bufferView": sp_idx, "componentType": 5121},
                              "values": {"bufferView": sp_val}})

    # --- the lamp: a quad facing -Y, every vertex from a sparse accessor without a view
    lp = np.array([[-0.5, 0, -0.5], [0.5, 0, -0.5], [-0.5, 0, 0.5], [0.5, 0, 0.5]])
    luv = np.array([[0, 0], [1, 0], [0, 1], [1, 1]], dtype=np.float64)
    lamp_idx = b.view(np.array([0, 1, 2, 3], "<u2").tobytes())
    lamp_val = b.view(f32(lp))
    a_lp = b.accessor(componentType=5126, count=4, type="VEC3", **minmax(lp),
                      sparse={"count": 4, "indices": {"bufferView": lamp_idx,
                                                      "componentType": 5123},
                              "values": {"bufferView": lamp_val}})
    a_ln = b.accessor(bufferView=b.view(f32(np.tile([0.0, -1.0, 0.0], (4, 1))), target=ARRAY),
                      componentType=5126, count=4, type="VEC3")
    a_luv = b.accessor(bufferView=b.view(f32(luv), target=ARRAY), componentType=5126, count=4,
                       type="VEC2")

    # --- the unit cube: 24 vertices, POSITION and NORMAL interleaved (stride 24), UVs as
    # normalized unsigned shorts, u16 indices
    faces = []   # (normal, u axis, v axis): u right, v down as seen from outside
    for axis in range(3):
        for sign in (1, -1):
            n = np.zeros(3)
            n[axis] = sign
            up = np.array([0.0, 1.0, 0.0]) if axis != 1 else np.array([0.0, 0.0, -sign])
            right = np.cross(up, n)
            faces.append((n, right, -up))
    pos, nrm, uv, idx = [], [], [], []
    for n, u, v in faces:
        k = len(pos)
        for cu, cv in ((0, 0), (1, 0), (0, 1), (1, 1)):
            pos.append(0.5 * n + (cu - 0.5) * u + (cv - 0.5) * v)
            nrm.append(n)
            uv.append((cu, cv))
        # (0,0) (1,0) (0,1): u x v = right x down = -(normal): wind the other way
        idx += [k, k + 2, k + 1, k + 1, k + 2, k + 3]
    pos, nrm = np.array(pos), np.array(nrm)
    inter = np.concatenate([pos, nrm], axis=1).astype("<f4").tobytes()
    v_inter = b.view(inter, stride=24, target=ARRAY)
    a_bp = b.accessor(bufferView=v_inter, byteOffset=0, componentType=5126, count=24,
                      type="VEC3", **minmax(pos))
    a_bn = b.accessor(bufferView=v_inter, byteOffset=12, componentType=5126, count=24,
                      type="VEC3")
    uv16 = np.round(np.array(uv) * 65535).astype("<u2")
    a_buv = b.accessor(bufferView=b.view(uv16.tobytes(), target=ARRAY), componentType=5123,
                       normalized=True, count=24, type="VEC2")
    a_bi = b.accessor(bufferView=b.view(np.array(idx, "<u2").tobytes(), target=ELEMENT),
                      componentType=5123, count=len(idx), type="SCALAR")

    # ---------------------------------------------------------------- materials
    def diffuse(name, colour, texture=None):
        pbr = {"baseColorFactor": list(colour) + [1.0], "metallicFactor": 0.0,
               "roughnessFactor": 0.8}
        if texture is not None:
            pbr["baseColorTexture"] = texture
        return {"name": name, "pbrMetallicRoughness": pbr,
                "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}}
    materials = [
        diffuse("white", [0.75, 0.74, 0.7]),
        diffuse("red", [0.7, 0.16, 0.1]),
        diffuse("green", [0.16, 0.55, 0.2]),
        diffuse("wall", [1.0, 1.0, 1.0],
                {"index": 1, "extensions": {"KHR_texture_transform": {"scale": [2.0, 1.0]}}}),
        diffuse("boxes", [0.95, 0.95, 0.95],
                {"index": 0, "extensions": {"KHR_texture_transform": {
                    "offset": [0.1, 0.25], "rotation": 0.5, "scale": [1.5, 1.25]}}}),
        {"name": "mirror", "pbrMetallicRoughness": {
            "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 1.0, "roughnessFactor": 0.0}},
        {"name": "glass", "pbrMetallicRoughness": {
            "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0.0, "roughnessFactor": 0.0},
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                        "KHR_materials_volume": {"thicknessFactor": 0.4},
                        "KHR_materials_ior": {"ior": 1.5}}},
        {"name": "lamp", "pbrMetallicRoughness": {
            "baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0},
         "emissiveFactor": [1.0, 0.92, 0.8], "emissiveTexture": {"index": 2},
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 20.0},
                        "KHR_materials_specular": {"specularFactor": 0.0}}},
    ]

    def prim(mode, p, n=None, t=None, ind=None, mat=None):
        pr = {"attributes": {"POSITION": p}, "material": mat}
        if n is not None:
            pr["attributes"]["NORMAL"] = n
        if t is not None:
            pr["attributes"]["TEXCOORD_0"] = t
        if ind is not None:
            pr["indices"] = ind
        if mode != 4:
            pr["mode"] = mode
        return pr
    meshes = [
        {"name": "quad_white", "primitives": [prim(5, a_qp, a_qn, a_quv, None, 0)]},
        {"name": "quad_red", "primitives": [prim(6, a_qp, a_qn, a_quv, a_fan, 1)]},
        {"name": "quad_green", "primitives": [prim(4, a_qp, a_qn, a_quv, a_l16, 2)]},
        {"name": "quad_wall", "primitives": [prim(4, a_qp, a_qn, a_quv, a_l32, 3)]},
        {"name": "box_tex", "primitives": [prim(4, a_bp, a_bn, a_buv, a_bi, 4)]},
        {"name": "mirror", "primitives": [prim(4, a_mp, a_qn, None, a_l16, 5)]},
        {"name": "glass_block", "primitives": [prim(4, a_bp, a_bn, None, a_bi, 6)]},
        {"name": "lamp", "primitives": [prim(4, a_lp, a_ln, a_luv, a_l16, 7)]},
    ]

    # ---------------------------------------------------------------- nodes
    # room space: x in [-1.5, 1.5], y in [0, 2], z in [-1, 1], open towards +z
    nodes = []

    def node(**kw):
        nodes.append(kw)
        return len(nodes) - 1
    shell_s = 1.0 / 0.8    # `shell` scales by 0.8: the wall matrices are drawn 1.25 x
    walls = [
        node(name="floor", mesh=0, matrix=col_major(np.diag([shell_s] * 3 + [1]) @ trs(
            (0, 0, 0), np.eye(4), (3, 1, 2)))),
        node(name="ceiling", mesh=0, matrix=col_major(np.diag([shell_s] * 3 + [1]) @ trs(
            (0, 2, 0), rot(0, 180), (3, 1, 2)))),
        node(name="back", mesh=3, matrix=col_major(np.diag([shell_s] * 3 + [1]) @ trs(
            (0, 1, -1), rot(0, 90), (3, 1, 2)))),
        node(name="left", mesh=1, matrix=col_major(np.diag([shell_s] * 3 + [1]) @ trs(
            (-1.5, 1, 0), rot(2, -90), (2, 1, 2)))),
        node(name="right", mesh=2, matrix=col_major(np.diag([shell_s] * 3 + [1]) @ trs(
            (1.5, 1, 0), rot(2, 90), (2, 1, 2)))),
    ]
    shell = node(name="shell", scale=[0.8, 0.8, 0.8], children=walls)
    tall = node(name="tall_box", mesh=4, translation=[-0.75, 0.6, -0.45],
                rotation=quat_axis([0, 1, 0], 20), scale=[0.5, 1.2, 0.5])
    short = node(name="short_box", mesh=4, translation=[0.55, 0.25, 0.3],
                 rotation=quat_axis([0, 1, 0], -25), scale=[0.5, 0.5, -0.5])
    mirror = node(name="mirror", mesh=5, matrix=col_major(trs(
        (1.0, 0.95, -0.55), rot(1, -35) @ rot(0, 90), (0.6, 1, 0.7))))
    glass = node(name="glass", mesh=6, matrix=col_major(trs(
        (-0.2, 0.33, 0.35), rot(1, 30), (0.45, 0.6, 0.35))))
    lamp_n = node(name="lamp", mesh=7, translation=[0.0, 1.98, -0.1], scale=[-0.7, 1.0, 0.45])
    point = node(name="point_light", translation=[0.9, 1.7, 0.5],
                 extensions={"KHR_lights_punctual": {"light": 0}})
    spot_pos = np.array([-1.2, 1.85, 0.85])
    spot = node(name="spot_light", translation=spot_pos.tolist(),
                rotation=quat_look(np.array([-0.75, 0.6, -0.45]) - spot_pos),
                extensions={"KHR_lights_punctual": {"light": 1}})
    furniture = node(name="furniture", translation=[0.0, 0.0, 0.0],
                     children=[tall, short, mirror, glass, lamp_n, point, spot])
    cam = node(name="camera", camera=0, rotation=quat_axis([1, 0, 0], -8))
    rig = node(name="rig", translation=[0.0, 1.35, 3.3], children=[cam])
    room = node(name="room", rotation=quat_axis([0, 1, 0], 12), translation=[0.4, -0.3, 0.2],
                children=[shell, furniture, rig])

    doc = {
        "asset": {"version": "2.0", "generator": "meshtrace tools/gen_gltf_room.py"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength",
                           "KHR_materials_ior", "KHR_materials_specular",
                           "KHR_materials_transmission", "KHR_materials_volume",
                           "KHR_texture_transform"],
        "scene": 0,
        "scenes": [{"name": "room", "nodes": [room]}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0},
                     {"source": 2}],
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497}],
        "images": [{"uri": "checker.png"}, {"uri": "wall.png"}, {"uri": "lamp.png"}],
        "cameras": [{"type": "perspective", "perspective": {
            "yfov": 0.75, "aspectRatio": 4 / 3, "znear": 0.05, "zfar": 100.0}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "point", "type": "point", "color": [1.0, 0.85, 0.7], "intensity": 1000.0},
            {"name": "spot", "type": "spot", "color": [0.7, 0.8, 1.0], "intensity": 3000.0,
             "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.4}},
        ]}},
        "buffers": [{"uri": "room.bin", "byteLength": len(b.bin)}],
        "bufferViews": b.views,
        "accessors": b.accessors,
    }
    return doc, bytes(b.bin)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--out-dir", default=os.path.join(here, "..", "tests", "scenes", "gltf_room"))
    args = ap.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)
    doc, data = build()
    files = []
    for name, img in (("checker.png", checker()), ("wall.png", wall()), ("lamp.png", lamp())):
        write_png(os.path.join(args.out_dir, name), img)
        files.append(name)
    with open(os.path.join(args.out_dir, "room.bin"), "wb") as fh:
        fh.write(data)
    with open(os.path.join(args.out_dir, "room.gltf"), "w") as fh:
        json.dump(doc, fh, indent=1)
        fh.write("\n")
    for name in files + ["room.bin", "room.gltf"]:
        path = os.path.join(args.out_dir, name)
        print("wrote %s (%d bytes)" % (os.path.relpath(path), os.path.getsize(path)))


if __name__ == "__main__":
    main()
