#!/usr/bin/env python3
"""A contact sheet of meshes rendered bare (`meshtrace render MESH.obj`), for docs/.

Renders every .obj in a folder (default ../shared/meshes) with the given meshtrace binary,
as a user would run it (only size, spp and device set), and lays the images out in a grid
with each mesh's name under its image.

Usage:
  python3 tools/contact_sheet.py OUT.png [--meshes DIR] [--meshtrace target/release/meshtrace]
      [--width 320 --height 240 --spp 64 --device cpu] [--columns 3]

Needs Pillow (`pip install pillow`).
"""
import argparse
import glob
import os
import subprocess
import sys
import tempfile

from PIL import Image, ImageDraw


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--meshes", default=os.path.join(here, "..", "..", "shared", "meshes"))
    ap.add_argument("--meshtrace", default=os.path.join(here, "..", "target", "release",
                                                        "meshtrace"))
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--columns", type=int, default=3)
    ap.add_argument("--title", default="")
    args = ap.parse_args()

    meshes = sorted(glob.glob(os.path.join(args.meshes, "*.obj")))
    if not meshes:
        sys.exit("contact_sheet: no .obj files in %s" % args.meshes)
    label = 22
    cols = args.columns
    rows = (len(meshes) + cols - 1) // cols
    top = 30 if args.title else 0
    sheet = Image.new("RGB", (cols * args.width, top + rows * (args.height + label)), "white")
    draw = ImageDraw.Draw(sheet)
    if args.title:
        draw.text((8, 8), args.title, fill="black")
    env = dict(os.environ, NODEVICE_SELECT="1")
    with tempfile.TemporaryDirectory() as tmp:
        for k, mesh in enumerate(meshes):
            name = os.path.splitext(os.path.basename(mesh))[0]
            png = os.path.join(tmp, name + ".png")
            cmd = [args.meshtrace, "render", mesh, "-o", png, "--quiet",
                   "--width", str(args.width), "--height", str(args.height),
                   "--spp", str(args.spp), "--device", args.device]
            subprocess.run(cmd, check=True, env=env)
            x, y = (k % cols) * args.width, top + (k // cols) * (args.height + label)
            sheet.paste(Image.open(png).convert("RGB"), (x, y))
            draw.text((x + 6, y + args.height + 4), name, fill="black")
            print("rendered", name, file=sys.stderr)
    sheet.save(args.out)


if __name__ == "__main__":
    main()
