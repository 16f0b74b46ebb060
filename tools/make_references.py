#!/usr/bin/env python3
"""Render a Mitsuba reference for one of our scenes and Mitsuba's own noise level.

Writes tests/references/<name>_ref.exr (the reference, --ref-spp samples per pixel) and
tests/references/<name>.json with Mitsuba's relMSE against that reference at each of
--spp: "mitsuba_relmse": {"64": mean over seeds 0..seeds-1, ...} and
"mitsuba_relmse_per_seed": {"64": [...], ...}; the reference passes use seeds far from
those, see mitsuba_render.pass_seed).

Usage:
  python3 tools/make_references.py assets/cornell/cornell.toml --name cornell \\
      --ref-spp 16384 --spp 16 64 --seeds 4 [--width 256 --height 256] \\
      [--spheres analytic|mesh]
  python3 tools/make_references.py --materials [NAME ...]

--materials regenerates the references of the material scenes in tests/scenes/ (all of
MATERIAL_SCENES below, or the ones named), each with the settings listed there; they are
checked by tests/mitsuba_references.rs. A scene may be a bare glTF file, which has no
[render] table: its entry gives the image size (meshtrace's bare-glTF defaults are used
for the rest: max_depth 8).
"""
import argparse
import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_render as mr  # noqa: E402
from compare import relmse  # noqa: E402

REF_SEED = 1_000_000_007 % (1 << 32)

# The material scenes: name -> (scene file, reference spp[, (width, height)]). Sizes,
# max_depth and the rest come from the scene files (a bare glTF file: the size given here); each reference is budgeted at about 6 minutes of
# Mitsuba (llvm_ad_rgb) on 2 cores. Spheres are Mitsuba's analytic spheres: rendering
# meshtrace's own icospheres instead (--spheres mesh) changed the images by a relMSE of
# 2e-5 to 4e-5 at 512 spp with the same seed, below 1% of Mitsuba's relMSE at 64 spp.
MATERIAL_SCENES = {
    "sky_gradient": ("tests/scenes/sky_gradient.toml", 16384),
    "glass_dof": ("tests/scenes/glass_dof.toml", 16384),
    "box_area": ("tests/scenes/box_area.toml", 8192),
    # image textures; cheap per sample (no spheres or glass), hence the higher count
    "textured": ("tests/scenes/textured.toml", 32768),
    # the pbr material's sub-cases that have exact Mitsuba twins
    "pbr_subcases": ("tests/scenes/pbr_subcases.toml", 8192),
    # point, spot and directional lights beside an area light
    "lights": ("tests/scenes/lights.toml", 16384),
    # glTF: the room of tests/scenes/gltf_room/ (tools/gen_gltf_room.py) as a bare file,
    # seen through its own camera, and placed by gltf_room.toml as an object
    "gltf_room_bare": ("tests/scenes/gltf_room/room.gltf", 32768, (96, 72)),
    "gltf_room": ("tests/scenes/gltf_room.toml", 32768),
    # lit only by an environment map with a real sun (assets/env/rooitou_park_256x128.hdr,
    # rotate 35, strength 0.8); cheap per sample (~1.3 ms per spp), hence the high count
    "env_sun": ("tests/scenes/env_sun.toml", 65536),
}


