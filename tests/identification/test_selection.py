"""Model selection by cross-validation: rigid data keeps dh, elastic data earns elastic."""

import numpy as np
import pytest
import yaml

from spherecal.cli import main
from spherecal.correction import (
    Dataset,
    load_robot,
    perturb,
    read_fixtures,
    registered_errors,
    save_robot,
    tool_point,
    write_fixtures,
    write_samples,
)
from spherecal.correction.elastic import with_compliance
from spherecal.correction.files.samples_csv import read_samples
from spherecal.identification.calibrate import calibrate
from spherecal.identification.problem import PRIOR
from spherecal.identification.selection import _bic_margin, _bic_on_all, groups_of, held_out_error, select_model
from spherecal.identification.synthetic import make_dataset
from spherecal.identification.workflow import WorkflowOptions, run_workflow

C_TRUE = np.array([0.0, 1 / 3e4, 1 / 3e4, 1 / 3e4, 0.0, 0.0, 0.0])


def _fit(start, data, spec, warm=None):  # as the workflow fits every candidate and fold
    return calibrate(start, data, spec, start=warm, check=False, prior=PRIOR)


def _data(compliance, noise, seed, per_fixture=150):
    rng = np.random.default_rng(seed)
    truth = perturb(load_robot("panda"), rng)
    if compliance is not None:
        truth = with_compliance(truth, compliance)
    dataset, spec = make_dataset(truth, per_fixture=per_fixture, rng=rng, noise=noise)
    return truth, dataset, spec


def test_groups_are_placements_when_names_carry_them():
    names = ["front_h0", "front_h1", "mid-high_h0", "P1", "a_hx", "_h1"]
    assert groups_of(names) == {"front_h0": "front", "front_h1": "front", "mid-high_h0": "mid-high", "P1": "P1",
                                "a_hx": "a_hx", "_h1": "_h1"}


def test_rigid_arm_keeps_dh():
    _, dataset, spec = _data(None, 3e-4, seed=11)
    selection = select_model("auto", _fit, load_robot("panda"), dataset, spec)
    assert selection.chosen == "dh" and len(selection.folds) == 3 and selection.criterion == "cross-validation"
    assert set(selection.scores) == {"dh", "scale", "elastic", "elastic+scale"}
    dh, el, gain, se = selection.stats()
    assert gain <= se and ("with dh on held-out fixtures" in selection.reason or "no richer" in selection.reason)


@pytest.mark.parametrize("seed", [2, 11, 14])
def test_auto_states_the_scores_and_calls_a_difference_within_its_standard_error_a_tie(seed):
    """A review: ``model: dh (no richer model predicts held-out fixtures better than dh)`` where elastic scored
    0.0005 mm from dh. The reason now gives dh's held-out error and the richer ones' against it, and calls a
    difference within the standard error of the fold-by-fold differences a tie (computed here from the folds' errors
    independently); dh is kept as before. Rigid simulated Pandas, 3 fixtures: seed 2 has elastic 0.0009 mm from dh
    (a tie), 11 none within (elastic the nearest, 0.0017 mm off at 0.001), 14 two ties."""
    _, dataset, spec = _data(None, 3e-4, seed=seed)
    selection = select_model("auto", _fit, load_robot("panda"), dataset, spec)
    errors, reason = selection.errors, selection.reason
    assert selection.chosen == "dh" and selection.criterion == "cross-validation"
    diff = {k: errors[k] - errors["dh"] for k in errors if k != "dh"}
    se = {k: np.std(d, ddof=1) / np.sqrt(d.size) for k, d in diff.items()}
    ties = [k for k in sorted(diff, key=lambda k: errors[k].mean()) if abs(diff[k].mean()) <= se[k]]
    assert bool(ties) == (seed != 11)  # the cases this test is about
    assert f"held-out error dh {errors['dh'].mean() * 1e3:.4f} mm" in reason, reason
    if ties:
        head = f"{' and '.join(ties)} {'ties' if len(ties) == 1 else 'tie'} with dh on held-out fixtures"
        assert reason.startswith(head) and "so the simpler dh is kept" in reason, reason
        named = ties
    else:
        nearest = min(diff, key=lambda k: errors[k].mean())
        assert reason.startswith(f"no richer model predicts held-out fixtures better than dh; the nearest is {nearest}")
        named = [nearest]
    for k in named:
        said = f"{k} {errors[k].mean() * 1e3:.4f} mm ({diff[k].mean() * 1e3:+.2g} mm, standard error"
        assert said in reason and f"{se[k] * 1e3:.2g} mm)" in reason, (said, reason)
    assert all(f"{k} " not in reason for k in diff if k not in named), reason  # only the ones it is about
    assert selection.summary().startswith(f"model: dh ({reason})")


