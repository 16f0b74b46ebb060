#!/usr/bin/env python3
"""Render one of meshtrace's scene files (TOML, version 1 plus version 2's image textures,
pbr, punctual lights, normal maps and glTF objects), or a bare glTF 2.0 file, with Mitsuba 3.

The scene is translated into the equivalent Mitsuba scene (see
shared/specs/scene-format.md):
  * meshes: each OBJ is parsed here (fan triangulation, negative indices, usemtl/mtllib)
    and written as a plain triangle OBJ per material into a temporary folder, then loaded
    with Mitsuba's `obj` shape (`face_normals` when the faces have no `vn`);
    the object's transform (scale, rotate X then Y then Z, translate, or `matrix`)
    becomes `to_world`;
  * spheres: Mitsuba's analytic `sphere` (meshtrace tessellates it: expect tiny
    differences at silhouettes), or with --spheres mesh meshtrace's own icosphere (same
    algorithm and default level as src/scene/sphere.rs) with smooth vertex normals;
  * diffuse -> twosided(diffuse); conductor -> twosided(conductor, material none);
    rough_conductor -> twosided(roughconductor ggx, alpha = roughness^2, material none);
    dielectric -> dielectric(int_ior = ior, ext_ior = 1); emission -> `area` emitter;
  * textures (`albedo`/`emission = { texture, scale, strength }`, MTL map_Kd / map_Ke):
    a `bitmap` texture (bilinear, repeat, raw) of the image decoded here to linear RGB
    (8-bit/16-bit formats through the sRGB curve, HDR/EXR as they are), multiplied by
    the constant factor (Kd, Ke or 1; times `strength` for emission), rows reversed
    (see "UV orientation" below), with to_uv = scale(su, sv); roughness textures are
    refused (see texture_value); only meshes with OBJ `vt` may use textures;
  * sky colour -> `constant`; sky gradient -> `envmap` of a lat-long bitmap whose rows
    hold lerp(horizon, zenith, 0.5 * (dir.y + 1)) (depends on dir.y only, so Mitsuba's
    azimuth convention does not matter);
  * sky environment map (`[sky] environment = "f.hdr" | "f.exr"`, `rotate` in degrees
    about +Y, `strength`) -> `envmap` with the image read here (as textures, HDR/EXR as
    stored) as its `bitmap`, `scale` = strength, to_world = rotate([0, 1, 0], rotate):
    exactly the format's d' = R_y(-rotate) d, u = atan2(d'.x, -d'.z) / 2 pi,
    v = acos(d'.y) / pi. Mitsuba interpolates bilinearly with the columns at texel centres
    (u = (j + 0.5) / W, wrapping) but the rows at v = i / (H - 1) (row 0 exactly at +Y),
    which is how meshtrace must read the map to match (tools/check_envmap.py). Refused:
    environment with color/zenith/horizon, rotate/strength without environment, a
    strength < 0, non-finite numbers, other extensions, a missing file; strength 0 (or an
    all-black map) is a black sky;
  * normal maps (`normal_map = { texture, scale, strength = 1 }` on any material, MTL
    map_Bump / bump / norm, glTF normalTexture with scale 1) -> Mitsuba's `normalmap`
    around the BSDF, the map read raw (see normal_map_bsdf for where this is exact);
  * glTF (bare, or `[[objects]] mesh = "x.gltf" / "x.glb"`): read here by gltf_read.py
    (not by meshtrace), its default scene's triangles written in world space (the object's
    transform on top of the node tree; corners swapped under a mirroring node, as glTF's
    winding rule says) as triangle OBJs per material; materials translated only where
    meshtrace's pbr has an exact Mitsuba twin (GltfMaterials), else refused with the JSON
    path; KHR_lights_punctual -> point / spot / directional (candela and lux / 683); a bare
    file gets meshtrace's bare-glTF set-up (build_bare_gltf);
  * camera -> `perspective` (or `thinlens`), fov_axis "y", fov = vfov;
  * film `hdrfilm` rgb float32 with a **box** pixel filter, sampler `independent`,
    integrator `path` (max_depth from the file, rr_depth 5).

UV orientation (checked with Mitsuba 3.9.1, llvm_ad_rgb, by tools/check_texture_uv.py):
Mitsuba's `bitmap` puts uv (0, 0) at the image's top-left texel and its `obj` loader
flips v by default (flip_tex_coords = true: uv = (u, 1 - v)), so by default an OBJ vt of
(0, 0) shows the image's bottom-left texel, as the scene format says; but a to_uv scale
then multiplies the flipped coordinate, sv * (1 - v), which equals the format's sv * v
measured from the bottom only for integer sv. So the script loads every OBJ with
flip_tex_coords = false (uv = vt as written) and reverses the image's rows itself, and
to_uv = scale(su, sv) is then the format's lookup at (su u, sv v) from the bottom-left
for every scale. check_texture_uv.py renders a textured emitting quad through this
script's own functions with an orthographic camera and compares it with a numpy
evaluation of the format's rule (bilinear, repeat, texel centres at half-integers,
x = u width - 0.5), at scales (1, 1), (3, 3), (2, 1.5) and (0.7, 1.3). glTF's
TEXCOORD_0 has (0, 0) at the image's top-left with v running down, which is Mitsuba's
bitmap convention: glTF UVs are written as they are, the image is not reversed, and
to_uv is KHR_texture_transform's matrix (check_texture_uv.py --gltf).

High sample counts are rendered in passes (at most --lanes samples in flight), each
with its own seed, and averaged; this equals one render at the full count because the
box filter weighs every sample alike.

Usage:
  python3 tools/mitsuba_render.py SCENE.toml|FILE.gltf|FILE.glb [--spp N] [--seed S]
        [--width W] [--height H] [--max-depth D] [-o out.exr] [--variant llvm_ad_rgb]
        [--spheres analytic|mesh]
"""
import argparse
import glob
import math
import os
import re
import sys
import tempfile
import time
import tomllib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_read as gr  # noqa: E402


# ---------------------------------------------------------------- Mitsuba set-up

def libllvm_versions():
    """The libLLVM shared libraries in the usual places, each with its major version (None
    where neither the file name nor an `llvm-N` folder says it)."""
    found = {}
    for d in ("/usr/lib/*", "/usr/lib", "/usr/lib64", "/usr/local/lib", "/usr/lib/llvm-*/lib",
              "/usr/lib64/llvm*/lib", "/opt/homebrew/opt/llvm/lib", "/usr/local/opt/llvm/lib"):
        for c in glob.glob(d + "/libLLVM*.so*") + glob.glob(d + "/libLLVM*.dylib"):
            m = (re.search(r"(\d+)", os.path.basename(c))
                 or re.search(r"llvm-?(\d+)", os.path.dirname(c)))
            found[c] = int(m.group(1)) if m else None
    return found


def setup_mitsuba(variant=None):
    """Import mitsuba and pick a variant: llvm_ad_rgb when a libLLVM >= 17 is found
    (DRJIT_LIBLLVM_PATH, else the newest of libllvm_versions()), else scalar_rgb.
    Mitsuba 3.9.1's kernels abort the process under libLLVM 15 and 16 ("Cannot select:
    fminimum"); 19 works (Debian 12: libllvm19). Where only older ones are found, the LLVM
    variants are skipped; where none of known version is, Dr.Jit looks for one itself."""
    llvm_found = "DRJIT_LIBLLVM_PATH" in os.environ
    if not llvm_found:
        found = libllvm_versions()
        good = sorted((v, c) for c, v in found.items() if v is not None and v >= 17)
        if good:
            os.environ["DRJIT_LIBLLVM_PATH"] = good[-1][1]
        # Dr.Jit would load one of these by itself, and an older one aborts the process.
        llvm_found = bool(good) or not found or None in found.values()
    import mitsuba as mi
    wanted = [variant] if variant else ["llvm_ad_rgb", "scalar_rgb"]
    err = None
    for v in wanted:
        if v.startswith("llvm") and not llvm_found:
            err = ("only libLLVM older than 17 found (Debian 12: apt-get install libllvm19, "
                   "or set DRJIT_LIBLLVM_PATH)")
            print("mitsuba_render: variant %s unavailable: %s" % (v, err), file=sys.stderr)
            continue
        try:
            mi.set_variant(v)
            if v.startswith("llvm"):
                import drjit as dr
                # force the JIT to initialise now, so a missing libLLVM fails here
                _ = dr.llvm.Float([1.0]) + 1.0
                dr.eval(_)
            return mi
        except Exception as e:  # noqa: BLE001
            err = e
            print("mitsuba_render: variant %s unavailable: %s" % (v, e), file=sys.stderr)
    raise SystemExit("mitsuba_render: no usable Mitsuba variant (%s)" % err)


# ---------------------------------------------------------------- scene parsing

class SceneError(Exception):
    pass


def check_keys(table, allowed, where):
    for k in table:
        if k not in allowed:
            raise SceneError("unknown key '%s' in %s" % (k, where))


def vec3(x, where):
    if isinstance(x, (int, float)):
        return [float(x)] * 3
    if not (isinstance(x, list) and len(x) == 3):
        raise SceneError("%s must be a list of 3 numbers" % where)
    return [float(v) for v in x]


