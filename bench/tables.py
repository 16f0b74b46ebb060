#!/usr/bin/env python3
"""The current benchmark tables of BENCHMARKS.md: measure this machine, store, render.

    python3 bench/tables.py run [--machine NAME] [--quick] [--skip embree,qps,bench]
                                [--device-json PATH] [--binary PATH]
    python3 bench/tables.py render

`run` runs the committed measurement scripts on this machine and collects their JSON:

  bench   target/release/meshtrace bench --json --repeats 3 (the Cornell box, the Stanford
          bunny from ../shared/meshes and the 2M-triangle terrain), with --device all when
          `meshtrace adapters` lists an adapter other than lavapipe (llvmpipe), else
          --device cpu
  embree  python3 bench/embree_compare.py --json (meshtrace against Embree 4, one thread,
          two views of the bunny, their bounces and shadow rays); skipped with a note
          where embreex (which bundles Embree 4) is missing, or with the script's error
          (no C compiler, for one)
  qps     python3 bench/quality_per_second.py --json OUT (CPU quality per second against
          Mitsuba 3 llvm_ad_rgb on three scenes)

and, with --device-json, copies in the JSON that bench/device.sh wrote on a GPU machine.
It writes everything to bench/results/MACHINE.json (replacing that file; committed, so the
tables can be regenerated without measuring again), then renders. --quick passes small
sizes, repeats and seeds to the scripts, for testing this script only: its tables say so.
MACHINE defaults to the CPU model, its widest vector extension and the threads this
process may use (`amd-epyc-avx2-2t`).

`render` rewrites the part of BENCHMARKS.md between the markers TABLES_BEGIN and
TABLES_END: one `### Machine: NAME` section per bench/results/*.json, sorted by name, each
with the date, CPU, GPU, binary, the commands run, and the tables with the targets of
issue 16 marked MET or MISSED.

Python 3.11, standard library only.
"""
import argparse
import datetime
import hashlib
import importlib.util
import json
import math
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
RESULTS = REPO / "bench" / "results"
BENCHMARKS = REPO / "BENCHMARKS.md"
TABLES_BEGIN = "<!-- tables:begin -->"
TABLES_END = "<!-- tables:end -->"
SCHEMA = 1
STEPS = ("bench", "embree", "qps")

# Targets of issue 16.
EMBREE_GOAL = 0.8       # CPU primary rays / Embree's, one thread each, on a view most rays hit
QPS_GOAL = 1.5          # CPU quality per second / Mitsuba 3 llvm_ad_rgb's, on every scene
QPS_SCENES = 3
GPU_PRIMARY_GOAL = 8000.0   # Mrays/s, H100/H200 class, on a mesh of at least 1M triangles
GPU_DIFFUSE_GOAL = 3000.0   # Mrays/s of diffuse bounces (`incoherent_rays`), same mesh
GPU_QPS_GOAL = 2.0      # GPU quality per second / Mitsuba 3 CUDA's
MILLION_TRIANGLE_SCENES = ("terrain-2M",)   # the bench scenes with at least 1M triangles


# --- running ----------------------------------------------------------------------------

def sh(cmd, **kw):
    """Runs `cmd` (a list) in the repository root; returns the CompletedProcess."""
    return subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, **kw)


def cpu_info():
    """The CPU's model name, family and model numbers, and its widest vector extensions
    (which decide Mitsuba's LLVM lane width and Embree's kernels)."""
    info = {"cpu": "unknown CPU", "family": None, "model": None, "flags": set()}
    with open("/proc/cpuinfo") as fh:
        for line in fh:
            key, _, value = line.partition(":")
            key, value = key.strip(), value.strip()
            if key == "model name" and info["cpu"] == "unknown CPU":
                info["cpu"] = value
            elif key == "cpu family" and info["family"] is None:
                info["family"] = int(value)
            elif key == "model" and info["model"] is None:
                info["model"] = int(value)
            elif key in ("flags", "Features") and not info["flags"]:  # x86, Arm
                info["flags"] = set(value.split())
    flags = info.pop("flags")
    info["simd"] = ("avx512" if "avx512f" in flags else "avx2" if "avx2" in flags
                    else "neon" if "asimd" in flags else "baseline")
    info["gfni"] = "gfni" in flags
    return info


