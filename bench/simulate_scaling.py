"""Time of ``spherecal simulate`` against ``--seconds``: seconds of CPU and wall per simulated second.

Runs the whole command (a new process each time, as a user would, ``OPENBLAS_NUM_THREADS=1``) at each
``--seconds`` given, ``--repeats`` times, from this checkout and, with ``--base``, from a baseline checkout
with its own venv (e.g. ``git worktree add ../base-sim HEAD~1`` and a ``.venv`` there), interleaved. For
each run: the whole-process wall time and the child's CPU time (user + sys: less sensitive to a busy
machine). Simulated time is fixtures x ``--seconds`` (3 default fixtures). Prints the medians, CPU and
wall per simulated second (flat in ``--seconds`` when the time is linear in it), the ratios this/base,
whether both checkouts wrote the same samples.csv for the same arguments (every line
but the provenance comments, which name the folder and the time), and ``uptime`` before
and after; writes ``bench/simulate_scaling.json`` (or ``--out``).

    .venv/bin/python bench/simulate_scaling.py --seconds 30 60 120 240 --repeats 3 --base ../base-sim
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import bench_common  # noqa: F401  (first: import path, BLAS threads)

HERE = Path(__file__).resolve().parents[1]
FIXTURES = 3  # simulate's default P1, P2, P3


def uptime() -> str:
    """The machine's load line (``uptime``)."""
    return subprocess.run(["uptime"], capture_output=True, text=True, check=False).stdout.strip()


def run_simulate(checkout: Path, out: Path, seconds: float, extra: list[str]) -> dict[str, float]:
    """One ``spherecal simulate`` from ``checkout``'s venv into ``out``: wall [s] and child CPU [s]."""
    executable = checkout / ".venv" / "bin" / "spherecal"
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "RERUN_ANALYTICS": "0"}
    args = [str(executable), "simulate", "--out", str(out), "--seconds", f"{seconds:g}", *extra]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(args, capture_output=True, text=True, env=env, check=False, cwd=out.parent)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        sys.exit(f"bench/simulate_scaling.py: {' '.join(args)} failed ({done.returncode}): "
                 f"{done.stderr.strip()[-400:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu}


def samples_rows(out: Path) -> list[str]:
    """The lines of ``out``/samples.csv but its comments (the provenance: command line, time)."""
    return [line for line in (out / "samples.csv").read_text().splitlines() if not line.startswith("#")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, nargs="+", default=[30.0, 60.0, 120.0, 240.0],
                        help="--seconds of simulate to time (default 30 60 120 240)")
    parser.add_argument("--repeats", type=int, default=3, help="runs of each (default 3)")
    parser.add_argument("--base", type=Path, help="baseline checkout with its own .venv, run interleaved")
    parser.add_argument("--args", default="", help="more simulate arguments, one string (e.g. '--seed 3')")
    parser.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"), help="JSON written")
    args = parser.parse_args()
    extra = args.args.split()
    checkouts = {"this": HERE}
    if args.base is not None:
        if not (args.base / ".venv" / "bin" / "spherecal").exists():
            sys.exit(f"bench/simulate_scaling.py: --base {args.base}: no .venv/bin/spherecal")
        checkouts = {"base": args.base.resolve(), "this": HERE}
    load_before = uptime()
    print(f"uptime before: {load_before}")
    runs: dict[str, dict[float, list[dict]]] = {name: {s: [] for s in args.seconds} for name in checkouts}
    identical: dict[float, bool] = {}
    with tempfile.TemporaryDirectory() as folder:
        for seconds in args.seconds:
            for k in range(args.repeats):
                for name, checkout in checkouts.items():
                    out = Path(folder) / f"{name}_{seconds:g}"
                    result = run_simulate(checkout, out, seconds, extra)
                    runs[name][seconds].append(result)
                    simulated = FIXTURES * seconds
                    print(f"  --seconds {seconds:5g} run {k + 1} {name:<4}: wall {result['wall_s']:7.1f} s "
                          f"cpu {result['cpu_s']:7.1f} s ({1e3 * result['cpu_s'] / simulated:6.1f} ms CPU per "
                          f"simulated s)", flush=True)
            if len(checkouts) == 2:
                identical[seconds] = samples_rows(Path(folder) / f"base_{seconds:g}") == \
                    samples_rows(Path(folder) / f"this_{seconds:g}")
    load_after = uptime()
    print(f"\nspherecal simulate {' '.join(extra)} (3 fixtures x --seconds simulated), medians of {args.repeats}, "
          "OPENBLAS_NUM_THREADS=1; per simulated second [ms]")
    print(f"{'checkout':<9} {'seconds':>8} {'wall_s':>8} {'cpu_s':>8} {'wall_ms/s':>10} {'cpu_ms/s':>9}"
          + (f" {'this/base cpu':>14} {'same samples':>13}" if len(checkouts) == 2 else ""))
    summary: dict[str, dict[str, dict]] = {name: {} for name in checkouts}
    for seconds in args.seconds:
        simulated = FIXTURES * seconds
        for name in checkouts:
            values = {key: statistics.median([r[key] for r in runs[name][seconds]]) for key in ("wall_s", "cpu_s")}
            summary[name][f"{seconds:g}"] = {**values, "wall_per_simulated_s": values["wall_s"] / simulated,
                                              "cpu_per_simulated_s": values["cpu_s"] / simulated,
                                              "runs": runs[name][seconds]}
            line = (f"{name:<9} {seconds:8g} {values['wall_s']:8.1f} {values['cpu_s']:8.1f} "
                    f"{1e3 * values['wall_s'] / simulated:10.1f} {1e3 * values['cpu_s'] / simulated:9.1f}")
            if name == "this" and len(checkouts) == 2:
                ratio = values["cpu_s"] / summary["base"][f"{seconds:g}"]["cpu_s"]
                line += f" {ratio:14.3f} {'yes' if identical[seconds] else 'NO':>13}"
            print(line)
    print(f"uptime after:  {load_after}")
    result = {
        "command": f"spherecal simulate --seconds S {' '.join(extra)}".strip(),
        "fixtures": FIXTURES,
        "repeats": args.repeats,
        "base": str(args.base) if args.base else None,
        "summary": summary,
        "samples_identical": {f"{s:g}": v for s, v in identical.items()},
        "uptime_before": load_before,
        "uptime_after": load_after,
        "machine": {"python": platform.python_version(), "processor": platform.processor(), "cpus": os.cpu_count()},
    }
    args.out.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
