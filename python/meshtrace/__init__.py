"""meshtrace: a physically based path tracer for triangle meshes, rendering to NumPy arrays.

    import meshtrace as mt
    r = mt.Renderer()                        # one device, kept across renders
    scene = mt.load("model.glb")             # .toml, .obj, .gltf, .glb, "builtin:cornell"
    out = r.render(scene, spp=64, width=256, height=256, aovs=["depth", "normal"])
    out["color"]                             # float32 (H, W, 3), linear radiance
    mt.save(out, "out.exr")

The keyword arguments are the command line's settings under the same names; bad input
raises MeshtraceError (a ValueError) with the command line's message. docs/python.md has
the whole API.
"""

import os
from collections.abc import Mapping

# Mesa's implicit device-select Vulkan layer only reorders adapters (meshtrace picks its
# own) and, on a headless machine, prints "XDG_RUNTIME_DIR is invalid" errors; the command
# line turns it off the same way.
os.environ.setdefault("NODEVICE_SELECT", "1")

from . import cameras  # noqa: E402
from ._meshtrace import (  # noqa: E402
    PRESETS,
    Camera,
    MeshtraceError,
    Output,
    Renderer,
    Scene,
    __version__,
    load,
    save,
)

# An Output is a read-only mapping of names to arrays: dict(out), out.items(), "depth" in out.
Mapping.register(Output)

__all__ = [
    "PRESETS",
    "Camera",
    "MeshtraceError",
    "Output",
    "Renderer",
    "Scene",
    "__version__",
    "cameras",
    "load",
    "save",
]
