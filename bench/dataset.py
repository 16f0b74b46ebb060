"""The dataset job: meshtrace's presets against the dataset scripts themselves, in Blender.

    python3 bench/dataset.py --blender-python VENV/bin/python --assets DIR \\
        --zero123 zero123/objaverse-rendering/scripts/blender_script.py \\
        [--objaverse objaverse-rendering/scripts/blender_script.py] [--out DIR] [--json]

For each script given, every `.glb` in `--assets` is rendered twice over:

* by the script, unchanged, in Blender (PyPI's `bpy`, through `bench/blender_run.py`), one
  process per object as the scripts' own `distributed.py` launches them; Cycles on the CPU
  (objaverse-rendering's default EEVEE needs a display, so it gets `--engine CYCLES`, which
  its docstring shows);
* by `meshtrace batch` with the matching preset, one run over all the objects.

It reports objects per hour of each, and the noise of each renderer's images: the RMS
difference, over the 8-bit RGBA pixels that either image covers, between a view and the
same view rendered by the same renderer with `--reference-spp` samples (Blender's with
adaptive sampling off, its denoiser as the script has it). Seeds make the script's random
cameras and lights the same in a run and its reference (`--seed`); meshtrace's are seeded
per object already. Only the first `--reference-views` views get references; the reference
runs keep the script's view count, since a ring's cameras depend on it.

`--reuse-blender` keeps the Blender images and times of an earlier run into the same `--out`
(Blender's part takes the longest), to try meshtrace's settings against them.
`--denoise` renders meshtrace's views with Open Image Denoise (a `--features denoise`
build, given with `--meshtrace`), as the scripts denoise theirs; `--spp` sets meshtrace's
samples (default: the preset's, as the scripts'). `--view-transform` forms meshtrace's
images (default `agx`: the view transform the scripts get in Blender 5, so that both
renderers' noise is counted in the same 8-bit levels), with the LUTs of `--blender-python`'s
`bpy` unless MESHTRACE_BLENDER_LUTS names others.
"""

import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

HERE = Path(__file__).resolve().parent

# preset name, the script's own views, the extra arguments its driver passes.
SCRIPTS = {
    "zero123": (12, []),
    "objaverse": (12, ["--engine", "CYCLES"]),
}


