"""Why a Kinova Gen3 lite (MUKCa's dinova_1) calibrated on one placement transfers poorly: noise, drift, residual
structure, and what bounds the held-out error.

The user's path: ``load_robot(gen3lite.urdf, tip_link="ball_link")`` (the URDF's own inertials), the recordings
read by the MUKCa importer. Four sections, each printed as a table:

* **noise**: a plain least-squares DH fit on each placement alone, on pairs and on all of them: the residual per
  axis and the noise it implies (residual sum of squares over the degrees of freedom left). A model that holds
  across the workspace keeps the single-placement noise when placements are pooled (the Pandas: 0.11-0.13 mm
  either way).
* **drift**: per socket, the straight-line drift of its centre in recording order (end to end, mm) and the
  chi-square it explains (in units of the fit's noise variance; ~1 per fitted column by chance).
* **structure**: residual structure the DH model leaves, tested as extra columns against the fit's own
  Jacobian (chi-square drop in units of the noise variance, ~1 per column by chance): per joint ``i`` an angle
  error ``dq_i = f`` for ``f`` in ``q_i`` (scale), ``sin/cos q_i``, ``sin/cos 2 q_i`` (harmonics), the gravity
  torque ``tau_i`` (compliance, from the URDF inertials), ``sign tau_i`` (backlash against gravity),
  ``sign dq_i`` between consecutive presses (backlash against motion); the ball's offset per placement
  (re-grasped); the base tilting under the arm's gravity moment (a mobile base on tyres).
* **held-out**: trained on each placement (``run_workflow`` defaults, forced so every row has a figure), test
  MAE on the others [mm]: nominal, calibrated, the floor (a DH model fitted on the held-out placements
  themselves), and a fit of the joint zero offsets alone (theta2..theta6, nothing else, plain least squares).

``--offset-spread-deg X`` replaces the prior spread of the joint zero offsets (theta; the layout's angle spread,
0.2 deg) for this run only (a what-if of ``correction.layout``, not an option of spherecal).

    .venv/bin/python bench/gen3lite_diagnosis.py [--data ../shared/data/mukca] [--exclude front_h0]
        [--offset-spread-deg 1.0]

Writes ``bench/gen3lite_diagnosis.json`` (versions, inputs, every figure).
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import subprocess
import sys
import warnings
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics
import numpy as np

ROBOT = "dinova_1"


def _placement(name: str) -> str:
    return name.rpartition("_h")[0]


def _fit(nominal, dataset, spec, prior=0.0):
    from spherecal.identification.calibrate import calibrate
    from spherecal.identification.selection import start_for

    return calibrate(start_for("dh", nominal), dataset, spec, check=False, prior=prior, max_change=1e9)


def noise_table(root, nominal, places) -> list[dict]:
    rows = []
    for chosen in [[p] for p in places] + [list(c) for c in itertools.combinations(places, 2)] + [places]:
        data, spec = bench_common.mukca_dataset(root, ROBOT, nominal, chosen)
        res = _fit(nominal, data, spec)
        problem, x = res.problem, res.x
        r = problem.residuals(x)[~problem.prior_rows()]
        unknowns = res.effective_unknowns or problem.n_unknowns
        rows.append({"placements": "+".join(chosen), "samples": data.n_samples, "unknowns": float(unknowns),
                     "rms_per_axis_mm": float(np.sqrt((problem.sample_errors(x) ** 2).mean()) * 1e3),
                     "noise_mm": float(np.sqrt(r @ r / (len(r) - unknowns)) * 1e3)})
    return rows


class Structure:
    """Extra columns tested against a fit's Jacobian (chi-square drop in units of its noise variance)."""

    def __init__(self, res):
        problem, x = res.problem, res.x
        self.jac, self.r = problem.jacobian(x), problem.residuals(x)
        self.k = problem.dataset.n_samples
        self.q_basis = np.linalg.qr(self.jac)[0]
        self.s2 = self.r @ self.r / (len(self.r) - self.jac.shape[1])
        self.problem, self.x = problem, x

    def gain(self, cols: np.ndarray) -> tuple[float, np.ndarray]:
        """cols: (3K, c) tool-point columns [m per unit]; returns (chi-square drop / sigma^2, coefficients)."""
        b = np.zeros((len(self.r), cols.shape[1]))
        b[: 3 * self.k] = cols
        b -= self.q_basis @ (self.q_basis.T @ b)
        coef = np.linalg.lstsq(b, self.r, rcond=None)[0]
        return float((self.r @ self.r - np.sum((self.r - b @ coef) ** 2)) / self.s2), coef


