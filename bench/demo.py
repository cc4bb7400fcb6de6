"""Wall time of ``spherecal demo`` and its self-motion's simulated-to-wall ratio, against a baseline checkout.

Runs the whole command (a new process each time, as a user would) from this checkout and from a
baseline checkout with its own venv (``--base``, e.g. the commit before issue 23 at
``/tmp/work/base-demo``), interleaved ``--repeats`` times, with ``OPENBLAS_NUM_THREADS=1``. For each
run: the whole-process wall time, the child's CPU time (user + sys, less sensitive to a busy
machine than the wall time), and the demo's own motion-stage time from its ``demo.json``
(``timings_s.motion``), whose ratio to the simulated time (fixtures x ``--seconds``) is the
self-motion's simulated-to-wall ratio. Prints medians, the ratios this/base, and ``uptime``
before and after; writes ``bench/demo.json``.

Targets (issue 23): self-motion >= 20x real time on one core; the demo <= 15 s on a quiet
2-core machine.

    .venv/bin/python bench/demo.py --base /tmp/work/base-demo --repeats 3
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import bench_common  # noqa: F401  (first: import path, BLAS threads)

HERE = Path(__file__).resolve().parents[1]
FIXTURES = 3  # the demo's P1, P2, P3


def uptime() -> str:
    """The machine's load line (``uptime``)."""
    return subprocess.run(["uptime"], capture_output=True, text=True, check=False).stdout.strip()


def run_demo(checkout: Path, seconds: float, seed: int) -> dict[str, float]:
    """One ``spherecal demo`` from ``checkout``'s venv: wall [s], child CPU [s], motion stage [s]."""
    executable = checkout / ".venv" / "bin" / "spherecal"
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "RERUN_ANALYTICS": "0"}
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "demo"
        args = [str(executable), "demo", "--out", str(out), "--quiet", "--seed", str(seed), "--seconds", f"{seconds:g}"]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        done = subprocess.run(args, capture_output=True, text=True, env=env, check=False, cwd=folder)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if done.returncode != 0:
            sys.exit(f"bench/demo.py: {executable} demo failed ({done.returncode}): {done.stderr.strip()[-400:]}")
        report = json.loads((out / "demo.json").read_text())
    headline = next((line for line in done.stdout.splitlines() if line.startswith("random workspace, mean")), "")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "motion_s": report["timings_s"]["motion"], "headline": headline}


def median(values: list[float]) -> float:
    ordered = sorted(values)
    middle = len(ordered) // 2
    return ordered[middle] if len(ordered) % 2 else 0.5 * (ordered[middle - 1] + ordered[middle])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", type=Path, default=Path("/tmp/work/base-demo"),
                        help="baseline checkout with its own .venv (default /tmp/work/base-demo)")
    parser.add_argument("--repeats", type=int, default=3, help="runs of each, interleaved (default 3)")
    parser.add_argument("--seconds", type=float, default=60.0,
                        help="simulated self-motion per fixture [s] (default 60)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the demo (default 0)")
    args = parser.parse_args()
    if not (args.base / ".venv" / "bin" / "spherecal").exists():
        sys.exit(f"bench/demo.py: --base {args.base}: no .venv/bin/spherecal (make a venv there and pip install -e .)")
    load_before = uptime()
    print(f"uptime before: {load_before}")
    simulated = FIXTURES * args.seconds
    runs: dict[str, list[dict]] = {"base": [], "this": []}
    for k in range(args.repeats):
        for name, checkout in (("base", args.base), ("this", HERE)):
            result = run_demo(checkout, args.seconds, args.seed)
            runs[name].append(result)
            print(f"  run {k + 1} {name:<4}: wall {result['wall_s']:6.1f} s  cpu {result['cpu_s']:6.1f} s  "
                  f"motion {result['motion_s']:6.1f} s ({simulated / result['motion_s']:5.1f}x real time)", flush=True)
    load_after = uptime()
    summary = {}
    print(f"\nspherecal demo --seed {args.seed} --seconds {args.seconds:g} ({simulated:g} s simulated), "
          f"medians of {args.repeats}, OPENBLAS_NUM_THREADS=1")
    print(f"{'checkout':<9} {'wall_s':>8} {'cpu_s':>8} {'motion_s':>9} {'sim/wall':>9}")
    for name in ("base", "this"):
        wall, cpu, motion = (median([r[key] for r in runs[name]]) for key in ("wall_s", "cpu_s", "motion_s"))
        summary[name] = {"wall_s": wall, "cpu_s": cpu, "motion_s": motion, "simulated_to_wall": simulated / motion,
                         "headline": runs[name][0]["headline"], "runs": runs[name]}
        print(f"{name:<9} {wall:8.1f} {cpu:8.1f} {motion:9.1f} {simulated / motion:8.1f}x")
    ratios = {key: summary["this"][key] / summary["base"][key] for key in ("wall_s", "cpu_s", "motion_s")}
    print(f"{'this/base':<9} {ratios['wall_s']:8.3f} {ratios['cpu_s']:8.3f} {ratios['motion_s']:9.3f}")
    for name in ("base", "this"):
        print(f"{name}: {summary[name]['headline']}")
    print(f"uptime after:  {load_after}")
    result = {
        "command": f"spherecal demo --seed {args.seed} --seconds {args.seconds:g} --quiet",
        "simulated_s": simulated,
        "repeats": args.repeats,
        "base": str(args.base),
        "summary": summary,
        "ratios_this_over_base": ratios,
        "uptime_before": load_before,
        "uptime_after": load_after,
        "targets": {"demo_wall_s_quiet": 15.0, "simulated_to_wall": 20.0},
        "machine": {"python": platform.python_version(), "processor": platform.processor(), "cpus": os.cpu_count()},
    }
    Path(__file__).with_suffix(".json").write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