def read_png(path):
    """An 8-bit RGBA (or RGB) non-interlaced PNG as (width, height, rows of bytes, channels)."""
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    channels = {2: 3, 6: 4}[colour]
    assert depth == 8 and interlace == 0, f"{path}: {depth}-bit, interlace {interlace}"
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1 : (y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = prev[i]
            c = prev[i - channels] if i >= channels else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, rows, channels


def noise(image, reference):
    """RMS difference of premultiplied RGBA in [0, 1] over pixels either image covers."""
    w, h, a, ca = read_png(image)
    w2, h2, b, cb = read_png(reference)
    assert (w, h) == (w2, h2), (image, reference)
    total, count = 0.0, 0
    for ra, rb in zip(a, b):
        for x in range(w):
            pa = ra[x * ca : x * ca + ca]
            pb = rb[x * cb : x * cb + cb]
            alpha_a = pa[3] / 255 if ca == 4 else 1.0
            alpha_b = pb[3] / 255 if cb == 4 else 1.0
            if alpha_a == 0 and alpha_b == 0:
                continue
            for k in range(3):
                d = pa[k] / 255 * alpha_a - pb[k] / 255 * alpha_b
                total += d * d
            total += (alpha_a - alpha_b) ** 2
            count += 4
    return (total / max(count, 1)) ** 0.5


def blender(args, script, extra, asset, out, views, seed, samples=None):
    cmd = [args.blender_python, str(HERE / "blender_run.py"), script, "--seed", str(seed)]
    if samples:
        cmd += ["--samples", str(samples), "--first", str(args.reference_views)]
    cmd += ["--", "--object_path", str(asset), "--output_dir", str(out)]
    cmd += ["--num_images", str(views)] + extra
    start = time.perf_counter()
    run = subprocess.run(cmd, capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    if run.returncode != 0 or "Failed to render" in run.stdout:
        sys.exit(f"{' '.join(cmd)} failed:\n{run.stdout[-2000:]}\n{run.stderr[-2000:]}")
    return elapsed


def lut_env(args):
    """The environment of meshtrace's runs: MESHTRACE_BLENDER_LUTS set, where unset, to the
    colour-management folder of the bpy that runs the scripts."""
    env = dict(os.environ)
    if args.view_transform != "standard" and not env.get("MESHTRACE_BLENDER_LUTS"):
        where = subprocess.run(
            [args.blender_python, "-c",
             "import bpy; print(bpy.utils.system_resource('DATAFILES', path='colormanagement'))"],
            capture_output=True, text=True, check=True,
        )
        env["MESHTRACE_BLENDER_LUTS"] = where.stdout.strip().splitlines()[-1]
    return env


def meshtrace(args, preset, assets, out, views, spp):
    manifest = out / "manifest.toml"
    out.mkdir(parents=True, exist_ok=True)
    render = f"spp = {spp}\n" if spp else ""
    if args.denoise:
        render += "denoise = true\n"
    render += f"view_transform = \"{args.view_transform}\"\n"
    manifest.write_text(
        f"[render]\n{render}\n[[jobs]]\nmeshes = \"{assets.resolve()}/*.glb\"\n"
        f"preset = \"{preset}\"\nviews = {views}\noutput = \"{{uid}}/{{view:03}}.png\"\n"
    )
    cmd = [args.meshtrace, "batch", str(manifest), "--device", args.device, "--quiet"]
    start = time.perf_counter()
    run = subprocess.run(cmd, capture_output=True, text=True, env=lut_env(args))
    elapsed = time.perf_counter() - start
    if run.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{run.stderr[-2000:]}")
    return elapsed, run.stderr.strip().splitlines()[-1]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--blender-python", required=True, help="a Python with PyPI's bpy")
    p.add_argument("--assets", required=True, type=Path, help="a folder of .glb files")
    p.add_argument("--zero123", help="zero123's objaverse-rendering/scripts/blender_script.py")
    p.add_argument("--objaverse", help="objaverse-rendering's scripts/blender_script.py")
    p.add_argument("--meshtrace", default=str(HERE.parent / "target/release/meshtrace"))
    p.add_argument("--device", default="cpu")
    p.add_argument("--spp", type=int, help="meshtrace's samples (default: the preset's)")
    p.add_argument("--denoise", action="store_true")
    p.add_argument("--view-transform", default="agx", choices=["standard", "filmic", "agx"])
    p.add_argument("--reference-spp", type=int, default=1024)
    p.add_argument("--reference-views", type=int, default=2)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", type=Path)
    p.add_argument(
        "--reuse-blender", action="store_true",
        help="take Blender's images and time from an earlier run into the same --out",
    )
    p.add_argument("--json", action="store_true")
    args = p.parse_args()
    assets = sorted(args.assets.glob("*.glb"))
    if not assets:
        sys.exit(f"{args.assets}: no .glb files")
    out = args.out or Path(tempfile.mkdtemp(prefix="meshtrace-dataset-"))
    rows = []
    for preset, script in [("zero123", args.zero123), ("objaverse", args.objaverse)]:
        if not script:
            continue
        views, extra = SCRIPTS[preset]
        base = out / preset
        timing = base / "blender_seconds.json"
        if args.reuse_blender and timing.exists():
            blender_time = json.loads(timing.read_text())
        else:
            shutil.rmtree(base, ignore_errors=True)
            # The script, one process per object, then its references.
            blender_time = 0.0
            for asset in assets:
                blender_time += blender(args, script, extra, asset, base / "blender", views, args.seed)
                blender(
                    args, script, extra, asset, base / "blender_ref",
                    views, args.seed, args.reference_spp,
                )
            timing.write_text(json.dumps(blender_time))
        for folder in ["meshtrace", "meshtrace_ref"]:
            shutil.rmtree(base / folder, ignore_errors=True)
        ours_time, summary = meshtrace(args, preset, args.assets, base / "meshtrace", views, args.spp)
        # The reference keeps the view count (a ring's cameras depend on it); the views past
        # the first few are left out by placing files where they go, which a batch skips as
        # complete, and removing them after.
        skipped = []
        for asset in assets:
            for v in range(args.reference_views, views):
                path = base / "meshtrace_ref" / asset.name.split(".")[0] / f"{v:03d}.png"
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_bytes(b"")
                skipped.append(path)
        meshtrace(args, preset, args.assets, base / "meshtrace_ref", views, args.reference_spp)
        for path in skipped:
            path.unlink()
        noise_of = {}
        for who in ["blender", "meshtrace"]:
            values = []
            for asset in assets:
                uid = asset.name.split(".")[0]
                for v in range(args.reference_views):
                    name = f"{uid}/{v:03d}.png"
                    values.append(noise(base / who / name, base / f"{who}_ref" / name))
            noise_of[who] = sum(values) / len(values)
        n = len(assets)
        row = {
            "preset": preset,
            "objects": n,
            "views": views,
            "blender_objects_per_hour": 3600 * n / blender_time,
            "meshtrace_objects_per_hour": 3600 * n / ours_time,
            "ratio": blender_time / ours_time,
            "blender_noise": noise_of["blender"],
            "meshtrace_noise": noise_of["meshtrace"],
            "meshtrace_summary": summary,
            "meshtrace_spp": args.spp,
            "denoise": args.denoise,
            "view_transform": args.view_transform,
            "device": args.device,
        }
        rows.append(row)
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        print(f"{'script':<10} {'objects':>7} {'Blender obj/h':>13} {'meshtrace obj/h':>15} "
              f"{'ratio':>6} {'noise Blender':>13} {'noise meshtrace':>15}")
        for r in rows:
            print(f"{r['preset']:<10} {r['objects']:>7} {r['blender_objects_per_hour']:>13.1f} "
                  f"{r['meshtrace_objects_per_hour']:>15.1f} {r['ratio']:>6.2f} "
                  f"{r['blender_noise']:>13.4f} {r['meshtrace_noise']:>15.4f}")
        print(f"images in {out}")


if __name__ == "__main__":
    main()