def drift_table(root, nominal, spec_all, data) -> list[dict]:
    st = Structure(_fit(nominal, data, spec_all))
    rows = []
    order = _order(data)
    for name in data.fixture_names:
        cols = []
        for axis in range(3):
            c = np.zeros((data.n_samples, 3))
            c[:, axis] = (data.labels == name) * order
            cols.append(c.reshape(-1, 1))
        g, coef = st.gain(np.hstack(cols))
        rows.append({"socket": name, "drift_end_to_end_mm": float(np.linalg.norm(coef) * 2e3), "chi2_drop": g})
    return rows


def _order(data) -> np.ndarray:
    """(K,) recording order within each socket, -1 (first press) .. 1 (last)."""
    order = np.zeros(data.n_samples)
    for name in data.fixture_names:
        idx = np.flatnonzero(data.labels == name)
        order[idx] = np.linspace(-1.0, 1.0, len(idx))
    return order


def structure_table(nominal, data, spec) -> dict:
    from spherecal.correction import tool_point
    from spherecal.correction.chain import link_frames
    from spherecal.correction.gravity import GRAVITY, gravity_torques, inertials_of
    from spherecal.correction.kinematics import joint_jacobian

    res = _fit(nominal, data, spec)
    st = Structure(res)
    model, q, k = res.model, data.q, data.n_samples
    jq, tau = joint_jacobian(model, q), gravity_torques(model, q)
    motion = np.zeros_like(q)
    for name in data.fixture_names:
        idx = np.flatnonzero(data.labels == name)
        step = np.sign(np.diff(q[idx], axis=0))
        motion[idx[1:]], motion[idx[0]] = step, step[0]
    features = {"q (scale)": q, "sin q": np.sin(q), "cos q": np.cos(q), "sin 2q": np.sin(2 * q),
                "cos 2q": np.cos(2 * q), "tau_g (compliance)": tau, "sign tau_g": np.sign(tau),
                "sign dq (motion)": motion}
    table: dict = {"noise_mm": float(np.sqrt(st.s2) * 1e3), "dof": int(len(st.r) - st.jac.shape[1]),
                   "max_gravity_torque_nm": np.abs(tau).max(axis=0).round(2).tolist(), "joint": {}}
    every = []
    for label, f in features.items():
        cols = [(jq[:, :, i] * f[:, i : i + 1]).reshape(-1, 1) for i in range(model.n_joints)]
        every += cols
        table["joint"][label] = [st.gain(c)[0] for c in cols] + [st.gain(np.hstack(cols))[0]]
    table["every joint column"] = {"columns": len(every), "chi2_drop": st.gain(np.hstack(every))[0]}
    names = list(st.problem.unknown_names)
    tool = st.jac[: 3 * k, [names.index(n) for n in ("tool_x", "tool_y", "tool_z")]].reshape(k, 3, 3)
    place = np.array([_placement(n) for n in data.labels])
    places = list(dict.fromkeys(place))
    cols = np.hstack([(tool * (place == p)[:, None, None]).reshape(3 * k, 3) for p in places[1:]])
    g, coef = st.gain(cols)
    table["ball offset per placement"] = {"columns": cols.shape[1], "chi2_drop": g, "offset_mm_vs_" + places[0]: {
        str(p): (coef[3 * i : 3 * i + 3] * 1e3).round(2).tolist() for i, p in enumerate(places[1:])}}
    masses, coms = inertials_of(model)
    poses = link_frames(model, q)
    n = model.n_joints
    frame = np.minimum(np.arange(n + 1), n - 1)
    centres = np.einsum("kbij,bj->kbi", poses[:, 1:, :3, :3][:, frame], coms) + poses[:, 1:, :3, 3][:, frame]
    moment = -np.cross((masses[None, :, None] * centres).sum(axis=1), GRAVITY)  # (K, 3) carried by the base
    point = tool_point(model, q)
    tilt = [(moment[:, a : a + 1] * np.cross(np.eye(3)[b], point)).reshape(-1, 1) for a in range(2) for b in range(2)]
    pivot = [(moment[:, a : a + 1] * np.eye(3)[b][None, :]).reshape(-1, 1) for a in range(2) for b in range(3)]
    table["base tilt under the arm's moment"] = {"columns": 10, "chi2_drop": st.gain(np.hstack(tilt + pivot))[0],
                                                 "moment_nm": [float(np.linalg.norm(moment[:, :2], axis=1).min()),
                                                               float(np.linalg.norm(moment[:, :2], axis=1).max())]}
    return table


