"""The solver against its floor, and `calibrate` whole-process against an in-process reference LM.

Usage: OPENBLAS_NUM_THREADS=1 python bench/solver.py [--repeats N] [--seed S] [--baseline-python PYTHON]

Data: 3 x 500 samples on a perturbed Panda (seed S), 0.3 mm fixture noise, known distances.

1. One solve of that problem, interleaved, medians of N (>= 5): ours (``levenberg_marquardt``),
   scipy's MINPACK (``least_squares(method='lm', x_scale='jac')``, tolerances 1e-12) and a plain
   column-scaled Gauss-Newton (the floor: full steps, no safeguard). Jacobian and residual
   evaluations, wall time, cost ratio and largest parameter difference in std against scipy's.
2. ``spherecal calibrate --model dh`` and ``spherecal calibrate`` (default ``auto``), each also as it
   was before (``*_before``: scipy's LM and scipy.special's chi-square tail patched back in), on the same
   samples as whole processes (start-up, reading, model selection, self-check, writing included),
   interleaved with two in-process references on the same data, both with scipy's LM as the solver:
   ``reference_lm_solve``, one ``least_squares(method='lm')`` on the already built problem, and
   ``reference_lm_calibration``, the library's lm calibration ``calibrate(panda, dataset, spec)`` as
   ``bench/identification.py`` times it (build, solve, prune, re-solve, covariance, self-check) with
   scipy's LM in place of ours. Ratios of medians; goal: default <= 0.3x the reference.
   With ``--baseline-python`` (the interpreter of another checkout's environment, e.g. the tree before a
   change), its ``spherecal calibrate`` runs too, interleaved (``*_baseline``): before / after on one load.
   Beside the wall time, each process's CPU time (user + system): less sensitive to a busy machine.
3. The floor of any whole process, interleaved with the runs above: ``python -c pass`` (the interpreter),
   ``python -c "import numpy"`` and ``python -c "import numpy, scipy.linalg"``, as ratios of the same
   reference (what share of the goal start-up alone already takes).

Prints a table and writes bench/solver.json (versions, seed, inputs, uptime before and after).
Timings on a shared machine are noisy: run with OPENBLAS_NUM_THREADS=1 (bench_common sets it when
unset) and read the load printed beside them.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import bench_common  # noqa: F401  (first: import path, BLAS threads)
import numpy as np  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402  (the reference)

from spherecal.correction import load_robot, perturb  # noqa: E402
from spherecal.correction.files.fixtures import write_fixtures  # noqa: E402
from spherecal.correction.files.samples_csv import write_samples  # noqa: E402
from spherecal.identification import calibrate as pipeline  # noqa: E402
from spherecal.identification.build import build_problem  # noqa: E402
from spherecal.identification.identifiability import predicted_std  # noqa: E402
from spherecal.identification.levenberg import gauss_newton, levenberg_marquardt  # noqa: E402
from spherecal.identification.solvers import solve_scipy  # noqa: E402
from spherecal.identification.synthetic import make_dataset  # noqa: E402

NOISE = 3e-4
#: The command as it was before issue 23's solver work, in the same tree: scipy's MINPACK LM as the
#: solver and scipy.special's chi-square tail in the self-check (both imported at start-up as before).
BEFORE = """
import sys
import numpy as np
from scipy.special import gammaincc
from spherecal.cli import main
from spherecal.identification import calibrate as pipeline, consistency, selfcheck
from spherecal.identification.solvers import solve_scipy
pipeline.solve_lm = lambda problem, x0, loss: solve_scipy(problem, x0, loss)
chi2 = lambda s, dof: float(np.log10(max(gammaincc(dof / 2, max(s, 0.0) / 2), 1e-300)))
consistency.log10_chi2_sf = selfcheck.log10_chi2_sf = chi2
sys.exit(main(sys.argv[1:]))
"""


def children_cpu() -> float:
    """CPU time [s] (user + system) of every finished child process so far."""
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


class Counted:
    """Residual and Jacobian callables of a problem, counting their calls."""

    def __init__(self, problem) -> None:
        self.problem, self.residuals_calls, self.jacobian_calls = problem, 0, 0

    def residuals(self, x):
        self.residuals_calls += 1
        return self.problem.residuals(x)

    def jacobian(self, x):
        self.jacobian_calls += 1
        return self.problem.jacobian(x)


def run_ours(problem):
    counted = Counted(problem)
    out = levenberg_marquardt(counted.residuals, counted.jacobian, problem.x0)
    return out.x, out.cost, counted


def run_scipy(problem):
    counted = Counted(problem)
    out = least_squares(
        counted.residuals, problem.x0, jac=counted.jacobian, method="lm", x_scale="jac", ftol=1e-12, xtol=1e-12,
        gtol=1e-12,
    )
    return out.x, float(out.cost), counted


def run_floor(problem):
    counted = Counted(problem)
    out = gauss_newton(counted.residuals, counted.jacobian, problem.x0)
    return out.x, out.cost, counted


def calibrate_with_scipy(panda, dataset, spec):
    """The library's lm calibration with scipy's MINPACK LM as its solver (the reference)."""
    original = pipeline.solve_lm
    pipeline.solve_lm = lambda problem, x0, loss: solve_scipy(problem, x0, loss)
    try:
        return pipeline.calibrate(panda, dataset, spec)
    finally:
        pipeline.solve_lm = original


def one_solve(problem, repeats: int) -> dict:
    solvers = {"ours": run_ours, "scipy_lm": run_scipy, "gauss_newton_floor": run_floor}
    walls: dict[str, list[float]] = {name: [] for name in solvers}
    ends: dict = {}
    for _ in range(repeats):  # interleaved: the load hits all three alike
        for name, solve in solvers.items():
            clock = time.perf_counter()
            ends[name] = solve(problem)
            walls[name].append(time.perf_counter() - clock)
    x_ref, cost_ref, _ = ends["scipy_lm"]
    sigma = np.sqrt(2 * cost_ref / (problem.n_residuals - problem.n_unknowns))
    std = predicted_std(problem.jacobian(x_ref), sigma)
    rows = {}
    for name, (x, cost, counted) in ends.items():
        rows[name] = {
            "median_s": float(np.median(walls[name])),
            "runs_s": walls[name],
            "jacobians": counted.jacobian_calls,
            "residuals": counted.residuals_calls,
            "cost_ratio_minus_1": cost / cost_ref - 1.0,
            "max_dx_over_std": float(np.max(np.abs(x - x_ref) / std)),
        }
    base = rows["scipy_lm"]["median_s"]
    print(f"one solve: {problem.n_residuals} residuals x {problem.n_unknowns} unknowns, medians of {repeats}")
    print(
        f"  {'solver':<20} {'median s':>9} {'x scipy':>8} {'Jacobians':>9} {'residuals':>9} "
        f"{'cost/ref-1':>11} {'max dx/std':>10}"
    )
    for name, row in rows.items():
        print(
            f"  {name:<20} {row['median_s']:9.4f} {row['median_s'] / base:8.2f} {row['jacobians']:9d} "
            f"{row['residuals']:9d} {row['cost_ratio_minus_1']:11.1e} {row['max_dx_over_std']:10.1e}"
        )
    return rows


def whole_process(folder: Path, problem_builder, calibration_with_scipy, repeats: int,
                  baseline: str | None = None) -> dict:
    arguments = ["calibrate", "--robot", "panda", "--samples", str(folder / "samples.csv"), "--fixtures",
                 str(folder / "fixtures.yaml")]
    after = [sys.executable, "-m", "spherecal", *arguments]
    before = [sys.executable, "-c", BEFORE, *arguments]
    variants = {
        "calibrate_dh": [*after, "--model", "dh"],
        "calibrate_default": after,
        "calibrate_dh_before": [*before, "--model", "dh"],
        "calibrate_default_before": before,
    }
    if baseline:
        variants["calibrate_dh_baseline"] = [baseline, "-m", "spherecal", *arguments, "--model", "dh"]
        variants["calibrate_default_baseline"] = [baseline, "-m", "spherecal", *arguments]
    floors = {  # no --out: start-up alone
        "floor_python": [sys.executable, "-c", "pass"],
        "floor_import_numpy": [sys.executable, "-c", "import numpy"],
        "floor_import_numpy_scipy_linalg": [sys.executable, "-c", "import numpy, scipy.linalg"],
    }
    walls: dict[str, list[float]] = {
        "reference_lm_solve": [], "reference_build": [], "reference_lm_calibration": [], **{k: [] for k in variants},
        **{k: [] for k in floors},
    }
    cpus: dict[str, list[float]] = {k: [] for k in [*variants, *floors]}
    for _ in range(repeats):
        clock = time.perf_counter()
        problem = problem_builder()
        walls["reference_build"].append(time.perf_counter() - clock)
        clock = time.perf_counter()
        run_scipy(problem)
        walls["reference_lm_solve"].append(time.perf_counter() - clock)
        clock = time.perf_counter()
        calibration_with_scipy()
        walls["reference_lm_calibration"].append(time.perf_counter() - clock)
        for name, extra in variants.items():
            out = folder / f"{name}.yaml"
            clock, cpu = time.perf_counter(), children_cpu()
            done = subprocess.run([*extra, "--out", str(out)], capture_output=True, text=True)
            walls[name].append(time.perf_counter() - clock)
            cpus[name].append(children_cpu() - cpu)
            if done.returncode != 0:
                raise SystemExit(f"{name} failed: {done.stderr.strip()}")
        for name, command in floors.items():
            clock, cpu = time.perf_counter(), children_cpu()
            subprocess.run(command, check=True)
            walls[name].append(time.perf_counter() - clock)
            cpus[name].append(children_cpu() - cpu)
    medians = {name: float(np.median(runs)) for name, runs in walls.items()}
    solve, calibration = medians["reference_lm_solve"], medians["reference_lm_calibration"]
    print(f"whole process, medians of {repeats} interleaved runs, against the in-process references (scipy's LM)")
    cpu_medians = {name: float(np.median(runs)) for name, runs in cpus.items()}
    print(f"  {'':<32} {'median s':>8} {'x solve':>8} {'x lm calibration':>16} {'CPU s':>6}")
    for name, median in medians.items():
        cpu = f"{cpu_medians[name]:6.3f}" if name in cpu_medians else ""
        print(f"  {name:<32} {median:8.3f} {median / solve:8.2f} {median / calibration:16.2f} {cpu}")
    for name in ("calibrate_default", "calibrate_dh"):
        goal = medians[name] / calibration
        print(f"  {name} / reference lm calibration: {goal:.2f} x (goal for default <= 0.3 x); "
              f"after / before: {medians[name] / medians[name + '_before']:.2f}")
    print(f"  floor: the interpreter alone {medians['floor_python'] / calibration:.2f} x, importing numpy "
          f"{medians['floor_import_numpy'] / calibration:.2f} x, numpy and scipy.linalg "
          f"{medians['floor_import_numpy_scipy_linalg'] / calibration:.2f} x the reference lm calibration")
    if baseline:
        for name in ("calibrate_default", "calibrate_dh"):
            print(f"  {name} / its baseline ({baseline}): wall {medians[name] / medians[name + '_baseline']:.2f}, "
                  f"CPU {cpu_medians[name] / cpu_medians[name + '_baseline']:.2f}")
    return {
        "medians_s": medians,
        "runs_s": walls,
        "cpu_medians_s": cpu_medians,
        "cpu_runs_s": cpus,
        "baseline_python": baseline,
        "ratio_to_reference_lm_solve": {k: v / solve for k, v in medians.items()},
        "ratio_to_reference_lm_calibration": {k: v / calibration for k, v in medians.items()},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="interleaved runs per figure (>= 5)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the true robot (the samples use seed + 1)")
    parser.add_argument("--baseline-python", default=None,
                        help="python of another checkout's environment: its calibrate runs interleaved")
    args = parser.parse_args()
    load_before = uptime()
    print(load_before, f"| OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")
    panda = load_robot("panda")
    true = perturb(panda, np.random.default_rng(args.seed))
    dataset, spec = make_dataset(true, rng=np.random.default_rng(args.seed + 1), noise=NOISE)
    problem = build_problem(panda, dataset, spec)
    inputs = {"robot": "panda (embedded)", "samples_per_fixture": 500, "fixtures": list(dataset.fixture_names),
              "noise_m": NOISE, "known_distances": True, "baseline_python": args.baseline_python}
    results: dict = {
        "openblas_num_threads": os.environ.get("OPENBLAS_NUM_THREADS"),
        "uptime_before": load_before,
    }
    results["one_solve"] = one_solve(problem, max(args.repeats, 5))
    with tempfile.TemporaryDirectory() as folder:
        write_samples(Path(folder) / "samples.csv", dataset)
        write_fixtures(Path(folder) / "fixtures.yaml", spec)
        results["whole_process"] = whole_process(
            Path(folder),
            lambda: build_problem(panda, dataset, spec),
            lambda: calibrate_with_scipy(panda, dataset, spec),
            max(args.repeats, 5),
            args.baseline_python,
        )
    results["uptime_after"] = uptime()
    print(results["uptime_after"])
    bench_common.write_json(Path(__file__).with_suffix(".json"), results, seed=args.seed, inputs=inputs)


if __name__ == "__main__":
    main()