def test_a_bic_margin_under_2_is_called_a_tie_and_the_choice_is_the_lowest_as_before():
    """BIC difference ~ 2 ln(Bayes factor): under 2 is no evidence either way (Kass & Raftery 1995). The margin says
    so; the choice stays the lowest score (dh in a tie where it is lowest)."""
    tie, clear = {"dh": 100.0, "scale": 101.5, "elastic": 107.0}, {"dh": 100.0, "scale": 103.0, "elastic": 107.0}
    assert _bic_margin(tie, "dh") == ("1.5 below the next candidate, scale, under 2: a tie, no evidence either way, "
                                      "and the simpler dh is kept")
    assert _bic_margin(clear, "dh") == "3.0 below the next candidate, scale"
    said = "1.5 below dh, under 2: a tie, no evidence either way, and elastic is taken as the lowest all the same"
    assert _bic_margin({"dh": 100.0, "elastic": 98.5}, "elastic") == said
    assert _bic_margin({"dh": 100.0, "elastic": 90.0}, "elastic") == "10.0 below dh"
    assert _bic_on_all(1.5, "elastic") == ("BIC on all samples does not disagree (elastic 1.5 below dh, under 2: a "
                                           "tie, no evidence either way)")
    assert _bic_on_all(-0.5, "elastic") == ("BIC on all samples does not agree (dh 0.5 below elastic, under 2: a tie, "
                                            "no evidence either way)")
    assert _bic_on_all(-3.0, "elastic") == "BIC on all samples prefers dh (3.0 below elastic)"
    assert _bic_on_all(560.0, "elastic") == "BIC on all samples agrees (560.0 below dh)"


def test_elastic_arm_earns_elastic_and_recovers_compliance():
    truth, dataset, spec = _data(C_TRUE, 1e-4, seed=12)
    panda = load_robot("panda")
    selection = select_model("auto", _fit, panda, dataset, spec)
    assert selection.chosen in ("elastic", "elastic+scale"), selection.summary()
    result = calibrate(with_compliance(panda, np.zeros(7)), dataset, spec)
    for i in (2, 3, 4):
        name = f"c{i}"
        estimate = result.model.params[result.model.layout.index(name)]
        assert name in result.identified and abs(estimate - C_TRUE[i - 1]) < 3 * result.std[name]
    assert "c1" in result.fixed and "c7" in result.fixed  # no load about a vertical axis / at the wrist


