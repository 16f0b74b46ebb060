#!/usr/bin/env python3
"""Check the `[sky] environment` translation (tools/mitsuba_render.py) against the scene
format's rule, on Mitsuba's side alone.

The rule (shared/specs/scene-format.md, [sky]): a direction d leaving the scene is turned
by d' = R_y(-rotate) d, R_y(t) = [[cos t, 0, sin t], [0, 1, 0], [-sin t, 0, cos t]]; the
map is read at u = atan2(d'.x, -d'.z) / 2 pi (wrapped to [0, 1)), v = acos(d'.y) / pi
(u = 0 the left edge, v = 0 the top row), bilinearly, times `strength`.

What "bilinearly" means on Mitsuba's side (Mitsuba 3.9.1 `envmap`), measured here:
  * along u at texel centres, with wrap-around: column j sits at u = (j + 0.5) / W
    (x = u W - 0.5; between the last column and the first the lookup wraps);
  * along v with the rows at v = i / (H - 1): row 0 exactly at the top (v = 0), row H - 1
    exactly at the bottom (v = 1), y = v (H - 1); *not* at texel centres
    ((i + 0.5) / H), as for u and as for the material textures.
The check evaluates Mitsuba's emitter (emitter.eval(si) with si.wi = -d) along random
directions, for several maps, rotations and strengths, through the script's own
environment_envmap(), and compares with a numpy evaluation of the rule with that lookup;
it also prints how far off the texel-centre reading of v would be, and checks the cases
measured by hand (a 4x3 map: u = 0.125 gives column 0 exactly, v = 0.25 the halfway point
between rows 0 and 1), that Mitsuba decodes the shipped .hdr maps exactly as rgbe.py does
(and test_16x8.exr to the same values as test_16x8.hdr), the rotation's direction (rotate = 90 puts the image centre at
+X), that invalid [sky] tables are refused with an error naming the field, and, end to
end, that the pixels of tests/references/env_sun_ref.exr which see the sky directly equal
the rule's lookup averaged over each pixel (8x8 rays through the scene's camera), which
a negated rotation fails by far.

Usage: python3 tools/check_envmap.py   (scalar_rgb; about 10 s; exit status 1 on failure)
"""
import math
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_render as mr  # noqa: E402
import rgbe  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def ry(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def spec_uv(d, rotate):
    dp = d @ ry(math.radians(-rotate)).T
    u = np.arctan2(dp[:, 0], -dp[:, 2]) / (2 * math.pi)
    u = u - np.floor(u)
    v = np.arccos(np.clip(dp[:, 1], -1, 1)) / math.pi
    return u, v


def spec_eval(img, d, rotate, strength, v_centres=False):
    """The rule, bilinear: u at texel centres with wrap; v with rows at i / (H - 1)
    (Mitsuba), or with v_centres at (i + 0.5) / H, clamped."""
    h, w, _ = img.shape
    u, v = spec_uv(d, rotate)
    x = u * w - 0.5
    j0 = np.floor(x).astype(int)
    fx = x - j0
    j1 = (j0 + 1) % w
    j0 = j0 % w
    y = v * h - 0.5 if v_centres else v * (h - 1)
    y = np.clip(y, 0, h - 1)
    i0 = np.minimum(np.floor(y).astype(int), h - 2)
    fy = y - i0
    i1 = i0 + 1
    fx, fy = fx[:, None], fy[:, None]
    top = img[i0, j0] * (1 - fx) + img[i0, j1] * fx
    bot = img[i1, j0] * (1 - fx) + img[i1, j1] * fx
    return strength * (top * (1 - fy) + bot * fy)


def mitsuba_eval(mi, emitter, d):
    out = np.zeros((len(d), 3))
    for k, dk in enumerate(d):
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*(-dk))
        out[k] = np.array(emitter.eval(si))[:3]
    return out


def envmap_of(mi, tmp, img, rotate, strength, fmt=".hdr"):
    """The script's own translation of [sky] environment = <img written as fmt>."""
    path = os.path.join(tmp, "map" + fmt)
    if fmt == ".hdr":
        img = rgbe.write_hdr(path, img)      # the values as RGBE stores them
    else:
        mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32),
                  mi.Bitmap.PixelFormat.RGB).write(path)
        img = img.astype(np.float32).astype(np.float64)
    mr._images.clear()
    mr._raw_images.clear()
    d = mr.environment_envmap(mi, {"environment": os.path.basename(path), "rotate": rotate,
                                   "strength": strength}, tmp)
    return mi.load_dict(d), img


def random_dirs(rng, n):
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return d[np.abs(d[:, 1]) < 0.995]        # away from the poles (u undefined there)