def default_machine(cpu, simd, threads):
    """A stable name from the CPU model, its widest vector extension and the thread count:
    `AMD EPYC`, avx2, 2 -> `amd-epyc-avx2-2t`."""
    name = re.sub(r"\((R|TM)\)|\bCPU\b|\bProcessor\b|@.*$|\d+-Core", " ", cpu, flags=re.I)
    slug = re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-") or "cpu"
    return f"{slug}-{simd}-{threads}t"


def adapters(binary):
    """`meshtrace adapters`, one line per adapter (none where Vulkan has no adapter)."""
    r = sh([str(binary), "adapters"])
    lines = r.stdout.splitlines() if r.returncode == 0 else []
    return [" ".join(line.split()) for line in lines if line.strip()]


def binary_info(binary):
    with open(binary, "rb") as fh:
        digest = hashlib.sha256(fh.read()).hexdigest()
    built = datetime.datetime.fromtimestamp(os.path.getmtime(binary), datetime.UTC)
    return {
        "path": os.path.relpath(binary, REPO),
        "version": sh([str(binary), "--version"]).stdout.strip(),
        "sha256": digest,
        "built": built.isoformat(timespec="seconds"),
        "commit": sh(["git", "rev-parse", "--short", "HEAD"]).stdout.strip() or None,
        "uncommitted_changes": bool(sh(["git", "status", "--porcelain", "--untracked-files=no"])
                                    .stdout.strip()),
    }


def script_json(cmd, commands, out_file=None):
    """Runs a measurement script and returns its JSON (from stdout, or `out_file`), or
    `{"skipped": why}` when it failed without any. A script that fails after writing its
    JSON (embree_compare.py's checks) keeps its JSON, which carries the failures."""
    commands.append(" ".join(str(c) for c in cmd))
    print("running:", commands[-1], file=sys.stderr, flush=True)
    r = sh([str(c) for c in cmd])
    sys.stderr.write(r.stderr)
    try:
        if out_file:
            with open(out_file) as fh:
                return json.load(fh)
        return json.loads(r.stdout)
    except (OSError, ValueError):
        tail = (r.stderr.strip().splitlines() or ["no output"])[-1]
        return {"skipped": f"exit status {r.returncode}: {tail}"}


def run(args):
    binary = args.binary.resolve()
    if not os.access(binary, os.X_OK):
        raise SystemExit(f"tables.py: no meshtrace binary at {binary} (cargo build --release)")
    skip = {s for s in args.skip.split(",") if s}
    if skip - set(STEPS):
        raise SystemExit(f"tables.py: --skip takes {','.join(STEPS)}, not {args.skip}")
    cpu, threads = cpu_info(), len(os.sched_getaffinity(0))
    listed = adapters(binary)
    gpus = [a for a in listed if "llvmpipe" not in a]
    py = sys.executable
    commands = []
    result = {
        "schema": SCHEMA,
        "machine": args.machine or default_machine(cpu["cpu"], cpu["simd"], threads),
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "quick": args.quick,
        # None where nothing ran here: the device JSON then describes its own machine
        "host": None if skip == set(STEPS) else
        {"cpu": cpu["cpu"], "family": cpu["family"], "model": cpu["model"],
         "simd": cpu["simd"], "gfni": cpu["gfni"], "threads": threads, "adapters": listed,
         "gpus": gpus},
        "binary": binary_info(binary),
        "commands": commands,
    }

    if "bench" in skip:
        result["bench"] = {"skipped": "--skip bench"}
    else:
        cmd = [binary, "bench", "--json", "--repeats", "1" if args.quick else "3",
               "--device", "all" if gpus else "cpu"]
        if args.quick:
            cmd += ["--width", "128", "--height", "128", "--spp", "1"]
        rows = script_json(cmd, commands)
        result["bench"] = rows if "skipped" in rows else {"rows": rows}

    if "embree" in skip:
        result["embree"] = {"skipped": "--skip embree"}
    elif importlib.util.find_spec("embreex") is None:
        result["embree"] = {"skipped": "embreex is not installed (pip install embreex)"}
    else:
        cmd = [py, "bench/embree_compare.py", "--json", "--binary", binary]
        if args.quick:
            cmd += ["--size", "128", "--repeats", "1", "--rounds", "1", "--verify", "32"]
        result["embree"] = script_json(cmd, commands)

    if "qps" in skip:
        result["qps"] = {"skipped": "--skip qps"}
    else:
        with tempfile.TemporaryDirectory(prefix="tables.") as tmp:
            out = Path(tmp) / "qps.json"
            cmd = [py, "bench/quality_per_second.py", "--json", out, "--meshtrace", binary]
            if args.quick:
                cmd += ["--spp", "8", "--seeds", "1"]
            result["qps"] = script_json(cmd, commands, out)
            commands[-1] = commands[-1].replace(str(out), "OUT.json")

    if args.device_json:
        with open(args.device_json) as fh:
            result["device"] = {"source": str(args.device_json), "data": json.load(fh)}

    commands[:] = [c.replace(str(REPO) + "/", "").replace(py, "python3") for c in commands]
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{result['machine']}.json"
    write_atomic(path, json.dumps(result, indent=2) + "\n")
    print(f"wrote {os.path.relpath(path, REPO)}", file=sys.stderr)
    render()


