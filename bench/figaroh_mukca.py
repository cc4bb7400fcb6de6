"""Against FIGAROH: its geometric calibration and ``spherecal calibrate`` on MUKCa's real recordings, held-out test MAE.

MUKCa's protocol (``bench/mukca.py``): train on ONE placement (its two sockets, centres 50 mm apart), score on every
socket of the other placements by ``bench_common.socket_mae`` (the mean distance of the calibrated tool points from
their mean, per socket, averaged; MUKCa's "test MAE"). Every placement with two sockets is the training one in turn.

* **nominal**: MUKCa's URDF to ``ball_link`` (``load_robot``).
* **spherecal**: the user's path, ``import --format mukca --robot URDF --tip-link ball_link``, ``calibrate`` with its
  defaults, ``load_robot`` + ``tool_point`` of the written file. A training the self-check refuses is calibrated
  again with ``--force`` and marked ``*``.
* **FIGAROH** (``pip install figaroh``, Apache-2.0; not a dependency of spherecal): run by
  ``bench/figaroh_driver.py`` in FIGAROH's own venv (``--figaroh-python``), used as its examples use it (full
  placement-error parameters of every joint, its structural base parameters by QR, the frame-absorbed ones dropped,
  free base and marker frames, Levenberg-Marquardt with its outlier exclusion), with its defaults (``FIG``) and with
  ``estimation.method: map`` (``FIG map``: its priors on every joint parameter). It takes measured marker positions
  in a world frame, so the ball-in-socket data goes in as the plate frame: every row of socket 0 measured at
  (0, 0, 0), of socket 1 at (0.05, 0, 0). The driver returns its tool points at the test sockets; they are scored
  here by the same formula (checked: its nominal tool points score as spherecal's nominal model, printed ``chk``).
* **MUKCa**: its published figure where there is one (``mukca.MUKCA``).

``--simulated N`` then checks the encoding on a simulated arm of each robot's family whose truth is known
(``simulated``: FIGAROH given known socket centres must land on the true arm; both tools trained on two sockets).

Wall time: ``spherecal calibrate`` in this process (``spherecal.cli.main``), FIGAROH's ``initialize()`` +
``solve()`` in the driver, both without interpreter start-up and imports, median of ``--repeats`` runs (spherecal
after one warm-up run; ``FIG map`` once). The load (``uptime``) is printed before and after.

    .venv/bin/python bench/figaroh_mukca.py --figaroh-python /path/to/figvenv/bin/python \\
        --data /tmp/work/mukca_layout [--robots panda_2_clean panda_4_clean dinova_1 kuka_14] [--repeats 3] \\
        [--simulated 3]

Prints a table [mm] and writes ``bench/figaroh_mukca.json`` (or ``--out``): versions of both sides, inputs, every
figure and time.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics
import numpy as np
from mukca import MUKCA

from spherecal.cli import main as cli_main
from spherecal.correction import load_robot, read_samples, tool_point, write_samples
from spherecal.identification.ingest.importers import MUKCA_DISTANCE

HERE = Path(__file__).resolve().parent
ROBOTS = ("panda_2_clean", "panda_4_clean", "dinova_1", "kuka_14")
#: FIGAROH's settings run: its defaults (``structural``), and ``map`` (its documented estimation method for weakly
#: excited data: every joint parameter under a zero-mean prior of 1 mm, 2 mrad, 0.02 rad of joint offset), timed
#: once (its ``initialize`` takes up to minutes).
VARIANTS = {"default": {}, "map": {"estimation": {"method": "map"}}}


def cli(argv: list) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = cli_main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def sockets_of(folder: Path) -> list[np.ndarray]:
    return [np.loadtxt(f, delimiter=",", ndmin=2) for f in sorted(folder.glob("hole_*.csv")) if f.stem[5:].isdigit()]


def spherecal_run(urdf: Path, train: Path, work: Path, sockets, repeats: int) -> dict:
    """``import`` + ``calibrate`` defaults (``--force`` again when refused), scored; calibrate's median time [s]."""
    code, _, err = cli(["import", train, "--format", "mukca", "--robot", urdf, "--tip-link", "ball_link",
                        "--out", work / "train"])
    if code:
        raise SystemExit(f"import failed: {train}\n{err}")
    argv = ["calibrate", "--robot", urdf, "--tip-link", "ball_link", "--samples", work / "train" / "samples.csv",
            "--fixtures", work / "train" / "fixtures.yaml", "--out", work / "cal.yaml"]
    code, out, err = cli(argv)
    row: dict = {"refused": ""}
    if code:
        row["refused"] = (err.strip().splitlines() or ["?"])[-1][:300]
        argv.append("--force")
        code, out, err = cli(argv)
        if code:
            raise SystemExit(f"calibrate --force failed: {train}\n{err}")
    row["chosen"] = next((line.split("model: ")[1].split(" ")[0] for line in out.splitlines()
                          if line.startswith("model: ")), "")
    row["test_mae_mm"] = bench_common.socket_mae(load_robot(work / "cal.yaml"), sockets) * 1e3
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        cli(argv)
        times.append(time.perf_counter() - start)
    row["seconds"] = times
    return row


