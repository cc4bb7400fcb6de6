"""A refused calibration names the cause the nominal model already shows: two sockets under one fixture name,
samples pressed into the other socket, a wrong known distance (real MUKCa Panda recordings, tests/data/mukca)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from spherecal.correction import load_robot
from spherecal.identification.ingest.importers import read_mukca
from spherecal.identification.misplaced import misplaced
from tests.refusal import refused

DATA = Path(__file__).parents[1] / "data" / "mukca"
PANDA = DATA / "panda_ball.yaml"
KINOVA = DATA / "gen3lite_ball.yaml"
PLACEMENTS = ("front_center", "back_left", "mid_right")


def _samples(path: Path, blocks: list[tuple[str, np.ndarray]]) -> Path:
    """A samples.csv of ``(fixture, (k, 7) q)`` blocks in this order."""
    lines = ["fixture,q1,q2,q3,q4,q5,q6,q7"] + [
        f"{name}," + ",".join(repr(float(v)) for v in row) for name, q in blocks for row in q]
    path.write_text("\n".join(lines) + "\n")
    return path


def _holes(placement: str) -> tuple[np.ndarray, np.ndarray]:
    folder = DATA / "panda_2_clean" / placement
    return tuple(np.loadtxt(folder / f"hole_{k}.csv", delimiter=",") for k in (0, 1))


def _calibrate(tmp_path: Path, samples: Path, distance: float = 0.05) -> list:
    fixtures = tmp_path / "fixtures.yaml"
    fixtures.write_text(f"fixtures:\n  A: {{}}\n  B: {{}}\ndistances:\n- [A, B, {distance}]\n")
    return ["calibrate", "--robot", PANDA, "--samples", samples, "--fixtures", fixtures, "--out", tmp_path / "c.yaml"]


def test_samples_pressed_into_the_other_socket_are_named(tmp_path, capsys) -> None:
    # two presses swapped between hole_0.csv and hole_1.csv: refused as 'residual noise 8 mm per axis ... the socket
    # or the ball moved while it was recorded'
    a, b = _holes("front_center")
    a, b = a.copy(), b.copy()
    a[[5, 12]], b[[7, 20]] = b[[7, 20]], a[[5, 12]].copy()
    samples = _samples(tmp_path / "samples.csv", [("A", a), ("B", b)])
    lines = [7, 14, len(a) + 2 + 7, len(a) + 2 + 20]  # header row 1: sample k of A is row k + 2, of B len(a) + 2 + k
    refused(_calibrate(tmp_path, samples), tmp_path, capsys,
            f"samples.csv: rows {', '.join(map(str, sorted(lines)))}, field 'fixture': 4 samples lie ",
            "4 of them among another fixture's samples (B, A): pressed into the wrong socket?",
            "calibrate --loss soft_l1")


def test_two_recordings_under_one_fixture_name_are_named(tmp_path, capsys) -> None:
    # a placement recorded again elsewhere, both imports joined under the same names: refused as 'the fit moves the
    # tool point 150 mm ...: the samples do not determine the parameters; record more self-motion'
    (a, b), (c, d) = _holes("front_center"), _holes("back_left")
    samples = _samples(tmp_path / "samples.csv", [("A", a), ("B", b), ("A", c), ("B", d)])
    first, second = len(a) + len(b), len(c)
    refused(_calibrate(tmp_path, samples), tmp_path, capsys,
            f"samples.csv: rows 2-{len(a) + 1} and {first + 2}-{first + second + 1}, field 'fixture': fixture A's "
            "samples come in separate runs of the file that the nominal model puts ",
            "two sockets under one name (a placement recorded twice, or two imports joined?)")


def test_a_wrong_known_distance_is_named(tmp_path, capsys) -> None:
    # MUKCa's 50 mm plate declared 80 mm: refused naming fixture B ('samples of another arm, a fixture that moved,
    # or a wrong label')
    a, b = _holes("front_center")
    samples = _samples(tmp_path / "samples.csv", [("A", a), ("B", b)])
    refused(_calibrate(tmp_path, samples, 0.08), tmp_path, capsys,
            "fixtures.yaml: row 5, field 'distances[0]': known distance A-B 80 mm, the nominal model puts their "
            "samples 57.03 mm apart", "is the distance right (import --distance, in metres)?")


@pytest.mark.parametrize("robot, folder", [(PANDA, DATA / "panda_2_clean"), (KINOVA, DATA / "dinova_1")])
def test_good_recordings_show_nothing_misplaced(robot, folder) -> None:
    # no false alarm on the real arms' recordings, every placement at once
    model = load_robot(robot)
    recording, spec = read_mukca(folder, model)
    assert misplaced(model, recording.dataset(), spec) is None


def test_a_socket_of_one_sample_is_refused_in_one_clean_line(tmp_path, capsys) -> None:
    # hole_1.csv with one row: the refusal carried "(after 1 warning: invalid value encountered in sqrt)" (a sum of
    # squares below zero by rounding in the leave-one-out) and named 'rows 33-33'
    a, b = _holes("front_center")
    samples = _samples(tmp_path / "samples.csv", [("A", a), ("B", b[:1])])
    err = refused(_calibrate(tmp_path, samples), tmp_path, capsys,
                  f"samples.csv: row {len(a) + 2}, field 'q*': the samples at fixture B hardly move the arm")
    assert "warning" not in err and "invalid value" not in err


def test_a_press_far_from_its_socket_is_named_with_the_remedies_when_it_is_all_that_is_wrong(tmp_path, capsys) -> None:
    # one press several mm off its socket (joint 4 off by 0.8 deg) was refused as 'the samples at fixture A disagree
    # with the other fixtures by ... mm rms ...: samples of another arm, a fixture that moved, or a wrong label', no
    # row named (review helper: 0.5 deg on front_left). Writing it anyway, judged without the press, also wrote a
    # wrong known distance and rows of another arm (second review): the refusal names the row and the remedies
    from spherecal.cli import main

    a, b = _holes("front_center")
    a = a.copy()
    a[4, 3] += np.deg2rad(0.8)
    samples = _samples(tmp_path / "samples.csv", [("A", a), ("B", b)])
    argv = _calibrate(tmp_path, samples)
    refused(argv, tmp_path, capsys, "field 'fixture'",  # header row 1: sample k of A is row k + 2
            f"\n  1 of {len(a) + len(b)} samples (row 6) lies over 4x the median distance from its socket, and without "
            "them the rest is consistent: remove them if the ball was not seated in its socket, or calibrate --loss "
            "huber to discount them")
    assert main([str(v) for v in [*argv, "--loss", "huber"]]) == 0  # the remedy the refusal names


def test_one_press_in_the_other_socket_is_named_in_the_singular(tmp_path, capsys) -> None:
    # 'rows 37, field 'fixture': 1 samples lie 52-52 mm' (review helper)
    a, b = _holes("front_center")
    a = a.copy()
    a[5] = b[7]
    samples = _samples(tmp_path / "samples.csv", [("A", a), ("B", b)])
    err = refused(_calibrate(tmp_path, samples), tmp_path, capsys,
                  "samples.csv: row 7, field 'fixture': 1 sample lies ", "pressed into the wrong socket?")
    assert "-" not in err.split("1 sample lies ")[1].split(" mm")[0], err  # one distance, not a range


def test_a_refusal_joining_two_findings_says_where_once() -> None:
    # a fixture's disagreement and its trend: the trend joins as its move (its clause), without the file and rows again
    from spherecal.identification.selfcheck_result import Finding, InconsistentDataError, SelfCheck

    where = "s.csv: rows 7-26, field 'fixture': "
    level = Finding("residual level", True, "residual 1 mm", {"per_fixture_std_mm": {"A": 1.0, "B": 1.0}})
    culprit = Finding("fixture A", False, f"{where}the samples at fixture A disagree", culprit=True)
    move = "the residual at fixture A moves 13.5 mm"
    trend = Finding("trend A", True, where + move, {"trend": True}, clause=move)
    with pytest.raises(InconsistentDataError) as refused:
        SelfCheck((level, culprit, trend), 3e-4, 3e-4).raise_if_inconsistent()
    assert str(refused.value) == (f"{where}the samples at fixture A disagree; {move}: the socket or the ball moved "
                                  "while it was recorded; leave it out (calibrate --exclude-fixture A) or record it "
                                  "again")
    assert refused.value.moved == ("A",)


def test_presses_far_off_under_a_robust_loss_are_not_advised_that_loss_again() -> None:
    # a refusal under --loss soft_l1 ended 'remove them, or calibrate --loss soft_l1 to discount them' (a review,
    # stop 10: four presses of another placement appended to a socket, three placements): the workflow says whether
    # the fit already discounted them
    from spherecal.correction import Dataset

    model = load_robot(PANDA)
    a, b = _holes("front_center")
    a = np.vstack([a, _holes("back_left")[0][:4]])  # four presses 0.25 m away
    dataset = Dataset(labels=np.array(["A"] * len(a) + ["B"] * len(b)), q=np.vstack([a, b]))
    advised = misplaced(model, dataset)
    loss = ", or calibrate --loss soft_l1 to discount them"
    assert "4 samples lie" in advised and advised.endswith("; remove them" + loss)
    assert misplaced(model, dataset, discounted=True) == advised.removesuffix(loss)