# --- rendering --------------------------------------------------------------------------

def num(x):
    """Three significant digits, never in exponent form."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    digits = 2 - math.floor(math.log10(abs(x))) if x else 0
    return f"{x:.{max(0, digits)}f}"


def verdict(ok):
    return "**MET**" if ok else "**MISSED**"


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return lines


def is_rows(value):
    """Whether `value` is `meshtrace bench` rows: objects with a measure and a median."""
    return isinstance(value, list) and bool(value) and all(
        isinstance(r, dict) and "measure" in r and "median" in r for r in value)


def bench_rows(data):
    """All `meshtrace bench` rows anywhere in a device JSON."""
    if is_rows(data):
        return data
    values = data.values() if isinstance(data, dict) else data if isinstance(data, list) else []
    return [r for v in values for r in bench_rows(v)]


def render_bench(rows):
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    keys = list(dict.fromkeys((r["measure"], r["device"], r.get("accel"), r["unit"])
                              for r in rows))
    cell = {(r["measure"], r["device"], r.get("accel"), r["scene"]): r for r in rows}
    body = []
    for measure, device, accel, unit in keys:
        line = [f"`{measure}`", device + (f" ({accel})" if accel else ""), unit]
        for s in scenes:
            r = cell.get((measure, device, accel, s))
            line.append("—" if r is None else num(r["median"]) if r["min"] == r["max"]
                        else f"{num(r['median'])} ({num(r['min'])}..{num(r['max'])})")
        body.append(line)
    repeats = max(r["repeats"] for r in rows)
    return table(["measure", "device", "unit"] + scenes, body) + [
        "",
        f"Median of {repeats} timed runs after a warm-up (min..max; `sah_cost` and the "
        "hit shares are computed once). "
        "`*_hits`: share of the view's rays whose closest hit is on the mesh; "
        "`incoherent_rays`: a cosine (diffuse) bounce from each primary hit.",
    ]


def gpu_targets(rows):
    """Issue 16's GPU ray-rate targets, from the GPU rows of the million-triangle scenes."""
    if not any(r["device"] == "gpu" for r in rows):
        return [f"* Targets for an H100/H200 class GPU (≥ {num(GPU_PRIMARY_GOAL / 1000)} "
                f"Grays/s primary, ≥ {num(GPU_DIFFUSE_GOAL / 1000)} Grays/s diffuse rays on a "
                "≥ 1M-triangle mesh): no GPU measured here."]
    lines = []
    for measure, goal, what in (("primary_rays", GPU_PRIMARY_GOAL, "primary rays"),
                                ("incoherent_rays", GPU_DIFFUSE_GOAL, "diffuse rays")):
        got = [r for r in rows if r["device"] == "gpu" and r["measure"] == measure
               and r["scene"] in MILLION_TRIANGLE_SCENES]
        best = max(got, key=lambda r: r["median"], default=None)
        status = ("not measured (no GPU rows on a ≥ 1M-triangle scene)" if best is None else
                  f"{num(best['median'] / 1000)} Grays/s on {best['scene']}: "
                  f"{verdict(best['median'] >= goal)}")
        lines.append(f"* Target (H100/H200 class GPU): ≥ {num(goal / 1000)} Grays/s {what} "
                     f"on a ≥ 1M-triangle mesh: {status}.")
    return lines