def run_driver(python: str, job: dict, work: Path) -> dict:
    """``figaroh_driver.py`` on ``job`` (each of ``VARIANTS``) in FIGAROH's venv; its tool points scored here."""
    job = {"tip_link": "ball_link", "variants": VARIANTS, **job}
    (work / "job.json").write_text(json.dumps(job))
    done = subprocess.run([python, str(HERE / "figaroh_driver.py"), str(work / "job.json"), str(work / "fig.json")],
                          capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"FIGAROH driver failed ({work}):\n{done.stderr[-3000:]}")
    out = json.loads((work / "fig.json").read_text())
    for fit in out["variants"].values():
        fit["test_mae_mm"] = bench_common.points_mae(fit["test_points"]) * 1e3
        fit["nominal_mae_mm"] = bench_common.points_mae(fit.pop("nominal_test_points")) * 1e3
        fit["seconds"] = [a + b for a, b in zip(fit["initialize_s"], fit["solve_s"], strict=True)]
    return out


def figaroh_run(python: str, urdf: Path, train: Path, sockets, repeats: int, work: Path) -> dict:
    """FIGAROH's calibration on ``train``'s two sockets, as the plate frame: socket k measured at (0.05 k, 0, 0)."""
    out = run_driver(python, {
        "urdf": str(urdf), "repeats": {name: repeats if name == "default" else 1 for name in VARIANTS},
        "train": [{"q": q.tolist(), "centre": [MUKCA_DISTANCE * k, 0.0, 0.0]}
                  for k, q in enumerate(sockets_of(train))],
        "test": [q.tolist() for q in sockets]}, work)
    for fit in out["variants"].values():
        fit.pop("test_points")
    return out