def offsets_only(nominal, data, spec):
    """Joint zero offsets theta2..thetan alone, plain least squares (theta1 is the gauge)."""
    from scipy.optimize import least_squares  # scipy.optimize: a what-if fit outside the library's solver

    from spherecal.correction import tool_point

    names = nominal.layout.names
    free = [names.index(f"theta{i + 1}") for i in range(1, nominal.n_joints)]
    fixtures = list(data.fixture_names)
    label = np.array([fixtures.index(n) for n in data.labels])

    def residuals(v):
        params = nominal.params.copy()
        params[free] = v[: len(free)]
        centres = v[len(free) :].reshape(-1, 3)
        r = (tool_point(nominal.with_params(params), data.q) - centres[label]).ravel()
        gaps = [np.linalg.norm(centres[fixtures.index(a)] - centres[fixtures.index(b)]) - d
                for a, b, d in spec.distances]
        return np.concatenate([r, 10.0 * np.array(gaps)])

    start = tool_point(nominal, data.q)
    centres = np.array([start[label == j].mean(axis=0) for j in range(len(fixtures))])
    v = least_squares(residuals, np.concatenate([nominal.params[free], centres.ravel()]), x_scale=1e-3).x
    params = nominal.params.copy()
    params[free] = v[: len(free)]
    return nominal.with_params(params)