def test_cli_records_the_choice_and_refuses_elastic_without_masses(tmp_path, capsys):
    _, dataset, spec = _data(C_TRUE, 1e-4, seed=13)
    write_samples(tmp_path / "s.csv", dataset)
    write_fixtures(tmp_path / "f.yaml", spec)
    args = ["calibrate", "--robot", "panda", "--samples", str(tmp_path / "s.csv"),
            "--fixtures", str(tmp_path / "f.yaml")]
    assert main([*args, "--model", "elastic", "--out", str(tmp_path / "el.yaml")]) == 0
    out = yaml.safe_load((tmp_path / "el.yaml").read_text())
    assert out["calibration"]["model_selection"]["chosen"] == "elastic" and len(out["compliance"]) == 7
    assert main([*args, "--model", "dh", "--out", str(tmp_path / "dh.yaml")]) == 0
    out = yaml.safe_load((tmp_path / "dh.yaml").read_text())
    assert "compliance" not in out and out["calibration"]["model_selection"]["chosen"] == "dh"
    bare = load_robot("panda")  # without masses, and 5 mm off the Panda so no embedded arm lends it theirs
    save_robot(bare.__class__(**{**bare.__dict__, "d": bare.d + np.eye(7)[2] * 0.005, "extras": {}}),
               tmp_path / "bare.yaml")
    args[2] = str(tmp_path / "bare.yaml")
    assert main([*args, "--model", "elastic", "--out", str(tmp_path / "x.yaml")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert "field 'inertials'" in err[-1] and not (tmp_path / "x.yaml").exists()


@pytest.mark.parametrize("model", ["auto"])
def test_cli_auto_prints_both_cv_errors(tmp_path, capsys, model):
    _, dataset, spec = _data(None, 3e-4, seed=14)
    write_samples(tmp_path / "s.csv", dataset)
    write_fixtures(tmp_path / "f.yaml", spec)
    assert main(["calibrate", "--robot", "panda", "--samples", str(tmp_path / "s.csv"), "--fixtures",
                 str(tmp_path / "f.yaml"), "--model", model, "--out", str(tmp_path / "c.yaml")]) == 0
    text = capsys.readouterr().out
    assert "held-out error [mm]" in text and "model: " in text
    assert all(f"{m} " in text for m in ("dh", "scale", "elastic", "elastic+scale"))
    block = yaml.safe_load((tmp_path / "c.yaml").read_text())["calibration"]["model_selection"]
    assert block["criterion"] == "cross-validation" and set(block["scores"]) == {"dh", "scale", "elastic",
                                                                                  "elastic+scale"}


#: One MUKCa-like placement: two sockets 50 mm apart (one fixture group: BIC, not cross-validation).
PLATE = {"front_h0": (0.5, -0.025, 0.15), "front_h1": (0.5, 0.025, 0.15)}


def _bic_choice(compliance, seed):
    rng = np.random.default_rng(seed)
    truth = perturb(load_robot("panda"), rng)
    if compliance is not None:
        truth = with_compliance(truth, compliance)
    dataset, spec = make_dataset(truth, PLATE, per_fixture=250, rng=rng, noise=1e-4)
    selection = select_model("auto", _fit, load_robot("panda"), dataset, spec)
    # one placement: every candidate with one kind of term beyond geometry, the combined one only by cross-validation
    assert selection.criterion == "BIC" and set(selection.scores) == {"dh", "scale", "elastic"}
    assert "elastic+scale only with 3 or more groups" in selection.reason
    return selection.chosen


@pytest.mark.slow
def test_bic_from_one_placement_keeps_dh_on_a_rigid_arm_and_finds_elasticity():
    """Kinematic simulation (identification.synthetic), 10 seeds each: >= 9 right."""
    rigid = [_bic_choice(None, seed) for seed in range(10)]
    elastic = [_bic_choice(C_TRUE, 100 + seed) for seed in range(10)]
    assert sum(c == "dh" for c in rigid) >= 9, rigid
    assert sum(c == "elastic" for c in elastic) >= 9, elastic


def test_a_negative_compliance_is_named_and_a_positive_one_is_not():
    # no joint gives against its load: a compliance fitted well below zero is another gravity-dependent error the
    # term absorbs, and the user is told not to read it as a stiffness (MUKCa's Pandas fit c2 < 0)
    panda = with_compliance(load_robot("panda"), np.zeros(7))
    for sign, named in ((-1.0, True), (1.0, False)):
        _, dataset, spec = _data(sign * C_TRUE, 1e-4, seed=12, per_fixture=80)
        result = calibrate(panda, dataset, spec, check=False)  # the warning does not depend on the self-check
        lines = [w for w in result.warnings if w.startswith("negative joint compliance")]
        assert bool(lines) == named, result.warnings
        if named:
            for i in (2, 3, 4):
                value = result.model.params[result.model.layout.index(f"c{i}")]
                assert value < -2 * result.std[f"c{i}"] and f"c{i} " in lines[0]


def test_a_robust_fit_is_judged_without_its_outliers():
    # ten samples slipped a tenth of a turn of joint 3: the held-out score was the outliers' (12.8 mm for every
    # candidate of MUKCa's Panda, within 0.04 mm of each other), whatever the model
    truth, dataset, spec = _data(None, 3e-4, seed=11)
    q = dataset.q.copy()
    q[np.random.default_rng(3).choice(dataset.n_samples, 10, replace=False), 2] += 0.3
    slipped = Dataset(dataset.labels, q)
    clean = held_out_error(truth, dataset, spec)
    assert held_out_error(truth, slipped, spec) > 10 * clean  # the plain score is the outliers'
    assert held_out_error(truth, slipped, spec, robust=True) == pytest.approx(clean, rel=0.05)
    assert held_out_error(truth, dataset, spec, robust=True) == pytest.approx(clean, rel=0.05)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 8])
