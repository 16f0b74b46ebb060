#!/usr/bin/env python3
"""A glTF 2.0 reader for the reference tools, independent of meshtrace (json, struct,
base64 and numpy only), written from the glTF 2.0 specification so that a bug in
meshtrace's own loader shows up as a mismatch against Mitsuba rather than being copied.

It reads `.gltf` (buffers and images in files beside it, or as data: URIs) and `.glb`
(JSON and BIN chunks), and gives what a renderer needs of the default scene (scene 0 if
the file names none):

  * `Part`s: each triangle primitive (modes 4, 5 and 6: lists, strips and fans; points and
    lines are skipped with a warning) of each node that instances a mesh, with its node's
    world matrix (TRS or `matrix`, composed from the root down), POSITION, NORMAL,
    TEXCOORD_0 and TANGENT in every component type with `normalized`, byteStride and
    sparse accessors, and its triangles' corners (strip triangle i = {v_i, v_(i+1+i%2),
    v_(i+2-i%2)}, fan triangle i = {v_(i+1), v_(i+2), v_0}, as the specification says);
  * the first perspective camera of the node tree, depth first (orthographic ones are
    skipped with a warning);
  * KHR_lights_punctual lights placed by their nodes (pointing down the node's -Z).

Materials, textures and images are left to the caller (`Doc.json`, `Doc.image`). Every
error is one line naming the file and the JSON path, as `room.gltf: meshes[2].primitives[0]
.indices: ...`; warnings are collected in `Doc.warnings`, one line each.

Usage as a script (a summary, for checking): python3 tools/gltf_read.py FILE.gltf
"""
import base64
import json
import math
import os
import re
import struct
import sys
import urllib.parse

import numpy as np


class GltfError(Exception):
    pass


# componentType -> (numpy little-endian dtype, name)
COMPONENTS = {
    5120: ("<i1", "BYTE"), 5121: ("<u1", "UNSIGNED_BYTE"), 5122: ("<i2", "SHORT"),
    5123: ("<u2", "UNSIGNED_SHORT"), 5125: ("<u4", "UNSIGNED_INT"), 5126: ("<f4", "FLOAT"),
}
TYPES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}

# The (componentType, normalized) pairs glTF 2.0 allows for each attribute we read, and
# what KHR_mesh_quantization adds.
F = [(5126, False)]
ALLOWED = {
    "POSITION": ("VEC3", F),
    "NORMAL": ("VEC3", F),
    "TANGENT": ("VEC4", F),
    "TEXCOORD_0": ("VEC2", F + [(5121, True), (5123, True)]),
    "indices": ("SCALAR", [(5121, False), (5123, False), (5125, False)]),
}
QUANT_ANY = F + [(c, n) for c in (5120, 5121, 5122, 5123) for n in (False, True)]
QUANT_SNORM = F + [(5120, True), (5122, True)]
ALLOWED_QUANTIZED = {
    "POSITION": ("VEC3", QUANT_ANY),
    "NORMAL": ("VEC3", QUANT_SNORM),
    "TANGENT": ("VEC4", QUANT_SNORM),
    "TEXCOORD_0": ("VEC2", QUANT_ANY),
    "indices": ALLOWED["indices"],
}

# The extensions whose meaning the tools know (a file requiring another is refused).
KNOWN_EXTENSIONS = {
    "KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_ior",
    "KHR_materials_specular", "KHR_materials_transmission", "KHR_materials_volume",
    "KHR_mesh_quantization", "KHR_texture_transform",
}

LUMENS_PER_WATT = 683.0


def _is_num(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool)


