"""Runs TRELLIS's own Blender script with every optional pass on the corpus's
`materials_joined.glb`: the reference of the `trellis` preset's `save_depth`,
`save_albedo`, `save_mist` and `save_normal` files.

Run with Blender 4.5 as a Python module (`pip install bpy==4.5.15`, Python 3.11; in Blender 5
the script's compositor set-up raises AttributeError), given the script from
microsoft/TRELLIS (`dataset_toolkits/blender_script/render.py`):

    python tools/gltf_corpus/trellis_passes.py render.py tests/data/gltf/corpus

It writes `trellis-passes.blender45/`: views 0 and 1 of 2 on the Hammersley sphere with the
preset's offsets for the uid `spheres`, at 256², as the script writes them (`000.png`,
`000_depth.png`, `000_albedo.png`, `000_mist.png`, `000_normal.exr`, `transforms.json`).
The script runs unchanged but for two things outside it, both needed in Blender 4.5: the
first view layer is named `View Layer` (the script looks it up by that name; a factory scene
made by the module calls it `ViewLayer`), and the working directory is `/` (4.5's File
Output nodes take their paths relative to it, and the script gives absolute ones).
"""

import json
import math
import os
import runpy
import shutil
import sys
import tempfile
from pathlib import Path

import bpy

sys.path.insert(0, str(Path(__file__).resolve().parent))
from blender_corpus import trellis_angles  # noqa: E402


def main():
    script, corpus = Path(sys.argv[1]).resolve(), Path(sys.argv[2]).resolve()
    out = corpus / "trellis-passes.blender45"
    views = [
        {"yaw": yaw, "pitch": pitch, "radius": 2.0, "fov": math.radians(40)}
        for yaw, pitch in trellis_angles("spheres", [0, 1], 2).values()
    ]
    with tempfile.TemporaryDirectory() as tmp:
        sys.argv = [
            "render.py", "--",
            "--views", json.dumps(views),
            "--object", str(corpus / "materials_joined.glb"),
            "--output_folder", tmp,
            "--resolution", "256",
            "--save_depth", "--save_albedo", "--save_mist", "--save_normal",
        ]  # fmt: skip
        bpy.context.scene.view_layers[0].name = "View Layer"
        os.chdir("/")
        runpy.run_path(str(script), run_name="__main__")
        shutil.rmtree(out, ignore_errors=True)
        shutil.copytree(tmp, out)
        out.chmod(0o755)
    print(f"{out}: {sorted(p.name for p in out.iterdir())} (bpy {bpy.app.version_string})")


if __name__ == "__main__":
    main()