def run_robot(root: Path, robot: str, python: str, repeats: int, work: Path) -> list[dict]:
    data = root / "data" / robot
    if not data.is_dir():
        raise SystemExit(f"{data}: no such robot folder (--data: a MUKCa layout with data/ and urdf/)")
    urdf = root / "urdf" / bench_common.MUKCA_FAMILIES[bench_common.mukca_family(robot)][0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        nominal = load_robot(urdf, tip_link="ball_link")
    places = sorted(p.name for p in data.iterdir() if p.is_dir() and sockets_of(p))
    rows = []
    for place in (p for p in places if len(sockets_of(data / p)) == 2):
        sockets = [q for p in places if p != place for q in sockets_of(data / p)]
        place_work = work / robot / place
        place_work.mkdir(parents=True)
        row = {"robot": robot, "train": place, "held_out_sockets": len(sockets),
               "nominal_mm": bench_common.socket_mae(nominal, sockets) * 1e3,
               "mukca_published_mm": MUKCA.get((robot, place))}
        row["spherecal"] = spherecal_run(urdf, data / place, place_work, sockets, repeats)
        row["figaroh"] = figaroh_run(python, urdf, data / place, sockets, repeats, place_work)
        rows.append(row)
        s, f = row["spherecal"], row["figaroh"]["variants"]
        theirs = "" if row["mukca_published_mm"] is None else f"{row['mukca_published_mm']:6.3f}"
        check = max(abs(v["nominal_mae_mm"] - row["nominal_mm"]) for v in f.values())
        print(f"{robot:<14} {place:<20} {row['nominal_mm']:8.3f} {f['default']['test_mae_mm']:8.3f}"
              f"{'!' if f['default']['status'] != 'CALIBRATED' else ' '}{f['map']['test_mae_mm']:8.3f} "
              f"{s['test_mae_mm']:8.3f}{'*' if s['refused'] else ' '} {theirs:>6} "
              f"{np.median(f['default']['seconds']):6.2f} {np.median(f['map']['seconds']):6.2f} "
              f"{np.median(s['seconds']):6.2f}  {s['chosen']:<14} {check:.0e}", flush=True)
    return rows


def simulated(root: Path, robot: str, seed: int, python: str, work: Path) -> dict:
    """The same on a simulated arm whose truth is known (``spherecal simulate``: a perturbed ``robot``'s URDF, 0.1 mm
    of socket noise per axis, 30 samples per socket), at four sockets where the real ones of ``robot``'s first two
    two-socket placements are (the nominal model's mean tool point of each).

    * ``known``: FIGAROH given every socket's true centre in the base frame (a plain position calibration), trained
      on 20 samples per socket: the mean distance [mm] of its tool points from the true arm's at the other 10 of
      each, and the nominal model's.
    * ``two sockets``: the encoding of the real runs, FIGAROH and ``calibrate`` trained on the first placement's two
      sockets (at their true distance), held-out MAE [mm] at the second's, beside the true arm's (the noise floor)
      and the nominal model's.
    """
    urdf = root / "urdf" / bench_common.MUKCA_FAMILIES[bench_common.mukca_family(robot)][0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        nominal = load_robot(urdf, tip_link="ball_link")
    data = root / "data" / robot
    places = [p.name for p in sorted(data.iterdir()) if p.is_dir() and len(sockets_of(p)) == 2][:2]
    centres = {f"{p}_h{k}": tool_point(nominal, q).mean(axis=0) for p in places
               for k, q in enumerate(sockets_of(data / p))}
    work.mkdir(parents=True)
    (work / "fx.yaml").write_text("fixtures:\n" + "".join(
        f"  {n}: {{position: [{c[0]:.6f}, {c[1]:.6f}, {c[2]:.6f}]}}\n" for n, c in centres.items()))
    code, _, err = cli(["simulate", "--robot", urdf, "--tip-link", "ball_link", "--fixtures", work / "fx.yaml",
                        "--per-fixture", 30, "--noise", 0.1, "--seed", seed, "--out", work / "sim"])
    if code:
        raise SystemExit(f"simulate failed: {err}")
    samples = read_samples(work / "sim" / "samples.csv", nominal)
    truth = load_robot(work / "sim" / "truth.yaml")
    per = {n: samples.q[samples.labels == n] for n in centres}
    row: dict = {"robot": robot, "seed": seed, "places": places}

    known = run_driver(python, {"urdf": str(urdf), "repeats": 1, "test": [q[20:].tolist() for q in per.values()],
                                "train": [{"q": q[:20].tolist(), "centre": centres[n].tolist()}
                                          for n, q in per.items()]}, work)
    def error(points: list) -> float:
        return float(np.mean([np.linalg.norm(np.asarray(p) - tool_point(truth, q[20:]), axis=1).mean()
                              for p, q in zip(points, per.values(), strict=True)])) * 1e3
    row["known"] = {"nominal_mm": error([tool_point(nominal, q[20:]) for q in per.values()]),
                    **{name: error(fit["test_points"]) for name, fit in known["variants"].items()},
                    "train_rmse_mm": {name: fit["train_rmse_m"] * 1e3 for name, fit in known["variants"].items()},
                    "params": {name: len(fit["param_name"]) for name, fit in known["variants"].items()}}

    (a, b), test = list(per)[:2], list(per.values())[2:]
    distance = float(np.linalg.norm(centres[a] - centres[b]))
    two = run_driver(python, {"urdf": str(urdf), "repeats": 1, "test": [q.tolist() for q in test],
                              "train": [{"q": per[a].tolist(), "centre": [0.0, 0.0, 0.0]},
                                        {"q": per[b].tolist(), "centre": [distance, 0.0, 0.0]}]}, work)
    write_samples(work / "samples.csv", samples.select(np.isin(samples.labels, [a, b])))
    (work / "fixtures.yaml").write_text(f"fixtures:\n  {a}: {{}}\n  {b}: {{}}\ndistances:\n- [{a}, {b}, {distance}]\n")
    argv = ["calibrate", "--robot", urdf, "--tip-link", "ball_link", "--samples", work / "samples.csv",
            "--fixtures", work / "fixtures.yaml", "--out", work / "cal.yaml"]
    code, _, _ = cli(argv)
    if code:
        code, _, err = cli([*argv, "--force"])
        if code:
            raise SystemExit(f"calibrate --force failed on the simulated {robot}: {err}")
    row["two_sockets"] = {"truth_mm": bench_common.socket_mae(truth, test) * 1e3,
                          "nominal_mm": bench_common.socket_mae(nominal, test) * 1e3,
                          **{name: fit["test_mae_mm"] for name, fit in two["variants"].items()},
                          "spherecal": bench_common.socket_mae(load_robot(work / "cal.yaml"), test) * 1e3,
                          "spherecal_refused": bool(code)}
    k, t = row["known"], row["two_sockets"]
    print(f"{robot:<14} {seed:4d}  known: nominal {k['nominal_mm']:6.3f} FIG {k['default']:6.3f} "
          f"FIG map {k['map']:6.3f}  | two sockets: truth {t['truth_mm']:6.3f} nominal {t['nominal_mm']:6.3f} "
          f"FIG {t['default']:6.3f} FIG map {t['map']:6.3f} spherecal {t['spherecal']:6.3f}", flush=True)
    return row


def summary(rows: list[dict]) -> list[str]:
    lines = ["", "mean over the trainings [mm]; wall time: median per training, mean over them [s]; "
             "FIGAROH / spherecal: ratio of the means",
             f"{'robot':<14} {'n':>2} {'nominal':>8} {'FIG':>8} {'FIG map':>8} {'spherecal':>9} {'FIG/s':>6} "
             f"{'map/s':>6} {'t FIG':>6} {'t map':>6} {'t sph':>6}"]
    for robot in dict.fromkeys(r["robot"] for r in rows):
        mine = [r for r in rows if r["robot"] == robot]
        fig = [r["figaroh"]["variants"]["default"] for r in mine]
        fmap = [r["figaroh"]["variants"]["map"] for r in mine]
        sph = [r["spherecal"] for r in mine]
        nominal = np.mean([r["nominal_mm"] for r in mine])
        a, b, c = (np.mean([f["test_mae_mm"] for f in v]) for v in (fig, fmap, sph))
        times = (np.mean([np.median(f["seconds"]) for f in v]) for v in (fig, fmap, sph))
        star = "*" if any(r["refused"] for r in sph) else " "
        lines.append(f"{robot:<14} {len(mine):2d} {nominal:8.3f} {a:8.3f} {b:8.3f} {c:8.3f}{star} {a / c:5.2f}x "
                     f"{b / c:5.2f}x " + " ".join(f"{t:6.2f}" for t in times))
    return lines


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figaroh-python", required=True,
                        help="the python of a venv with figaroh and pin installed (runs bench/figaroh_driver.py)")
    parser.add_argument("--data", type=Path, default=None,
                        help="MUKCa layout root (data/<robot>/<placement>/hole_*.csv, urdf/); "
                        "default: shared/data/mukca beside the checkout")
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), help="robot folders under DATA/data")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per training and tool (default 3)")
    parser.add_argument("--simulated", type=int, default=0, metavar="N",
                        help="also the check on a simulated arm of each robot's family, seeds 1..N (default 0: none)")
    parser.add_argument("--out", type=Path, default=HERE / "figaroh_mukca.json", help="result file")
    args = parser.parse_args()
    root = args.data or bench_common.find_mukca()
    load_before = uptime()
    print(f"uptime: {load_before}")
    print(f"{'robot':<14} {'training':<20} {'nominal':>8} {'FIG':>8} {'FIG map':>8} {'spherecal':>9} "
          f"{'MUKCa':>6} {'t FIG':>6} {'t map':>6} {'t sph':>6}  {'spherecal model':<14} chk")
    clock = time.perf_counter()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for robot in args.robots:
            rows += run_robot(root, robot, args.figaroh_python, args.repeats, Path(tmp))
        print("\n".join(summary(rows)))
        sims = []
        if args.simulated:
            print("\nsimulated arms [mm] (known: |tool point - true|; two sockets: held-out MAE)")
        for robot in args.robots if args.simulated else ():
            sims += [simulated(root, robot, seed, args.figaroh_python, Path(tmp) / "sim" / f"{robot}_{seed}")
                     for seed in range(1, args.simulated + 1)]
    load_after = uptime()
    print(f"uptime: {load_after}")
    out = bench_common.write_json(args.out, {
        "uptime": [load_before, load_after], "seconds": time.perf_counter() - clock,
        "figaroh_versions": rows[0]["figaroh"]["packages"] if rows else {}, "figaroh_variants": VARIANTS,
        "socket_distance_m": MUKCA_DISTANCE, "rows": rows, "simulated": sims},
        seed=list(range(1, args.simulated + 1)) or None,
        inputs={"data": Path(root), "robots": args.robots, "repeats": args.repeats,
                "figaroh_python": args.figaroh_python}, indent=1)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
