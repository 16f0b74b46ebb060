"""Writes the seeds of the `draco` and `meshopt` fuzz targets (fuzz/corpus/{draco,meshopt})
from the compressed files of the glTF corpus, in the inputs' layouts that
fuzz/src/lib.rs's `draco` and `meshopt` harnesses describe.

    python3 tools/gltf_corpus/fuzz_seeds.py
"""

import json
import struct
from pathlib import Path

root = Path(__file__).resolve().parents[2]
corpus = root / "tests/data/gltf/corpus"
fuzz = root / "fuzz/corpus"


def read_glb(path):
    data = path.read_bytes()
    length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + length])
    at = 20 + length
    bin_length = struct.unpack_from("<I", data, at)[0]
    return doc, data[at + 8 : at + 8 + bin_length]


def view_bytes(doc, blob, v):
    view = doc["bufferViews"][v]
    start = view.get("byteOffset", 0)
    return blob[start : start + view["byteLength"]]


def draco_seeds():
    out = fuzz / "draco"
    out.mkdir(parents=True, exist_ok=True)
    for glb in sorted(corpus.glob("*draco*.glb")):
        doc, blob = read_glb(glb)
        for m, mesh in enumerate(doc["meshes"]):
            for p, prim in enumerate(mesh["primitives"]):
                ext = prim["extensions"]["KHR_draco_mesh_compression"]
                points = doc["accessors"][prim["attributes"]["POSITION"]]["count"]
                corners = doc["accessors"][prim["indices"]]["count"]
                if points >= 1 << 16 or corners >= 1 << 16:
                    continue
                stream = view_bytes(doc, blob, ext["bufferView"])
                name = out / f"seed-{glb.stem}-{m}-{p}"
                name.write_bytes(struct.pack("<HH", points, corners) + stream)


def meshopt_seeds():
    out = fuzz / "meshopt"
    out.mkdir(parents=True, exist_ok=True)
    for glb in sorted(corpus.glob("*meshopt*.glb")):
        doc, blob = read_glb(glb)
        for m, mesh in enumerate(doc["meshes"]):
            for p, prim in enumerate(mesh["primitives"]):
                position = doc["accessors"][prim["attributes"]["POSITION"]]
                indices = doc["accessors"][prim["indices"]]
                exts = []
                for accessor in (position, indices):
                    view = doc["bufferViews"][accessor["bufferView"]]
                    (name, ext), = view["extensions"].items()
                    exts.append((name, ext))
                (name, vx), (_, ix) = exts
                if vx["byteStride"] not in (8, 12) or position.get("byteOffset", 0):
                    continue
                flags = (vx["byteStride"] == 8) | (vx.get("filter") == "EXPONENTIAL") << 1
                flags |= (ix["mode"] == "INDICES") << 2 | (ix["byteStride"] == 2) << 3
                flags |= name.startswith("KHR") << 4
                buffer = doc["buffers"][vx["buffer"]]
                data = blob if "uri" not in buffer else None
                vertices = data[vx.get("byteOffset", 0) : vx.get("byteOffset", 0) + vx["byteLength"]]
                index_stream = data[ix.get("byteOffset", 0) : ix.get("byteOffset", 0) + ix["byteLength"]]
                if vx["count"] >= 1 << 16 or ix["count"] >= 1 << 16:
                    continue
                head = struct.pack("<BHHH", flags, vx["count"], ix["count"], len(vertices))
                (out / f"seed-{glb.stem}-{m}-{p}").write_bytes(head + vertices + index_stream)


draco_seeds()
meshopt_seeds()