def cpu_detail(host):
    """`(family 25, model 1; AVX2, no AVX-512)`, or a note where the result predates it."""
    if "simd" not in host:
        return " (vector extensions not recorded)"
    simd = {"avx512": "AVX-512", "avx2": "AVX2, no AVX-512", "neon": "NEON",
            "baseline": "no AVX2 or NEON"}[host["simd"]]
    return (f" (family {host['family']}, model {host['model']}; {simd}"
            f"{', GFNI' if host['gfni'] else ''})")


def render_embree(e):
    views = e.get("views", {})
    # Results from before embree_rays.c traced Embree through the embreex bindings, whose
    # scenes set RTC_SCENE_FLAG_ROBUST (Mitsuba 3's do not).
    direct = all("modes" in v["embree"] for v in views.values())
    body, met = [], []
    for view, v in views.items():
        m, em = v.get("meshtrace") or {}, v["embree"]
        hits = m.get("mesh_hit_fraction")
        mostly = hits is not None and hits > 0.5
        if mostly and v.get("ratio") is not None:
            met.append(v["ratio"] >= EMBREE_GOAL)
        lo_hi = m.get("min_max")
        rate = num(m.get("mrays")) + (f" ({num(lo_hi[0])}..{num(lo_hi[1])})"
                                      if lo_hi and lo_hi[0] != lo_hi[1] else "")
        modes = em.get("modes", {})
        extra = [num(modes[k]["mrays"]) if k in modes else "—"
                 for k in ("robust", "packet8", "packet16")] if direct else []
        body.append([f"`{view}`", num(hits), num(em["hit_fraction"]), rate,
                     num(em["mrays"]), *extra, num(v.get("ratio")),
                     f"≥ {EMBREE_GOAL}: {verdict(v['ratio'] >= EMBREE_GOAL)}"
                     if mostly and v.get("ratio") is not None
                     else "—" if hits is None else "— (most rays miss the mesh)"])
    mt, emb = e.get("meshtrace") or {}, e["embree"]
    body.append(["BVH build, Mtris/s", "", "", num(mt.get("bvh_build_mtris")),
                 num(emb["bvh_build_mtris"]), *([""] * 3 if direct else []),
                 num(e.get("ratio_build")), ""])
    versions = ", ".join(v if v.startswith(k) else f"{k} {v}"
                         for k, v in e.get("versions", {}).items() if v)
    head = ["view", "rays on the mesh (meshtrace)", "rays hitting (Embree)",
            "meshtrace Mrays/s", "Embree Mrays/s"]
    if direct:
        head += ["Embree robust", "Embree ×8 packets", "Embree ×16 packets"]
    how = (f"Embree traced by `bench/embree_rays.c`, built as Mitsuba 3 builds its scenes "
           f"(build quality high, no scene flags); `rtcIntersect1`/`rtcOccluded1` a ray, the "
           f"measure; for reference the same with `RTC_SCENE_FLAG_ROBUST`, and packets of 8 "
           f"and 16 consecutive rays (`rtcIntersect8`/`16`, what Mitsuba's LLVM variant "
           f"calls). Ratio: the median over {e.get('rounds', 1)} rounds of meshtrace and "
           f"Embree measured in turn." if direct else
           "Embree traced through the embreex bindings, whose scenes set "
           "`RTC_SCENE_FLAG_ROBUST`, which Mitsuba 3 does not set and which cost Embree "
           "about a fifth of its rate when measured on 2026-12-04 (BENCHMARKS.md, "
           "Traversal, Against Embree 4): these ratios flatter meshtrace.")
    lines = table(head + ["ratio", "target"], body) + [
        "",
        f"{e['name']}, {e['triangles']} triangles, {e['width']}×{e['height']} rays a view, "
        f"median of {e['repeats']}; Embree's build on {emb['bvh_build_threads']} thread(s). "
        f"{versions}. {how}"
        + (" `incoherent`: a cosine bounce from each hit of `primary` (closest hit); "
           "`shadow`: a ray from each such hit towards a point on a light (occlusion, "
           "Embree's `rtcOccluded1`)." if "incoherent" in views else ""),
        f"* Target: CPU primary rays ≥ {EMBREE_GOAL}× Embree per thread on a view where most "
        "rays hit: " + (verdict(any(met)) if met else "not measured (no such view)")
        + ("" if direct or not met else " against Embree's robust mode, not against "
           "Embree as Mitsuba runs it") + ".",
    ]
    if e.get("failures"):
        lines.append("* Check failures: " + "; ".join(e["failures"]) + ".")
    return lines


