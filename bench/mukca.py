"""Real robots: MUKCa's recordings through `spherecal import`, `calibrate` and `validate` (socket-only).

For each robot of ``../shared/data/mukca`` (or ``--data``): train on one placement and validate on all
the others (MUKCa's protocol: panda_2_clean trained on front_center, their figure 7.79 -> 0.347 mm test
MAE), then leave-one-placement-out (train on all placements but one, validate on that one). Test MAE =
mean over held-out sockets of the mean distance of the predicted ball centres from their mean; distance
error = mean |distance between a placement's two socket means - 50 mm|. Prints a table and writes
``bench/mukca.json``.

    .venv/bin/python bench/mukca.py [--data ../shared/data/mukca]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
import time
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics

from spherecal.cli import main

HERE = Path(__file__).resolve().parent
ROBOTS = {  # robot folder -> (robot file with the ball as tool point, training placement of protocol 1)
    "panda_2_clean": (HERE.parent / "tests/data/mukca/panda_ball.yaml", "front_center"),
    "panda_4_clean": (HERE.parent / "tests/data/mukca/panda_ball.yaml", "front"),
    "dinova_1": (HERE.parent / "tests/data/mukca/gen3lite_ball.yaml", "front"),
}


def _run(argv: list[str]) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(argv)
    if code != 0:
        raise SystemExit(f"failed ({code}): spherecal {' '.join(argv)}\n{out.getvalue()}")
    return out.getvalue()


def _folder_of(placements: list[Path], where: Path) -> Path:
    """A folder of links to some placement folders (what `import --format mukca` reads)."""
    where.mkdir(parents=True)
    for p in placements:
        (where / p.name).symlink_to(p)
    return where


def experiment(robot: Path, train: list[Path], everything: Path, work: Path, name: str) -> dict:
    """Import the training placements, calibrate, validate on every placement (held-out summary)."""
    clock = time.perf_counter()
    source = _folder_of(train, work / f"{name}_src")
    _run(["import", str(source), "--format", "mukca", "--robot", str(robot), "--out", str(work / f"{name}_train")])
    calibrated = work / f"{name}_cal.yaml"
    calibrate = [
        "calibrate",
        "--robot",
        str(robot),
        "--samples",
        str(work / f"{name}_train/samples.csv"),
        "--fixtures",
        str(work / f"{name}_train/fixtures.yaml"),
        "--out",
        str(calibrated),
    ]
    errors = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(errors):
        refused = main(calibrate) != 0
    if refused:  # the self-check refused it: say so, and measure the forced result anyway
        _run([*calibrate, "--force"])
    report = work / f"{name}_validate.json"
    _run(
        [
            "validate",
            "--nominal",
            str(robot),
            "--calibrated",
            str(calibrated),
            "--samples",
            str(everything / "samples.csv"),
            "--fixtures",
            str(everything / "fixtures.yaml"),
            "--out",
            str(report),
        ]
    )
    held = json.loads(report.read_text())["sockets"]["held_out"]
    return {
        "train": [p.name for p in train],
        "refused": errors.getvalue().strip() if refused else "",
        "seconds": time.perf_counter() - clock,
        **{f"{m}_{k}_mm": None if v is None else v * 1e3 for m, s in held.items() for k, v in s.items()},
    }


def main_bench() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(bench_common.find_mukca() / "data"))
    args = parser.parse_args()
    data = Path(args.data)
    results: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        for robot_dir, (robot, first) in ROBOTS.items():
            folder = data / robot_dir
            if not folder.is_dir():
                print(f"{robot_dir}: not found under {data}, skipped")
                continue
            work = Path(tmp) / robot_dir
            everything = work / "all"
            _run(["import", str(folder), "--format", "mukca", "--robot", str(robot), "--out", str(everything)])
            placements = sorted(p for p in folder.iterdir() if p.is_dir())
            rows = {"protocol": experiment(robot, [folder / first], everything, work, f"one_{first}")}
            for held in placements:
                rest = [p for p in placements if p != held]
                rows[f"lopo_{held.name}"] = experiment(robot, rest, everything, work, f"lopo_{held.name}")
            results[robot_dir] = rows
    header = (
        f"{'robot':<14} {'experiment':<24} {'test MAE nom':>12} {'cal':>7} {'dist err nom':>12} {'cal':>7} {'s':>5}"
    )
    print("MUKCa real recordings, held-out sockets [mm] (test MAE: mean distance from the socket's mean point)")
    print(header)
    for robot_dir, rows in results.items():
        for name, r in rows.items():
            print(
                f"{robot_dir:<14} {name:<24} {r['nominal_test_mae_mm']:12.3f} {r['calibrated_test_mae_mm']:7.3f} "
                f"{r['nominal_distance_error_mean_abs_mm']:12.3f} {r['calibrated_distance_error_mean_abs_mm']:7.3f} "
                f"{r['seconds']:5.2f}{'  refused (--force): ' + r['refused'][:100] if r['refused'] else ''}"
            )
        lopo = [r for n, r in rows.items() if n.startswith("lopo_")]
        mean = {k: sum(r[k] for r in lopo) / len(lopo) for k in lopo[0] if k.endswith("_mm")}
        rows["lopo_mean"] = mean
        print(
            f"{robot_dir:<14} {'lopo mean':<24} {mean['nominal_test_mae_mm']:12.3f} "
            f"{mean['calibrated_test_mae_mm']:7.3f} {mean['nominal_distance_error_mean_abs_mm']:12.3f} "
            f"{mean['calibrated_distance_error_mean_abs_mm']:7.3f}"
        )
    out = Path(__file__).with_suffix(".json")
    bench_common.write_json(out, {"mukca": results}, inputs={"data": data})
    print(f"wrote {out}")


if __name__ == "__main__":
    main_bench()
