"""Runs a dataset script as Blender's executable would, in Python with PyPI's `bpy`.

    python bench/blender_run.py SCRIPT [--seed N] [--samples N] -- SCRIPT_ARGS...

Blender runs a `-P` script with `bpy` and `mathutils` already imported; the scripts rely on
that (Zero123's imports `mathutils` before `bpy`), so this imports `bpy` first and then runs
SCRIPT as `__main__` with `sys.argv` as Blender would give it (everything after `--` is the
script's own). The script itself is not changed. Two options serve the benchmark:

* `--seed N` seeds Python's `random` and NumPy's generator first. The scripts draw their
  cameras and lights from them unseeded; seeded, a second run draws the same ones.
* `--samples N` makes every render take N Cycles samples without adaptive sampling (set in
  a `render_pre` handler, after the script has set its own): the reference of a run with
  the same seed. With `--first K`, only the first K renders do; the others take one
  sample. A script whose cameras depend on how many views it renders (a ring) keeps its
  view count, and its reference costs K views.
"""

import argparse
import random
import runpy
import sys

import bpy  # noqa: F401  (imported first, as in Blender's own executable)
import numpy as np


def main():
    ours, theirs = sys.argv[1:], []
    if "--" in ours:
        k = ours.index("--")
        ours, theirs = ours[:k], ours[k:]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("script")
    parser.add_argument("--seed", type=int)
    parser.add_argument("--samples", type=int)
    parser.add_argument("--first", type=int)
    args = parser.parse_args(ours)
    if args.seed is not None:
        random.seed(args.seed)
        np.random.seed(args.seed)
    if args.samples is not None:

        renders = [0]

        def more_samples(scene, *_):
            first = args.first is None or renders[0] < args.first
            scene.cycles.samples = args.samples if first else 1
            scene.cycles.use_adaptive_sampling = False
            renders[0] += 1

        bpy.app.handlers.render_pre.append(more_samples)
    sys.argv = [args.script] + theirs
    runpy.run_path(args.script, run_name="__main__")


if __name__ == "__main__":
    main()