def held_out_table(root, nominal, data, places) -> list[dict]:
    from mukca import held_out

    from spherecal.identification.workflow import WorkflowOptions, run_workflow

    rows = []
    for place in places:
        train, train_spec = bench_common.mukca_dataset(root, ROBOT, nominal, [place])
        others = [p for p in places if p != place]
        test, test_spec = bench_common.mukca_dataset(root, ROBOT, nominal, others)
        done = run_workflow(nominal, train, train_spec, WorkflowOptions(force=True))
        refused = ""
        try:
            done.result.selfcheck.raise_if_inconsistent()
        except Exception as error:  # noqa: BLE001 - the refusal's text is the figure
            refused = str(error)
        figures = {"nominal": held_out(nominal, test)[0], "calibrated": held_out(done.model, test)[0],
                   "floor": held_out(_fit(nominal, test, test_spec).model, test)[0],
                   "offsets_only": held_out(offsets_only(nominal, train, train_spec), test)[0]}
        rows.append({"train": place, "chosen": done.selection.chosen, "refused": refused,
                     **{f"{k}_mm": v * 1e3 for k, v in figures.items()}})
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=None, help="MUKCa root (data/, urdf/)")
    parser.add_argument("--exclude", nargs="*", default=[], help="sockets left out of the structure section")
    parser.add_argument("--offset-spread-deg", type=float, default=None,
                        help="what-if: prior spread of the joint zero offsets [deg] (default: the layout's)")
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # the importer's joint-limit warning and the Hayati note, known here
    if args.offset_spread_deg is not None:
        import spherecal.correction.layout as layout

        offset = dataclasses.replace(layout.ANGLE, prior_std=float(np.deg2rad(args.offset_spread_deg)))
        layout.JOINT_FIELDS = tuple((n, offset if n == "theta" else k) for n, k in layout.JOINT_FIELDS)
    from spherecal.correction import load_robot
    from spherecal.identification.training import exclude_fixtures

    root = args.data or bench_common.find_mukca()
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"uptime: {uptime}")
    nominal = load_robot(root / "urdf" / "gen3lite.urdf", tip_link="ball_link")
    print(f"theta prior spread {np.rad2deg(nominal.layout.kinds[3].prior_std):.3g} deg")
    data, spec = bench_common.mukca_dataset(root, ROBOT, nominal)
    places = list(dict.fromkeys(_placement(n) for n in data.fixture_names))

    noise = noise_table(root, nominal, places)
    print("\nnoise: plain least-squares DH fit [mm]")
    for r in noise:
        print(f"  {r['placements']:45} K={r['samples']:3d} unknowns {r['unknowns']:5.1f}  "
              f"rms/axis {r['rms_per_axis_mm']:5.2f}  noise {r['noise_mm']:5.2f}")
    drift = drift_table(root, nominal, spec, data)
    print("\ndrift of each socket in recording order (fit on every placement)")
    for r in drift:
        print(f"  {r['socket']:16} end to end {r['drift_end_to_end_mm']:6.2f} mm   chi2 drop {r['chi2_drop']:6.1f}")
    kept, kept_spec = exclude_fixtures(data, spec, tuple(args.exclude))
    structure = structure_table(nominal, kept, kept_spec)
    print(f"\nstructure (every placement{' but ' + ', '.join(args.exclude) if args.exclude else ''}; noise "
          f"{structure['noise_mm']:.2f} mm, {structure['dof']} dof): chi2 drop / sigma^2, ~1 per column by chance")
    print(f"  max |gravity torque| per joint [Nm]: {structure['max_gravity_torque_nm']}")
    print(f"  {'joint angle error':20}" + "".join(f"{'j' + str(i + 1):>7}" for i in range(nominal.n_joints))
          + "    all")
    for label, gains in structure["joint"].items():
        print(f"  {label:20}" + "".join(f"{g:7.1f}" for g in gains))
    for label in ("every joint column", "ball offset per placement", "base tilt under the arm's moment"):
        entry = structure[label]
        print(f"  {label}: {entry['columns']} columns, chi2 drop {entry['chi2_drop']:.1f}")
    offsets = structure["ball offset per placement"]
    moved = [(k[len("offset_mm_vs_"):], o) for k, o in offsets.items() if k.startswith("offset")]
    listed = ", ".join(f"{ref} -> {p} {v}" for ref, o in moved for p, v in o.items())
    print(f"  ball offset per placement [mm]: {listed}")
    held = held_out_table(root, nominal, data, places)
    print("\nheld-out test MAE [mm], trained on one placement (defaults; * = the self-check refuses it)")
    print(f"  {'train':12} {'nominal':>8} {'calibrated':>11} {'ratio':>6} {'floor':>6} {'offsets only':>13}  "
          "auto chose")
    for r in held:
        print(f"  {r['train']:12} {r['nominal_mm']:8.2f} {r['calibrated_mm']:10.2f}{'*' if r['refused'] else ' '} "
              f"{r['calibrated_mm'] / r['nominal_mm']:6.2f} {r['floor_mm']:6.2f} {r['offsets_only_mm']:13.2f}  "
              f"{r['chosen']}")
    ratios = {k: float(np.mean([r[f"{k}_mm"] / r["nominal_mm"] for r in held]))
              for k in ("calibrated", "floor", "offsets_only")}
    print("  mean ratio to nominal: " + ", ".join(f"{k} {v:.2f}x" for k, v in ratios.items()))
    out = bench_common.write_json(Path(__file__).with_name("gen3lite_diagnosis.json"), {
        "uptime": uptime, "offset_spread_deg": args.offset_spread_deg, "excluded": args.exclude, "noise": noise,
        "drift": drift, "structure": structure, "held_out": held, "mean_ratio": ratios},
        seed=0, inputs={"data": Path(root)})
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
