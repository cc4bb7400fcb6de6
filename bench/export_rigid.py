"""What the URDF export keeps of a real calibration: test MAE through the calibrated file, through the URDF
`export` writes (the best rigid fit to the full model) and through the URDF of the geometric part alone (the
compliance dropped, what export wrote before).

MUKCa's protocol on the real Pandas: `import` one placement with MUKCa's own `panda.urdf` (no masses: the
embedded Panda's are taken), `calibrate --model elastic` (and the default `auto`), `export --format urdf`;
held-out sockets = every other placement. Test MAE = mean over held-out sockets of the mean distance of the
predicted ball centres from their mean; distance error = mean |socket distance - 50 mm|. Each URDF is read
back with `correction.load_urdf` (the ball is its tip link, panda_link8). Writes ``bench/export_rigid.json``.

    .venv/bin/python bench/export_rigid.py [--data ../shared/data/mukca]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import tempfile
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics
import numpy as np

from spherecal.correction import geometric_part, load_robot, load_urdf, tool_point
from spherecal.correction.files.urdf_write import robot_to_urdf

#: robot folder -> (training placement, MUKCa's published test MAE [mm] for it, or None)
ROBOTS = {"panda_2_clean": ("front_center", 0.347), "panda_4_clean": ("front", 0.278)}


def _scores(model, dataset) -> tuple[float, float]:
    """(test MAE, distance error) [mm] of the held-out sockets through ``model``."""
    points = tool_point(model, dataset.q)
    means, spread = {}, []
    for name in dataset.fixture_names:
        p = points[dataset.labels == name]
        means[name] = p.mean(axis=0)
        spread.append(np.linalg.norm(p - means[name], axis=1).mean())
    placements = sorted({name.rpartition("_h")[0] for name in dataset.fixture_names})
    gaps = [abs(np.linalg.norm(means[f"{p}_h0"] - means[f"{p}_h1"]) - 0.05) for p in placements]
    return 1e3 * float(np.mean(spread)), 1e3 * float(np.mean(gaps))


def main_bench() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(bench_common.find_mukca()))
    args = parser.parse_args()
    root, run = Path(args.data), bench_common.run_cli
    urdf = root / "urdf" / "panda.urdf"
    print(subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for robot, (train, mukca) in ROBOTS.items():
            folder = root / "data" / robot
            if not folder.is_dir():
                print(f"{robot}: not found under {root}, skipped")
                continue
            work = Path(tmp) / robot
            run(["import", str(folder / train), "--format", "mukca", "--robot", str(urdf), "--tip-link", "ball_link",
                 "--out", str(work / "train")])
            held = [p.name for p in sorted(folder.iterdir()) if p.is_dir() and p.name != train]
            nominal = load_robot(urdf, tip_link="ball_link")
            dataset, _ = bench_common.mukca_dataset(root, robot, nominal, held)
            for kind in ("elastic", "auto"):
                cal = work / f"cal_{kind}.yaml"
                printed = run(["calibrate", "--robot", str(urdf), "--tip-link", "ball_link", "--samples",
                               str(work / "train/samples.csv"), "--fixtures", str(work / "train/fixtures.yaml"),
                               "--model", kind, "--out", str(cal)])
                chosen = next((line for line in printed.splitlines() if line.startswith("model:")), "model: ?")
                exported = work / f"cal_{kind}.urdf"
                notes = run(["export", str(cal), "--format", "urdf", "--out", str(exported)]).splitlines()[1:]
                model = load_robot(cal)
                plain = work / f"plain_{kind}.urdf"
                plain.write_text(robot_to_urdf(geometric_part(model)))
                row = {"model": chosen, "export_notes": notes,
                       "nominal": _scores(nominal, dataset), "calibrated_file": _scores(model, dataset),
                       "export_urdf": _scores(load_urdf(exported), dataset),
                       "plain_urdf": _scores(load_urdf(plain), dataset), "mukca_test_mae": mukca}
                results[f"{robot} {kind}"] = row
    print("MUKCa protocol (one placement trained, the others held out) [mm]: test MAE / distance error")
    print(f"{'robot, --model':<24} {'chosen':<22} {'nominal':>13} {'cal file':>13} {'export URDF':>13} "
          f"{'plain URDF':>13} {'MUKCa':>6}")
    for name, r in results.items():
        cells = " ".join(f"{r[k][0]:6.3f}/{r[k][1]:6.3f}" for k in ("nominal", "calibrated_file", "export_urdf",
                                                                   "plain_urdf"))
        print(f"{name:<24} {r['model'][7:29]:<22} {cells} {r['mukca_test_mae']:6.3f}")
        for line in r["export_notes"]:
            print(f"    {line}")
    out = Path(__file__).with_suffix(".json")
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main_bench()
