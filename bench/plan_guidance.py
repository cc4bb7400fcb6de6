"""Recording guidance at the robot: 50 candidate plate placements ranked, start-up included.

A real recording (MUKCa ``panda_2_clean/front_center``, imported with `spherecal import`) and the recorded
plate placed over a 5 x 5 grid in front of the arm in 2 orientations (50 placements): the whole command
``spherecal plan --samples ... --plate-grid ... --out plan.json`` as a fresh process, median of ``--repeats``
runs, against `spherecal calibrate` of the same recording in the same script (the baseline: what the user
runs anyway). Goal: under 10 s on 2 cores. Prints ``uptime`` before and after; writes
``bench/plan_guidance.json``.

    .venv/bin/python bench/plan_guidance.py [--data ../shared/data/mukca] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics

HERE = Path(__file__).resolve().parent
ROBOT = HERE.parent / "tests/data/mukca/panda_ball.yaml"
GRID = "0.3,0.6,5;-0.4,0.4,5;0.05,0.05,1"
ORIENTATIONS = 2
SEED = 0


def _uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def _timed(argv: list[str]) -> float:
    clock = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    seconds = time.perf_counter() - clock
    if done.returncode != 0:
        raise SystemExit(f"failed: {' '.join(argv)}\n{done.stdout}\n{done.stderr}")
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=None, help="MUKCa data folder (default: shared/data/mukca found upward)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    root = Path(args.data) if args.data else bench_common.find_mukca()
    spherecal = str(Path(sys.executable).with_name("spherecal"))
    before = _uptime()
    print(before)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "src").mkdir()
        (tmp / "src" / "front_center").symlink_to(root / "data" / "panda_2_clean" / "front_center")
        _timed([spherecal, "import", str(tmp / "src"), "--format", "mukca", "--robot", str(ROBOT), "--out",
                str(tmp / "rec")])
        recording = ["--robot", str(ROBOT), "--samples", str(tmp / "rec/samples.csv"), "--fixtures",
                     str(tmp / "rec/fixtures.yaml")]
        plan = [spherecal, "plan", *recording, "--plate-grid", GRID, "--plate-orientations", str(ORIENTATIONS),
                "--seed", str(SEED), "--out", str(tmp / "plan.json")]
        calibrate = [spherecal, "calibrate", *recording, "--out", str(tmp / "cal.yaml")]
        plans, calibrations = [], []
        for _ in range(args.repeats):  # interleaved: both see the same load
            plans.append(_timed(plan))
            calibrations.append(_timed(calibrate))
        result = json.loads((tmp / "plan.json").read_text())
    after = _uptime()
    median = sorted(plans)[len(plans) // 2]
    baseline = sorted(calibrations)[len(calibrations) // 2]
    placements = len(result["ranking"]) + len(result["refused"])
    print(f"spherecal plan, {placements} plate placements ({len(result['ranking'])} recordable), start-up included: "
          f"median {median:.2f} s (runs {', '.join(f'{t:.2f}' for t in plans)}); spherecal calibrate of the same "
          f"recording: median {baseline:.2f} s; ratio {median / baseline:.2f}")
    print("stages of the last plan [s]: " + ", ".join(f"{k} {v:.2f}" for k, v in result["timings_s"].items()))
    print(f"best: {result['ranking'][0]['name']} {result['ranking'][0]['predicted_error_m'] * 1e3:.4f} mm; "
          f"{result['stop']['line']}")
    print(after)
    out = bench_common.write_json(HERE / "plan_guidance.json", {
        "plan_seconds": plans, "calibrate_seconds": calibrations, "median_s": median, "baseline_median_s": baseline,
        "uptime_before": before, "uptime_after": after,
    }, seed=SEED, inputs={"data": root, "placements": placements, "grid": GRID, "orientations": ORIENTATIONS})
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
