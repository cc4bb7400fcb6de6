"""False-alarm rate of the calibration self-check, and its verdict on real recordings.

Simulated (``identification.synthetic.make_dataset``: kinematic, fast): for every seed, a true robot
(``perturb``: 1 mm, 0.2 deg), the three Panda fixtures moved by up to 5 cm at random, then ten cases: 1, 2
or 3 fixtures, with and without their known distances (1 fixture: without), noise-free and 0.3 mm noise,
declared noise 0.3 mm (the default). The self-check must fire at most once in 100 calibrations.

Real (``--real``): the MUKCa Panda recordings in ``shared/data/mukca`` beside the checkout (a 3D-printed
ball held in the gripper, hand-guided into two printed sockets 50 mm apart, several placements): every placement alone
(two fixtures ``<placement>_h0/_h1``, their 0.050 m distance) and all placements together, for
panda_2_clean and panda_4_clean, at the default noise 0.3 mm and at 0.2 mm. None may be refused.

The recordings are read by the importer (``identification.importers.read_mukca``, through
``bench_common.mukca_dataset``). The ball centre (the tool point) is that of
``tests/data/mukca/panda_ball.yaml``: the fixed joints of MUKCa's ``urdf/panda.urdf`` from ``panda_link7``
to ``ball_link`` (flange 0.107 m, hand -45 deg about z, TCP 0.1034 m, ball offset).

MuJoCo (``--mujoco N``): N seeds of `spherecal simulate`'s protocol (3 fixtures, 20 s, 500 samples, 0.3 mm
compliance noise, correlated over 0.05 s), with and without the known distances.

    .venv/bin/python bench/selfcheck_false_alarms.py [--seeds 100] [--per-fixture 300] [--mujoco 10] [--real]

Prints a summary and writes ``bench/selfcheck_false_alarms.json`` (seeds, cases, how many fired, which check).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import bench_common  # first: one BLAS thread, before numpy loads
import numpy as np

from spherecal.correction import load_robot, perturb
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.identification.calibrate import calibrate
from spherecal.identification.synthetic import PANDA_FIXTURES, make_dataset

ROOT = bench_common.find_mukca()


def placements(robot: str) -> list[str]:
    """Placements recorded for ``robot`` (folder names), sorted."""
    return sorted(p.name for p in (ROOT / "data" / robot).iterdir() if (p / "hole_0.csv").exists())


# ------------------------------------------------------------------------------------ simulated
CASES: tuple[tuple[int, bool], ...] = ((1, False), (2, False), (2, True), (3, False), (3, True))
NOISES: tuple[float, ...] = (0.0, 3e-4)


def simulated(seeds: int, per_fixture: int) -> dict:
    """Run every case on ``seeds`` seeds; returns the JSON record."""
    panda = load_robot("panda")
    fired, runs, walls = [], 0, []
    for seed in range(seeds):
        rng = np.random.default_rng(1000 + seed)
        true = perturb(panda, rng)
        centres = {k: np.asarray(c) + rng.uniform(-0.05, 0.05, 3) for k, c in PANDA_FIXTURES.items()}
        for noise in NOISES:
            dataset, spec = make_dataset(true, centres, per_fixture, rng, noise)
            for count, with_distances in CASES:
                names = dataset.fixture_names[:count]
                subset = dataset.select(np.flatnonzero(np.isin(dataset.labels, names)))
                distances = [d for d in spec.distances if d[0] in names and d[1] in names] if with_distances else []
                clock = time.perf_counter()
                result = calibrate(panda, subset, FixtureSpec(names=names, distances=distances), force=True)
                walls.append(time.perf_counter() - clock)
                runs += 1
                check = result.selfcheck
                if not check.consistent:
                    fired.append(
                        {
                            "seed": seed,
                            "noise_mm": noise * 1e3,
                            "fixtures": count,
                            "distances": with_distances,
                            "checks": [f.check for f in check.failed],
                            "refusal": check.refusal,
                        }
                    )
                    print(
                        f"  fired: seed {seed} noise {noise * 1e3:g} mm {count} fixtures distances {with_distances}: "
                        f"{check.refusal}"
                    )
        print(f"seed {seed}: {runs} calibrations, {len(fired)} fired", flush=True)
    by_check: dict[str, int] = {}
    for record in fired:
        for name in record["checks"]:
            key = name.split(" ")[0]
            by_check[key] = by_check.get(key, 0) + 1
    return {
        "seeds": seeds,
        "per_fixture": per_fixture,
        "cases": [{"fixtures": c, "distances": d, "noise_mm": n * 1e3} for n in NOISES for c, d in CASES],
        "calibrations": runs,
        "fired": len(fired),
        "rate": len(fired) / max(runs, 1),
        "fired_by_check": by_check,
        "fired_runs": fired,
        "calibrate_s": {"median": float(np.median(walls)), "p90": float(np.percentile(walls, 90))},
    }


# ------------------------------------------------------------------------------------ MuJoCo
def mujoco(runs: int) -> dict:
    """``runs`` seeds of `spherecal simulate`'s protocol (MuJoCo, 3 default fixtures, 20 s, 500 samples,
    0.3 mm compliance noise), calibrated with and without the known distances."""
    from spherecal.controller.self_motion import SelfMotionSettings, collect_self_motion
    from spherecal.validation.experiments.experiment import default_fixtures

    panda = load_robot("panda")
    fired, count = [], 0
    for seed in range(runs):
        rng = np.random.default_rng(2000 + seed)
        true = perturb(panda, rng)
        fixtures = default_fixtures()
        run = collect_self_motion(true, panda, fixtures, rng, SelfMotionSettings(noise=3e-4))
        names = tuple(fixtures)
        distances = [
            (a, b, float(np.linalg.norm(fixtures[a] - fixtures[b])))
            for i, a in enumerate(names)
            for b in names[i + 1 :]
        ]
        for known in (distances, []):
            check = calibrate(panda, run.dataset(), FixtureSpec(names, distances=known), force=True).selfcheck
            count += 1
            if not check.consistent:
                fired.append({"seed": seed, "distances": bool(known), "refusal": check.refusal})
            verdict = "ok" if check.consistent else "FIRED " + check.refusal
            print(f"mujoco seed {seed} distances {bool(known)}: {verdict}")
    return {"runs": runs, "calibrations": count, "fired": len(fired), "fired_runs": fired}


# ------------------------------------------------------------------------------------ real
def real(noises: tuple[float, ...] = (3e-4, 2e-4)) -> list[dict]:
    """Every placement alone and all together, per robot and declared noise; returns the JSON rows."""
    panda = bench_common.mukca_panda()
    rows = []
    for robot in ("panda_2_clean", "panda_4_clean"):
        for chosen in [[p] for p in placements(robot)] + [None]:
            dataset, spec = bench_common.mukca_dataset(ROOT, robot, panda, chosen)
            for noise in noises:
                result = calibrate(panda, dataset, spec, noise=noise, force=True)
                check = result.selfcheck
                figures = {f.check: f.figures for f in check.findings}
                row = {
                    "robot": robot,
                    "placements": chosen or "all",
                    "samples": dataset.n_samples,
                    "noise_declared_mm": noise * 1e3,
                    "residual_std_mm": check.sigma * 1e3,
                    "predicted_mean_mm": figures["prediction"]["predicted_mean_mm"],
                    "nominal_expected_mm": figures["prediction"]["nominal_expected_mean_mm"],
                    "refused": not check.consistent,
                    "refusal": check.refusal,
                }
                rows.append(row)
                print(
                    f"{robot:<14} {str(chosen[0] if chosen else 'all'):<13} {dataset.n_samples:4d} samples  noise "
                    f"{noise * 1e3:.1f} mm: residual {row['residual_std_mm']:.3f} mm, predicted "
                    f"{row['predicted_mean_mm']:.3f} mm (nominal {row['nominal_expected_mm']:.2f} mm)  "
                    f"{'REFUSED: ' + check.refusal if row['refused'] else 'written'}"
                )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--per-fixture", type=int, default=300)
    parser.add_argument("--real", action="store_true", help="also the real MUKCa recordings")
    parser.add_argument("--no-simulated", action="store_true")
    parser.add_argument("--mujoco", type=int, default=0, help="also this many MuJoCo-simulated seeds (~10 s each)")
    args = parser.parse_args()
    out = Path(__file__).with_suffix(".json")
    record = json.loads(out.read_text()) if out.exists() else {}  # kept: parts of an earlier run not redone
    record = {k: v for k, v in record.items() if k not in ("command", "provenance")}
    if not args.no_simulated:
        record["simulated"] = simulated(args.seeds, args.per_fixture)
        sim = record["simulated"]
        print(
            f"simulated: {sim['seeds']} seeds x {len(sim['cases'])} cases = {sim['calibrations']} calibrations, "
            f"fired {sim['fired']} ({sim['rate']:.2%}) by check {sim['fired_by_check']}; calibrate median "
            f"{sim['calibrate_s']['median']:.2f} s"
        )
    if args.mujoco:
        record["mujoco"] = mujoco(args.mujoco)
        print(f"mujoco: {record['mujoco']['fired']} fired of {record['mujoco']['calibrations']}")
    if args.real:
        record["real"] = real()
        print(f"real: {sum(r['refused'] for r in record['real'])} refused of {len(record['real'])}")
    bench_common.write_json(out, record, inputs=vars(args))


if __name__ == "__main__":
    main()