def render_qps(q):
    """quality_per_second.py's result."""
    body, ratios = [], []
    for s in q["scenes"]:
        name = s.get("name", s["scene"])
        if "skipped" in s:
            body.append([name] + ["—"] * 7 + [f"skipped: {s['skipped']}"])
            continue
        a, b = s["meshtrace"], s["mitsuba"]
        ratios.append(s["ratio"])
        body.append([name, num(a["relmse"]), num(b["relmse"]), num(a["seconds"]),
                     num(b["seconds"]), num(a["quality_per_second"]),
                     num(b["quality_per_second"]), num(s["ratio"]),
                     f"≥ {QPS_GOAL}: {verdict(s['ratio'] >= QPS_GOAL)}"])
    met = len(ratios) >= QPS_SCENES and min(ratios) >= QPS_GOAL
    return table(["scene", "relMSE meshtrace", "relMSE Mitsuba", "s meshtrace", "s Mitsuba",
                  "q/s meshtrace", "q/s Mitsuba", "ratio", "goal"], body) + [
        "",
        f"Mitsuba {q.get('mitsuba', '?')} {q.get('variant', '')}"
        + (f" (Dr.Jit on {os.path.basename(q['libllvm'])})" if q.get("libllvm") else "")
        + f"; {q.get('spp')} spp, "
        f"{q.get('seeds')} seed(s): relMSE the mean, s the median render seconds, "
        "q/s = 1 / (relMSE × s), ratio = q/s meshtrace / Mitsuba.",
        f"* Target: CPU quality per second ≥ {QPS_GOAL}× Mitsuba on the {QPS_SCENES} scenes: "
        + (verdict(met) if ratios else "not measured") + ".",
    ]


def flatten(value, key=""):
    """(dotted key, text) for every scalar in `value` outside bench rows; a list of scalars
    is one entry."""
    if is_rows(value):
        return []
    if isinstance(value, dict):
        return [kv for k, v in value.items() for kv in flatten(v, f"{key}.{k}" if key else k)]
    if isinstance(value, list) and any(isinstance(v, (dict, list)) for v in value):
        return [kv for i, v in enumerate(value) for kv in flatten(v, f"{key}[{i}]")]
    if isinstance(value, list):
        return [(key, ", ".join(num(v) if isinstance(v, float) else str(v) for v in value))]
    return [(key, num(value) if isinstance(value, float) else str(value))]


def render_device(device):
    """bench/device.sh's JSON: its `meshtrace bench` rows as the bench table, everything
    else as key/value pairs, then the GPU targets."""
    rows = bench_rows(device["data"])
    lines = [f"From `{device['source']}` (bench/device.sh).", ""]
    if rows:
        lines += render_bench(rows) + [""]
    pairs = flatten(device["data"])
    if pairs:
        lines += table(["key", "value"], [[f"`{k}`", v] for k, v in pairs]) + [""]
    return lines + gpu_targets(rows) + [
        f"* Target (H100/H200 class GPU): quality per second ≥ {GPU_QPS_GOAL}× Mitsuba 3 "
        "CUDA's: not evaluated here; see the key/value table."]