def object_matrix(obj, where):
    """4x4 to_world (row-major, numpy) of an object: scale, rotate X, Y, Z, translate."""
    if "matrix" in obj:
        if any(k in obj for k in ("translate", "rotate", "scale")):
            raise SceneError("%s: `matrix` excludes translate/rotate/scale" % where)
        m = obj["matrix"]
        if not (isinstance(m, list) and len(m) == 16):
            raise SceneError("%s: matrix must have 16 numbers" % where)
        return np.array(m, dtype=np.float64).reshape(4, 4)
    s = vec3(obj.get("scale", 1.0), where + ".scale")
    r = vec3(obj.get("rotate", [0.0, 0.0, 0.0]), where + ".rotate")
    t = vec3(obj.get("translate", [0.0, 0.0, 0.0]), where + ".translate")

    def rot(axis, deg):
        a = math.radians(deg)
        c, sn = math.cos(a), math.sin(a)
        if deg % 90 == 0:  # exact for right angles
            c, sn = [(1, 0), (0, 1), (-1, 0), (0, -1)][int(deg // 90) % 4]
        m = np.eye(4)
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        m[i, i], m[i, j], m[j, i], m[j, j] = c, -sn, sn, c
        return m

    S = np.diag([s[0], s[1], s[2], 1.0])
    T = np.eye(4)
    T[:3, 3] = t
    return T @ rot(2, r[2]) @ rot(1, r[1]) @ rot(0, r[0]) @ S


# ---------------------------------------------------------------- textures

_warned = set()


def warn(msg):
    """Prints a warning on stderr once (the same MTL material may be met many times)."""
    if msg not in _warned:
        _warned.add(msg)
        print("mitsuba_render: warning: %s" % msg, file=sys.stderr)


class TexRef:
    """A textured parameter: factor (RGB) x image lookup. `path` is absolute; `where`
    names the parameter for errors. The lookup is at (su u, sv v) with `scale` (OBJ `vt`
    and TOML textures: (0, 0) at the image's bottom-left), or with `gltf_uv` at
    `matrix` . (u, v, 1) (a 3x3 affine matrix: KHR_texture_transform; (0, 0) at the image's
    top-left, v running down). `linear`: the image is data (normal maps), never
    sRGB-decoded. `flip_green`: the green channel is read as 1 - g (a normal map's y
    negated, for triangles whose UVs are mirrored, see normal_map_bsdf)."""
    __slots__ = ("path", "scale", "factor", "where", "gltf_uv", "matrix", "linear",
                 "flip_green", "wrap")

    def __init__(self, path, scale, factor, where, gltf_uv=False, matrix=None, linear=False,
                 flip_green=False, wrap="repeat"):
        self.path, self.scale, self.factor, self.where = path, scale, factor, where
        self.gltf_uv, self.matrix, self.linear = gltf_uv, matrix, linear
        self.flip_green, self.wrap = flip_green, wrap

    def flipped(self):
        """The same texture with its green channel read as 1 - g."""
        return TexRef(self.path, self.scale, self.factor, self.where, self.gltf_uv,
                      self.matrix, self.linear, not self.flip_green, self.wrap)


# parameters that may hold a texture table in a TOML material (of pbr's only base_color
# translates, and only where the pbr material is Lambertian, see pbr_twin)
TEXTURABLE = ("albedo", "emission", "roughness", "base_color", "metallic", "transmission")

NORMAL_MAP_STRENGTH_REFUSED = (
    "a normal map strength other than 1 has no exact Mitsuba twin: meshtrace scales the "
    "decoded x and y before normalising, Mitsuba's normalmap reads the map as it is")

ROUGHNESS_TEXTURE_REFUSED = (
    "a roughness texture cannot be translated to Mitsuba: meshtrace's GGX alpha is "
    "(roughness x texture)^2 per lookup, which a bilinear Mitsuba bitmap (of roughness "
    "or of alpha) does not reproduce exactly")


def toml_texture(v, base, where, emission):
    """{ texture = "file", scale = [su, sv], wrap = mode or [u, v], strength = s (emission
    only) } -> TexRef. Mitsuba's bitmap has one wrap mode for both axes, so [u, v] must
    agree; meshtrace's names (repeat, clamp, mirror) are Mitsuba's."""
    keys = {"texture", "scale", "wrap"}
    check_keys(v, keys | {"strength"} if emission else keys, where)
    if "texture" not in v:
        raise SceneError("%s: a texture table needs `texture`" % where)
    name = v["texture"]
    if not isinstance(name, str) or not name:
        raise SceneError("%s.texture must be a file name" % where)
    path = os.path.join(base, name)
    if not os.path.isfile(path):
        raise SceneError("%s: texture file not found: %s" % (where, path))
    sc = v.get("scale", [1.0, 1.0])
    if not (isinstance(sc, list) and len(sc) == 2
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in sc)):
        raise SceneError("%s.scale must be a list of 2 numbers [su, sv]" % where)
    strength = v.get("strength", 1.0)
    if not isinstance(strength, (int, float)) or isinstance(strength, bool):
        raise SceneError("%s.strength must be a number" % where)
    wrap = v.get("wrap", "repeat")
    if isinstance(wrap, list) and len(wrap) == 2:
        if wrap[0] != wrap[1]:
            raise SceneError("%s.wrap: %s differs between u and v: Mitsuba's bitmap has one "
                             "wrap mode for both axes (no exact twin)" % (where, wrap))
        wrap = wrap[0]
    if wrap not in ("repeat", "clamp", "mirror"):
        raise SceneError("%s.wrap must be repeat, clamp or mirror, got %r" % (where, wrap))
    return TexRef(path, (float(sc[0]), float(sc[1])), [float(strength)] * 3, where,
                  wrap=wrap)


def resolve_toml_material(mat, base, where):
    """A copy of a TOML material with its texture tables replaced by TexRefs (the normal
    map's as linear data)."""
    out = dict(mat)
    for key, val in mat.items():
        w = "%s.%s" % (where, key)
        if key == "normal_map":
            if not isinstance(val, dict):
                raise SceneError("%s must be a texture table { texture = ... }" % w)
            ref = toml_texture(val, base, w, emission=True)
            if ref.factor != [1.0, 1.0, 1.0]:
                raise SceneError("%s.strength: %s" % (w, NORMAL_MAP_STRENGTH_REFUSED))
            ref.linear = True
            out[key] = ref
            continue
        if not isinstance(val, dict):
            continue
        if key not in TEXTURABLE:
            raise SceneError("%s: a texture is not allowed here (or not translated)" % w)
        if key == "roughness":
            raise SceneError("%s: %s" % (w, ROUGHNESS_TEXTURE_REFUSED))
        out[key] = toml_texture(val, base, w, emission=(key == "emission"))
    return out


def uses_texture(mat):
    return any(isinstance(v, TexRef) for v in mat.values())


def srgb_to_linear(x):
    """The sRGB transfer function (IEC 61966-2-1), decoding."""
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


_raw_images = {}
_images = {}


def load_raw(mi, path, where):
    """An image's channels as float64 in [0, 1] for integer formats (value / max) or as
    stored for float ones, HxWxC, row 0 = the top of the image; and whether it was an
    integer format."""
    if path in _raw_images:
        return _raw_images[path]
    try:
        bmp = mi.Bitmap(path)
    except Exception as e:  # noqa: BLE001
        raise SceneError("%s: cannot read texture %s: %s" % (where, path, e))
    a = np.array(bmp)
    if a.ndim == 2:
        a = a[:, :, None]
    integer = bool(np.issubdtype(a.dtype, np.integer))
    x = a.astype(np.float64) / np.iinfo(a.dtype).max if integer else a.astype(np.float64)
    if x.ndim != 3 or x.shape[2] < 1:
        raise SceneError("%s: texture %s has no channels" % (where, path))
    if x.shape[0] < 1 or x.shape[1] < 1:
        raise SceneError("%s: texture %s is empty" % (where, path))
    _raw_images[path] = (x, integer)
    return x, integer


def load_texture(mi, path, where, linear=False):
    """An image as RGB float64, HxWx3, row 0 = the top of the image. Integer formats
    (8-bit PNG, JPEG, BMP, TGA; also 16-bit PNG) are sRGB-decoded unless `linear` (data
    such as normal maps: value / max), float formats (HDR, EXR) taken as they are; grey
    images become grey RGB; alpha is dropped."""
    key = (path, linear)
    if key in _images:
        return _images[key]
    raw, integer = load_raw(mi, path, where)
    x = srgb_to_linear(raw) if integer and not linear else raw
    ch = x.shape[2]
    if ch in (1, 2):      # Y, YA
        x = np.repeat(x[:, :, :1], 3, axis=2)
    else:                 # RGB, RGBA
        x = x[:, :, :3]
    _images[key] = x
    return x


def bitmap_texture(mi, ref):
    """Mitsuba `bitmap` texture of factor x image (raw, bilinear, repeat). OBJ/TOML
    lookups at (su u, sv v) with (0, 0) at the image's bottom-left: rows reversed,
    because meshes are loaded with flip_tex_coords = false (see the module docstring, "UV
    orientation"). glTF lookups: the image as it is (Mitsuba's uv (0, 0) is its top-left,
    as glTF's), to_uv = the KHR_texture_transform matrix."""
    img = load_texture(mi, ref.path, ref.where, ref.linear) * np.array(ref.factor)[None, None, :]
    if ref.flip_green:
        img = img.copy()
        img[:, :, 1] = 1.0 - img[:, :, 1]
    if not ref.gltf_uv:
        img = img[::-1]
    img = np.ascontiguousarray(img, dtype=np.float32)
    if ref.matrix is not None:
        to_uv = mi.ScalarTransform3f(np.asarray(ref.matrix, dtype=np.float64).tolist())
    else:
        to_uv = mi.ScalarTransform3f().scale([ref.scale[0], ref.scale[1]])
    return {"type": "bitmap", "bitmap": mi.Bitmap(img, mi.Bitmap.PixelFormat.RGB),
            "raw": True, "filter_type": "bilinear", "wrap_mode": ref.wrap, "to_uv": to_uv}


def colour_value(mi, v, default, where):
    """A Mitsuba spectrum/texture for an RGB (or grey) parameter or a TexRef."""
    if v is None:
        v = default
    if isinstance(v, TexRef):
        return bitmap_texture(mi, v)
    return rgb_spec(vec3(v, where))


# MTL texture statements: which ones translate, which warn, which are refused
MTL_MAP_KEYS = {"map_Kd", "map_Ke", "map_Pr", "map_Pm", "map_Bump", "map_bump", "bump", "norm",
                "map_d", "map_Ka", "map_Ks", "map_Ns", "map_Tr", "disp", "decal", "refl",
                "map_Ps", "map_Pc", "map_Pcr", "map_aniso", "map_anisor", "map_Ni"}
# the MTL statements that name a tangent-space normal map
NORMAL_MAP_KEYS = ("map_Bump", "map_bump", "bump", "norm")
# option flags of MTL maps and how many arguments each takes (min, max)
MTL_MAP_FLAGS = {"-s": (1, 3), "-o": (1, 3), "-t": (1, 3), "-mm": (1, 2), "-bm": (1, 1),
                 "-boost": (1, 1), "-texres": (1, 1), "-blendu": (1, 1), "-blendv": (1, 1),
                 "-cc": (1, 1), "-clamp": (1, 1), "-imfchan": (1, 1), "-type": (1, 1)}


def _is_number(t):
    try:
        float(t)
        return True
    except ValueError:
        return False


def parse_map(rest, where):
    """`[-flag args ...] file name` of an MTL map -> (file name, (su, sv), wrap mode).
    `-s su [sv [sw]]` sets the scale (missing ones 1), `-clamp on` the wrap mode "clamp"
    (else "repeat"); every other flag is ignored with a warning."""
    tok = rest.split()
    scale = (1.0, 1.0)
    wrap = "repeat"
    i = 0
    while i < len(tok) and tok[i].startswith("-") and not _is_number(tok[i]):
        flag = tok[i]
        lo, hi = MTL_MAP_FLAGS.get(flag, (0, 3))
        args = []
        i += 1
        numeric = flag in ("-s", "-o", "-t", "-mm", "-bm", "-boost", "-texres") or \
            flag not in MTL_MAP_FLAGS
        while len(args) < hi and i < len(tok) - 1 and (not numeric or _is_number(tok[i])):
            args.append(tok[i])
            i += 1
        if len(args) < lo:
            raise SceneError("%s: option %s needs %d argument(s)" % (where, flag, lo))
        if flag == "-s":
            s = [float(x) for x in args] + [1.0, 1.0]
            scale = (s[0], s[1])
        elif flag == "-clamp":
            if args[0] not in ("on", "off"):
                raise SceneError("%s: -clamp takes on or off, got %s" % (where, args[0]))
            wrap = "clamp" if args[0] == "on" else "repeat"
        else:
            warn("%s: option %s%s ignored" % (where, flag,
                                              "" if flag in MTL_MAP_FLAGS else " (unknown)"))
    name = " ".join(tok[i:])
    if not name:
        raise SceneError("%s: no file name" % where)
    return name, scale, wrap


def read_mtl(path):
    mats = {}
    cur = None
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            for line in fh:
                tok = line.split()
                if not tok or tok[0].startswith("#"):
                    continue
                if tok[0] == "newmtl":
                    cur = " ".join(tok[1:])
                    mats[cur] = {"_mtl": path}
                elif cur is not None and tok[0] in MTL_MAP_KEYS and len(tok) >= 2:
                    mats[cur][tok[0]] = line.strip().split(None, 1)[1]   # the raw rest
                elif cur is not None and len(tok) >= 2:
                    vals = []
                    for x in tok[1:]:
                        try:
                            vals.append(float(x))
                        except ValueError:
                            break
                    if vals:
                        mats[cur][tok[0]] = vals
    except OSError as e:
        print("mitsuba_render: warning: cannot read %s: %s" % (path, e), file=sys.stderr)
    return mats


def mtl_to_material(m, name="?"):
    """Our material table from MTL entries (scene-format.md, 'OBJ and MTL' and 'MTL
    texture maps'); textured parameters become TexRefs (factor Kd, or Ke where present
    and else 1)."""
    def rgb(key, default):
        v = m.get(key)
        if v is None:
            return default
        # negative values are read as 0, as meshtrace does (with a warning there)
        return [max(0.0, x) for x in ([v[0]] * 3 if len(v) < 3 else v[:3])]
    kd = rgb("Kd", [0.8, 0.8, 0.8])
    ke = rgb("Ke", [0.0, 0.0, 0.0])
    illum = int(m["illum"][0]) if "illum" in m else None
    pm = m.get("Pm", [0.0])[0]
    pr = m.get("Pr", [0.0])[0]
    d = m.get("d", [1.0])[0]
    ni = m.get("Ni", [1.5])[0]
    mtl_path = m.get("_mtl", "?")
    where = "%s: material '%s'" % (mtl_path, name)

    def tex(key, factor):
        """TexRef of map `key`, or None (absent, or file missing: warned)."""
        if key not in m:
            return None
        w = "%s: %s" % (where, key)
        fname, scale, wrap = parse_map(m[key], w)
        path = os.path.join(os.path.dirname(mtl_path), fname)
        if not os.path.isfile(path):
            warn("%s: texture file not found: %s (the constant factor is used)" % (w, path))
            return None
        return TexRef(path, scale, [float(x) for x in factor], w, wrap=wrap)

    if "map_Pm" in m:
        raise SceneError("%s: map_Pm is not translated to Mitsuba (metallic texture)" % where)
    for key in m:
        if key in MTL_MAP_KEYS and key not in ("map_Kd", "map_Ke", "map_Pr") + NORMAL_MAP_KEYS:
            warn("%s: %s ignored" % (where, key))
    # map_Bump / bump / norm: a tangent-space normal map (scene-format.md), linear data
    bumps = [k for k in NORMAL_MAP_KEYS if k in m]
    if len(bumps) > 1:
        raise SceneError("%s: %s: more than one normal map; which one meshtrace reads is not "
                         "specified" % (where, " and ".join(bumps)))
    normal_map = None
    if bumps:
        normal_map = tex(bumps[0], [1.0, 1.0, 1.0])
        if normal_map is not None:
            normal_map.linear = True

    # map_Ke multiplies Ke; without Ke the factor is 1 (scene-format.md)
    ke_tex = tex("map_Ke", ke if "Ke" in m else [1.0, 1.0, 1.0])
    out = {"emission": ke_tex if ke_tex is not None else
           (ke if "map_Ke" not in m or "Ke" in m else [1.0, 1.0, 1.0])}
    kd_tex = tex("map_Kd", kd)
    if illum == 7 or (illum != 3 and pm < 0.5 and d < 1.0 and ni > 1.0):
        out.update(type="dielectric", ior=ni if "Ni" in m else 1.5)
        if "map_Kd" in m:
            warn("%s: map_Kd ignored on a dielectric" % where)
        if "map_Pr" in m:
            warn("%s: map_Pr ignored on a dielectric" % where)
    elif illum == 3 or pm >= 0.5:
        if "Ks" in m:
            if "map_Kd" in m:
                raise SceneError("%s: map_Kd on a conductor whose albedo is Ks is ambiguous; "
                                 "not translated" % where)
            alb = rgb("Ks", kd)
        else:
            alb = kd_tex if kd_tex is not None else kd
        if "map_Pr" in m and tex("map_Pr", [pr] * 3) is not None:
            raise SceneError("%s: map_Pr: %s" % (where, ROUGHNESS_TEXTURE_REFUSED))
        if pr > 0:
            out.update(type="rough_conductor", albedo=alb, roughness=pr)
        else:
            out.update(type="conductor", albedo=alb)
    else:
        out.update(type="diffuse", albedo=kd_tex if kd_tex is not None else kd)
        if "map_Pr" in m:
            warn("%s: map_Pr ignored on a diffuse material" % where)
    if normal_map is not None:
        out["normal_map"] = normal_map
    return out


DEFAULT_MATERIAL = {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}


def mirrored_uvs(p, uv, n, gltf):
    """For triangles (T, 3, 3) positions `p`, (T, 3, 2) UVs `uv` and (T, 3) shading-side
    normals `n` (the corners' mean normal, or the face normal): whether Mitsuba's
    t = cross(n, dp/du) points away from image-up, which is +dp/dv for OBJ `vt` and -dp/dv
    for glTF (v runs down). Such triangles need their normal map's green flipped."""
    dp0, dp1 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    d0, d1 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    det = d0[:, 0] * d1[:, 1] - d0[:, 1] * d1[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(det != 0, 1.0 / det, 0.0)[:, None]
    dp_du = (d1[:, 1:2] * dp0 - d0[:, 1:2] * dp1) * inv
    dp_dv = (-d1[:, 0:1] * dp0 + d0[:, 0:1] * dp1) * inv
    t = np.cross(n, dp_du)
    up = -dp_dv if gltf else dp_dv
    return np.einsum("ij,ij->i", t, up) < 0


def split_obj(path, tmpdir, stem, split_mirrored=None, matrix=None):
    """Parse an OBJ; write one triangle OBJ per (material, has-normals, has-UVs) group,
    `vt` carried over as written (u, v; a missing v is 0; load it with
    flip_tex_coords = false). Returns [(file, material_name or None, has_vn, has_vt,
    mtl_materials, mirrored)]. `split_mirrored(material_name, mtl_materials)` says which
    groups carry a normal map: those are split again by whether their UVs are mirrored
    under `matrix` (the object's to_world, see mirrored_uvs), and `mirrored` is then True
    or False; it is None for the others."""
    vs, vns, vts = [], [], []
    groups = {}          # (mtl name, has_vn, has_vt) -> triangles [(vi, ti, ni), ...]
    mtl = {}
    cur = None
    base = os.path.dirname(path)

    def idx(s, n):
        i = int(s)
        return i - 1 if i > 0 else n + i

    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            tok = line.split()
            if not tok:
                continue
            k = tok[0]
            if k == "v":
                vs.append(tok[1:4])
            elif k == "vn":
                vns.append(tok[1:4])
            elif k == "vt":
                vts.append((tok[1], tok[2] if len(tok) > 2 else "0"))
            elif k == "usemtl":
                cur = " ".join(tok[1:]) if len(tok) > 1 else None
            elif k == "mtllib":
                for name in tok[1:]:
                    mtl.update(read_mtl(os.path.join(base, name)))
            elif k == "f":
                corners = []
                for c in tok[1:]:
                    parts = c.split("/")
                    vi = idx(parts[0], len(vs))
                    ti = idx(parts[1], len(vts)) if len(parts) > 1 and parts[1] else None
                    ni = idx(parts[2], len(vns)) if len(parts) > 2 and parts[2] else None
                    for i, n, what in ((vi, len(vs), "v"), (ti, len(vts), "vt"),
                                       (ni, len(vns), "vn")):
                        if i is not None and not 0 <= i < n:
                            raise SceneError("%s: face index out of range (%s): %s"
                                             % (path, what, line.strip()))
                    corners.append((vi, ti, ni))
                if len(corners) < 3:
                    continue
                has_vt = all(c[1] is not None for c in corners)
                has_vn = all(c[2] is not None for c in corners)
                g = groups.setdefault((cur, has_vn, has_vt), [])
                for i in range(1, len(corners) - 1):
                    g.append((corners[0], corners[i], corners[i + 1]))
    pieces = []
    for (mname, has_vn, has_vt), tris in groups.items():
        if has_vt and split_mirrored is not None and split_mirrored(mname, mtl):
            M = np.eye(4) if matrix is None else np.asarray(matrix, dtype=np.float64)
            P = np.array([[[float(x) for x in vs[c[0]]] for c in t] for t in tris])
            P = P @ M[:3, :3].T + M[:3, 3]
            UV = np.array([[[float(x) for x in vts[c[1]]] for c in t] for t in tris])
            face = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
            if has_vn:
                N = np.array([[[float(x) for x in vns[c[2]]] for c in t] for t in tris])
                N = N @ np.linalg.inv(M[:3, :3])       # (M^-T n) as rows
                N = (N / np.linalg.norm(N, axis=2, keepdims=True)).mean(axis=1)
            else:
                N = face
            mir = mirrored_uvs(P, UV, N, gltf=False)
            for flag in (False, True):
                sel = [t for t, f in zip(tris, mir) if f == flag]
                if sel:
                    pieces.append((mname, has_vn, has_vt, flag, sel))
        else:
            pieces.append((mname, has_vn, has_vt, None, tris))
    out = []
    for gi, (mname, has_vn, has_vt, mirrored, tris) in enumerate(pieces):
        fn = os.path.join(tmpdir, "%s_%d.obj" % (stem, gi))
        used_v = sorted({c[0] for t in tris for c in t})
        vmap = {v: i + 1 for i, v in enumerate(used_v)}
        tmap, nmap = {}, {}
        with open(fn, "w") as fh:
            fh.write("".join("v %s %s %s\n" % tuple(vs[v]) for v in used_v))
            if has_vt:
                used_t = sorted({c[1] for t in tris for c in t})
                tmap = {t: i + 1 for i, t in enumerate(used_t)}
                fh.write("".join("vt %s %s\n" % vts[t] for t in used_t))
            if has_vn:
                used_n = sorted({c[2] for t in tris for c in t})
                nmap = {n: i + 1 for i, n in enumerate(used_n)}
                fh.write("".join("vn %s %s %s\n" % tuple(vns[n]) for n in used_n))

            def corner(c):
                s = str(vmap[c[0]])
                if has_vt and has_vn:
                    return "%s/%d/%d" % (s, tmap[c[1]], nmap[c[2]])
                if has_vt:
                    return "%s/%d" % (s, tmap[c[1]])
                if has_vn:
                    return "%s//%d" % (s, nmap[c[2]])
                return s
            fh.write("".join("f %s %s %s\n" % (corner(a), corner(b), corner(c))
                             for a, b, c in tris))
        out.append((fn, mname, has_vn, has_vt, mtl, mirrored))
    return out


def rgb_spec(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def mitsuba_bsdf(mi, mat, where):
    """Mitsuba BSDF of a material (TOML values, or TexRefs for textured parameters)."""
    t = mat.get("type", "diffuse")
    allowed = {"type", "emission", "normal_map", "alpha", "alpha_cutoff"}
    if t == "diffuse":
        allowed |= {"albedo"}
        b = {"type": "twosided", "bsdf": {
            "type": "diffuse",
            "reflectance": colour_value(mi, mat.get("albedo"), 0.8, where + ".albedo")}}
    elif t == "conductor":
        allowed |= {"albedo"}
        b = {"type": "twosided", "bsdf": {
            "type": "conductor", "material": "none",
            "specular_reflectance": colour_value(mi, mat.get("albedo"), 1.0, where + ".albedo")}}
    elif t == "rough_conductor":
        allowed |= {"albedo", "roughness"}
        if isinstance(mat.get("roughness"), TexRef):
            raise SceneError("%s.roughness: %s" % (where, ROUGHNESS_TEXTURE_REFUSED))
        r = float(mat.get("roughness", 0.5))
        b = {"type": "twosided", "bsdf": {
            "type": "roughconductor", "material": "none", "distribution": "ggx",
            "alpha": max(r * r, 1e-4), "sample_visible": True,
            "specular_reflectance": colour_value(mi, mat.get("albedo"), 1.0, where + ".albedo")}}
    elif t == "dielectric":
        allowed |= {"ior"}
        b = {"type": "dielectric", "int_ior": float(mat.get("ior", 1.5)), "ext_ior": 1.0}
    elif t == "pbr":
        allowed |= {"base_color", "metallic", "roughness", "ior", "specular", "transmission"}
        b = pbr_twin(mi, mat, where)
    else:
        raise SceneError("%s: unknown material type '%s'" % (where, t))
    check_keys(mat, allowed, where)
    if mat.get("normal_map") is not None:
        b = normal_map_bsdf(mi, b, mat["normal_map"])
    return b


def alpha_visible(mi, mat, where):
    """A TOML alpha mask (`alpha_cutoff`, with `alpha` as its factor, default 1): whether
    the surface is there. Only a constant alpha translates (no texture, or an albedo /
    base_color texture whose alpha is 1 everywhere): the surface is then whole or cut out
    entirely; a varying texture alpha is refused (meshtrace cuts where the bilinear alpha is
    below the cut-off, which no Mitsuba texture reproduces). `alpha` alone is an error, as
    in meshtrace (it does not blend)."""
    if "alpha_cutoff" not in mat:
        if "alpha" in mat:
            raise SceneError("%s.alpha: is read only by an alpha mask: set alpha_cutoff too "
                             "(meshtrace does not blend)" % where)
        return True
    cutoff = float(mat["alpha_cutoff"])
    alpha = float(mat.get("alpha", 1.0))
    for key in ("albedo", "base_color"):
        ref = mat.get(key)
        if isinstance(ref, TexRef):
            raw, _ = load_raw(mi, ref.path, ref.where)
            if raw.shape[2] in (2, 4) and not np.all(raw[:, :, -1] >= 1.0):
                raise SceneError("%s.alpha_cutoff: the %s texture's alpha varies: an alpha mask "
                                 "that follows a texture has no exact Mitsuba twin" % (where, key))
    return alpha >= cutoff


def normal_map_bsdf(mi, b, ref):
    """`b` with its shading normal taken from the tangent-space normal map `ref` (linear
    RGB, n = 2 rgb - 1, OpenGL convention: +Y up the image): Mitsuba's `normalmap` around
    the one-sided BSDF (inside `twosided`, so that the back of a two-sided surface sees
    the map too, mirrored through the surface as meshtrace's turned frame does).

    Mitsuba reads the map in the shading frame (s, t, n) with s = dp/du made orthogonal to
    n and t = cross(n, s); MikkTSpace (meshtrace) has T along dp/du and B = +-cross(N, T)
    towards image-up (+vt for OBJ, -v for glTF). These agree on flat triangles whose UVs
    are not mirrored; the callers give triangles with mirrored UVs a map whose green
    channel is flipped (TexRef.flipped), so that flat geometry is exact either way. On
    curved geometry MikkTSpace interpolates per-vertex tangents where Mitsuba uses each
    triangle's dp/du: not exact there. `use_shadowing_function` is off (Mitsuba's default
    smooths shadow terminators with a term meshtrace does not have)."""
    def wrap(inner):
        return {"type": "normalmap", "normalmap": bitmap_texture(mi, ref),
                "use_shadowing_function": False, "bsdf": inner}
    if b.get("type") == "twosided":
        return {"type": "twosided", "bsdf": wrap(b["bsdf"])}
    return wrap(b)


PBR_NO_TWIN = ("has no exact Mitsuba twin; only these pbr sub-cases translate: specular 0 "
               "without metallic or transmission (Lambertian), metallic 1 roughness 0 "
               "with a white base colour (a perfect mirror), and transmission 1 "
               "roughness 0 with a white base colour and specular 1 (a dielectric)")


def pbr_twin(mi, mat, where):
    """The Mitsuba BSDF that a `pbr` material equals exactly, for its sub-cases that have
    one (see src/render/bsdf.rs); anything else is refused rather than approximated. A
    base_color texture translates in the Lambertian case (specular 0), where the BSDF is
    linear in it; other textured parameters are refused."""
    for key in ("metallic", "roughness", "transmission"):
        if isinstance(mat.get(key), TexRef):
            raise SceneError("%s.%s: a textured pbr parameter %s" % (where, key, PBR_NO_TWIN))
    base_tex = mat.get("base_color") if isinstance(mat.get("base_color"), TexRef) else None
    base = [1.0, 1.0, 1.0] if base_tex is not None else \
        vec3(mat.get("base_color", 0.8), where + ".base_color")
    metallic = float(mat.get("metallic", 0.0))
    roughness = float(mat.get("roughness", 0.5))
    specular = float(mat.get("specular", 1.0))
    transmission = float(mat.get("transmission", 0.0))
    ior = float(mat.get("ior", 1.5))
    white = base == [1.0, 1.0, 1.0] and base_tex is None
    if specular == 0.0 and metallic == 0.0 and transmission == 0.0:
        refl = bitmap_texture(mi, base_tex) if base_tex is not None else rgb_spec(base)
        return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": refl}}
    if metallic == 1.0 and roughness == 0.0 and white:
        return {"type": "twosided", "bsdf": {
            "type": "conductor", "material": "none",
            "specular_reflectance": rgb_spec([1.0, 1.0, 1.0])}}
    if (transmission == 1.0 and roughness == 0.0 and metallic == 0.0 and white
            and specular == 1.0):
        return {"type": "dielectric", "int_ior": ior, "ext_ior": 1.0}
    if base_tex is not None:
        raise SceneError("%s.base_color: a textured base colour outside the Lambertian case "
                         "(specular 0) %s" % (where, PBR_NO_TWIN))
    raise SceneError("%s: this pbr material %s" % (where, PBR_NO_TWIN))


def punctual_light(mi, light, where):
    """Mitsuba's `point`, `spot` or `directional` emitter for a [[lights]] table (the same
    units: W/sr intensity, W/m^2 irradiance; a spot's falloff linear in angle from its beam
    width to its cutoff, as Mitsuba's `spot`)."""
    t = light.get("type")
    if t == "point":
        check_keys(light, {"type", "position", "intensity"}, where)
        return {"type": "point", "position": vec3(light["position"], where + ".position"),
                "intensity": rgb_spec(vec3(light["intensity"], where + ".intensity"))}
    if t == "spot":
        check_keys(light, {"type", "position", "direction", "intensity", "cutoff_angle",
                           "beam_width"}, where)
        p = np.array(vec3(light["position"], where + ".position"))
        d = np.array(vec3(light["direction"], where + ".direction"))
        d = d / np.linalg.norm(d)
        up = [0.0, 1.0, 0.0] if abs(d[1]) < 0.9 else [1.0, 0.0, 0.0]
        cutoff = float(light.get("cutoff_angle", 20.0))
        return {"type": "spot",
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=p.tolist(), target=(p + d).tolist(), up=up),
                "intensity": rgb_spec(vec3(light["intensity"], where + ".intensity")),
                "cutoff_angle": cutoff,
                "beam_width": float(light.get("beam_width", 0.75 * cutoff))}
    if t == "directional":
        check_keys(light, {"type", "direction", "irradiance"}, where)
        return {"type": "directional",
                "direction": vec3(light["direction"], where + ".direction"),
                "irradiance": rgb_spec(vec3(light["irradiance"], where + ".irradiance"))}
    raise SceneError("%s: unknown light type '%s'" % (where, t))


def emission_of(mi, mat, where):
    e = mat.get("emission", [0.0, 0.0, 0.0])
    if isinstance(e, TexRef):
        if max(e.factor) <= 0.0:
            return None
        return {"type": "area", "radiance": bitmap_texture(mi, e)}
    e = vec3(e, where + ".emission")
    if max(e) <= 0.0:
        return None
    return {"type": "area", "radiance": rgb_spec(e)}


def gradient_envmap(mi, zenith, horizon, width=64, height=1024):
    """Lat-long bitmap for Mitsuba's envmap: row j covers theta = pi*(j+0.5)/height
    measured from +Y (Mitsuba: uv.y = acos(dir.y)/pi), so dir.y = cos(theta)."""
    theta = (np.arange(height) + 0.5) / height * math.pi
    t = 0.5 * (np.cos(theta) + 1.0)
    z, h = np.array(zenith), np.array(horizon)
    rows = h[None, :] * (1.0 - t[:, None]) + z[None, :] * t[:, None]
    img = np.repeat(rows[:, None, :], width, axis=1).astype(np.float32)
    return {"type": "envmap", "bitmap": mi.Bitmap(img, mi.Bitmap.PixelFormat.RGB)}


def _sky_number(sky, key, default):
    v = sky.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise SceneError("[sky].%s must be a number, got %r" % (key, v))
    v = float(v)
    if not math.isfinite(v):
        raise SceneError("[sky].%s must be finite, got %r" % (key, v))
    return v


def environment_envmap(mi, sky, base):
    """[sky] environment = "f.hdr" | "f.exr", rotate (degrees about +Y), strength -> Mitsuba
    `envmap` (None where strength is 0: a black sky). The scene format reads the map at
    d' = R_y(-rotate) d, u = atan2(d'.x, -d'.z) / 2 pi, v = acos(d'.y) / pi (u = 0 the left
    edge, v = 0 the top row), which is Mitsuba's envmap with to_world = rotate(+Y, rotate),
    scale = strength (checked by tools/check_envmap.py). The image is read here
    (load_texture: HDR and EXR as stored, RGB) and handed over as a float bitmap, so that
    Mitsuba sees exactly the numbers our reader decodes."""
    for key in ("color", "zenith", "horizon"):
        if key in sky:
            raise SceneError("[sky].environment cannot be combined with `%s`" % key)
    name = sky["environment"]
    if not isinstance(name, str) or not name:
        raise SceneError("[sky].environment must be a file name, got %r" % (name,))
    ext = os.path.splitext(name)[1].lower()
    if ext not in (".hdr", ".exr"):
        raise SceneError("[sky].environment: %s: an environment map must be a .hdr or .exr "
                         "file" % name)
    path = os.path.join(base, name)
    if not os.path.isfile(path):
        raise SceneError("[sky].environment: file not found: %s" % path)
    rotate = _sky_number(sky, "rotate", 0.0)
    strength = _sky_number(sky, "strength", 1.0)
    if strength < 0:
        raise SceneError("[sky].strength must be >= 0, got %r" % strength)
    img = load_texture(mi, path, "[sky].environment")
    if not np.all(np.isfinite(img)) or np.any(img < 0):
        raise SceneError("[sky].environment: %s has negative or non-finite texels" % path)
    if strength == 0 or not np.any(img > 0):
        return None
    bmp = mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32), mi.Bitmap.PixelFormat.RGB)
    return {"type": "envmap", "bitmap": bmp, "scale": strength,
            "to_world": mi.ScalarTransform4f().rotate([0.0, 1.0, 0.0], rotate)}


