"""Camera layouts: orbits like `meshtrace batch`'s turntables, and the dataset presets'
cameras (Zero123, Objaverse, Objaverse-XL, SyncDreamer, TRELLIS; docs/datasets.md).

    cams = mt.cameras.orbit(scene, views=12, elevation=30)
    cams = mt.cameras.preset(scene, "zero123")
    out = r.render(scene, camera=cams[0], **mt.cameras.preset_settings("zero123"))
"""

from ._meshtrace import orbit, preset, preset_settings

__all__ = ["orbit", "preset", "preset_settings"]
