"""Wall time, peak memory and BLAS threads of ``spherecal calibrate`` on many fixtures: this checkout against
another (``--old``), in the same session.

Usage: python bench/factorisation.py [--old TREE] [--runs N] [--data DIR]

The data: the embedded Panda simulated (``spherecal simulate``, seed 2, 0.3 mm noise) at 10 fixtures x 2000
samples with every centre-to-centre distance known, and at the first 3 of them x 500 (about a minute, once;
``--data`` keeps it for the next run). Each case (default model selection; ``--model dh``) is calibrated ``--runs``
times in fresh processes, this checkout's code and ``--old``'s alternating so both meet the same load; the
figures are medians. A run also reports its CPU time over its wall time (about 1 on one thread) and the thread
count of every BLAS/OpenMP library loaded when it ends (the command line caps them at 1: a library loaded
during the run uncapped would show here), and the printed output of the two trees is compared (but for its
timing figures). Prints the figures with ``uptime``'s load and writes bench/factorisation.json.

``--old``: a checkout of another commit (``git worktree add /tmp/old <commit>``); its modules are imported in
place of this checkout's (the same mapping of folders into ``spherecal`` as pyproject.toml's).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import bench_common  # first: import path, BLAS threads
import numpy as np  # noqa: E402

from spherecal.validation.threads import VARIABLES  # noqa: E402

HERE = Path(__file__).resolve().parents[1]
#: Fixture centres [m] in front of the Panda: five pairs 50 mm apart.
CENTRES = {"A0": [0.45, -0.25, 0.15], "A1": [0.45, -0.20, 0.15], "B0": [0.55, 0.0, 0.20], "B1": [0.55, 0.05, 0.20],
           "C0": [0.40, 0.25, 0.30], "C1": [0.40, 0.30, 0.30], "D0": [0.60, -0.10, 0.40], "D1": [0.60, -0.05, 0.40],
           "E0": [0.35, 0.10, 0.50], "E1": [0.35, 0.15, 0.50]}
#: case -> (data folder, extra calibrate options)
CASES = {"10x2000 default": ("10x2000", []), "10x2000 --model dh": ("10x2000", ["--model", "dh"]),
         "3x500 default": ("3x500", [])}

#: What a run executes: ``tree`` mapped into ``spherecal`` ahead of the installed one, then the command line.
CHILD = r"""
import json, resource, sys, time
from importlib.util import spec_from_file_location
from pathlib import Path

tree = Path(sys.argv[1])
folders = {"spherecal": "spherecal", "spherecal.correction": "correction", "spherecal.identification": "identification",
           "spherecal.controller": "controller", "spherecal.validation": "validation"}

class Tree:
    @staticmethod
    def find_spec(name, path=None, target=None):
        if name not in folders:
            return None
        init = tree / folders[name] / "__init__.py"
        return spec_from_file_location(name, init, submodule_search_locations=[str(init.parent)])

sys.meta_path.insert(0, Tree)
from spherecal.cli import main

start, cpu = time.perf_counter(), resource.getrusage(resource.RUSAGE_SELF)
code = main(sys.argv[2:])
wall, end = time.perf_counter() - start, resource.getrusage(resource.RUSAGE_SELF)
from threadpoolctl import threadpool_info
import spherecal.identification
print("BENCH " + json.dumps({
    "code": code, "wall_s": wall, "cpu_s": end.ru_utime + end.ru_stime - cpu.ru_utime - cpu.ru_stime,
    "max_rss_mib": end.ru_maxrss / 1024, "from": spherecal.identification.__file__,
    "threads": {Path(i["filepath"]).name: i["num_threads"] for i in threadpool_info()}}), file=sys.stderr)
