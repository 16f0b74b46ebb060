#!/usr/bin/env bash
# Rebuilds tests/data/gltf/corpus from third-party writers, then validates every file:
# Blender 5's glTF exporter (the PyPI package bpy, with its Draco library) writes the
# originals and what Blender's importer sees in each (blender_corpus.py); gltf-transform
# derives the compressed and instanced forms; Khronos' glTF-Validator must report no errors.
#
#   TOOLS=/path/with/node_modules PYTHON=/path/to/venv/bin/python tools/gltf_corpus/make.sh
#
# TOOLS holds `npm install @gltf-transform/cli@4.5.1 gltf-validator@2.0.0-dev.3.10`; PYTHON
# has `pip install bpy==5.0.0` (Python 3.11).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=$(realpath "$here/../../tests/data/gltf/corpus")
: "${TOOLS:?set TOOLS to the folder holding node_modules}"
: "${PYTHON:?set PYTHON to a Python with bpy}"
mkdir -p "$out"
"$PYTHON" "$here/blender_corpus.py" "$out" | grep "triangles as"
transform() { (cd "$TOOLS" && npx gltf-transform "$@" >/dev/null); }
transform instance "$out/crowd.glb" "$out/crowd_instanced.glb"
transform meshopt "$out/skinned_arm.glb" "$out/skinned_arm_meshopt.glb"
transform meshopt "$out/morph_box.glb" "$out/morph_box_meshopt.glb"
transform meshopt "$out/crowd.glb" "$out/crowd_meshopt.glb"
transform draco "$out/crowd.glb" "$out/crowd_draco.glb"
transform draco "$out/skinned_arm.glb" "$out/skinned_arm_draco.glb"
(cd "$TOOLS" && NODE_PATH=node_modules node "$here/spec_gloss.cjs" "$out")
(cd "$TOOLS" && node "$here/validate.mjs" "$out"/*.glb)
# TRELLIS's own files of its optional passes need Blender 4.5 (PYTHON45 with
# `pip install bpy==4.5.15`) and the script (TRELLIS_SCRIPT: microsoft/TRELLIS's
# dataset_toolkits/blender_script/render.py).
if [ -n "${PYTHON45:-}" ] && [ -n "${TRELLIS_SCRIPT:-}" ]; then
    "$PYTHON45" "$here/trellis_passes.py" "$TRELLIS_SCRIPT" "$out" | tail -n 1
else
    echo "trellis-passes.blender45 kept as it is: set PYTHON45 and TRELLIS_SCRIPT to remake it"
fi
# Wonder3D's own files need Blender 4.2 with BlenderProc's sources (PYTHON42 with the
# packages wonder3d_blenderproc.py lists, BLENDERPROC a checkout of DLR-RM/BlenderProc)
# and the script (WONDER3D_SCRIPT: xxlong0/Wonder3D's render_codes/blenderProc_ortho.py).
if [ -n "${PYTHON42:-}" ] && [ -n "${BLENDERPROC:-}" ] && [ -n "${WONDER3D_SCRIPT:-}" ]; then
    PYTHONPATH="$BLENDERPROC" "$PYTHON42" "$here/wonder3d_blenderproc.py" "$WONDER3D_SCRIPT" "$out" | tail -n 1
else
    echo "wonder3d.blenderproc kept as it is: set PYTHON42, BLENDERPROC and WONDER3D_SCRIPT to remake it"
fi
