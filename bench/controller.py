"""Speed of one control step and of a full simulated data collection (one core).

Prints median and 95th percentile time of one control step (Jacobian, QP build and solve)
along a self-motion trajectory, for the default (closed form when no bound is active, else the
persistent OSQP), the persistent OSQP alone, qpsolvers' OSQP path (re-created every call) and
DAQP through qpsolvers; then the wall time to simulate and record 3 default fixtures x 20 s.
Writes ``bench/controller.json``.
Targets (issue 4): <= 50 us per step with the default; <= 10 s for the 3 fixtures.
"""

from __future__ import annotations

import platform
import time
import warnings
from pathlib import Path

import bench_common  # first: import path, BLAS threads
import numpy as np  # noqa: E402
import qpsolvers  # noqa: E402

from spherecal.controller.nullspace import NullSpaceController  # noqa: E402
from spherecal.controller.self_motion import (  # noqa: E402
    DEFAULT_FIXTURES,  # noqa: E402
    SelfMotionSettings,
    collect_self_motion,
)
from spherecal.correction import load_robot, perturb  # noqa: E402


def step_times(panda, trajectory: np.ndarray, q_r: np.ndarray, solver: str, persistent: bool,
               closed_form: bool = False) -> np.ndarray:
    """(K,) seconds per ``controller.step`` along a recorded trajectory."""
    controller = NullSpaceController(panda, solver=solver, persistent=persistent, closed_form=closed_form)
    for q, v in zip(trajectory[:50], q_r[:50], strict=True):  # warm up
        controller.step(q, v)
    times = np.empty(trajectory.shape[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for k, (q, v) in enumerate(zip(trajectory, q_r, strict=True)):
            start = time.perf_counter()
            controller.step(q, v)
            times[k] = time.perf_counter() - start
    return times


def main() -> None:
    panda = load_robot("panda")
    rng = np.random.default_rng(0)
    true = perturb(panda, rng)
    fixtures = {k: np.array(v) for k, v in DEFAULT_FIXTURES.items()}
    start = time.perf_counter()
    run = collect_self_motion(true, panda, fixtures, rng, SelfMotionSettings(seconds=20.0))
    wall = time.perf_counter() - start

    # steps along a real self-motion path: 1 kHz slices of the recorded trajectory
    trajectory = run.trajectory_q[:3000]
    q_r = np.gradient(trajectory, 0.01, axis=0)
    results = {}
    print("one control step (Jacobian + QP build + solve), self-motion trajectory, 3000 steps")
    print(f"{'solver':<30} {'median_us':>10} {'p95_us':>10} {'ratio':>7}")
    cases = [("closed form + osqp (default)", "osqp", True, True), ("osqp persistent", "osqp", True, False),
             ("qpsolvers osqp", "osqp", False, False), ("qpsolvers daqp", "daqp", False, False)]
    base = None
    for label, solver, persistent, closed_form in cases:
        if solver not in qpsolvers.available_solvers:
            print(f"{label:<30} not installed (pip install daqp)")
            continue
        times = step_times(panda, trajectory, q_r, solver, persistent, closed_form) * 1e6
        median, p95 = float(np.median(times)), float(np.percentile(times, 95))
        base = base or median
        results[label] = {"median_us": median, "p95_us": p95}
        print(f"{label:<30} {median:10.1f} {p95:10.1f} {median / base:7.2f}")
    print(f"\nsimulate and record 3 fixtures x 20 s (coverage mode, default solver): {wall:.2f} s wall")
    print(run.coverage_table())
    results["three_fixtures_20s_wall_s"] = wall
    results["targets"] = {"step_median_us": 50, "three_fixtures_wall_s": 10}
    results["machine"] = {"python": platform.python_version(), "processor": platform.processor()}
    bench_common.write_json(Path(__file__).with_suffix(".json"), results, seed=0)


if __name__ == "__main__":
    main()
