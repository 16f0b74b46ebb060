#!/usr/bin/env python3
"""Generate assets/cornell/ (OBJ files + cornell.toml) from Mitsuba 3's cornell_box().

The numbers below are copied from `mitsuba.cornell_box()` (mitsuba/python/util.py,
Mitsuba 3, BSD-3-Clause, Wenzel Jakob et al.).  Every Mitsuba shape becomes one OBJ,
already transformed into world space (computed in double precision with exact
trigonometry for multiples of 90 degrees), so the TOML needs no transforms.

Mitsuba `rectangle` = the square [-1,1]^2 in z=0 with normal +Z; `cube` = [-1,1]^3.
Triangles are written counter-clockwise seen from the side the Mitsuba normal points
to: the light emits downwards, the walls face into the room, the boxes face outwards.

With --check (needs mitsuba) the vertices are compared with Mitsuba's own transforms.

Usage: python3 tools/gen_cornell.py [--out assets/cornell] [--check]
"""
import argparse
import math
import os

HEADER = """\
# Cornell box, built in to meshtrace.
#
# Geometry, camera, materials and light are those of Mitsuba 3's `mitsuba.cornell_box()`
# (Mitsuba 3, Copyright (c) Wenzel Jakob et al., BSD-3-Clause licence), converted by
# tools/gen_cornell.py: each Mitsuba shape is one OBJ here, already in world space.
# Mitsuba's film uses a gaussian pixel filter; meshtrace uses a box filter, and so do
# the references rendered with tools/mitsuba_render.py (tests/references/).
"""

WHITE = [0.885809, 0.698859, 0.666422]
GREEN = [0.105421, 0.37798, 0.076425]
RED = [0.570068, 0.0430135, 0.0443706]
LIGHT_RADIANCE = [18.387, 13.9873, 6.75357]

# name: (mitsuba type, translate, (axis, degrees) or None, scale, material)
SHAPES = {
    "light": ("rectangle", [0.0, 0.99, 0.01], ([1, 0, 0], 90), [0.23, 0.19, 0.19], "light"),
    "floor": ("rectangle", [0.0, -1.0, 0.0], ([1, 0, 0], -90), [1, 1, 1], "white"),
    "ceiling": ("rectangle", [0.0, 1.0, 0.0], ([1, 0, 0], 90), [1, 1, 1], "white"),
    "back": ("rectangle", [0.0, 0.0, -1.0], None, [1, 1, 1], "white"),
    "green_wall": ("rectangle", [1.0, 0.0, 0.0], ([0, 1, 0], -90), [1, 1, 1], "green"),
    "red_wall": ("rectangle", [-1.0, 0.0, 0.0], ([0, 1, 0], 90), [1, 1, 1], "red"),
    "small_box": ("cube", [0.335, -0.7, 0.38], ([0, 1, 0], -17), [0.3, 0.3, 0.3], "white"),
    "large_box": ("cube", [-0.33, -0.4, -0.28], ([0, 1, 0], 18.25), [0.3, 0.61, 0.3], "white"),
}
MITSUBA_NAME = {"green_wall": "green-wall", "red_wall": "red-wall",
                "small_box": "small-box", "large_box": "large-box"}


def cos_sin(deg):
    if deg % 90 == 0:
        k = int(deg // 90) % 4
        return [(1, 0), (0, 1), (-1, 0), (0, -1)][k]
    r = math.radians(deg)
    return math.cos(r), math.sin(r)


def rot(axis, deg):
    c, s = cos_sin(deg)
    if axis == [1, 0, 0]:
        return [[1, 0, 0], [0, c, -s], [0, s, c]]
    if axis == [0, 1, 0]:
        return [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    raise ValueError(axis)


def transform(p, t, r, s):
    q = [p[i] * s[i] for i in range(3)]
    if r is not None:
        m = rot(*r)
        q = [sum(m[i][j] * q[j] for j in range(3)) for i in range(3)]
    return [q[i] + t[i] for i in range(3)]


def local_mesh(kind):
    """Vertices and CCW triangles of Mitsuba's rectangle / cube in local space."""
    if kind == "rectangle":
        v = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]
        f = [[0, 1, 2], [0, 2, 3]]
        return v, f
    v = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    idx = {tuple(p): i for i, p in enumerate(v)}
    f = []
    for axis in range(3):
        for sign in (-1, 1):
            # quad on face axis=sign, CCW seen from outside
            a, b = (axis + 1) % 3, (axis + 2) % 3
            corners = []
            for ua, ub in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0, 0, 0]
                p[axis], p[a], p[b] = sign, ua, ub
                corners.append(idx[tuple(p)])
            if sign < 0:
                corners.reverse()
            f.append([corners[0], corners[1], corners[2]])
            f.append([corners[0], corners[2], corners[3]])
    return v, f


