"""The Python API over many renders: the time of each render of a small scene (the first
against the thousandth), and resident memory over renders of distinct generated scenes.

    pip install ./python
    python bench/python_renders.py --device cpu --renders 10000 --json > cpu.json
    VK_DRIVER_FILES=... python bench/python_renders.py --device gpu

Prints, for one Renderer: the first, the 10th, the 1,000th and the median render's wall time
of `builtin:cornell` at 64×64 and 4 spp; then resident memory every tenth of `--renders`
renders of distinct scenes (python/tests/test_memory.py's spheres, 32×32, 1 spp, with
depth), with the growth after the first tenth (the test allows 10%).
"""

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python" / "tests"))

import meshtrace as mt  # noqa: E402
from test_memory import distinct, rss  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--device", default="cpu", choices=["auto", "cpu", "gpu"])
    parser.add_argument("--renders", type=int, default=10000)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    began = time.perf_counter()
    renderer = mt.Renderer(device=args.device)
    opened = time.perf_counter() - began
    scene = mt.load("builtin:cornell")
    times = []
    for _ in range(1000):
        t = time.perf_counter()
        renderer.render(scene, spp=4, width=64, height=64)
        times.append(time.perf_counter() - t)

    curve = []
    every = max(1, args.renders // 10)
    for i in range(args.renders):
        renderer.render(distinct(i), spp=1, width=32, height=32, aovs=["depth"])
        if (i + 1) % every == 0:
            curve.append((i + 1, rss()))
    settled = curve[0][1]
    result = {
        "device": renderer.name,
        "open_s": opened,
        "first_s": times[0],
        "tenth_s": times[9],
        "thousandth_s": times[999],
        "median_s": statistics.median(times),
        "rss_mb": [(n, round(b / 1e6, 1)) for n, b in curve],
        "growth_after_first_tenth": max(b for _, b in curve) / settled - 1.0,
    }
    if args.json:
        print(json.dumps(result, indent=1))
        return
    print(f"{renderer.name}: opened in {opened * 1e3:.1f} ms")
    print(
        f"render of builtin:cornell 64×64 4 spp: first {times[0] * 1e3:.2f} ms, 10th "
        f"{times[9] * 1e3:.2f} ms, 1000th {times[999] * 1e3:.2f} ms, median {result['median_s'] * 1e3:.2f} ms"
    )
    print("RSS (MB) after n renders of distinct scenes: " + ", ".join(f"{n}: {m}" for n, m in result["rss_mb"]))
    print(f"growth after the first tenth: {result['growth_after_first_tenth'] * 100:.2f}%")


if __name__ == "__main__":
    main()
