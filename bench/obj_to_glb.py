"""Turns OBJ meshes into the GLBs the dataset scripts take, with Blender's own importer and
glTF exporter (PyPI's `bpy`): `python bench/obj_to_glb.py OUT_DIR MESH.obj...`."""

import sys
from pathlib import Path

import bpy


def main():
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    for mesh in map(Path, sys.argv[2:]):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        bpy.ops.wm.obj_import(filepath=str(mesh))
        glb = out / f"{mesh.stem}.glb"
        bpy.ops.export_scene.gltf(filepath=str(glb), export_format="GLB")
        print(glb)


if __name__ == "__main__":
    main()