def icosphere(level):
    """Unit-sphere vertices and counter-clockwise triangles of an icosahedron subdivided
    `level` times: the algorithm, vertex and face order of meshtrace's src/scene/sphere.rs."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    verts = [np.array(v, dtype=np.float64) / np.linalg.norm(v) for v in (
        [-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
        [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1])]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9),
             (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2),
             (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
             (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        mid = {}

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                v = verts[a] + verts[b]
                verts.append(v / np.linalg.norm(v))
                mid[key] = len(verts) - 1
            return mid[key]
        nxt = []
        for a, b, c in faces:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nxt += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = nxt
    return np.array(verts), np.array(faces)


def default_subdivisions():
    """meshtrace's default level: the first whose largest gap between a triangle (at its
    centroid) and the unit sphere is below 1/1000 (src/scene/sphere.rs)."""
    level = 0
    while True:
        v, f = icosphere(level)
        if (1.0 - np.linalg.norm(v[f].mean(axis=1), axis=1)).max() < 1e-3:
            return level
        level += 1


def icosphere_obj(path, level):
    """Writes the unit icosphere as an OBJ with smooth normals (the vertex directions)."""
    v, f = icosphere(level)
    with open(path, "w") as fh:
        fh.write("".join("v %.9g %.9g %.9g\n" % tuple(p) for p in v))
        fh.write("".join("vn %.9g %.9g %.9g\n" % tuple(p) for p in v))
        fh.write("".join("f %d//%d %d//%d %d//%d\n" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1)
                         for a, b, c in f))


# ---------------------------------------------------------------- glTF

def is_gltf(path):
    return os.path.splitext(path)[1].lower() in (".gltf", ".glb")


GLTF_NO_TWIN = (
    "has no exact Mitsuba twin; a glTF material (meshtrace's pbr) translates only as: "
    "KHR_materials_specular specularFactor 0 with metallic 0 and no transmission "
    "(Lambertian: base colour x texture), metallic 1 roughness 0 with a white base colour "
    "(a perfect mirror), or transmission 1 roughness 0 metallic 0 with a white base "
    "colour, specular 1 and KHR_materials_volume thicknessFactor > 0 (a dielectric of the "
    "KHR_materials_ior ior)")

# glTF sampler wrap modes -> Mitsuba's bitmap wrap_mode
WRAP_MODES = {10497: "repeat", 33071: "clamp", 33648: "mirror"}
# material extensions the translation reads (any other on a material is refused)
MATERIAL_EXTENSIONS = {"KHR_materials_emissive_strength", "KHR_materials_ior",
                       "KHR_materials_specular", "KHR_materials_transmission",
                       "KHR_materials_volume"}


class GltfMaterials:
    """glTF materials translated on first use (as meshtrace converts them): each a dict
    with `bsdf` (Mitsuba), `emitter` (an `area` emitter or None), `emissive` (meshtrace's
    is_emissive: emissiveFactor x strength > 0), `visible` (False for an alpha MASK whose
    constant alpha is below its cut-off), `textured` (a texture of the material was read:
    meshtrace then needs TEXCOORD_0), `normal_map` (a TexRef or None; `bsdf` is without
    it, see normal_map_bsdf)."""

    def __init__(self, mi, doc, tmpdir, stem):
        self.mi, self.doc, self.tmpdir, self.stem = mi, doc, tmpdir, stem
        self.cache = {}
        self.images = {}

    def error(self, at, msg):
        return gr.GltfError("%s: %s: %s" % (self.doc.shown, at, msg))

    def number(self, x, at, default):
        x = default if x is None else x
        if not (isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)):
            raise self.error(at, "must be a finite number")
        return float(x)

    def unit(self, x, at, default):
        """A factor in [0, 1]: one outside is clamped with a warning (as meshtrace)."""
        x = self.number(x, at, default)
        if not 0.0 <= x <= 1.0:
            self.doc.warn(at, "%g is outside [0, 1] and is clamped" % x)
        return min(max(x, 0.0), 1.0)

    def image_path(self, source, at):
        """A file path Mitsuba can read for image `source` (embedded images are written to
        the temporary folder), or None when its file is missing (a warning)."""
        if source in self.images:
            return self.images[source]
        img = self.doc.image(source, at)
        path = None
        if img is not None and img[0] == "file":
            path = img[1]
        elif img is not None:
            data, mime = img[1], img[2]
            ext = {"image/png": ".png", "image/jpeg": ".jpg"}.get(mime)
            if ext is None:
                ext = ".png" if data[:8] == b"\x89PNG\r\n\x1a\n" else \
                    ".jpg" if data[:2] == b"\xff\xd8" else None
            if ext is None:
                raise self.error("images[%d]" % source, "is neither PNG nor JPEG (mimeType %r)"
                                 % (mime,))
            path = os.path.join(self.tmpdir, "%s_image%d%s" % (self.stem, source, ext))
            with open(path, "wb") as fh:
                fh.write(data)
            # a file of this name read before (another scene in this process) is stale
            _raw_images.pop(path, None)
            _images.pop((path, False), None)
            _images.pop((path, True), None)
        self.images[source] = path
        return path

    def texture(self, info, at, factor, linear=False):
        """TexRef of a textureInfo (KHR_texture_transform included), or None when its
        image file is missing (a warning: the factor alone is used, as meshtrace)."""
        if not isinstance(info, dict):
            raise self.error(at, "must be a textureInfo object")
        idx = info.get("index")
        tex = self.doc.get("textures", idx, at + ".index")
        wrap = "repeat"
        if "sampler" in tex:
            smp = self.doc.get("samplers", tex["sampler"], "textures[%d].sampler" % idx)
            ws, wt = smp.get("wrapS", 10497), smp.get("wrapT", 10497)
            if ws not in WRAP_MODES or wt not in WRAP_MODES:
                raise self.error("samplers[%d]" % tex["sampler"], "invalid wrap mode")
            if ws != wt:
                raise self.error("samplers[%d]" % tex["sampler"], "wrapS %d and wrapT %d "
                                 "differ: Mitsuba's bitmap has one wrap mode for both axes "
                                 "(no exact twin)" % (ws, wt))
            wrap = WRAP_MODES[ws]
        tex_coord = info.get("texCoord", 0)
        matrix = np.eye(3)
        tt = info.get("extensions", {}).get("KHR_texture_transform")
        if tt is not None:
            ta = at + ".extensions.KHR_texture_transform"
            off = tt.get("offset", [0.0, 0.0])
            sc = tt.get("scale", [1.0, 1.0])
            rot = self.number(tt.get("rotation"), ta + ".rotation", 0.0)
            if not (isinstance(off, list) and len(off) == 2 and isinstance(sc, list)
                    and len(sc) == 2):
                raise self.error(ta, "offset and scale must be 2 numbers each")
            off = [self.number(v, ta + ".offset", 0.0) for v in off]
            sc = [self.number(v, ta + ".scale", 1.0) for v in sc]
            # KHR_texture_transform: T * R * S with R = [[cos, sin], [-sin, cos]] (the
            # image turns clockwise seen with v down: Khronos's TextureTransformTest; see
            # check_texture_uv.py --gltf)
            c, sn = math.cos(rot), math.sin(rot)
            matrix = np.array([[c * sc[0], sn * sc[1], off[0]],
                               [-sn * sc[0], c * sc[1], off[1]],
                               [0.0, 0.0, 1.0]])
            tex_coord = tt.get("texCoord", tex_coord)
        if tex_coord != 0:
            raise self.error(at, "uses TEXCOORD_%s: only TEXCOORD_0 is translated (Mitsuba "
                             "meshes carry one UV set)" % tex_coord)
        if "source" not in tex:
            raise self.error("textures[%d]" % idx, "has no source image")
        path = self.image_path(tex["source"], "textures[%d].source" % idx)
        if path is None:
            return None
        return TexRef(path, (1.0, 1.0), [float(x) for x in factor], at, gltf_uv=True,
                      matrix=matrix, linear=linear, wrap=wrap)

    def all_max(self, ref, channels):
        """Whether the image of `ref` is 1 (the format's maximum) in every texel of
        `channels` (0-3: R, G, B, A; a grey image's one channel stands for R, G and B, and
        an image without alpha has alpha 1)."""
        raw, _ = load_raw(self.mi, ref.path, ref.where)
        n = raw.shape[2]
        for c in channels:
            if c == 3:
                k = {2: 1, 4: 3}.get(n)
            else:
                k = 0 if n < 3 else c
            if k is not None and not np.all(raw[:, :, k] >= 1.0):
                return False
        return True

    def get(self, i, prim_at):
        if i in self.cache:
            return self.cache[i]
        if i is None:
            raise self.error(prim_at, "has no material: glTF's default material (white, "
                             "metallic 1, roughness 1) " + GLTF_NO_TWIN)
        m = self.doc.get("materials", i, prim_at + ".material")
        out = self.convert(i, m)
        self.cache[i] = out
        return out

    def convert(self, i, m):
        at = "materials[%d]" % i
        ext = m.get("extensions", {})
        for e in ext:
            if e not in MATERIAL_EXTENSIONS:
                raise self.error("%s.extensions.%s" % (at, e), GLTF_NO_TWIN)
        pbr = m.get("pbrMetallicRoughness", {})
        pa = at + ".pbrMetallicRoughness"
        bcf = pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0])
        if not (isinstance(bcf, list) and len(bcf) == 4):
            raise self.error(pa + ".baseColorFactor", "must be 4 numbers")
        base = [self.unit(v, pa + ".baseColorFactor", 1.0) for v in bcf]
        metallic = self.unit(pbr.get("metallicFactor"), pa + ".metallicFactor", 1.0)
        rough = self.unit(pbr.get("roughnessFactor"), pa + ".roughnessFactor", 1.0)
        textured = False
        base_tex = None
        if "baseColorTexture" in pbr:
            base_tex = self.texture(pbr["baseColorTexture"], pa + ".baseColorTexture", base[:3])
        mr_tex = None
        if "metallicRoughnessTexture" in pbr:
            mr_tex = self.texture(pbr["metallicRoughnessTexture"],
                                  pa + ".metallicRoughnessTexture", [1.0] * 3, linear=True)
        specular, spec_colour = 1.0, [1.0, 1.0, 1.0]
        sp = ext.get("KHR_materials_specular")
        spa = at + ".extensions.KHR_materials_specular"
        if sp is not None:
            specular = self.unit(sp.get("specularFactor"), spa + ".specularFactor", 1.0)
            spec_colour = sp.get("specularColorFactor", [1.0, 1.0, 1.0])
            if not (isinstance(spec_colour, list) and len(spec_colour) == 3):
                raise self.error(spa + ".specularColorFactor", "must be 3 numbers")
            spec_colour = [self.number(v, spa + ".specularColorFactor", 1.0)
                           for v in spec_colour]
        transmission, tr_tex = 0.0, None
        tr = ext.get("KHR_materials_transmission")
        tra = at + ".extensions.KHR_materials_transmission"
        if tr is not None:
            transmission = self.unit(tr.get("transmissionFactor"),
                                     tra + ".transmissionFactor", 0.0)
            if "transmissionTexture" in tr:
                tr_tex = self.texture(tr["transmissionTexture"], tra + ".transmissionTexture",
                                      [1.0] * 3, linear=True)
        vol = ext.get("KHR_materials_volume")
        thick = False
        if vol is not None:
            va = at + ".extensions.KHR_materials_volume"
            thick = self.number(vol.get("thicknessFactor"), va + ".thicknessFactor", 0.0) > 0
            ad = vol.get("attenuationDistance")
            if ad is not None or vol.get("attenuationColor", [1, 1, 1]) != [1, 1, 1]:
                raise self.error(va, "volume attenuation " + GLTF_NO_TWIN)
        ior = 1.5
        if "KHR_materials_ior" in ext:
            ia = at + ".extensions.KHR_materials_ior.ior"
            ior = self.number(ext["KHR_materials_ior"].get("ior"), ia, 1.5)
            if ior == 0.0:
                self.doc.warn(ia, "an ior of 0 is not supported; 1.5 is used")
                ior = 1.5
            elif ior < 1.0:
                raise self.error(ia, "must be at least 1, got %g" % ior)
        ef = m.get("emissiveFactor", [0.0, 0.0, 0.0])
        if not (isinstance(ef, list) and len(ef) == 3):
            raise self.error(at + ".emissiveFactor", "must be 3 numbers")
        emission = [self.number(v, at + ".emissiveFactor", 0.0) for v in ef]
        if min(emission) < 0:
            raise self.error(at + ".emissiveFactor", "must be at least 0")
        es = ext.get("KHR_materials_emissive_strength")
        if es is not None:
            sa = at + ".extensions.KHR_materials_emissive_strength.emissiveStrength"
            strength = self.number(es.get("emissiveStrength"), sa, 1.0)
            if strength < 0:
                raise self.error(sa, "must be at least 0")
            emission = [e * strength for e in emission]
        em_tex = None
        if "emissiveTexture" in m:
            em_tex = self.texture(m["emissiveTexture"], at + ".emissiveTexture", emission)
        normal_map = None
        if "normalTexture" in m:
            na = at + ".normalTexture"
            nscale = self.number(m["normalTexture"].get("scale"), na + ".scale", 1.0)
            if nscale != 1.0:
                raise self.error(na + ".scale", NORMAL_MAP_STRENGTH_REFUSED.replace(
                    "a normal map strength", "a normalTexture scale"))
            normal_map = self.texture(m["normalTexture"], na, [1.0] * 3, linear=True)
        if "occlusionTexture" in m:
            self.doc.warn(at + ".occlusionTexture", "is ignored (a path tracer's own "
                          "shadowing stands for it), as meshtrace does")
        textured = any(t is not None for t in (base_tex, mr_tex, tr_tex, em_tex, normal_map))

        # alpha: OPAQUE; MASK with a constant alpha is opaque or absent; the rest refused
        mode = m.get("alphaMode", "OPAQUE")
        visible = True
        if mode not in ("OPAQUE", "MASK", "BLEND"):
            raise self.error(at + ".alphaMode", "is not OPAQUE, MASK or BLEND")
        if mode != "OPAQUE":
            tex_alpha_one = base_tex is None or self.all_max(base_tex, [3])
            if mode == "BLEND":
                if not (base[3] == 1.0 and tex_alpha_one):
                    raise self.error(at + ".alphaMode", "BLEND with an alpha below 1 " +
                                     GLTF_NO_TWIN + " (meshtrace cuts out at 0.5; the "
                                     "specification blends)")
            else:
                if not tex_alpha_one:
                    raise self.error(at + ".alphaMode", "MASK with a base colour texture's "
                                     "varying alpha has no exact Mitsuba twin (the cut-out "
                                     "follows the bilinear alpha)")
                cutoff = self.unit(m.get("alphaCutoff"), at + ".alphaCutoff", 0.5)
                visible = base[3] >= cutoff

        white = base[:3] == [1.0, 1.0, 1.0] and (base_tex is None or
                                                  self.all_max(base_tex, [0, 1, 2]))
        desc = ("(base colour %s%s, metallic %g, roughness %g, specular %g, transmission %g%s)"
                % ([round(x, 6) for x in base[:3]], " x texture" if base_tex else "",
                   metallic, rough, specular, transmission,
                   ", volume" if thick else ""))
        if specular == 0.0 and metallic == 0.0 and transmission == 0.0:
            refl = bitmap_texture(self.mi, base_tex) if base_tex is not None else \
                rgb_spec(base[:3])
            bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": refl}}
        elif metallic == 1.0 and rough == 0.0 and white:
            if mr_tex is not None and not self.all_max(mr_tex, [2]):
                raise self.error(pa + ".metallicRoughnessTexture", "a metallic texture "
                                 "below 1 " + GLTF_NO_TWIN)
            bsdf = {"type": "twosided", "bsdf": {
                "type": "conductor", "material": "none",
                "specular_reflectance": rgb_spec([1.0, 1.0, 1.0])}}
        elif (transmission == 1.0 and rough == 0.0 and metallic == 0.0 and white
              and specular == 1.0 and spec_colour == [1.0, 1.0, 1.0] and thick):
            if tr_tex is not None and not self.all_max(tr_tex, [0]):
                raise self.error(tra + ".transmissionTexture", "a transmission texture "
                                 "below 1 " + GLTF_NO_TWIN)
            if sp is not None and ("specularTexture" in sp or "specularColorTexture" in sp):
                raise self.error(spa, "specularTexture / specularColorTexture on a "
                                 "dielectric " + GLTF_NO_TWIN)
            bsdf = {"type": "dielectric", "int_ior": ior, "ext_ior": 1.0}
        else:
            raise self.error(at, "this material %s %s" % (desc, GLTF_NO_TWIN))
        emitter = None
        if max(emission) > 0:
            rad = bitmap_texture(self.mi, em_tex) if em_tex is not None else \
                rgb_spec(emission)
            emitter = {"type": "area", "radiance": rad}
        name = m.get("name", at)
        return {"bsdf": bsdf, "emitter": emitter, "emissive": max(emission) > 0,
                "visible": visible, "textured": textured, "normal_map": normal_map,
                "name": name, "at": at}


def mitsuba_light(mi, light):
    """Mitsuba emitter of a glTF punctual light (gltf_read.Light, world space)."""
    p = [float(x) for x in light.position]
    if light.type == "point":
        return {"type": "point", "position": p, "intensity": rgb_spec(light.power)}
    d = np.asarray(light.direction, dtype=np.float64)
    if light.type == "directional":
        return {"type": "directional", "direction": d.tolist(),
                "irradiance": rgb_spec(light.power)}
    up = [0.0, 1.0, 0.0] if abs(d[1]) < 0.9 else [1.0, 0.0, 0.0]
    return {"type": "spot",
            "to_world": mi.ScalarTransform4f().look_at(origin=p, target=(np.array(p) + d).tolist(),
                                                       up=up),
            "intensity": rgb_spec(light.power),
            "cutoff_angle": math.degrees(light.cutoff),
            "beam_width": math.degrees(light.beam_width)}


def write_obj(fn, P, N, UV):
    """A triangle OBJ of corner arrays (T, 3, 3) positions, normals or None, (T, 3, 2) UVs
    or None (written as they are: load with flip_tex_coords = false)."""
    T = len(P)
    with open(fn, "w") as fh:
        fh.write("".join("v %.9g %.9g %.9g\n" % tuple(v) for v in P.reshape(-1, 3)))
        if UV is not None:
            fh.write("".join("vt %.9g %.9g\n" % tuple(v) for v in UV.reshape(-1, 2)))
        if N is not None:
            fh.write("".join("vn %.9g %.9g %.9g\n" % tuple(v) for v in N.reshape(-1, 3)))
        k = np.arange(1, 3 * T + 1).reshape(T, 3)
        if UV is not None and N is not None:
            fh.write("".join("f %d/%d/%d %d/%d/%d %d/%d/%d\n" % (a, a, a, b, b, b, c, c, c)
                             for a, b, c in k))
        elif UV is not None:
            fh.write("".join("f %d/%d %d/%d %d/%d\n" % (a, a, b, b, c, c) for a, b, c in k))
        elif N is not None:
            fh.write("".join("f %d//%d %d//%d %d//%d\n" % (a, a, b, b, c, c) for a, b, c in k))
        else:
            fh.write("".join("f %d %d %d\n" % (a, b, c) for a, b, c in k))


def gltf_geometry(mi, path, M, override, tmpdir, stem, shape_with):
    """The shapes and lights a glTF file brings, its nodes' world matrices under the
    object matrix M (numpy 4x4). `override` is (name, TOML material, where) replacing the
    file's materials, or None; `shape_with(shape, material, where)` completes a shape with
    a TOML material. Returns (shapes, lights, info) with info: camera
    (gltf_read.Camera or None), bounds (min, max of the world-space vertices of the
    non-degenerate triangles, or None), emissive (whether a triangle's material emits),
    warnings printed."""
    doc = gr.Doc(path)
    try:
        return _gltf_geometry(mi, doc, M, override, tmpdir, stem, shape_with)
    except (AttributeError, TypeError, KeyError, ValueError, IndexError) as e:
        # a value of the wrong JSON type deeper than gltf_read.Doc checks
        raise gr.GltfError("%s: the JSON does not follow the glTF 2.0 schema (%s: %s)"
                           % (doc.shown, type(e).__name__, e))


def _gltf_geometry(mi, doc, M, override, tmpdir, stem, shape_with):
    sc = gr.read_scene(doc)
    mats = GltfMaterials(mi, doc, tmpdir, stem)
    groups = {}     # (material key, has normals, has uvs, mirrored) -> [P, N, UV] lists
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    emissive = False
    for part in sc.parts:
        W = M @ part.matrix
        L = W[:3, :3]
        P = part.positions @ L.T + W[:3, 3]
        tris = part.tris.copy()
        if np.linalg.det(part.matrix[:3, :3]) < 0:
            # a mirroring node: its front faces wind clockwise (glTF 2.0, 3.7.4), so
            # the corners are swapped to keep the front counter-clockwise, as meshtrace
            tris[:, [1, 2]] = tris[:, [2, 1]]
        Pt = P[tris]
        # meshtrace drops triangles of zero (or non-finite) area, computed in f32
        P32 = P.astype(np.float32)[tris]
        area2 = np.linalg.norm(np.cross(P32[:, 1] - P32[:, 0], P32[:, 2] - P32[:, 0]), axis=1)
        keep = np.isfinite(area2) & (area2 > 0)
        if override is not None:
            mat, key = override[1], ("toml",)
        else:
            mat = mats.get(part.material, part.at)
            key = ("gltf", part.material)
        if keep.any():
            lo = np.minimum(lo, Pt[keep].reshape(-1, 3).min(axis=0))
            hi = np.maximum(hi, Pt[keep].reshape(-1, 3).max(axis=0))
        if override is None:
            emissive |= bool(keep.any() and mat["emissive"])
            if mat["textured"] and part.uvs is None:
                raise gr.GltfError("%s: %s: material %s uses a texture, but the primitive has "
                                   "no TEXCOORD_0" % (doc.shown, part.at, mat["name"]))
            if not mat["visible"]:
                continue
        elif uses_texture(mat) and part.uvs is None:
            raise gr.GltfError("%s: %s: material '%s' uses a texture, but the primitive has "
                               "no TEXCOORD_0" % (doc.shown, part.at, override[0]))
        tris, Pt = tris[keep], Pt[keep]
        if not len(tris):
            continue
        has_n = np.zeros(len(tris), dtype=bool)
        Nt = None
        if part.normals is not None:
            Nw = part.normals @ np.linalg.inv(L)          # (L^-T n) as rows
            ln = np.linalg.norm(Nw, axis=1, keepdims=True)
            with np.errstate(divide="ignore", invalid="ignore"):
                Nw = np.where((ln > 0) & np.isfinite(ln), Nw / ln, 0.0)
            Nt = Nw[tris]
            # a corner without a normal (zero) leaves the triangle flat-shaded
            has_n = np.all(np.any(Nt != 0, axis=2), axis=1)
        UVt = part.uvs[tris] if part.uvs is not None else None
        face = np.cross(Pt[:, 1] - Pt[:, 0], Pt[:, 2] - Pt[:, 0])
        if override is None and mat["emitter"] is not None and Nt is not None:
            bad = has_n & np.any(np.einsum("tkj,tj->tk", Nt, face) < 0, axis=1)
            if bad.any():
                raise gr.GltfError(
                    "%s: %s: an emissive triangle's vertex normals face away from its "
                    "winding: meshtrace emits from the winding's front, Mitsuba's area "
                    "emitter from the shading normal's side (no exact twin)"
                    % (doc.shown, part.at))
        nmap = mat.get("normal_map")
        mirrored = np.zeros(len(tris), dtype=bool)
        if nmap is not None and UVt is not None:
            ns = np.where(has_n[:, None], Nt.mean(axis=1) if Nt is not None else face, face)
            mirrored = mirrored_uvs(Pt, UVt, ns, gltf=True)
            if part.tangents is not None:
                check_tangents(doc, part, tris, Pt, UVt, Nt, has_n, face, mirrored, L)
        for hn in (False, True):
            for mir in (False, True):
                sel = (has_n == hn) & (mirrored == mir)
                if not sel.any():
                    continue
                g = groups.setdefault((key, hn, UVt is not None, mir), [[], [], [], mat])
                g[0].append(Pt[sel])
                g[1].append(Nt[sel] if hn else None)
                g[2].append(UVt[sel] if UVt is not None else None)
    shapes = []
    for gi, ((key, hn, huv, mir), (Ps, Ns, UVs, mat)) in enumerate(groups.items()):
        fn = os.path.join(tmpdir, "%s_%d.obj" % (stem, gi))
        write_obj(fn, np.concatenate(Ps), np.concatenate(Ns) if hn else None,
                  np.concatenate(UVs) if huv else None)
        shape = {"type": "obj", "filename": fn, "face_normals": not hn,
                 "flip_tex_coords": False}
        if key[0] == "toml":
            m = mat
            if mir:
                m = dict(mat)
                m["normal_map"] = mat["normal_map"].flipped()
            shape = shape_with(shape, m, override[2])
            if shape is not None:
                shapes.append(shape)
            continue
        bsdf = mat["bsdf"]
        if mat["normal_map"] is not None:
            nm = mat["normal_map"]
            bsdf = normal_map_bsdf(mi, bsdf, nm.flipped() if mir else nm)
        shape["bsdf"] = bsdf
        if mat["emitter"] is not None:
            shape["emitter"] = mat["emitter"]
        shapes.append(shape)
    lights = []
    for light in sc.lights:
        placed = gr.transform_light(light, M)
        if placed is None:
            warn("%s: a light's direction collapses under its object's transform; the light "
                 "is dropped" % doc.shown)
            continue
        lights.append(mitsuba_light(mi, placed))
    for w in doc.warnings:
        warn(w)
    bounds = (lo, hi) if np.all(np.isfinite(lo)) else None
    return shapes, lights, {"camera": sc.camera, "bounds": bounds, "emissive": emissive}


def check_tangents(doc, part, tris, Pt, UVt, Nt, has_n, face, mirrored, L):
    """A normal-mapped primitive with its own TANGENT attribute: meshtrace uses those
    tangents, Mitsuba builds its frame from dp/du (normal_map_bsdf). The translation is
    exact only where they agree: at every corner, the file's tangent made perpendicular to
    the shading normal must be Mitsuba's s (to 1e-3), and its bitangent w (n x t) (w
    flipped by a mirroring transform) must point the way the map's y is read (t, or -t
    where the green channel is flipped). Anything else is refused."""
    T = part.tangents[tris]                                      # (n, 3, 4)
    sign = -1.0 if np.linalg.det(L) < 0 else 1.0
    Tw = T[:, :, :3] @ L.T
    n = np.where(has_n[:, None, None], Nt if Nt is not None else 0.0, face[:, None, :])
    n = n / np.linalg.norm(n, axis=2, keepdims=True)
    Tw = Tw - n * np.einsum("tkj,tkj->tk", Tw, n)[..., None]
    lt = np.linalg.norm(Tw, axis=2, keepdims=True)
    given = (lt[..., 0] > 0) & np.all(T[:, :, 3:] != 0, axis=2)
    with np.errstate(divide="ignore", invalid="ignore"):
        Tw = Tw / lt
    dp0, dp1 = Pt[:, 1] - Pt[:, 0], Pt[:, 2] - Pt[:, 0]
    d0, d1 = UVt[:, 1] - UVt[:, 0], UVt[:, 2] - UVt[:, 0]
    det = d0[:, 0] * d1[:, 1] - d0[:, 1] * d1[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        dp_du = (d1[:, 1:2] * dp0 - d0[:, 1:2] * dp1) / det[:, None]
    sm = dp_du[:, None, :] - n * np.einsum("tj,tkj->tk", dp_du, n)[..., None]
    with np.errstate(divide="ignore", invalid="ignore"):
        sm = sm / np.linalg.norm(sm, axis=2, keepdims=True)
    y_axis = np.cross(n, sm) * np.where(mirrored, -1.0, 1.0)[:, None, None]
    bw = (T[:, :, 3] * sign)[..., None] * np.cross(n, Tw)
    bad = given & ((np.linalg.norm(Tw - sm, axis=2) > 1e-3) |
                   (np.einsum("tkj,tkj->tk", bw, y_axis) <= 0))
    if bad.any():
        raise gr.GltfError(
            "%s: %s.attributes[\"TANGENT\"]: the file's tangents differ from the frame Mitsuba's "
            "normalmap builds from the UVs (dp/du) at %d of %d corners; meshtrace uses the "
            "file's tangents, so the normal map has no exact Mitsuba twin here"
            % (doc.shown, part.at, int(bad.sum()), bad.size))


def framing_camera(lo, hi):
    """meshtrace's camera for a bare mesh (src/scene/camera.rs Camera::framing): vfov 40,
    looking at the bounds' centre from the front (+Z) and slightly above, at a distance
    that fits the bounding sphere with a margin of 1.1."""
    vfov = 40.0
    center = 0.5 * (lo + hi)
    resolvable = 1e-5 * (1.0 + np.abs(center).max())
    radius = max(0.5 * np.linalg.norm(hi - lo), resolvable)
    distance = 1.1 * radius / math.sin(0.5 * math.radians(vfov))
    d = np.array([0.0, 0.25, 1.0])
    position = center + distance * d / np.linalg.norm(d)
    return position, center, [0.0, 1.0, 0.0], vfov


def build_bare_gltf(mi, path, args, tmpdir):
    """A bare glTF file as meshtrace loads it (src/scene/load.rs load_bare_gltf): its first
    perspective camera (else the bare-mesh framing), a black sky when it brings its own
    light (punctual lights or emissive materials), else a white constant sky; meshtrace's
    default render settings (640 x 480, 64 spp, max_depth 8, seed 0) unless overridden."""
    width = args.width or 640
    height = args.height or 480
    spp = args.spp or 64
    max_depth = args.max_depth if args.max_depth is not None else 8
    seed = args.seed if args.seed is not None else 0

    def shape_with(shape, mat, where):
        raise AssertionError("no TOML materials in a bare glTF")
    shapes, lights, info = gltf_geometry(mi, path, np.eye(4), None, tmpdir, "g", shape_with)
    if info["bounds"] is None:
        raise SceneError("%s: scene: the default scene has no triangles to render" % path)
    cam = info["camera"]
    if cam is not None:
        pos = cam.position.tolist()
        target = (cam.position + cam.forward).tolist()
        up, vfov = cam.up.tolist(), cam.yfov_deg
    else:
        p, c, up, vfov = framing_camera(*info["bounds"])
        pos, target = p.tolist(), c.tolist()
    scene = {"type": "scene",
             "integrator": {"type": "path", "max_depth": max_depth, "rr_depth": 5,
                            "hide_emitters": False},
             "sensor": perspective_sensor(mi, pos, target, up, vfov, width, height, spp)}
    if not (info["emissive"] or lights):
        scene["sky"] = {"type": "constant", "radiance": rgb_spec([1.0, 1.0, 1.0])}
    for i, s in enumerate(shapes):
        scene["shape_%d" % i] = s
    for i, li in enumerate(lights):
        scene["light_%d" % i] = li
    return scene, dict(width=width, height=height, spp=spp, seed=seed, max_depth=max_depth)


def perspective_sensor(mi, pos, target, up, vfov, width, height, spp):
    # Mitsuba's look_at: image x grows towards cross(forward, up), as in meshtrace.
    return {
        "type": "perspective",
        "fov_axis": "y",
        "fov": vfov,
        "near_clip": 1e-4,
        "far_clip": 1e7,
        "to_world": mi.ScalarTransform4f().look_at(origin=pos, target=target, up=up),
        "sampler": {"type": "independent", "sample_count": spp},
        "film": {"type": "hdrfilm", "width": width, "height": height,
                 "pixel_format": "rgb", "component_format": "float32",
                 "rfilter": {"type": "box"}},
    }


def build_scene_dict(mi, path, args, tmpdir):
    """The Mitsuba scene dict of a scene TOML or a bare glTF file, and its render options."""
    if is_gltf(path):
        return build_bare_gltf(mi, path, args, tmpdir)
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    check_keys(doc, {"camera", "render", "sky", "materials", "objects", "lights"}, "scene")
    base = os.path.dirname(os.path.abspath(path))

    render = doc.get("render", {})
    check_keys(render, {"width", "height", "spp", "max_depth", "seed"}, "[render]")
    width = args.width or int(render.get("width", 640))
    height = args.height or int(render.get("height", 480))
    spp = args.spp or int(render.get("spp", 64))
    max_depth = args.max_depth if args.max_depth is not None else int(render.get("max_depth", 8))
    seed = args.seed if args.seed is not None else int(render.get("seed", 0))

    cam = doc.get("camera")
    if cam is None:
        raise SceneError("missing [camera]")
    check_keys(cam, {"position", "look_at", "up", "vfov", "aperture", "focus_distance"}, "[camera]")
    pos = vec3(cam["position"], "camera.position")
    at = vec3(cam["look_at"], "camera.look_at")
    up = vec3(cam.get("up", [0.0, 1.0, 0.0]), "camera.up")
    vfov = float(cam.get("vfov", 40.0))
    aperture = float(cam.get("aperture", 0.0))
    focus = float(cam.get("focus_distance", math.dist(pos, at)))
    # Mitsuba's look_at: image x grows towards cross(forward, up), as in meshtrace.
    sensor = {
        "type": "thinlens" if aperture > 0 else "perspective",
        "fov_axis": "y",
        "fov": vfov,
        "near_clip": 1e-4,
        "far_clip": 1e7,
        "to_world": mi.ScalarTransform4f().look_at(origin=pos, target=at, up=up),
        "sampler": {"type": "independent", "sample_count": spp},
        "film": {"type": "hdrfilm", "width": width, "height": height,
                 "pixel_format": "rgb", "component_format": "float32",
                 "rfilter": {"type": "box"}},
    }
    if aperture > 0:
        sensor["aperture_radius"] = aperture / 2.0
        sensor["focus_distance"] = focus

    scene = {"type": "scene",
             "integrator": {"type": "path", "max_depth": max_depth, "rr_depth": 5,
                            "hide_emitters": False},
             "sensor": sensor}

    sky = doc.get("sky")
    if sky is not None:
        check_keys(sky, {"color", "zenith", "horizon", "environment", "rotate", "strength"},
                   "[sky]")
        if "environment" in sky:
            env = environment_envmap(mi, sky, base)
            if env is not None:
                scene["sky"] = env
        elif "rotate" in sky or "strength" in sky:
            raise SceneError("[sky].%s: only valid with `environment`"
                             % ("rotate" if "rotate" in sky else "strength"))
        elif "color" in sky:
            if "zenith" in sky or "horizon" in sky:
                raise SceneError("[sky]: `color` excludes zenith/horizon")
            c = vec3(sky["color"], "sky.color")
            if max(c) > 0:
                scene["sky"] = {"type": "constant", "radiance": rgb_spec(c)}
        elif "zenith" in sky or "horizon" in sky:
            z = vec3(sky.get("zenith", [0.0, 0.0, 0.0]), "sky.zenith")
            h = vec3(sky.get("horizon", [0.0, 0.0, 0.0]), "sky.horizon")
            if z == h:
                if max(z) > 0:
                    scene["sky"] = {"type": "constant", "radiance": rgb_spec(z)}
            else:
                scene["sky"] = gradient_envmap(mi, z, h)

    n_lights = 0
    for li, light in enumerate(doc.get("lights", [])):
        scene["light_%d" % li] = punctual_light(mi, light, "lights[%d]" % li)
        n_lights += 1

    materials = {}
    for name, mat in doc.get("materials", {}).items():
        where = "[materials.%s]" % name
        materials[name] = resolve_toml_material(mat, base, where)
        mitsuba_bsdf(mi, materials[name], where)  # validate early

    def shape_with(shape, mat, where):
        """The shape with its material; None where a constant alpha mask cuts it out."""
        shape["bsdf"] = mitsuba_bsdf(mi, mat, where)
        if not alpha_visible(mi, mat, where):
            return None
        em = emission_of(mi, mat, where)
        if em is not None:
            shape["emitter"] = em
        return shape

    def add_shape(shape):
        nonlocal n_shapes
        if shape is not None:
            scene["shape_%d" % n_shapes] = shape
            n_shapes += 1

    n_shapes = 0
    for oi, obj in enumerate(doc.get("objects", [])):
        where = "objects[%d]" % oi
        check_keys(obj, {"mesh", "sphere", "material", "translate", "rotate", "scale", "matrix"},
                   where)
        mname = obj.get("material")
        if mname is not None and mname not in materials:
            raise SceneError("%s: unknown material '%s'" % (where, mname))
        M = object_matrix(obj, where)
        if ("mesh" in obj) == ("sphere" in obj):
            raise SceneError("%s: needs exactly one of `mesh` and `sphere`" % where)
        if "sphere" in obj:
            sp = obj["sphere"]
            check_keys(sp, {"center", "radius", "subdivisions"}, where + ".sphere")
            c = vec3(sp["center"], where + ".sphere.center")
            r = float(sp["radius"])
            to_world = M @ np.array([[r, 0, 0, c[0]], [0, r, 0, c[1]], [0, 0, r, c[2]],
                                     [0, 0, 0, 1.0]])
            if getattr(args, "spheres", "analytic") == "mesh":
                level = int(sp.get("subdivisions", default_subdivisions()))
                fn = os.path.join(tmpdir, "sphere_%d.obj" % level)
                if not os.path.exists(fn):
                    icosphere_obj(fn, level)
                shape = {"type": "obj", "filename": fn, "face_normals": False,
                         "to_world": mi.ScalarTransform4f(to_world.tolist())}
            else:
                if "subdivisions" in sp:
                    print("mitsuba_render: note: %s uses an analytic sphere (subdivisions "
                          "ignored)" % where, file=sys.stderr)
                sv = np.linalg.svd(M[:3, :3], compute_uv=False)
                if sv.max() - sv.min() > 1e-9 * max(sv.max(), 1.0):
                    raise SceneError("%s: non-uniform transform of a sphere is not supported "
                                     "with --spheres analytic" % where)
                shape = {"type": "sphere", "to_world": mi.ScalarTransform4f(to_world.tolist())}
            mat = materials[mname] if mname is not None else DEFAULT_MATERIAL
            if uses_texture(mat):
                raise SceneError("%s: material '%s' uses a texture, but a sphere has no "
                                 "UVs" % (where, mname))
            add_shape(shape_with(shape, mat, where))
            continue
        mesh_path = os.path.join(base, obj["mesh"])
        if not os.path.exists(mesh_path):
            raise SceneError("%s: mesh file not found: %s" % (where, mesh_path))
        if is_gltf(mesh_path):
            override = None if mname is None else (mname, materials[mname],
                                                   "[materials.%s]" % mname)
            try:
                shapes, lights, _ = gltf_geometry(mi, mesh_path, M, override, tmpdir,
                                                  "o%d" % oi, shape_with)
            except gr.GltfError as e:
                raise SceneError("%s: %s" % (where, e))
            for shape in shapes:
                add_shape(shape)
            for li in lights:
                scene["light_%d" % n_lights] = li
                n_lights += 1
            continue

        def pick(obj_mtl, mtl):
            if mname is not None:
                return materials[mname], mname
            if obj_mtl is not None and obj_mtl in mtl:
                return mtl_to_material(mtl[obj_mtl], obj_mtl), obj_mtl
            return DEFAULT_MATERIAL, None

        def has_normal_map(obj_mtl, mtl):
            return pick(obj_mtl, mtl)[0].get("normal_map") is not None
        for fn, obj_mtl, has_vn, has_vt, mtl, mirrored in split_obj(
                mesh_path, tmpdir, "o%d" % oi, has_normal_map, M):
            mat, mat_name = pick(obj_mtl, mtl)
            if mirrored:
                mat = dict(mat)
                mat["normal_map"] = mat["normal_map"].flipped()
            if uses_texture(mat) and not has_vt:
                raise SceneError("%s (%s): material '%s' uses a texture, but the mesh has "
                                 "faces without UVs (vt)" % (where, obj["mesh"], mat_name))
            shape = {"type": "obj", "filename": fn, "face_normals": not has_vn,
                     "flip_tex_coords": False,
                     "to_world": mi.ScalarTransform4f(M.tolist())}
            add_shape(shape_with(shape, mat, where))
    return scene, dict(width=width, height=height, spp=spp, seed=seed, max_depth=max_depth)


# ---------------------------------------------------------------- rendering

def pass_seed(seed, k):
    """Seed of pass k: pass 0 uses `seed` itself (so a one-pass render with seed s is
    Mitsuba's render with seed s); later passes are spread far from small seeds."""
    return (seed + k * 2654435761) % (1 << 32)


def render(mi, scene, width, height, spp, seed, lanes, verbose=True):
    per_pass = max(1, min(spp, lanes // (width * height)))
    acc = np.zeros((height, width, 3), dtype=np.float64)
    done, k = 0, 0
    t0 = time.time()
    while done < spp:
        n = min(per_pass, spp - done)
        img = mi.render(scene, spp=n, seed=pass_seed(seed, k))
        acc += np.array(img, dtype=np.float64)[:, :, :3] * n
        done += n
        k += 1
        if verbose and (k == 1 or k % 8 == 0 or done == spp):
            print("  %d/%d spp, %.1f s" % (done, spp, time.time() - t0), file=sys.stderr)
    return (acc / spp).astype(np.float32), time.time() - t0


def write_exr(mi, img, path):
    d = os.path.dirname(os.path.abspath(path))
    os.makedirs(d, exist_ok=True)
    mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32), mi.Bitmap.PixelFormat.RGB).write(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--spp", type=int)
    ap.add_argument("--seed", type=int)
    ap.add_argument("--width", type=int)
    ap.add_argument("--height", type=int)
    ap.add_argument("--max-depth", type=int)
    ap.add_argument("-o", "--output", default="mitsuba.exr")
    ap.add_argument("--variant", help="Mitsuba variant (default: llvm_ad_rgb, else scalar_rgb)")
    ap.add_argument("--lanes", type=int, default=1 << 23,
                    help="samples per pass at most (memory); default 2^23")
    ap.add_argument("--spheres", choices=("analytic", "mesh"), default="analytic",
                    help="`sphere` objects as Mitsuba's analytic sphere (default) or as "
                         "meshtrace's own icosphere mesh with smooth normals")
    args = ap.parse_args()
    mi = setup_mitsuba(args.variant)
    with tempfile.TemporaryDirectory(prefix="mitsuba_render_") as tmp:
        try:
            d, opts = build_scene_dict(mi, args.scene, args, tmp)
        except gr.GltfError as e:
            raise SystemExit("mitsuba_render: %s" % e)
        except (SceneError, KeyError, ValueError, TypeError, IndexError) as e:
            raise SystemExit("mitsuba_render: %s: %s" % (args.scene, e))
        scene = mi.load_dict(d)
    print("mitsuba_render: %s, %dx%d, %d spp, max_depth %d, seed %d, variant %s"
          % (args.scene, opts["width"], opts["height"], opts["spp"], opts["max_depth"],
             opts["seed"], mi.variant()), file=sys.stderr)
    img, secs = render(mi, scene, opts["width"], opts["height"], opts["spp"], opts["seed"],
                       args.lanes)
    write_exr(mi, img, args.output)
    print("mitsuba_render: wrote %s (%.1f s)" % (args.output, secs), file=sys.stderr)


if __name__ == "__main__":
    main()
