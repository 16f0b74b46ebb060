"""Loading every kind of input, the arrays a render returns, and their conventions."""

import os

import numpy as np
import pytest

import meshtrace as mt

SMALL = dict(spp=2, width=32, height=24)


def sphere_dict(radius=1.0, colour=(0.8, 0.2, 0.2)):
    return {
        "camera": {"position": [0.0, 0.5, 4.0], "look_at": [0.0, 0.0, 0.0], "vfov": 40.0},
        "materials": {"red": {"type": "diffuse", "albedo": list(colour)}},
        "objects": [{"sphere": {"center": [0.0, 0.0, 0.0], "radius": radius}, "material": "red"}],
        "lights": [{"type": "point", "position": [2.0, 3.0, 4.0], "intensity": [20.0, 20.0, 20.0]}],
    }


def test_every_kind_of_input_renders(cpu, glb, obj):
    scenes = [
        mt.load(glb),
        mt.load(obj),
        mt.load("builtin:cornell"),
        mt.Scene.from_dict(sphere_dict()),
    ]
    for scene in scenes:
        out = cpu.render(scene, **SMALL)
        color = out["color"]
        assert color.shape == (24, 32, 3) and color.dtype == np.float32, scene
        assert np.isfinite(color).all() and color.max() > 0.0, scene
        assert out.samples == 2


def test_a_path_renders_without_loading_first(cpu, glb):
    a = cpu.render(glb, **SMALL)["color"]
    b = cpu.render(mt.load(glb), **SMALL)["color"]
    assert np.array_equal(a, b)


def test_aovs_have_their_shapes_and_meanings(cpu):
    scene = mt.Scene.from_dict(sphere_dict())
    out = cpu.render(
        scene,
        spp=4,
        width=48,
        height=48,
        aovs=["depth", "normal", "albedo", "alpha", "object_id", "material_id"],
    )
    assert list(out.keys()) == ["color", "depth", "normal", "albedo", "alpha", "object_id", "material_id"]
    depth, normal, alpha = out["depth"], out["normal"], out["alpha"]
    assert depth.shape == (48, 48) and normal.shape == (48, 48, 3) and alpha.shape == (48, 48)
    assert out["object_id"].dtype == np.uint32
    # The corners see the sky; the centre sees the sphere, 4.03 from the camera less its radius.
    assert alpha[0, 0] == 0.0 and np.isinf(depth[0, 0]) and out["object_id"][0, 0] == 2**32 - 1
    assert alpha[24, 24] == 1.0 and out["object_id"][24, 24] == 0
    assert abs(depth[24, 24] - (np.hypot(4.0, 0.5) - 1.0)) < 0.02
    # A unit normal that faces the camera (+Z) at the centre.
    assert abs(np.linalg.norm(normal[24, 24]) - 1.0) < 1e-5 and normal[24, 24, 2] > 0.9
    assert np.allclose(out["albedo"][24, 24], [0.8, 0.2, 0.2], atol=1e-6)


def test_arrays_come_without_a_copy(cpu):
    out = cpu.render("builtin:cornell", **SMALL, aovs=["depth"])
    for name in ("color", "depth"):
        a = out[name]
        # NumPy does not own the buffer: the render's vector is it, held by `a.base`.
        assert not a.flags.owndata and a.base is not None, name
        assert a.flags.c_contiguous and a.flags.writeable
    assert out["color"] is out["color"], "the same array each time"


def test_an_empty_aov_list_asks_for_none(cpu):
    assert list(cpu.render("builtin:cornell", **SMALL, aovs=[]).keys()) == ["color"]


def test_output_is_a_mapping(cpu):
    out = cpu.render("builtin:cornell", **SMALL, aovs=["alpha"])
    assert isinstance(out, __import__("collections.abc").abc.Mapping)
    assert set(dict(out)) == {"color", "alpha"} and "alpha" in out and "depth" not in out
    assert out.get("depth") is None and len(out) == 2
    with pytest.raises(KeyError):
        out["depth"]


def test_transparent_color_is_premultiplied_with_its_alpha(cpu):
    out = cpu.render(mt.Scene.from_dict(sphere_dict()), spp=4, width=32, height=32, transparent=True)
    assert "alpha" in out
    assert np.all(out["color"][out["alpha"] == 0.0] == 0.0)


def test_camera_and_settings_override_the_scene(cpu):
    scene = mt.Scene.from_dict(sphere_dict())
    own = cpu.render(scene, **SMALL, aovs=["depth"])
    far = mt.Camera.look_at([0.0, 0.0, 8.0], [0.0, 0.0, 0.0], fov=30.0)
    moved = cpu.render(scene, **SMALL, aovs=["depth"], camera=far)
    assert abs(moved["depth"][12, 16] - 7.0) < 0.05
    assert not np.array_equal(own["color"], moved["color"])
    # Another seed, another image; the same seed, the same bits.
    assert not np.array_equal(cpu.render(scene, **SMALL, seed=1)["color"], own["color"])
    assert np.array_equal(cpu.render(scene, **SMALL)["color"], own["color"])


def test_geometry_only_renders_the_base_colour(cpu):
    out = cpu.render(mt.Scene.from_dict(sphere_dict()), spp=1, width=32, height=32, geometry_only=True)
    assert np.allclose(out["color"][16, 16], [0.8, 0.2, 0.2], atol=1e-6)