def fmt(x):
    s = "%.9f" % x
    s = s.rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def world_mesh(name):
    kind, t, r, s, _ = SHAPES[name]
    v, f = local_mesh(kind)
    return [transform(p, t, r, s) for p in v], f


def check_against_mitsuba(meshes):
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    d = mi.cornell_box()
    worst = 0.0
    for name, (v, f) in meshes.items():
        m = d[MITSUBA_NAME.get(name, name)]["to_world"]
        kind = SHAPES[name][0]
        lv, _ = local_mesh(kind)
        for p, q in zip(lv, v):
            mp = m @ mi.ScalarPoint3f(p)
            worst = max(worst, max(abs(mp[i] - q[i]) for i in range(3)))
        # orientation: our winding normal vs Mitsuba's transformed +Z / outward normal
        a, b, c = (v[i] for i in f[0])
        n = [(b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]),
             (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]),
             (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])]
        if kind == "rectangle":
            mn = m @ mi.ScalarNormal3f(0, 0, 1)
            assert sum(n[i] * mn[i] for i in range(3)) > 0, name
        else:  # cube: every triangle faces away from the box centre
            ctr = [sum(p[i] for p in v) / len(v) for i in range(3)]
            for tri in f:
                a, b, c = (v[i] for i in tri)
                e1 = [b[i] - a[i] for i in range(3)]
                e2 = [c[i] - a[i] for i in range(3)]
                nn = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                      e1[0] * e2[1] - e1[1] * e2[0]]
                assert sum(nn[i] * (a[i] - ctr[i]) for i in range(3)) > 0, name
    print("max |vertex - mitsuba| = %.3g" % worst)
    assert worst < 1e-5
    cam = d["sensor"]
    print("sensor fov", cam["fov"], "fov_axis", cam["fov_axis"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "assets", "cornell"))
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    meshes = {name: world_mesh(name) for name in SHAPES}
    for name, (v, f) in meshes.items():
        kind = SHAPES[name][0]
        with open(os.path.join(args.out, name + ".obj"), "w") as fh:
            fh.write("# Mitsuba 3 cornell_box() shape '%s' (%s), world space, generated by "
                     "tools/gen_cornell.py\n" % (MITSUBA_NAME.get(name, name), kind))
            for p in v:
                fh.write("v %s %s %s\n" % tuple(fmt(x) for x in p))
            for tri in f:
                fh.write("f %d %d %d\n" % tuple(i + 1 for i in tri))

    def vec(a):
        return "[" + ", ".join(repr(float(x)) for x in a) + "]"

    toml = [HEADER]
    toml.append("[camera]\nposition = [0.0, 0.0, 3.9]\nlook_at = [0.0, 0.0, 0.0]\n"
                "up = [0.0, 1.0, 0.0]\n"
                "vfov = 39.3077   # Mitsuba: fov 39.3077, fov_axis 'smaller' (square image)\n")
    toml.append("[render]\nwidth = 256\nheight = 256\nspp = 64\nmax_depth = 8\n")
    toml.append("[materials.white]\ntype = \"diffuse\"\nalbedo = %s\n" % vec(WHITE))
    toml.append("[materials.red]\ntype = \"diffuse\"\nalbedo = %s\n" % vec(RED))
    toml.append("[materials.green]\ntype = \"diffuse\"\nalbedo = %s\n" % vec(GREEN))
    toml.append("# Mitsuba: the light rectangle has the white BSDF and an area emitter; it emits\n"
                "# downwards (front face, counter-clockwise winding seen from below).\n"
                "[materials.light]\ntype = \"diffuse\"\nalbedo = %s\nemission = %s\n"
                % (vec(WHITE), vec(LIGHT_RADIANCE)))
    for name in SHAPES:
        toml.append("[[objects]]   # Mitsuba '%s'\nmesh = \"%s.obj\"\nmaterial = \"%s\"\n"
                    % (MITSUBA_NAME.get(name, name), name, SHAPES[name][4]))
    with open(os.path.join(args.out, "cornell.toml"), "w") as fh:
        fh.write("\n".join(toml))
    if args.check:
        check_against_mitsuba(meshes)


if __name__ == "__main__":
    main()