def make_reference(mi, scene_path, name, ref_spp, spps, seeds, out_dir, lanes,
                   width=None, height=None, max_depth=None, spheres="analytic"):
    class A:  # overrides for build_scene_dict
        pass
    A.width, A.height, A.max_depth = width, height, max_depth
    A.spp, A.seed, A.spheres = None, None, spheres

    with tempfile.TemporaryDirectory(prefix="mitsuba_ref_") as tmp:
        d, o = mr.build_scene_dict(mi, scene_path, A, tmp)
        scene = mi.load_dict(d)
    w, h = o["width"], o["height"]
    print("%s: variant %s, %dx%d, max_depth %d" % (name, mi.variant(), w, h, o["max_depth"]))

    ref, t_ref = mr.render(mi, scene, w, h, ref_spp, REF_SEED, lanes)
    print("%s: reference %d spp: %.1f s" % (name, ref_spp, t_ref))
    os.makedirs(out_dir, exist_ok=True)
    ref_path = os.path.join(out_dir, "%s_ref.exr" % name)
    mr.write_exr(mi, ref, ref_path)
    ref = ref.astype("float64")

    result = {
        "scene": os.path.relpath(os.path.abspath(scene_path)),
        "reference": os.path.relpath(os.path.abspath(ref_path)),
        "width": w, "height": h,
        "reference_spp": ref_spp,
        "spp": o["spp"],
        "max_depth": o["max_depth"],
        "renderer": "Mitsuba %s (%s), path integrator rr_depth 5, box filter, "
                    "tools/mitsuba_render.py" % (mi.__version__, mi.variant()),
        "spheres": spheres,
        "metric": "mean((x-ref)^2/(ref^2+1e-2))",
        "mitsuba_relmse": {},
        "mitsuba_relmse_per_seed": {},
        "seeds": list(range(seeds)),
        "timings_s": {"reference": round(t_ref, 1)},
    }
    for spp in spps:
        per, ts = [], []
        for s in range(seeds):
            img, t = mr.render(mi, scene, w, h, spp, s, lanes, verbose=False)
            per.append(relmse(img.astype("float64"), ref))
            ts.append(t)
        mean = sum(per) / len(per)
        result["mitsuba_relmse"][str(spp)] = mean
        result["mitsuba_relmse_per_seed"][str(spp)] = per
        result["timings_s"]["%d_spp" % spp] = round(sum(ts) / len(ts), 2)
        print("%s: %d spp: relMSE mean %.6g per seed %s (%.2f s each)"
              % (name, spp, mean, ["%.6g" % p for p in per], sum(ts) / len(ts)))
    json_path = os.path.join(out_dir, "%s.json" % name)
    with open(json_path, "w") as fh:
        json.dump(result, fh, indent=2)
        fh.write("\n")
    print("wrote", ref_path, json_path)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene", nargs="*",
                    help="a scene file (with --name), or with --materials the names to redo")
    ap.add_argument("--name")
    ap.add_argument("--materials", action="store_true",
                    help="the material scenes of MATERIAL_SCENES (tests/scenes/)")
    ap.add_argument("--out-dir", default="tests/references")
    ap.add_argument("--ref-spp", type=int,
                    help="default 16384, or with --materials each scene's own")
    ap.add_argument("--spp", type=int, nargs="+", default=[16, 64])
    ap.add_argument("--seeds", type=int, help="default 4, or 8 with --materials")
    ap.add_argument("--width", type=int)
    ap.add_argument("--height", type=int)
    ap.add_argument("--max-depth", type=int)
    ap.add_argument("--variant")
    ap.add_argument("--lanes", type=int, default=1 << 23)
    ap.add_argument("--spheres", choices=("analytic", "mesh"), default="analytic",
                    help="`sphere` objects as Mitsuba spheres (default) or as meshtrace's "
                         "icospheres with smooth normals")
    args = ap.parse_args()

    if args.materials:
        names = args.scene or list(MATERIAL_SCENES)
        for n in names:
            if n not in MATERIAL_SCENES:
                ap.error("unknown material scene %r (known: %s)"
                         % (n, ", ".join(MATERIAL_SCENES)))
        mi = mr.setup_mitsuba(args.variant)
        for n in names:
            path, ref_spp, *size = MATERIAL_SCENES[n]
            width, height = size[0] if size else (args.width, args.height)
            make_reference(mi, path, n, args.ref_spp or ref_spp, args.spp, args.seeds or 8,
                           args.out_dir, args.lanes, args.width or width,
                           args.height or height, args.max_depth, args.spheres)
        return
    if len(args.scene) != 1 or not args.name:
        ap.error("give one scene file and --name (or --materials)")
    mi = mr.setup_mitsuba(args.variant)
    make_reference(mi, args.scene[0], args.name, args.ref_spp or 16384, args.spp,
                   args.seeds or 4, args.out_dir, args.lanes, args.width, args.height,
                   args.max_depth, args.spheres)


if __name__ == "__main__":
    main()