def test_save_writes_what_the_command_line_writes(cpu, tmp_path):
    out = cpu.render("builtin:cornell", **SMALL, aovs=["depth"])
    mt.save(out, tmp_path / "a.png")
    assert (tmp_path / "a.png").exists() and (tmp_path / "a.aovs.exr").exists()
    out.save(tmp_path / "b.png", bit_depth=16)
    with pytest.raises(mt.MeshtraceError, match="bit_depth"):
        out.save(tmp_path / "c.png", bit_depth=12)


def test_save_forms_the_image_by_the_view_transform(cpu, tmp_path, monkeypatch):
    out = cpu.render("builtin:cornell", **SMALL)
    with pytest.raises(mt.MeshtraceError, match="view_transform: `aces` is not one of"):
        out.save(tmp_path / "a.png", view_transform="aces")
    with pytest.raises(mt.MeshtraceError, match="hold the linear radiance"):
        out.save(tmp_path / "a.exr", view_transform="agx")
    if os.environ.get("MESHTRACE_BLENDER_LUTS"):
        out.save(tmp_path / "standard.png")
        out.save(tmp_path / "agx.png", view_transform="agx")
        assert (tmp_path / "agx.png").read_bytes() != (tmp_path / "standard.png").read_bytes()
    # The LUTs are read once per folder: another folder's are read anew.
    other = tmp_path / "other"
    (other / "luts").mkdir(parents=True)
    (other / "luts" / "AgX_Base_sRGB.cube").write_text(
        "LUT_3D_SIZE 2\n" + "".join(f"{r} {g} {b}\n" for b in (0, 1) for g in (0, 1) for r in (0, 1))
    )
    monkeypatch.setenv("MESHTRACE_BLENDER_LUTS", str(other))
    out.save(tmp_path / "identity.png", view_transform="agx")
    if (tmp_path / "agx.png").exists():
        assert (tmp_path / "identity.png").read_bytes() != (tmp_path / "agx.png").read_bytes()
    with pytest.raises(mt.MeshtraceError, match="filmic_desat_33.cube not found"):
        out.save(tmp_path / "b.png", view_transform="filmic")
    assert not (tmp_path / "b.png").exists()


def test_without_the_studio_the_mask_holds_the_mesh_alone(cpu, glb, repo):
    env = repo / "assets" / "env" / "studio.hdr"
    staged = cpu.render(mt.load(glb), **SMALL, transparent=True)
    bare = mt.load(glb, studio=False, environment=env)
    alone = cpu.render(bare, **SMALL, transparent=True)
    # The studio's ground covers the frame's bottom; without it the mesh leaves sky there.
    assert staged["alpha"][-1].min() == 1.0 and alone["alpha"][-1].max() == 0.0
    assert alone["color"].max() > 0.0, "lit by the environment"
    # A render that asks for another environment keeps the scene's studio=False.
    park = repo / "assets" / "env" / "rooitou_park_256x128.hdr"
    other = cpu.render(bare, **SMALL, transparent=True, environment=park)
    assert np.array_equal(other["alpha"], alone["alpha"])
    assert not np.array_equal(other["color"], alone["color"])


def test_a_lighting_preset_replaces_the_scenes_light(cpu, glb):
    # A black world lights nothing; the mask stays the mesh's.
    sphere = mt.Scene.from_dict(sphere_dict())
    assert cpu.render(sphere, **SMALL)["color"].max() > 0.0
    dark = cpu.render(sphere, **SMALL, transparent=True, lighting={"preset": "uniform", "color": [0, 0, 0]})
    assert dark["alpha"].max() == 1.0 and dark["color"].max() == 0.0
    suns = mt.load(glb, lighting="suns")
    lit = cpu.render(suns, **SMALL, transparent=True)
    assert lit["color"].max() > 0.0
    with pytest.raises(mt.MeshtraceError, match="lighting.count: is not a parameter of the `area` preset"):
        cpu.render(glb, **SMALL, lighting={"preset": "area", "count": 3})
    with pytest.raises(mt.MeshtraceError, match="`sunny` is not a lighting preset"):
        mt.load(glb, lighting="sunny")


def test_the_dataset_example_writes_a_dataset(repo, tmp_path):
    import subprocess
    import sys

    meshes = tmp_path / "meshes"
    meshes.mkdir()
    for name in ("materials_joined.glb", "vertex_colors.glb"):
        (meshes / name).write_bytes((repo / "tests/data/gltf/corpus" / name).read_bytes())
    (meshes / "broken.obj").write_text("v 0 0 0\n")
    done = subprocess.run(
        [sys.executable, str(repo / "examples" / "dataset.py"), meshes, tmp_path / "out",
         "--views", "2", "--spp", "1", "--size", "16", "--device", "cpu"],
        capture_output=True, text=True,
    )
    assert done.returncode == 1, "one mesh failed"
    assert "broken.obj" in done.stderr and "2 of 3 meshes, 4 images" in done.stdout
    for stem in ("materials_joined", "vertex_colors"):
        folder = tmp_path / "out" / stem
        assert sorted(p.name for p in folder.iterdir()) == [
            "000.aovs.exr", "000.png", "001.aovs.exr", "001.png", "transforms.json"]
