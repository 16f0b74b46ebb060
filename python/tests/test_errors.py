"""Bad input raises MeshtraceError, a ValueError, with the command line's one-line message
(a setting named as the keyword argument rather than the flag)."""

import pytest

import meshtrace as mt


def cli_message(cli, *args):
    done = cli(*args, check=False)
    assert done.returncode != 0
    lines = [l for l in done.stderr.splitlines() if l.startswith("error: ")]
    assert len(lines) == 1, done.stderr
    return lines[0].removeprefix("error: ")


def test_the_error_is_a_value_error():
    assert issubclass(mt.MeshtraceError, ValueError)


def test_a_missing_file_says_what_the_command_line_says(cpu, cli, tmp_path):
    missing = tmp_path / "missing.glb"
    with pytest.raises(mt.MeshtraceError) as e:
        mt.load(missing)
    assert str(e.value) == cli_message(cli, "render", missing, "-o", tmp_path / "x.png")


def test_a_broken_file_names_the_json_path(cpu, cli, tmp_path):
    bad = tmp_path / "bad.gltf"
    bad.write_text('{"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": {"POSITION": 5}}]}]}')
    with pytest.raises(mt.MeshtraceError) as e:
        cpu.render(mt.load(bad), spp=1)
    message = cli_message(cli, "render", bad, "-o", tmp_path / "x.png")
    assert str(e.value) == message and "meshes[0]" in message


@pytest.mark.parametrize(
    "kwargs, flags",
    [
        (dict(spp=0), ["--spp", "0"]),
        (dict(max_depth=0), ["--max-depth", "0"]),
        (dict(branches=65), ["--branches", "65"]),
        (dict(filter_width=11.0), ["--filter-width", "11"]),
        (dict(max_texture_size=0), ["--max-texture-size", "0"]),
    ],
)
def test_a_bad_setting_says_what_the_flag_says(cpu, cli, tmp_path, kwargs, flags):
    with pytest.raises(mt.MeshtraceError) as e:
        cpu.render("builtin:cornell", **kwargs)
    expected = cli_message(cli, "render", "builtin:cornell", *flags, "-o", tmp_path / "x.png")
    field = next(iter(kwargs))
    assert str(e.value) == expected.replace("--" + field.replace("_", "-"), field)


def test_bad_names_are_errors():
    with pytest.raises(mt.MeshtraceError, match="device: `tpu` is not one of auto, cpu, gpu"):
        mt.Renderer(device="tpu")
    with pytest.raises(mt.MeshtraceError, match="aovs: "):
        mt.Renderer(device="cpu").render("builtin:cornell", aovs=["colour"])
    with pytest.raises(mt.MeshtraceError, match="up: `w`"):
        mt.load("builtin:cornell", up="w")
    with pytest.raises(TypeError):
        mt.Renderer(device="cpu").render("builtin:cornell", sp=4)


def test_a_dict_error_names_the_key_path():
    with pytest.raises(mt.MeshtraceError) as e:
        mt.Scene.from_dict(
            {
                "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0]},
                "objects": [
                    {"sphere": {"center": [0, 0, 0], "radius": 1}},
                    {"sphere": {"center": [0, 0, 0], "radius": 1}, "colour": [1, 0, 0]},
                ],
            }
        )
    assert str(e.value).startswith("scene dict: objects[1]"), str(e.value)
    with pytest.raises(mt.MeshtraceError, match=r"camera\.vfov: a NoneType has no place"):
        mt.Scene.from_dict({"camera": {"vfov": None}})
    with pytest.raises(mt.MeshtraceError, match=r"camera\.vfov: must be in \(0, 180\)"):
        mt.Scene.from_dict({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "vfov": 200.0}})
