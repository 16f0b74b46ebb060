"""Runs Wonder3D's own BlenderProc script on the corpus's `materials_joined.glb`: the
reference of the `wonder3d` preset's files.

BlenderProc normally downloads a Blender of its own; its sources after release 2.8.0 (from
DLR-RM/BlenderProc a80f75d) also run inside the PyPI `bpy` module of Blender 4.2
(`USE_EXTERNAL_BPY_MODULE=1`, set here). Run with a Python 3.11 that has
`pip install bpy==4.2.0 "numpy<2" "opencv-python-headless<4.11" scipy pillow pyyaml imageio
gitpython scikit-image pypng matplotlib h5py scikit-learn rich trimesh==4.4.0
pyrender==0.1.45 progressbar` (BlenderProc's own list, which it installs into its Blender)
and BlenderProc's checkout on PYTHONPATH (not pip-installed: in this mode it takes its
parent folder off `sys.path`), given the script from xxlong0/Wonder3D
(`render_codes/blenderProc_ortho.py`):

    PYTHONPATH=BlenderProc python tools/gltf_corpus/wonder3d_blenderproc.py \
        blenderProc_ortho.py tests/data/gltf/corpus

It writes `wonder3d.blenderproc/`: the script's files for the object as `spheres.glb` (its
uid `spheres`), run unchanged with the arguments `render_batch_ortho.sh` gives but two:
`--resolution 128` (for a small reference) and no `--random_pose` (the script draws the
rig's turn from NumPy's unseeded generator, which no other renderer can repeat). So: per
view of the rig, `rgb_000_{name}.webp` and `normals_000_{name}.webp` (Pillow's lossy WebP,
quality 100), `000_{name}_RT.txt`, and `scale_offset_matrix.txt`.
"""

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path


def main():
    script, corpus = Path(sys.argv[1]).resolve(), Path(sys.argv[2]).resolve()
    out = corpus / "wonder3d.blenderproc"
    with tempfile.TemporaryDirectory() as tmp:
        glb = Path(tmp) / "spheres.glb"
        shutil.copy(corpus / "materials_joined.glb", glb)
        args = [
            sys.executable, str(script),
            "--object_path", str(glb),
            "--output_folder", str(Path(tmp) / "out"),
            "--resolution", "128",
            "--ortho_scale", "1.35",
            "--view", "0",
        ]  # fmt: skip
        env = dict(os.environ, USE_EXTERNAL_BPY_MODULE="1")
        # bpy 4.2 as a module may crash as the process exits (SIGSEGV), after the script
        # has written everything: the files, not the status, say whether it ran.
        status = subprocess.run(args, env=env, cwd=tmp).returncode
        files = Path(tmp) / "out" / "sp" / "spheres"
        if len(list(files.glob("*.webp"))) != 26:
            sys.exit(f"the script (status {status}) did not write its 26 images into {files}")
        shutil.rmtree(out, ignore_errors=True)
        shutil.copytree(files, out)
        out.chmod(0o755)
    print(f"{out}: {len(list(out.iterdir()))} files")


if __name__ == "__main__":
    main()
