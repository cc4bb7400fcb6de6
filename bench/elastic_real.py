"""Elastic joints on real Pandas (MUKCa recordings): leave-one-placement-out held-out error of dh, elastic, auto.

Data: ``shared/data/mukca`` beside the checkout (MIT licence), ``data/<robot>/<placement>/hole_0.csv`` / ``hole_1.csv``
(7 joint angles per row [rad]), sockets 50 mm apart on one plate per placement. Fixtures are named
``<placement>_h0`` / ``_h1`` with their 50 mm distance known, so ``auto``'s own cross-validation leaves
one placement out.

Model: the embedded Panda (modified DH, Gaz et al. inertials + Franka Hand payload) with the tool point
at MUKCa's ``ball_link`` (panda.urdf: flange, hand turned -45 deg about z, 0.1034 m TCP, ball offset
(7.77e-05, -4.21e-05, 0.030128) m). The ball's own mass (a few grams of PLA) is neglected.

Protocol, per robot and per held-out placement: fit on the other placements, then on the held-out
placement the MUKCa metric (per socket: mean distance of the predicted ball centres from their mean,
"MAE") and the error of the 50 mm distance. ``auto`` runs its own inner cross-validation on the training
placements (nested: the outer held-out placement never informs the choice). Finally the elastic model on
all placements: identified compliances with their std.

    python bench/elastic_real.py [--data ../shared/data/mukca] [--robots panda_2_clean panda_4_clean]

Prints a table [mm] and writes bench/elastic_real.json.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import bench_common  # first: one BLAS thread, before numpy loads
import numpy as np

from spherecal.correction import Dataset, FixtureSpec, geometric_part, tool_point
from spherecal.identification.calibrate import calibrate
from spherecal.identification.ingest.importers import MUKCA_DISTANCE
from spherecal.identification.problem import PRIOR
from spherecal.identification.selection import elastic_start, select_model


def _fit(start, data, spec, warm=None):  # as identification.workflow fits candidates and folds
    return calibrate(start, data, spec, start=warm, check=False, prior=PRIOR)


def _placement(name: str) -> str:
    return name.rpartition("_h")[0]


def held_out(model, data: Dataset) -> tuple[float, float]:
    """MUKCa metric on one placement: mean socket MAE [m] and |distance - 50 mm| [m]."""
    points = tool_point(model, data.q)
    means, maes = [], []
    for name in data.fixture_names:
        p = points[data.labels == name]
        means.append(p.mean(axis=0))
        maes.append(float(np.linalg.norm(p - means[-1], axis=1).mean()))
    return float(np.mean(maes)), abs(float(np.linalg.norm(means[0] - means[1])) - MUKCA_DISTANCE)


def evaluate(robot: str, dataset: Dataset, spec: FixtureSpec, nominal) -> dict:
    placements = list(dict.fromkeys(_placement(n) for n in dataset.fixture_names))
    rows = []
    for held in placements:
        mask = np.array([_placement(label) == held for label in dataset.labels])
        train, test = dataset.select(~mask), dataset.select(mask)
        train_spec = FixtureSpec(names=train.fixture_names,
                                 distances=[d for d in spec.distances if _placement(d[0]) != held])
        clock = time.perf_counter()
        models = {"dh": _fit(geometric_part(nominal), train, train_spec).model,
                  "elastic": _fit(elastic_start(nominal), train, train_spec).model}
        choice = select_model("auto", _fit, nominal, train, train_spec, samples=10**6)
        models["auto"] = models.get(choice.chosen) or choice.fits[choice.chosen].model
        row = {"placement": held, "auto_chose": choice.chosen, "seconds": time.perf_counter() - clock}
        for key, model in models.items():
            mae, dist = held_out(model, test)
            row[key] = {"mae_m": mae, "distance_error_m": dist}
        rows.append(row)
    full = calibrate(elastic_start(nominal), dataset, spec)
    lay = full.model.layout
    compliance = {n: {"value": float(full.model.params[lay.index(n)]), "std": full.std.get(n)}
                  for n in lay.names[lay.compliance]}
    reasons = {n: full.fixed[n] for n in lay.names[lay.compliance] if n in full.fixed}
    selection_all = select_model("auto", _fit, nominal, dataset, spec, samples=10**6)
    summary = {}
    for key in ("dh", "elastic", "auto"):
        mae = np.array([r[key]["mae_m"] for r in rows])
        dist = np.array([r[key]["distance_error_m"] for r in rows])
        summary[key] = {"mae_mean_m": float(mae.mean()), "distance_error_mean_m": float(dist.mean())}
    diff = np.array([r["dh"]["mae_m"] - r["auto"]["mae_m"] for r in rows])
    summary["auto_minus_dh_standard_error_m"] = float(np.std(diff, ddof=1) / np.sqrt(len(diff)))
    return {"robot": robot, "samples": dataset.counts(), "folds": rows, "summary": summary,
            "compliance_all_placements": compliance, "compliance_fixed": reasons,
            "residual_rms_all_m": full.rms_after, "auto_on_all_placements": selection_all.block()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(bench_common.find_mukca()), help="MUKCa subset root")
    parser.add_argument("--robots", nargs="+", default=["panda_2_clean", "panda_4_clean"])
    args = parser.parse_args(argv)
    root = Path(args.data)
    nominal = bench_common.mukca_panda()
    results = []
    for robot in args.robots:
        dataset, spec = bench_common.mukca_dataset(root, robot, nominal)
        result = evaluate(robot, dataset, spec, nominal)
        results.append(result)
        s = result["summary"]
        print(f"{robot}: {len(result['folds'])} placements, {dataset.n_samples} configurations; "
              f"leave-one-placement-out held-out [mm]")
        print(f"  {'model':<8} {'socket MAE':>11} {'50 mm error':>12}")
        for key in ("dh", "elastic", "auto"):
            print(f"  {key:<8} {s[key]['mae_mean_m'] * 1e3:11.4f} {s[key]['distance_error_mean_m'] * 1e3:12.4f}")
        print(f"  auto vs dh: {(s['dh']['mae_mean_m'] - s['auto']['mae_mean_m']) * 1e3:+.4f} mm "
              f"(fold spread {s['auto_minus_dh_standard_error_m'] * 1e3:.4f} mm); auto chose "
              f"{', '.join(r['auto_chose'] for r in result['folds'])}")
        for r in result["folds"]:
            print(f"    {r['placement']:<14} dh {r['dh']['mae_m'] * 1e3:.4f}  "
                  f"elastic {r['elastic']['mae_m'] * 1e3:.4f}  "
                  f"auto({r['auto_chose']}) {r['auto']['mae_m'] * 1e3:.4f}")
        c = ", ".join(f"{n} {v['value'] * 1e6:.1f} +- {v['std'] * 1e6:.1f}" for n, v in
                      result["compliance_all_placements"].items() if v["std"] is not None)
        print(f"  elastic on all placements: {c} urad/Nm; fixed: {', '.join(result['compliance_fixed'])}; "
              f"auto on all: {result['auto_on_all_placements']['chosen']}")
    out = Path(__file__).with_suffix(".json")
    bench_common.write_json(out, {"results": results}, inputs={"data": root, "robots": args.robots}, indent=1)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