def check_reference_sky(mi, scene="tests/scenes/env_sun.toml",
                        ref="tests/references/env_sun_ref.exr", n=8):
    import tomllib
    scene, ref = os.path.join(ROOT, scene), os.path.join(ROOT, ref)
    if not os.path.exists(ref):
        print("(no %s: end-to-end check skipped)" % ref)
        return True
    with open(scene, "rb") as fh:
        doc = tomllib.load(fh)
    cam, sky, r = doc["camera"], doc["sky"], doc["render"]
    w, h = r["width"], r["height"]
    img = load_map(mi, os.path.join(os.path.dirname(scene), sky["environment"]))
    pos, at = np.array(cam["position"], float), np.array(cam["look_at"], float)
    f = (at - pos) / np.linalg.norm(at - pos)
    right = np.cross(f, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    t = math.tan(math.radians(cam.get("vfov", 40.0)) / 2)
    s = (np.arange(n) + 0.5) / n
    sx, sy = np.meshgrid(s, s)
    refimg = np.array(mi.Bitmap(ref), dtype=np.float64)[:, :, :3]
    rows = []
    for i in range(h):
        for j in range(w):
            x = ((j + sx.ravel()) / w * 2 - 1) * t * w / h
            y = (1 - (i + sy.ravel()) / h * 2) * t
            d = f[None, :] + x[:, None] * right[None, :] + y[:, None] * up[None, :]
            d /= np.linalg.norm(d, axis=1)[:, None]
            if d[:, 1].min() > 0.0 and pos[1] > 1.0:      # above every object, going up
                rows.append((i, j, d))
    if not rows:
        print("end to end: no sky pixels in %s" % ref)
        return False
    strength, rot = sky.get("strength", 1.0), sky.get("rotate", 0.0)
    errs = {}
    for name, kw in (("rule", dict(rotate=rot)), ("v at texel centres", dict(rotate=rot, v_centres=True)),
                     ("rotate negated", dict(rotate=-rot))):
        e = []
        for i, j, d in rows:
            want = spec_eval(img, d, kw["rotate"], strength, kw.get("v_centres", False)).mean(axis=0)
            e.append(np.abs(refimg[i, j] - want) / want)
        errs[name] = (np.mean(e), np.max(e))
    good = errs["rule"][1] < 0.01 and errs["rotate negated"][1] > 0.05
    print("%-58s %s" % ("env_sun reference, %d sky pixels vs the rule:" % len(rows),
                        "ok" if good else "FAIL"))
    for name, (mean, mx) in errs.items():
        print("    %-20s mean rel. error %.2e, max %.2e" % (name, mean, mx))
    return good


def load_map(mi, path):
    mr._images.clear()
    return mr.load_texture(mi, path, "map")


def main():
    mi = mr.setup_mitsuba("scalar_rgb")
    rng = np.random.default_rng(7)
    ok = True

    def report(name, err, tol, extra=""):
        nonlocal ok
        good = err <= tol
        ok &= good
        print("%-58s max rel. error %.2e %s%s" % (name, err, "ok" if good else "FAIL", extra))

    with tempfile.TemporaryDirectory(prefix="check_envmap_") as tmp:
        # 1. the hand measurements on a 4x3 map
        img = np.zeros((3, 4, 3))
        img[:, :, 0] = np.arange(1, 5)[None, :]
        img[:, :, 1] = 10 * np.arange(1, 4)[:, None]
        img[:, :, 2] = 0.5
        em, img = envmap_of(mi, tmp, img, 0.0, 1.0, ".exr")

        def dir_uv(u, v):
            p, t = 2 * math.pi * u, math.pi * v
            return np.array([[math.sin(t) * math.sin(p), math.cos(t), -math.sin(t) * math.cos(p)]])
        cases = [((0.125, 0.5), (1.0, 20.0)), ((0.25, 0.5), (1.5, 20.0)),
                 ((0.0, 0.5), (2.5, 20.0)), ((0.125, 0.25), (1.0, 15.0)),
                 ((0.125, 0.75), (1.0, 25.0)), ((0.125, 0.999), (1.0, 29.98))]
        worst = 0.0
        for (u, v), (r, g) in cases:
            m = mitsuba_eval(mi, em, dir_uv(u, v))[0]
            worst = max(worst, abs(m[0] - r) / r, abs(m[1] - g) / g)
        report("4x3 map: u = 0.125 -> column 0, v = 0.25 -> rows 0|1 half", worst, 2e-3)

        # 2. random maps and directions, several rotations and strengths, .hdr and .exr
        for (w, h, rot, strength, fmt) in [(16, 8, 0.0, 1.0, ".hdr"), (16, 8, 35.0, 0.8, ".hdr"),
                                           (7, 5, -90.0, 2.5, ".exr"), (32, 16, 123.4, 1.0, ".exr"),
                                           (256, 128, 35.0, 0.8, ".hdr")]:
            img = rng.uniform(0.05, 4.0, size=(h, w, 3))
            em, img = envmap_of(mi, tmp, img, rot, strength, fmt)
            d = random_dirs(rng, 400)
            m = mitsuba_eval(mi, em, d)
            want = spec_eval(img, d, rot, strength)
            alt = spec_eval(img, d, rot, strength, v_centres=True)
            err = np.max(np.abs(m - want) / want)
            err_alt = np.max(np.abs(m - alt) / alt)
            report("%dx%d%s rotate %g strength %g" % (w, h, fmt, rot, strength), err, 1e-4,
                   " (v at texel centres instead: %.2e)" % err_alt)

        # 3. the shipped test map, through its own file
        img = rgbe.read_hdr(os.path.join(ROOT, "assets/env/test_16x8.hdr"))
        d = random_dirs(rng, 400)
        mr._images.clear()
        em = mi.load_dict(mr.environment_envmap(
            mi, {"environment": "test_16x8.hdr", "rotate": 35.0, "strength": 0.8},
            os.path.join(ROOT, "assets/env")))
        m = mitsuba_eval(mi, em, d)
        want = spec_eval(img, d, 35.0, 0.8)
        report("assets/env/test_16x8.hdr rotate 35 strength 0.8", float(np.max(
            np.abs(m - want) / np.maximum(want, 1e-6))), 1e-4)

        # 3b. the shipped maps: Mitsuba's RGBE reading equals rgbe.py's, bit for bit
        for name in sorted(os.listdir(os.path.join(ROOT, "assets/env"))):
            if not name.endswith((".hdr", ".exr")):
                continue
            path = os.path.join(ROOT, "assets/env", name)
            m = np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]
            twin = path[:-4] + ".hdr"          # an .exr is compared with its .hdr twin
            if not os.path.exists(twin):
                continue
            ours = rgbe.read_hdr(twin)
            good = m.shape == ours.shape and np.array_equal(m, ours)
            ok &= good
            print("%-58s %s" % ("assets/env/%s: Mitsuba reads %s" % (
                name, "rgbe.py's values" if name.endswith(".hdr") else "the .hdr's values"),
                "ok" if good else "FAIL"))

        # 4. the rotation's direction: a map bright at its centre column only
        img = np.full((9, 16, 3), 0.01)
        img[:, 7:9] = 100.0
        em, img = envmap_of(mi, tmp, img, 90.0, 1.0, ".exr")
        px = mitsuba_eval(mi, em, np.array([[1.0, 0.0, 0.0]]))[0, 0]
        pz = mitsuba_eval(mi, em, np.array([[0.0, 0.0, 1.0]]))[0, 0]
        good = px > 50 and pz < 1
        ok &= good
        print("%-58s +X %.3g, +Z %.3g %s" % ("rotate = 90: the image centre lands at +X", px, pz,
                                             "ok" if good else "FAIL"))

        # 5. invalid [sky] tables are refused, naming the field
        rgbe.write_hdr(os.path.join(tmp, "sky.hdr"), np.ones((4, 8, 3)))
        open(os.path.join(tmp, "sky.png"), "wb").write(b"")
        bad = [
            ('environment = "sky.hdr"\ncolor = [1, 1, 1]', "color"),
            ('environment = "sky.hdr"\nzenith = [1, 1, 1]', "zenith"),
            ('color = [1, 1, 1]\nrotate = 10.0', "rotate"),
            ('zenith = [1, 1, 1]\nstrength = 2.0', "strength"),
            ('environment = "sky.hdr"\nstrength = -1.0', "strength"),
            ('environment = "sky.hdr"\nstrength = inf', "strength"),
            ('environment = "sky.hdr"\nrotate = nan', "rotate"),
            ('environment = "sky.hdr"\nrotate = "east"', "rotate"),
            ('environment = "missing.hdr"', "environment"),
            ('environment = "sky.png"', "environment"),
            ('environment = 3', "environment"),
            ('environment = "sky.hdr"\nbrightness = 2.0', "brightness"),
        ]
        for body, field in bad:
            scene = os.path.join(tmp, "s.toml")
            with open(scene, "w") as fh:
                fh.write("[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n[sky]\n%s\n" % body)

            class A:
                width = height = spp = seed = max_depth = None
                spheres = "analytic"
            try:
                mr.build_scene_dict(mi, scene, A, tmp)
                msg = None
            except mr.SceneError as e:
                msg = str(e)
            good = msg is not None and field in msg
            ok &= good
            print("%-58s %s %s" % ("refused: " + body.replace("\n", "; "), "ok" if good else "FAIL",
                                   repr(msg)))
        # and valid ones are accepted (strength 0: no emitter, a black sky)
        for body, has_sky in [('environment = "sky.hdr"', True),
                              ('environment = "sky.hdr"\nrotate = -720.5\nstrength = 0', False),
                              ('environment = "sky.hdr"\nrotate = 35\nstrength = 3', True)]:
            with open(scene, "w") as fh:
                fh.write("[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n[sky]\n%s\n" % body)
            d, _ = mr.build_scene_dict(mi, scene, A, tmp)
            good = ("sky" in d) == has_sky
            ok &= good
            print("%-58s %s" % ("accepted: " + body.replace("\n", "; "), "ok" if good else "FAIL"))
    # 6. end to end: the pixels of the committed env_sun reference that see the sky directly
    #    (every ray through them goes upwards from above the scene) against the rule,
    #    supersampled over each pixel (the film's box filter); a wrong rotation's sign shows
    ok &= check_reference_sky(mi)
    print("all ok" if ok else "FAILED")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
