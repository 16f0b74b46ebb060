"""Memory stays flat over many renders of distinct scenes: at most 10% more resident
memory at the end than after the first tenth. MESHTRACE_MEMORY_RENDERS sets how many (2,000
by default; the closing figures in BENCHMARKS.md took 10,000)."""

import os

import numpy as np

import meshtrace as mt

RENDERS = int(os.environ.get("MESHTRACE_MEMORY_RENDERS", "2000"))


def rss():
    """Resident memory in bytes (Linux)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def distinct(i):
    """Scene i: a sphere of its own size, tessellation, colour and place."""
    rng = np.random.default_rng(i)
    return mt.Scene.from_dict(
        {
            "camera": {"position": [0.0, 0.0, 4.0], "look_at": [0.0, 0.0, 0.0]},
            "materials": {"m": {"type": "diffuse", "albedo": rng.uniform(0.1, 0.9, 3).tolist()}},
            "objects": [
                {
                    "sphere": {
                        "center": rng.uniform(-0.5, 0.5, 3).tolist(),
                        "radius": float(rng.uniform(0.2, 1.0)),
                        "subdivisions": int(i % 5),
                    },
                    "material": "m",
                }
            ],
        }
    )


def check_flat(renderer):
    curve = []
    for i in range(RENDERS):
        out = renderer.render(distinct(i), spp=1, width=32, height=32, aovs=["depth"])
        assert out["color"].shape == (32, 32, 3)
        curve.append(rss())
    settled = curve[RENDERS // 10]
    assert max(curve[RENDERS // 10 :]) <= 1.1 * settled, (settled, max(curve))


def test_memory_is_flat_on_the_cpu(cpu):
    check_flat(cpu)


def test_memory_is_flat_on_the_gpu(gpu):
    check_flat(gpu)
