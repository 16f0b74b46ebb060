"""Shared fixtures: the repository's files, the `meshtrace` command line to compare with,
and renderers on the CPU and on a Vulkan GPU (lavapipe where there is no other).

MESHTRACE_BIN names the command line (by default the workspace's target/release/meshtrace);
MESHTRACE_REQUIRE_CLI=1 and MESHTRACE_REQUIRE_GPU=1 (CI) make a missing one a failure
instead of a skip.
"""

import os
import subprocess
from pathlib import Path

import pytest

import meshtrace as mt

REPO = Path(__file__).resolve().parents[2]
CORPUS = REPO / "tests" / "data" / "gltf" / "corpus"


def _required(name):
    return os.environ.get(name) == "1"


@pytest.fixture(scope="session")
def repo():
    return REPO


@pytest.fixture(scope="session")
def glb():
    """A GLB written by Blender's exporter (tests/data/gltf/corpus/README.md)."""
    return CORPUS / "materials_joined.glb"


@pytest.fixture(scope="session")
def obj():
    return REPO / "assets" / "cornell" / "small_box.obj"


@pytest.fixture(scope="session")
def cli():
    """Runs `meshtrace ARGS...`; returns the completed process."""
    exe = Path(os.environ.get("MESHTRACE_BIN", REPO / "target" / "release" / "meshtrace"))
    if not exe.exists():
        message = f"no meshtrace command line at {exe} (cargo build --release, or set MESHTRACE_BIN)"
        if _required("MESHTRACE_REQUIRE_CLI"):
            pytest.fail(message)
        pytest.skip(message)

    def run(*args, check=True):
        env = dict(os.environ, NODEVICE_SELECT="1")
        done = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, env=env)
        if check and done.returncode != 0:
            raise AssertionError(f"meshtrace {' '.join(map(str, args))}: {done.stderr}")
        return done

    return run


@pytest.fixture(scope="session")
def cpu():
    return mt.Renderer(device="cpu")


@pytest.fixture(scope="session")
def gpu():
    """A renderer on a Vulkan adapter, lavapipe included."""
    try:
        return mt.Renderer(device="gpu")
    except mt.MeshtraceError as e:
        if _required("MESHTRACE_REQUIRE_GPU"):
            pytest.fail(f"no Vulkan adapter: {e}")
        pytest.skip(f"no Vulkan adapter: {e}")