def render_machine(r):
    host, b = r["host"], r["binary"]
    commit = (b["commit"] or "unknown") + (" with uncommitted changes" if b["uncommitted_changes"]
                                           else "")
    lines = [
        f"### Machine: {r['machine']}", "",
        f"* Date: {r['date'][:16].replace('T', ' ')} UTC",
        *([f"* CPU: {host['cpu']}{cpu_detail(host)}, {host['threads']} threads",
           "* GPU: " + (", ".join(host["gpus"]) or "none; Vulkan adapters: "
                        + (", ".join(host["adapters"]) or "none"))]
          if host else ["* CPU and GPU: as the device JSON below records them"]),
        f"* Binary: `{b['path']}` ({b['version']}, sha256 {b['sha256'][:12]}, built "
        f"{b['built']}), measured at commit {commit}",
    ]
    if r["commands"]:
        lines += ["* Commands:", "", "  ```sh", *[f"  {c}" for c in r["commands"]], "  ```"]
    lines.append("")
    if r["quick"]:
        lines += ["**Quick run** (`--quick`: small images, one repeat, one seed): a test of "
                  "the scripts, not a measurement.", ""]
    sections = [
        ("Ray tracing and paths", "bench",
         lambda d: render_bench(d["rows"]) + gpu_targets(d["rows"])),
        ("Against Embree 4, one thread", "embree", render_embree),
        ("Quality per second against Mitsuba 3", "qps", render_qps),
        ("GPU", "device", render_device),
    ]
    for title, key, fn in sections:
        d = r.get(key)
        if d is None:
            continue
        lines += [f"#### {title}", ""]
        lines += [f"Not measured: {d['skipped']}."] if "skipped" in d else fn(d)
        lines.append("")
    return lines


def render():
    """Rewrites the tables between the markers of BENCHMARKS.md from bench/results/."""
    results = []
    for path in sorted(RESULTS.glob("*.json")):
        with open(path) as fh:
            r = json.load(fh)
        if r.get("schema") != SCHEMA:
            raise SystemExit(f"tables.py: {path}: schema {r.get('schema')}, not {SCHEMA}")
        results.append(r)
    lines = ["", "Generated by `python3 bench/tables.py render` from `bench/results/*.json`; "
             "do not edit by hand.", ""]
    if not results:
        lines += ["No results yet: `python3 bench/tables.py run` measures this machine.", ""]
    for r in sorted(results, key=lambda r: r["machine"]):
        lines += render_machine(r)
    text = BENCHMARKS.read_text()
    start, end = text.find(TABLES_BEGIN), text.find(TABLES_END)
    if start < 0 or end < start:
        raise SystemExit(f"tables.py: {BENCHMARKS.name} lacks {TABLES_BEGIN} ... {TABLES_END}")
    write_atomic(BENCHMARKS, text[:start + len(TABLES_BEGIN)] + "\n".join(lines) + text[end:])
    print(f"rendered {len(results)} machine(s) into {BENCHMARKS.name}", file=sys.stderr)


def write_atomic(path, text):
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    os.chmod(tmp, 0o644)
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="measure this machine, store its results, render")
    r.add_argument("--machine", help="results name (default: from the CPU model and threads)")
    r.add_argument("--quick", action="store_true",
                   help="small sizes, one repeat, one seed: for testing this script")
    r.add_argument("--skip", default="", help=f"comma-separated steps to skip: {','.join(STEPS)}")
    r.add_argument("--device-json", type=Path, help="the JSON bench/device.sh wrote")
    r.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "meshtrace")
    sub.add_parser("render", help="regenerate BENCHMARKS.md's tables from bench/results/")
    args = ap.parse_args()
    if args.command == "run":
        run(args)
    else:
        render()


if __name__ == "__main__":
    main()
