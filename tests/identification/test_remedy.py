"""A refusal that advises leaving out a drifting socket says what that gives (:func:`.workflow._remedy_tried`)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import spherecal.identification.selection as selection
import spherecal.identification.workflow as workflow
from spherecal.correction import load_robot
from spherecal.correction.files.samples import DatasetError
from spherecal.identification.calibrate import _discounted_socket
from spherecal.identification.selfcheck_result import ONLY_FIXTURE, Finding, InconsistentDataError, SelfCheck
from spherecal.identification.workflow import WorkflowOptions


def _refused(*moved: str) -> InconsistentDataError:
    return InconsistentDataError("samples.csv: rows 1-20, field 'fixture': ... leave it out", moved or ("P2",))


def _written(warnings: int = 0):
    result = SimpleNamespace(warnings=("w",) * warnings, selfcheck=None)
    return SimpleNamespace(result=result)


@pytest.mark.parametrize(("writes", "verdict", "advised"), [
    ({("P1", "P2")}, "without P2 the rest is consistent and is written (calibrate --exclude-fixture P1 "
                     "--exclude-fixture P2)", ("P2",)),
    ({("P1", "P2", "P3")}, "without P2 and P3 the rest is consistent and is written (calibrate --exclude-fixture P1 "
                           "--exclude-fixture P2 --exclude-fixture P3)", ("P2", "P3")),
    (set(), "leaving P2 and P3 out does not help: without P2 and P3 the rest is refused too (calibrate "
            "--exclude-fixture P1 --exclude-fixture P2 --exclude-fixture P3 says why)", ("P2", "P3")),
])
def test_the_remedy_leaves_out_the_strongest_trends_first_and_its_verdict_ends_the_refusal(monkeypatch, writes,
                                                                                          verdict, advised) -> None:
    """Two drifting sockets named, strongest first (P2): without P2 alone, then without both; a socket that did not
    move keeps its samples when leaving out the stronger one is enough (a review: a refusal had named four sockets,
    two of them untouched, and its command wrote the rest from 2 of 6)."""
    tried = []

    def run(nominal, dataset, spec, options, start=None, try_remedy=True):
        tried.append((options.exclude_fixtures, try_remedy))
        if options.exclude_fixtures not in writes:
            raise DatasetError("samples.csv: refused")
        return _written()

    monkeypatch.setattr(workflow, "run_workflow", run)
    said = workflow._remedy_tried(_refused("P2", "P3"), load_robot("panda"), None, None,
                                  WorkflowOptions(exclude_fixtures=("P1",)), None)
    assert tried[0] == (("P1", "P2"), False)  # the user's exclusions kept; the remedy is not tried again inside
    assert len(tried) == (1 if advised == ("P2",) else 2)
    assert str(said).endswith("leave it out; " + verdict) and said.moved == advised


def test_the_verdict_says_whether_what_would_be_written_warns(monkeypatch) -> None:
    monkeypatch.setattr(workflow, "run_workflow", lambda *args, **kwargs: _written(2))
    said = workflow._remedy_tried(_refused(), load_robot("panda"), None, None, WorkflowOptions(), None)
    assert str(said).endswith("without P2 the rest is consistent and is written, with warnings "
                              "(calibrate --exclude-fixture P2)")
    monkeypatch.setattr(workflow, "run_workflow", lambda *args, **kwargs: _written(0))
    said = workflow._remedy_tried(_refused(), load_robot("panda"), None, None, WorkflowOptions(), None)
    assert str(said).endswith("without P2 the rest is consistent and is written (calibrate --exclude-fixture P2)")


def test_a_fault_in_the_remedy_run_leaves_the_refusal_as_it_was(monkeypatch) -> None:
    def run(*args, **kwargs):
        raise ZeroDivisionError

    monkeypatch.setattr(workflow, "run_workflow", run)
    refused = _refused()
    assert workflow._remedy_tried(refused, load_robot("panda"), None, None, WorkflowOptions(), None) is refused


def _trend(name: str, change_mm: float = 6.0) -> Finding:
    move = f"the residual at fixture {name} moves {change_mm:g} mm with recording order"
    return Finding(f"trend {name}", True, f"samples.csv: rows 21-40, field 'fixture': {move}",
                   {"trend": True, "change_mm": change_mm}, clause=move)


def test_the_fixtures_to_leave_out_come_strongest_trend_first() -> None:
    level = Finding("residual level", False, "samples.csv: rows 1-60: residual noise 2 mm per axis")
    check = SelfCheck((level, _trend("P2", 5.0), _trend("P3", 9.0)), 3e-4, 2e-3)
    with pytest.raises(InconsistentDataError) as refused:
        check.raise_if_inconsistent()
    assert refused.value.moved == ("P3", "P2")


def test_a_fixture_blamed_alone_is_advised_out_when_it_also_drifts() -> None:
    """A review drifted one socket of a real Panda by 0.5-2 deg over its presses: the refusal blamed that fixture
    alone ('the samples at fixture X disagree ...') and said nothing of its trend nor of leaving it out."""
    blamed = Finding("fixture P2", False, "samples.csv: rows 21-40, field 'fixture': the samples at fixture P2 "
                     "disagree with the other fixtures by 3 mm rms", culprit=True)
    check = SelfCheck((blamed, _trend("P2"), _trend("P3")), 3e-4, 3e-4)
    with pytest.raises(InconsistentDataError) as refused:
        check.raise_if_inconsistent()
    assert refused.value.moved == ("P2",)
    assert str(refused.value).endswith("by 3 mm rms; the residual at fixture P2 moves 6 mm with recording order: the "
                                       "socket or the ball moved while it was recorded; leave it out (calibrate "
                                       "--exclude-fixture P2) or record it again")


@pytest.mark.parametrize("alien", [False, True])
def test_a_refusal_names_the_drifting_fixtures_it_advises_leaving_out(alien) -> None:
    level = Finding("residual level", False, "samples.csv: rows 1-40: residual noise 2 mm per axis",
                    {"not_a_socket": alien})
    check = SelfCheck((level, _trend("P2")), 3e-4, 2e-3)
    with pytest.raises(InconsistentDataError) as refused:
        check.raise_if_inconsistent()
    if alien:  # a model that does not describe the arm moves every residual: no socket to leave out
        assert refused.value.moved == () and "exclude-fixture" not in str(refused.value)
    else:
        assert refused.value.moved == ("P2",)
        assert str(refused.value).endswith("the residual at fixture P2 moves 6 mm with recording order: the socket or "
                                           "the ball moved while it was recorded; leave it out (calibrate "
                                           "--exclude-fixture P2) or record it again")


def test_a_refusal_of_the_only_fixture_advises_recording_it_again_not_leaving_it_out() -> None:
    # a review: a one-socket Gen3 lite placement (MUKCa dinova_2 gen3lite) was refused advising
    # 'calibrate --exclude-fixture gen3lite_h0', which leaves nothing to calibrate
    level = Finding("residual level", False, "samples.csv: rows 1-20: residual noise 2 mm per axis",
                    {"per_fixture_std_mm": {"P2": 2.0}})
    check = SelfCheck((level, _trend("P2")), 3e-4, 2e-3)
    with pytest.raises(InconsistentDataError) as refused:
        check.raise_if_inconsistent()
    assert refused.value.moved == () and "exclude-fixture" not in str(refused.value)
    assert str(refused.value).endswith("moved while it was recorded; record it again (it is the only fixture)")


def test_a_forced_calibration_of_the_only_fixture_advises_recording_it_again_in_its_summary() -> None:
    # a review: a forced one-socket calibration (MUKCa dinova_1 front_h0, drifting) printed 'leave it out (calibrate
    # --exclude-fixture front_h0) or record it again' under its summary and in its file's warnings
    level = Finding("residual level", False, "samples.csv: rows 1-20: residual noise 2 mm per axis",
                    {"per_fixture_std_mm": {"P2": 2.0}})
    check = SelfCheck((level, _trend("P2")), 3e-4, 2e-3)
    assert not check.consistent
    (warning,) = check.warnings
    assert warning.endswith("moved while it was recorded; record it again (it is the only fixture)")
    summary = "\n".join(check.lines())
    assert "record it again (it is the only fixture)" in summary
    assert "exclude-fixture" not in summary and "leave it out" not in summary
    assert all("exclude-fixture" not in w for w in check.block()["warnings"])


def test_a_forced_calibration_of_several_fixtures_still_advises_leaving_the_drifting_one_out() -> None:
    level = Finding("residual level", False, "samples.csv: rows 1-40: residual noise 2 mm per axis",
                    {"per_fixture_std_mm": {"P1": 0.4, "P2": 2.0}})
    (warning,) = SelfCheck((level, _trend("P2")), 3e-4, 2e-3).warnings
    assert warning.endswith("leave it out (calibrate --exclude-fixture P2) or record it again")


def test_a_written_calibration_of_the_only_fixture_does_not_advise_leaving_it_out() -> None:
    level = Finding("residual level", True, "residual 0.3 mm per axis", {"per_fixture_std_mm": {"P2": 0.3}})
    check = SelfCheck((level, _trend("P2")), 3e-4, 3e-4)
    check.raise_if_inconsistent()  # consistent: nothing raised
    (warning,) = check.warnings
    assert warning.endswith("changes along the self-motion; the checks pass, so it is kept; to tell which, record it "
                            "again (it is the only fixture)")
    assert "exclude-fixture" not in warning and "other fixtures" not in warning


def test_the_only_fixture_is_advised_recorded_again_in_one_phrase_wherever_it_is_named() -> None:
    """A review: a discounted only socket read 'it is the only fixture: record it again', a refused trending one
    'record it again (it is the only fixture)', a written one 'it is the only fixture, so it is kept (record it again
    to check it)'. Each now ends with the one phrase (:data:`ONLY_FIXTURE`)."""
    assert ONLY_FIXTURE == "record it again (it is the only fixture)"
    only = {"per_fixture_std_mm": {"P2": 2.0}}
    refused = SelfCheck((Finding("residual level", False, "samples.csv: rows 1-20: residual noise 2 mm", only),
                         _trend("P2")), 3e-4, 2e-3)
    written = SelfCheck((Finding("residual level", True, "residual 0.3 mm per axis", only), _trend("P2")), 3e-4, 3e-4)
    inliers = np.arange(10) >= 6  # six of the only fixture's ten samples far: a socket's worth
    problem = SimpleNamespace(dataset=SimpleNamespace(fixture_index=np.zeros(10, int), fixture_names=("P2",)),
                              inliers=lambda x: inliers)
    (discounted,) = _discounted_socket(problem, None, "huber")
    said = [refused.refusal, *refused.warnings, *written.warnings, discounted]
    assert len(said) == 4 and all(text.endswith(ONLY_FIXTURE) for text in said), said
    assert all(text.count("only fixture") == 1 and "exclude-fixture" not in text for text in said), said


def test_a_written_calibration_keeps_its_drifting_fixture_and_advises_no_exclusion() -> None:
    check = SelfCheck((Finding("residual level", True, "residual 0.3 mm per axis"), _trend("P2")), 3e-4, 3e-4)
    check.raise_if_inconsistent()  # consistent: nothing raised
    assert check.refusal == "" and check._refusal()[1] == ()
    (warning,) = check.warnings
    assert warning.endswith("so it is kept (calibrate --exclude-fixture P2 leaves it out)")
    assert "leave it out" not in warning


def test_the_verdict_lists_the_fixtures_it_names() -> None:
    assert selection.listed(("P2",)) == "P2"
    assert selection.listed(("P2", "P3")) == "P2 and P3"
    assert selection.listed(("P1", "P2", "P3")) == "P1, P2 and P3"