def test_folds_alone_do_not_earn_a_richer_model_that_bic_on_all_samples_rejects(tmp_path, seed):
    # short self-motion of a rigid Panda: the folds took elastic+scale by 0.005 / 0.014 mm, more than their spread,
    # and the calibration's mean error over the workspace was 0.83 / 1.55 mm against dh's 0.43 / 0.26 mm
    folder = tmp_path / "sim"
    assert main(["simulate", "--out", str(folder), "--seed", str(seed), "--seconds", "10", "--per-fixture", "200",
                 "--known-distances"]) == 0
    panda, truth = load_robot("panda"), load_robot(folder / "truth.yaml")
    dataset, spec = read_samples(folder / "samples.csv", panda), read_fixtures(folder / "fixtures.yaml")
    done = run_workflow(panda, dataset, spec, WorkflowOptions())
    assert done.selection.criterion == "cross-validation"
    assert done.selection.chosen == "dh", done.selection.reason
    assert "BIC on all samples prefers dh" in done.selection.reason, done.selection.reason
    q = panda.random_configurations(1000, np.random.default_rng(7))
    richer = run_workflow(panda, dataset, spec, WorkflowOptions(model="elastic+scale")).model
    error = {name: float(np.mean(registered_errors(tool_point(m, q), tool_point(truth, q))))
             for name, m in (("dh", done.model), ("elastic+scale", richer))}
    assert error["dh"] < error["elastic+scale"], error  # what the folds would have taken is worse


def test_a_candidate_whose_own_terms_are_all_barely_excited_is_no_candidate() -> None:
    """MUKCa's real Gen3 lite on ``left``: one placement, 20 presses per socket at ~0.8 mm of noise per axis. Every
    compliance and every scale is pruned as barely excited, so 'elastic' and 'scale' are dh fitted along other
    pruning paths; BIC took 'elastic' by 2.8 (4.35 mm held out against dh's 3.91). ``auto`` now keeps dh, the same
    fit as ``--model dh``, and says why."""
    from pathlib import Path

    from spherecal.correction import load_robot
    from spherecal.correction.files.samples import JointLimitWarning
    from spherecal.identification.ingest.importers import read_mukca

    root = Path(__file__).resolve().parents[1] / "data" / "mukca"
    urdf = root.parent / "urdf" / "gen3lite.urdf"  # MUKCa's, to its ball
    with pytest.warns(Warning):  # joint_3 nearly parallel to joint_2: described with a Hayati beta
        nominal = load_robot(urdf, tip_link="ball_link")
    with pytest.warns(JointLimitWarning, match="used as recorded"):  # q6 beyond gen3lite.urdf's limits, said
        recording, spec = read_mukca(root / "dinova_1" / "left", nominal)
    dataset = Dataset(labels=recording.labels, q=recording.q, fixture_names=spec.names)
    auto = run_workflow(nominal, dataset, spec, WorkflowOptions())
    dh = run_workflow(nominal, dataset, spec, WorkflowOptions(model="dh"))
    assert auto.selection.chosen == "dh"
    assert "scale and elastic left out: every term of their own barely excited" in auto.selection.reason
    assert set(auto.selection.fits) == {"dh"}
    np.testing.assert_allclose(auto.model.params, dh.model.params, atol=1e-5)  # from another start: within 2 um


def test_auto_on_an_arm_without_masses_says_the_elastic_models_were_not_tried(tmp_path) -> None:
    """A new arm's trial: a URDF without <inertial> calibrated with --model auto printed 'model: dh (scale's held-out
    gain ...)', the elastic candidates gone without a word; only --model elastic said why."""
    from tests.validation.new_arm_urdfs import big_urdf

    path = tmp_path / "big.urdf"
    path.write_text(big_urdf())
    nominal = load_robot(path, tip_link="ball")
    assert "inertials" not in nominal.extras
    rng = np.random.default_rng(0)
    true = perturb(nominal, rng)
    centres = {"P1": np.array([0.9, -0.3, 0.6]), "P2": np.array([0.9, 0.0, 0.5]), "P3": np.array([0.8, 0.3, 0.6])}
    dataset, spec = make_dataset(true, centres, per_fixture=40, rng=rng, noise=2e-4)
    done = run_workflow(nominal, dataset, spec, WorkflowOptions())
    said = ("elastic and elastic+scale not tried (big6 has no link masses and matches no embedded arm: give them "
            "with --inertials FILE or <inertial> elements in its URDF)")
    assert said in done.selection.summary()
    # once, in what calibrate prints and in the file (a review read it twice in model selection's report)
    assert done.summary().count("not tried") == 1 and done.block["model_selection"]["reason"].count("not tried") == 1
    # the same with too few groups to cross-validate (BIC), from two of the sockets
    two = dataset.select(np.flatnonzero(dataset.labels != "P3"))
    two = Dataset(labels=two.labels, q=two.q, fixture_names=("P1", "P2"))
    assert run_workflow(nominal, two, None, WorkflowOptions()).summary().count("not tried") == 1