class Doc:
    """A parsed glTF file: its JSON (`json`), its buffers read on demand, warnings."""

    def __init__(self, path):
        self.path = path
        self.shown = path
        self.dir = os.path.dirname(os.path.abspath(path))
        self.warnings = []
        self._buffers = {}
        try:
            with open(path, "rb") as fh:
                data = fh.read()
        except OSError as e:
            raise GltfError("%s: cannot read: %s" % (path, e))
        self.bin = None
        if data[:4] == b"glTF":
            text = self._split_glb(data)
        else:
            text = data
        if text[:3] == b"\xef\xbb\xbf":
            text = text[3:]
        try:
            self.json = json.loads(text.decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as e:
            raise GltfError("%s: %s: malformed JSON: %s" % (
                path, "GLB JSON chunk" if data[:4] == b"glTF" else "JSON", e))
        if not isinstance(self.json, dict):
            raise self.error("JSON", "the document is not a JSON object")
        # the schema's shapes that the reader relies on: arrays of objects, objects
        for key in ("accessors", "bufferViews", "buffers", "cameras", "images", "materials",
                    "meshes", "nodes", "samplers", "scenes", "textures"):
            arr = self.json.get(key, [])
            if not isinstance(arr, list):
                raise self.error(key, "must be an array")
            for i, x in enumerate(arr):
                if not isinstance(x, dict):
                    raise self.error("%s[%d]" % (key, i), "must be an object")
        for key in ("asset", "extensions"):
            if not isinstance(self.json.get(key, {}), dict):
                raise self.error(key, "must be an object")
        for key in ("extensionsUsed", "extensionsRequired"):
            if not isinstance(self.json.get(key, []), list):
                raise self.error(key, "must be an array")
        version = self.json.get("asset", {}).get("version")
        if not isinstance(version, str) or not version.startswith("2."):
            raise self.error("asset.version", "is %r; glTF 2.x is read" % (version,))
        for e in self.json.get("extensionsRequired", []):
            if e not in KNOWN_EXTENSIONS:
                raise self.error("extensionsRequired", "extension %s is not supported" % e)
        for e in self.json.get("extensionsUsed", []):
            if e not in KNOWN_EXTENSIONS:
                self.warn("extensionsUsed", "extension %s is not read" % e)
        self.quantized = "KHR_mesh_quantization" in self.json.get("extensionsUsed", [])

    # ------------------------------------------------------------ messages

    def error(self, at, msg):
        return GltfError("%s: %s: %s" % (self.shown, at, msg))

    def warn(self, at, msg):
        line = "%s: %s: %s" % (self.shown, at, msg)
        if line not in self.warnings:
            self.warnings.append(line)

    def get(self, key, i, at):
        """self.json[key][i], or an error at `at` naming the missing element."""
        arr = self.json.get(key, [])
        if not isinstance(i, int) or isinstance(i, bool) or not 0 <= i < len(arr):
            one = "mesh" if key == "meshes" else key[:-1]
            raise self.error(at, "%s %r does not exist (the file has %d)" % (one, i, len(arr)))
        return arr[i]

    # ------------------------------------------------------------ containers and buffers

    def _split_glb(self, data):
        if len(data) < 12:
            raise self.error("GLB header", "the file is shorter than the 12-byte GLB header")
        _, version, length = struct.unpack_from("<4sII", data, 0)
        if version != 2:
            raise self.error("GLB header", "GLB version %d; version 2 is read" % version)
        if length > len(data):
            raise self.error("GLB header", "the header says %d bytes, the file has %d"
                             % (length, len(data)))
        at, chunks = 12, []
        while at < length:
            if at + 8 > length:
                raise self.error("GLB chunk", "a chunk header is cut off at byte %d" % at)
            size, kind = struct.unpack_from("<I4s", data, at)
            if at + 8 + size > length:
                raise self.error("GLB chunk", "a chunk of %d bytes at byte %d runs past the "
                                 "end of the file" % (size, at))
            chunks.append((kind, data[at + 8:at + 8 + size]))
            at += 8 + size
        if not chunks or chunks[0][0] != b"JSON":
            raise self.error("GLB JSON chunk", "the first chunk is not JSON")
        if len(chunks) > 1 and chunks[1][0] == b"BIN\x00":
            self.bin = chunks[1][1]
        return chunks[0][1]

    def read_uri(self, uri, at):
        """Bytes of a data: URI or of a file relative to the glTF (percent-decoded)."""
        if uri.startswith("data:"):
            header, sep, payload = uri[5:].partition(",")
            if not sep:
                raise self.error(at, "a data: URI without a comma before its data")
            if header.endswith(";base64"):
                try:
                    return base64.b64decode(payload, validate=False), "its data URI"
                except ValueError as e:
                    raise self.error(at, "bad base64 data: %s" % e)
            return urllib.parse.unquote_to_bytes(payload), "its data URI"
        if re.match(r"^[A-Za-z][A-Za-z0-9+.-]*:", uri):
            raise self.error(at, "%r: only relative paths and data: URIs are read" % uri)
        path = os.path.join(self.dir, urllib.parse.unquote(uri))
        with open(path, "rb") as fh:      # OSError: the caller decides
            return fh.read(), path

    def buffer(self, i, at):
        if i in self._buffers:
            return self._buffers[i]
        b = self.get("buffers", i, at)
        where = "buffers[%d]" % i
        if "uri" in b:
            try:
                data, source = self.read_uri(b["uri"], where + ".uri")
            except OSError as e:
                raise self.error(where + ".uri", "cannot read: %s" % e)
        elif i == 0 and self.bin is not None:
            data, source = self.bin, "the GLB BIN chunk"
        else:
            raise self.error(where, "has no uri and no GLB BIN chunk stands for it")
        n = b.get("byteLength")
        if not _is_num(n) or n < 0:
            raise self.error(where + ".byteLength", "must be a number >= 0")
        if len(data) < n:
            raise self.error(where, "byteLength is %d bytes, but %s holds %d" % (n, source, len(data)))
        self._buffers[i] = data[:int(n)]
        return self._buffers[i]

    def view(self, i, at):
        """(bytes of bufferView i, its byteStride or None)."""
        v = self.get("bufferViews", i, at)
        data = self.buffer(v.get("buffer"), "bufferViews[%d].buffer" % i)
        start = int(v.get("byteOffset", 0))
        n = int(v.get("byteLength", 0))
        if start + n > len(data):
            raise self.error(at, "bufferView %d (bytes %d to %d) lies past the end of its "
                             "buffer (%d bytes)" % (i, start, start + n, len(data)))
        return data[start:start + n], v.get("byteStride")

    # ------------------------------------------------------------ accessors

    def accessor(self, i, at, use):
        """Accessor i as an array of shape (count, components): float64 for attributes
        (normalized integers mapped as the specification says: unsigned /(2^n - 1), signed
        max(x / (2^(n-1) - 1), -1)), uint32 for indices. `use` is a key of ALLOWED."""
        a = self.get("accessors", i, at)
        where = "%s: accessor %d" % (at, i)
        ctype, ty, norm = a.get("componentType"), a.get("type"), bool(a.get("normalized", False))
        if ctype not in COMPONENTS or ty not in TYPES:
            raise GltfError("%s: %s: has an invalid type or componentType" % (self.shown, where))
        want_ty, allowed = (ALLOWED_QUANTIZED if self.quantized else ALLOWED)[use]
        if ty != want_ty or (ctype, norm) not in allowed:
            raise GltfError("%s: %s: holds %s of %s%s; %s must be %s of %s" % (
                self.shown, where, ty, "normalized " if norm else "", COMPONENTS[ctype][1],
                use, want_ty, " or ".join(("normalized " if n else "") + COMPONENTS[c][1]
                                          for c, n in allowed)))
        dt = np.dtype(COMPONENTS[ctype][0])
        comps = TYPES[ty]
        count = int(a.get("count", 0))
        elem = comps * dt.itemsize
        off = int(a.get("byteOffset", 0))
        if "bufferView" in a:
            data, stride = self.view(a["bufferView"], at)
            stride = int(stride) if stride else elem
            if stride < elem:
                raise GltfError("%s: %s: byteStride %d is less than its %d-byte elements"
                                % (self.shown, where, stride, elem))
            need = off + (count - 1) * stride + elem if count else off
            if need > len(data):
                raise GltfError("%s: %s: reads past the end of bufferView %d (needs %d bytes, "
                                "has %d)" % (self.shown, where, a["bufferView"], need, len(data)))
            if count:
                rows = np.lib.stride_tricks.as_strided(
                    np.frombuffer(data, dtype=np.uint8, count=need - off, offset=off),
                    shape=(count, elem), strides=(stride, 1))
                raw = np.ascontiguousarray(rows).view(dt).reshape(count, comps)
            else:
                raw = np.zeros((0, comps), dtype=dt)
        else:
            raw = np.zeros((count, comps), dtype=dt)
        raw = raw.copy()
        sp = a.get("sparse")
        if sp is not None:
            n = int(sp.get("count", 0))
            if n > count:
                raise GltfError("%s: %s's sparse count %d exceeds its count %d"
                                % (self.shown, where, n, count))
            ix = sp.get("indices", {})
            ic = ix.get("componentType")
            if ic not in (5121, 5123, 5125):
                raise GltfError("%s: %s's sparse indices must be unsigned bytes, shorts or "
                                "ints" % (self.shown, where))
            idt = np.dtype(COMPONENTS[ic][0])
            data, _ = self.view(ix.get("bufferView"), at)
            o = int(ix.get("byteOffset", 0))
            if o + n * idt.itemsize > len(data):
                raise GltfError("%s: %s's sparse indices read past the end of their bufferView"
                                % (self.shown, where))
            idx = np.frombuffer(data, dtype=idt, count=n, offset=o).astype(np.int64)
            if n and (idx.max() >= count or np.any(np.diff(idx) <= 0)):
                raise GltfError("%s: %s's sparse indices must be strictly increasing and below "
                                "%d" % (self.shown, where, count))
            vx = sp.get("values", {})
            data, _ = self.view(vx.get("bufferView"), at)
            o = int(vx.get("byteOffset", 0))
            if o + n * elem > len(data):
                raise GltfError("%s: %s's sparse values read past the end of their bufferView"
                                % (self.shown, where))
            raw[idx] = np.frombuffer(data, dtype=dt, count=n * comps, offset=o).reshape(n, comps)
        if use == "indices":
            return raw.astype(np.uint32).reshape(-1)
        x = raw.astype(np.float64)
        if norm and dt.kind in "iu":
            bits = dt.itemsize * 8
            if dt.kind == "u":
                x = x / (2.0 ** bits - 1)
            else:
                x = np.maximum(x / (2.0 ** (bits - 1) - 1), -1.0)
        return x

    # ------------------------------------------------------------ images

    def image(self, i, at):
        """Image i as ("file", path) or ("bytes", data, mime or None); None (with a
        warning) when its file cannot be read."""
        img = self.get("images", i, at)
        where = "images[%d]" % i
        mime = img.get("mimeType")
        if "uri" in img:
            uri = img["uri"]
            if not uri.startswith("data:"):
                if re.match(r"^[A-Za-z][A-Za-z0-9+.-]*:", uri):
                    raise self.error(where + ".uri", "%r: only relative paths and data: URIs "
                                     "are read" % uri)
                path = os.path.join(self.dir, urllib.parse.unquote(uri))
                if not os.path.isfile(path):
                    self.warn(where + ".uri", "image %s could not be read; its textures fall "
                              "back to their factors" % path)
                    return None
                return ("file", path)
            data, _ = self.read_uri(uri, where + ".uri")
            m = re.match(r"data:([^;,]*)", uri)
            return ("bytes", data, mime or (m.group(1) if m and m.group(1) else None))
        if "bufferView" in img:
            data, _ = self.view(img["bufferView"], where)
            return ("bytes", bytes(data), mime)
        raise self.error(where, "has neither a uri nor a bufferView")


# ---------------------------------------------------------------- the node tree

def quat_matrix(q):
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def local_matrix(doc, node, at):
    """A node's own 4x4 matrix (row-major numpy): `matrix` (column-major in the file) or
    T * R * S."""
    def finite(key, vals, n):
        if not (isinstance(vals, list) and len(vals) == n and all(_is_num(v) for v in vals)
                and all(math.isfinite(v) for v in vals)):
            raise doc.error("%s.%s" % (at, key), "must be %d finite numbers" % n)
        return [float(v) for v in vals]
    if "matrix" in node:
        m = finite("matrix", node["matrix"], 16)
        return np.array(m, dtype=np.float64).reshape(4, 4).T
    t = finite("translation", node.get("translation", [0, 0, 0]), 3)
    r = finite("rotation", node.get("rotation", [0, 0, 0, 1]), 4)
    s = finite("scale", node.get("scale", [1, 1, 1]), 3)
    length = math.sqrt(sum(x * x for x in r))
    if not length > 0:
        raise doc.error(at + ".rotation", "must be a unit quaternion, not zero")
    M = np.eye(4)
    M[:3, :3] = quat_matrix([x / length for x in r]) @ np.diag(s)
    M[:3, 3] = t
    return M


class Part:
    """One triangle primitive placed by a node. Arrays are in the mesh's own space:
    positions (N, 3), normals (N, 3) or None (non-finite ones zeroed), uvs (N, 2) or
    None, tangents (N, 4) or None; tris (T, 3) int64 corner indices in the file's order;
    matrix the node's world matrix (4x4); material the glTF material index or None."""
    __slots__ = ("at", "node", "mesh", "material", "matrix", "positions", "normals", "uvs",
                 "tangents", "tris")


def read_primitive(doc, m, p, prim):
    at = "meshes[%d].primitives[%d]" % (m, p)
    mode = prim.get("mode", 4)
    if mode in (0, 1, 2, 3):
        doc.warn(at, "mode %s draws no triangles; the primitive is skipped"
                 % ["POINTS", "LINES", "LINE_LOOP", "LINE_STRIP"][mode])
        return None
    if mode not in (4, 5, 6):
        raise doc.error(at + ".mode", "is not a primitive mode")
    attrs = prim.get("attributes", {})

    def attr(name):
        return "%s.attributes[\"%s\"]" % (at, name)
    if "POSITION" not in attrs:
        raise doc.error(at + ".attributes", "has no POSITION")
    pos = doc.accessor(attrs["POSITION"], attr("POSITION"), "POSITION")
    if not np.all(np.isfinite(pos)):
        k = int(np.argwhere(~np.isfinite(pos))[0][0])
        raise doc.error(attr("POSITION"), "vertex %d is not finite" % k)
    n = len(pos)

    def same(name, arr):
        if len(arr) != n:
            raise doc.error(attr(name), "has %d elements, but POSITION has %d" % (len(arr), n))
        return arr
    part = Part()
    part.positions = pos
    part.normals = part.uvs = part.tangents = None
    if "NORMAL" in attrs:
        nrm = same("NORMAL", doc.accessor(attrs["NORMAL"], attr("NORMAL"), "NORMAL"))
        nrm[~np.all(np.isfinite(nrm), axis=1)] = 0.0
        part.normals = nrm
    if "TEXCOORD_0" in attrs:
        uv = same("TEXCOORD_0", doc.accessor(attrs["TEXCOORD_0"], attr("TEXCOORD_0"),
                                             "TEXCOORD_0"))
        if not np.all(np.isfinite(uv)):
            raise doc.error(attr("TEXCOORD_0"), "a texture coordinate is not finite")
        part.uvs = uv
    if "TANGENT" in attrs:
        tg = same("TANGENT", doc.accessor(attrs["TANGENT"], attr("TANGENT"), "TANGENT"))
        tg[~np.all(np.isfinite(tg), axis=1)] = 0.0
        part.tangents = tg
    if "COLOR_0" in attrs:
        doc.warn(at, "vertex colours (COLOR_0) are ignored")
    if prim.get("targets"):
        doc.warn(at, "morph targets are not applied; the base shape is drawn")
    if "indices" in prim:
        v = doc.accessor(prim["indices"], at + ".indices", "indices").astype(np.int64)
        if len(v) and v.max() >= n:
            k = int(np.argmax(v >= n))
            raise doc.error(at + ".indices", "index %d (entry %d) is out of range: POSITION "
                            "has %d vertices" % (v[k], k, n))
    else:
        v = np.arange(n, dtype=np.int64)
    if mode == 4:
        if len(v) % 3:
            doc.warn(at, "%d vertices do not make whole triangles; the last %d are ignored"
                     % (len(v), len(v) % 3))
        tris = v[:len(v) - len(v) % 3].reshape(-1, 3)
    else:
        k = np.arange(max(len(v) - 2, 0))
        if mode == 5:      # strip
            tris = np.stack([v[k], v[k + 1 + k % 2], v[k + 2 - k % 2]], axis=1)
        else:              # fan
            tris = np.stack([v[k + 1], v[k + 2], np.full_like(k, v[0] if len(v) else 0)],
                            axis=1)
    part.tris = tris.reshape(-1, 3)
    part.material = prim.get("material")
    return part


class Camera:
    __slots__ = ("position", "forward", "up", "yfov_deg", "at")


class Light:
    """A punctual light in world space, radiometric: type "point" | "spot" |
    "directional", position, direction (unit), power (RGB: W/sr or W/m^2), and for spots
    cutoff / beam_width in radians (outerConeAngle / innerConeAngle)."""
    __slots__ = ("type", "position", "direction", "power", "cutoff", "beam_width", "at")


def read_light(doc, l, world, at):
    lights = doc.json.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    if not isinstance(l, int) or not 0 <= l < len(lights):
        raise doc.error(at + ".extensions.KHR_lights_punctual.light",
                        "light %r does not exist (the file has %d)" % (l, len(lights)))
    js = lights[l]
    la = "extensions.KHR_lights_punctual.lights[%d]" % l
    colour = np.array(js.get("color", [1.0, 1.0, 1.0]), dtype=np.float64)
    if colour.shape != (3,) or not np.all(np.isfinite(colour)) or colour.min() < 0:
        raise doc.error(la + ".color", "must be 3 finite numbers >= 0")
    intensity = js.get("intensity", 1.0)
    if not _is_num(intensity) or not math.isfinite(intensity) or intensity < 0:
        raise doc.error(la + ".intensity", "must be finite and at least 0")
    if "range" in js:
        doc.warn(la + ".range", "is ignored: lights fall off with the inverse square of "
                 "distance alone")
    out = Light()
    out.at = la
    out.type = js.get("type")
    out.power = colour * float(intensity) / LUMENS_PER_WATT
    out.position = world[:3, 3].copy()
    d = world[:3, :3] @ np.array([0.0, 0.0, -1.0])
    nd = np.linalg.norm(d)
    out.direction = d / nd if nd > 0 and np.isfinite(nd) else None
    out.cutoff = out.beam_width = None
    if out.type == "spot":
        spot = js.get("spot")
        if not isinstance(spot, dict):
            raise doc.error(la + ".spot", "is required for a spot light")
        outer = spot.get("outerConeAngle", math.pi / 4)
        inner = spot.get("innerConeAngle", 0.0)
        if not (_is_num(outer) and 0 < outer <= math.pi / 2):
            raise doc.error(la + ".spot.outerConeAngle", "must be in (0, pi/2]")
        if not (_is_num(inner) and 0 <= inner < outer):
            raise doc.error(la + ".spot.innerConeAngle", "must be in [0, outerConeAngle)")
        out.cutoff, out.beam_width = float(outer), float(inner)
    elif out.type not in ("point", "directional"):
        raise doc.error(la + ".type", "is not point, spot or directional")
    if out.type != "point" and out.direction is None:
        doc.warn(at, "its transform collapses its light's direction; the light is dropped")
        return None
    return out


def transform_light(light, M):
    """The light moved by the 4x4 matrix M (an object's transform on top of the file's):
    its position as a point, its direction as a vector, renormalised; None when M collapses
    the direction or takes the position out of finite space."""
    out = Light()
    for k in Light.__slots__:
        setattr(out, k, getattr(light, k))
    out.position = M[:3, :3] @ light.position + M[:3, 3]
    if not np.all(np.isfinite(out.position)):
        return None
    if light.direction is not None:
        d = M[:3, :3] @ light.direction
        n = np.linalg.norm(d)
        if not (n > 0 and np.isfinite(n)):
            if light.type != "point":
                return None
            out.direction = None
        else:
            out.direction = d / n
    return out


def read_camera(doc, c, world, at):
    cam = doc.get("cameras", c, at + ".camera")
    ca = "cameras[%d]" % c
    if cam.get("type") == "orthographic":
        doc.warn(ca, "orthographic cameras are not supported; skipped")
        return None
    p = cam.get("perspective")
    if cam.get("type") != "perspective" or not isinstance(p, dict):
        raise doc.error(ca, "is not a valid perspective camera")
    yfov = p.get("yfov")
    if not (_is_num(yfov) and 0 < yfov < math.pi):
        raise doc.error(ca + ".perspective.yfov", "must be in (0, pi) radians")
    out = Camera()
    out.at = ca
    out.position = world[:3, 3].copy()
    f = world[:3, :3] @ np.array([0.0, 0.0, -1.0])
    out.forward = f / np.linalg.norm(f)
    out.up = world[:3, :3] @ np.array([0.0, 1.0, 0.0])
    out.yfov_deg = math.degrees(yfov)
    return out


class Scene:
    """The default scene: parts (list of Part), camera (Camera or None), lights."""

    def __init__(self):
        self.parts, self.camera, self.lights = [], None, []


def read_scene(doc):
    js = doc.json
    scenes = js.get("scenes", [])
    if "scene" in js:
        s = js["scene"]
        if not isinstance(s, int) or not 0 <= s < len(scenes):
            raise doc.error("scene", "scene %r does not exist (the file has %d)" % (s, len(scenes)))
    elif scenes:
        s = 0
    else:
        raise doc.error("scenes", "the file has no scene to render")
    out = Scene()
    meshes = {}
    visited = set()
    stack = [(n, np.eye(4), "scenes[%d].nodes[%d]" % (s, k))
             for k, n in reversed(list(enumerate(scenes[s].get("nodes", []))))]
    while stack:
        n, parent, referrer = stack.pop()
        node = doc.get("nodes", n, referrer)
        at = "nodes[%d]" % n
        if n in visited:
            raise doc.error(at, "is reached twice in scene %d's node tree" % s)
        visited.add(n)
        world = parent @ local_matrix(doc, node, at)
        if "mesh" in node:
            m = node["mesh"]
            mesh = doc.get("meshes", m, at + ".mesh")
            if "skin" in node:
                doc.warn(at, "skinning is not applied; the mesh is drawn in its bind pose")
            if m not in meshes:
                meshes[m] = [(p, read_primitive(doc, m, p, prim))
                             for p, prim in enumerate(mesh.get("primitives", []))]
            for p, prim in meshes[m]:
                if prim is None:
                    continue
                part = Part()
                for k in ("positions", "normals", "uvs", "tangents", "tris", "material"):
                    setattr(part, k, getattr(prim, k))
                part.at, part.node, part.mesh, part.matrix = \
                    "meshes[%d].primitives[%d]" % (m, p), at, m, world
                out.parts.append(part)
        if "camera" in node:
            cam = read_camera(doc, node["camera"], world, at)
            if out.camera is None and cam is not None:
                out.camera = cam
        ext = node.get("extensions", {}).get("KHR_lights_punctual")
        if ext is not None:
            light = read_light(doc, ext.get("light"), world, at)
            if light is not None:
                out.lights.append(light)
        for k, c in reversed(list(enumerate(node.get("children", [])))):
            stack.append((c, world, "%s.children[%d]" % (at, k)))
    return out


def main():
    if len(sys.argv) != 2:
        raise SystemExit(__doc__.split("\n\n")[-1])
    try:
        doc = Doc(sys.argv[1])
        sc = read_scene(doc)
    except GltfError as e:
        raise SystemExit(str(e))
    for p in sc.parts:
        print("%s at %s: %d vertices, %d triangles, material %s%s%s" % (
            p.at, p.node, len(p.positions), len(p.tris), p.material,
            ", normals" if p.normals is not None else "", ", uvs" if p.uvs is not None else ""))
    if sc.camera is not None:
        c = sc.camera
        print("camera %s: position %s forward %s yfov %.3f deg" % (c.at, c.position, c.forward,
                                                                 c.yfov_deg))
    for li in sc.lights:
        print("light %s: %s at %s towards %s, power %s" % (li.at, li.type, li.position,
                                                          li.direction, li.power))
    for w in doc.warnings:
        print("warning:", w)


if __name__ == "__main__":
    main()
