"""`Renderer.render` gives the bits that `meshtrace render` writes, on the CPU and on a
Vulkan GPU (lavapipe in CI), read back from the command line's EXR by OpenEXR."""

import numpy as np
import OpenEXR
import pytest

import meshtrace as mt

SETTINGS = dict(spp=4, width=40, height=30, seed=7)
FLAGS = ["--spp", "4", "--width", "40", "--height", "30", "--seed", "7"]


def exr_channels(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {name: c.pixels.copy() for name, c in f.channels().items()}


def check_same_bits(renderer, device, cli, tmp_path, scene):
    cli_exr = tmp_path / "cli.exr"
    cli("render", scene, "--device", device, *FLAGS, "--aov", "depth,normal,object_id", "-q", "-o", cli_exr)
    out = renderer.render(scene, **SETTINGS, aovs=["depth", "normal", "object_id"])
    channels = exr_channels(cli_exr)
    color = np.stack([channels["R"], channels["G"], channels["B"]], axis=-1)
    assert np.array_equal(out["color"], color)
    assert np.array_equal(out["depth"], channels["Z"])
    normal = np.stack([channels[f"normal.{k}"] for k in "XYZ"], axis=-1)
    assert np.array_equal(out["normal"], normal)
    assert np.array_equal(out["object_id"], channels["object_id"])
    # And saved, the same file to the byte.
    mt.save(out, tmp_path / "python.exr")
    assert (tmp_path / "python.exr").read_bytes() == cli_exr.read_bytes()


@pytest.mark.parametrize("which", ["builtin:cornell", "glb"])
def test_cpu_renders_the_command_lines_bits(cpu, cli, tmp_path, glb, which):
    check_same_bits(cpu, "cpu", cli, tmp_path, glb if which == "glb" else which)


def test_gpu_renders_the_command_lines_bits(gpu, cli, tmp_path, glb):
    assert gpu.device == "gpu"
    check_same_bits(gpu, "gpu", cli, tmp_path, glb)
    # The renderer keeps its device: a second scene on it matches too.
    check_same_bits(gpu, "gpu", cli, tmp_path, "builtin:cornell")


def test_kept_tables_render_the_bits_of_fresh_ones(cpu, gpu, glb):
    """A scene keeps its tables on a renderer's device for the next render: renders that
    differ in camera, settings and AOVs on them give the bits of renders on a fresh load."""
    for renderer in (cpu, gpu):
        scene = mt.load(glb)
        cams = mt.cameras.orbit(scene, views=3, elevation=20)
        asks = [
            dict(camera=cams[0], spp=2, width=24, height=16),
            dict(camera=cams[1], spp=3, width=20, height=20, aovs=["depth"], seed=4),
            dict(camera=cams[2], spp=2, width=24, height=16, transparent=True, caustics=False),
            dict(spp=1, width=16, height=16, geometry_only=True, aovs=["normal"]),
            dict(camera=cams[0], spp=2, width=24, height=16),
        ]
        for ask in asks:
            kept = renderer.render(scene, **ask)
            fresh = renderer.render(mt.load(glb), **ask)
            assert list(kept.keys()) == list(fresh.keys())
            for name in kept.keys():
                assert np.array_equal(kept[name], fresh[name]), (renderer.device, ask, name)


def test_bounce_limits_are_the_flags(cpu, cli, tmp_path):
    """The bounce limits' keywords give the bits of the flags of the same names, and a
    diffuse limit of 0 (direct light alone) darkens the Cornell box."""
    exr = tmp_path / "cli.exr"
    limits = ["--diffuse-bounces", "0", "--transmission-bounces", "2"]
    cli("render", "builtin:cornell", "--device", "cpu", *FLAGS, *limits, "-q", "-o", exr)
    out = cpu.render("builtin:cornell", **SETTINGS, diffuse_bounces=0, transmission_bounces=2)
    channels = exr_channels(exr)
    color = np.stack([channels["R"], channels["G"], channels["B"]], axis=-1)
    assert np.array_equal(out["color"], color)
    full = cpu.render("builtin:cornell", **SETTINGS)
    assert out["color"].mean() < 0.9 * full["color"].mean()