"""


def make_data(folder: Path) -> None:
    """The two simulated data sets under ``folder`` (kept when there)."""
    for name, count, names in (("10x2000", 2000, list(CENTRES)), ("3x500", 500, ["A0", "B0", "C1"])):
        out = folder / name
        if (out / "samples.csv").is_file():
            continue
        out.mkdir(parents=True, exist_ok=True)
        spec = out / "layout.yaml"
        spec.write_text("fixtures:\n" + "".join(f"  {n}: {{position: {CENTRES[n]}}}\n" for n in names))
        print(f"simulating {name} ...", flush=True)
        bench_common.run_cli(["simulate", "--out", str(out), "--fixtures", str(spec), "--per-fixture", str(count),
                              "--seconds", str(max(20, count // 25)), "--seed", "2", "--known-distances"])


def run(tree: Path, argv: list[str]) -> tuple[dict, str]:
    """One calibration in a fresh process on ``tree``'s code: its figures and what it printed."""
    env = {k: v for k, v in os.environ.items() if k not in VARIABLES}  # the command line's own cap, not ours
    done = subprocess.run([sys.executable, "-c", CHILD, str(tree), *argv], capture_output=True, text=True, env=env)
    lines = [line for line in done.stderr.splitlines() if line.startswith("BENCH ")]
    if not lines:
        raise SystemExit(f"failed: {tree}: spherecal {' '.join(argv)}\n{done.stderr}")
    return json.loads(lines[-1][6:]), done.stdout


def untimed(text: str) -> str:
    """Printed output without its timing figures (``in 4.79 s``, ``2.85 s)``)."""
    return re.sub(r"\d+\.\d+ s\b", "T s", text)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, help="checkout to compare with (default: none, this one alone)")
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--data", type=Path, help="folder of the simulated data (default: a temporary one)")
    parser.add_argument("--cases", default=",".join(CASES), help="comma-separated, of: " + ", ".join(CASES))
    args = parser.parse_args()
    data = args.data or Path(tempfile.mkdtemp(prefix="spherecal-factorisation-"))
    make_data(data)
    trees = {"new": HERE, **({"old": args.old.resolve()} if args.old else {})}
    load = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"load before: {load}")
    results: dict = {"load_before": load, "runs": args.runs, "cases": {}}
    out = Path(tempfile.mkdtemp(prefix="spherecal-factorisation-out-"))
    for case in args.cases.split(","):
        folder, extra = CASES[case]
        figures: dict = {name: [] for name in trees}
        printed: dict = {}
        for _ in range(args.runs):
            for name, tree in trees.items():
                argv = ["calibrate", "--robot", "panda", "--samples", str(data / folder / "samples.csv"),
                        "--fixtures", str(data / folder / "fixtures.yaml"), *extra, "--out", str(out / f"{name}.yaml")]
                got, text = run(tree, argv)
                figures[name].append(got)
                printed.setdefault(name, untimed(text.replace(str(out / f"{name}.yaml"), "OUT")))
        row: dict = {}
        for name, runs in figures.items():
            wall = [r["wall_s"] for r in runs]
            row[name] = {"median_wall_s": float(np.median(wall)), "wall_s": wall,
                         "cpu_over_wall": float(np.median([r["cpu_s"] / r["wall_s"] for r in runs])),
                         "max_rss_mib": float(np.median([r["max_rss_mib"] for r in runs])),
                         "threads": runs[-1]["threads"], "code_from": runs[-1]["from"]}
            print(f"{case:<20} {name}: median {row[name]['median_wall_s']:.2f} s (runs "
                  f"{', '.join(f'{w:.2f}' for w in wall)}), cpu/wall {row[name]['cpu_over_wall']:.2f}, peak "
                  f"{row[name]['max_rss_mib']:.0f} MiB, BLAS threads {row[name]['threads']}", flush=True)
        if "old" in row:
            row["new_over_old"] = row["new"]["median_wall_s"] / row["old"]["median_wall_s"]
            row["same_output"] = printed["new"] == printed["old"]
            print(f"{case:<20} new / old {row['new_over_old']:.2f}, same printed output: {row['same_output']} "
                  f"(code from {row['new']['code_from']} and {row['old']['code_from']})")
        results["cases"][case] = row
    load = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"load after: {load}")
    results["load_after"] = load
    bench_common.write_json(Path(__file__).with_suffix(".json"), results,
                            inputs={"data": str(data), "old": str(args.old) if args.old else None})


if __name__ == "__main__":
    main()
