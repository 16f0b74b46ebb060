"""Renders a folder of meshes into a dataset through meshtrace's Python API.

Per mesh, a folder named after it with, per view, an RGBA PNG (`000.png`) and its depth,
normal and alpha in `000.aovs.exr`, and one `transforms.json` (NeRF's layout: OpenGL
camera-to-world matrices and the intrinsics). Cameras go round the mesh (`--views`,
`--elevation`), or are a dataset preset's (`--preset zero123`, with its size and samples
unless given). The meshes are lit by the studio's environment map, without its ground. A mesh that cannot be loaded or rendered is reported and skipped.

    python examples/dataset.py meshes/ out/ --views 12 --spp 64 --size 256
    python examples/dataset.py meshes/ out/ --preset zero123
"""

import argparse
import json
import sys
import time
from pathlib import Path

import meshtrace as mt

MESHES = (".obj", ".glb", ".gltf")


def frame(camera, size, file_path):
    k = camera.intrinsics(size, size)
    return {
        "file_path": file_path,
        "transform_matrix": camera.matrix("opengl").tolist(),
        "fl_x": k[0, 0],
        "fl_y": k[1, 1],
        "cx": k[0, 2],
        "cy": k[1, 2],
        "w": size,
        "h": size,
    }


# The studio's light without its ground: the masks hold the object alone.
STUDIO = Path(__file__).resolve().parents[1] / "assets" / "env" / "studio.hdr"


def render_mesh(renderer, mesh, out_dir, args):
    scene = mt.load(mesh, studio=False, environment=STUDIO)
    if args.preset:
        cameras = mt.cameras.preset(scene, args.preset, views=args.views)
        settings = mt.cameras.preset_settings(args.preset)
    else:
        cameras = mt.cameras.orbit(scene, views=args.views or 12, elevation=args.elevation)
        settings = {"width": 256, "height": 256, "spp": 64}
    if args.size:
        settings.update(width=args.size, height=args.size)
    if args.spp:
        settings["spp"] = args.spp
    size = settings["width"]
    out_dir.mkdir(parents=True, exist_ok=True)
    frames = []
    for view, camera in enumerate(cameras):
        out = renderer.render(
            scene, camera=camera, transparent=True, aovs=["depth", "normal", "alpha"], **settings
        )
        out.save(out_dir / f"{view:03}.png")
        frames.append(frame(camera, size, f"{view:03}.png"))
    (out_dir / "transforms.json").write_text(json.dumps({"frames": frames}, indent=2))
    return len(frames)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("meshes", type=Path, help="a folder of .obj, .glb and .gltf files")
    parser.add_argument("out", type=Path, help="the dataset's folder")
    parser.add_argument("--preset", choices=mt.PRESETS, help="a dataset script's cameras and settings")
    parser.add_argument("--views", type=int, help="views per mesh (12, or the preset's)")
    parser.add_argument("--elevation", type=float, default=30.0, help="an orbit's elevation in degrees")
    parser.add_argument("--size", type=int, help="image side in pixels (256, or the preset's)")
    parser.add_argument("--spp", type=int, help="samples per pixel (64, or the preset's)")
    parser.add_argument("--device", default="auto", choices=["auto", "cpu", "gpu"])
    args = parser.parse_args()

    meshes = sorted(p for p in args.meshes.iterdir() if p.suffix.lower() in MESHES)
    if not meshes:
        sys.exit(f"{args.meshes}: no .obj, .glb or .gltf files")
    renderer = mt.Renderer(device=args.device)
    began, images, failed = time.perf_counter(), 0, 0
    for mesh in meshes:
        try:
            images += render_mesh(renderer, mesh, args.out / mesh.name.split(".")[0], args)
        except mt.MeshtraceError as e:
            failed += 1
            print(f"skipped: {e}", file=sys.stderr)
    took = time.perf_counter() - began
    print(
        f"{len(meshes) - failed} of {len(meshes)} meshes, {images} images on {renderer.name} "
        f"in {took:.1f} s -> {args.out}"
    )
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
