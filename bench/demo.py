"""Wall time of ``spherecal demo`` and its self-motion's simulated-to-wall ratio, against a baseline checkout.

Runs the whole command (a new process each time, as a user would) from this checkout and from a
baseline checkout with its own venv (``--base``, e.g. ``git worktree add ../base-demo d7b2fe6`` and a
``.venv`` there: the commit before issue 23), interleaved ``--repeats`` times, with ``OPENBLAS_NUM_THREADS=1``. For each
run: the whole-process wall time, the child's CPU time (user + sys: on one core of a quiet machine
the wall time; less sensitive to a busy machine), the demo's motion-stage time from its
``demo.json``; then the demo's self-motion alone (same seed, robot, fixtures, settings) in a
process of its own, wall and CPU time: simulated time (3 fixtures x ``--seconds``) over them is the
self-motion's simulated-to-wall ratio. Prints medians, the ratios this/base, and ``uptime`` before
and after; writes ``bench/demo.json``.

Targets (issue 23): self-motion >= 20x real time on one core; the demo <= 15 s on a quiet
2-core machine.

    .venv/bin/python bench/demo.py --base ../base-demo --repeats 3
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


#: Run in each checkout's venv: the demo's self-motion alone (its seeded true robot, fixtures and settings),
#: wall and CPU time of this process [s] as JSON.
MOTION = """
import json, sys, time
import numpy as np
from spherecal.controller.self_motion import DEFAULT_FIXTURES, SelfMotionSettings, collect_self_motion
from spherecal.correction import load_robot, perturb
seconds, seed = float(sys.argv[1]), int(sys.argv[2])
rng = np.random.default_rng(seed)
nominal = load_robot("panda")
truth = perturb(nominal, rng)
fixtures = {k: np.asarray(v, dtype=float) for k, v in DEFAULT_FIXTURES.items()}
wall, cpu = time.perf_counter(), time.process_time()
run = collect_self_motion(truth, nominal, fixtures, rng, SelfMotionSettings(seconds=seconds, samples=1500, noise=3e-4))
print(json.dumps({"wall_s": time.perf_counter() - wall, "cpu_s": time.process_time() - cpu,
                  "max_violation_m": run.max_violation.tolist(), "min_coverage": float(run.coverage.min())}))
"""


def run_motion(checkout: Path, seconds: float, seed: int) -> dict:
    """The demo's self-motion alone in ``checkout``'s venv: wall and CPU time [s] of the simulation."""
    python = checkout / ".venv" / "bin" / "python"
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    done = subprocess.run([str(python), "-c", MOTION, f"{seconds:g}", str(seed)], capture_output=True, text=True,
                          env=env, check=False, cwd=tempfile.gettempdir())
    if done.returncode != 0:
        sys.exit(f"bench/demo.py: self-motion in {checkout} failed: {done.stderr.strip()[-400:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", type=Path, required=True,
                        help="baseline checkout with its own .venv (e.g. ../base-demo)")
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
            motion = run_motion(checkout, args.seconds, args.seed)
            result.update({"sim_wall_s": motion["wall_s"], "sim_cpu_s": motion["cpu_s"],
                           "max_violation_m": motion["max_violation_m"], "min_coverage": motion["min_coverage"]})
            runs[name].append(result)
            print(f"  run {k + 1} {name:<4}: demo wall {result['wall_s']:6.1f} s cpu {result['cpu_s']:6.1f} s "
                  f"motion stage {result['motion_s']:6.1f} s | self-motion alone wall {motion['wall_s']:6.1f} s "
                  f"cpu {motion['cpu_s']:6.1f} s ({simulated / motion['cpu_s']:5.1f}x real time per CPU second)",
                  flush=True)
    load_after = uptime()
    summary = {}
    print(f"\nspherecal demo --seed {args.seed} --seconds {args.seconds:g} ({simulated:g} s simulated), "
          f"medians of {args.repeats}, OPENBLAS_NUM_THREADS=1")
    keys = ("wall_s", "cpu_s", "motion_s", "sim_wall_s", "sim_cpu_s")
    print("demo: whole process (wall, CPU) and its motion stage (wall); self-motion alone (wall, CPU), "
          "simulated / self-motion time")
    print(f"{'checkout':<9} {'wall_s':>8} {'cpu_s':>8} {'motion_s':>9} {'sim_wall_s':>11} {'sim_cpu_s':>10} "
          f"{'sim/wall':>9} {'sim/cpu':>8}")
    for name in ("base", "this"):
        values = {key: statistics.median([r[key] for r in runs[name]]) for key in keys}
        summary[name] = {**values, "simulated_to_wall": simulated / values["sim_wall_s"],
                         "simulated_to_cpu": simulated / values["sim_cpu_s"],
                         "headline": runs[name][0]["headline"], "runs": runs[name]}
        print(f"{name:<9} {values['wall_s']:8.1f} {values['cpu_s']:8.1f} {values['motion_s']:9.1f} "
              f"{values['sim_wall_s']:11.1f} {values['sim_cpu_s']:10.1f} "
              f"{summary[name]['simulated_to_wall']:8.1f}x {summary[name]['simulated_to_cpu']:7.1f}x")
    ratios = {key: summary["this"][key] / summary["base"][key] for key in keys}
    print(f"{'this/base':<9} {ratios['wall_s']:8.3f} {ratios['cpu_s']:8.3f} {ratios['motion_s']:9.3f} "
          f"{ratios['sim_wall_s']:11.3f} {ratios['sim_cpu_s']:10.3f}")
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
