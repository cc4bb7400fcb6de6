"""A refusal that advises leaving out a drifting socket says what that gives (:func:`.workflow._remedy_tried`)."""

from __future__ import annotations

import pytest

import spherecal.identification.workflow as workflow
from spherecal.correction import load_robot
from spherecal.correction.files.samples import DatasetError
from spherecal.identification.selfcheck_result import Finding, InconsistentDataError, SelfCheck
from spherecal.identification.workflow import WorkflowOptions


def _refused() -> InconsistentDataError:
    return InconsistentDataError("samples.csv: rows 1-20, field 'fixture': ... leave it out", ("P2",))


@pytest.mark.parametrize(("outcome", "verdict"), [
    (None, "without it the rest is consistent and is written (calibrate --exclude-fixture P1 --exclude-fixture P2)"),
    (DatasetError("samples.csv: field 'fixture': --exclude-fixture leaves no fixture"),
     "without it the rest is refused too (calibrate --exclude-fixture P1 --exclude-fixture P2 says why): record it "
     "again"),
])
def test_the_remedy_is_run_without_the_named_fixtures_and_its_verdict_ends_the_refusal(monkeypatch, outcome,
                                                                                       verdict) -> None:
    seen = {}

    def run(nominal, dataset, spec, options, start=None, try_remedy=True):
        seen.update(excluded=options.exclude_fixtures, again=try_remedy)
        if outcome is not None:
            raise outcome

    monkeypatch.setattr(workflow, "run_workflow", run)
    said = workflow._remedy_tried(_refused(), load_robot("panda"), None, None,
                                  WorkflowOptions(exclude_fixtures=("P1",)), None)
    assert seen == {"excluded": ("P1", "P2"), "again": False}  # the user's exclusions kept; tried once, not again
    assert str(said).endswith("leave it out; " + verdict) and said.moved == ("P2",)


def test_a_fault_in_the_remedy_run_leaves_the_refusal_as_it_was(monkeypatch) -> None:
    def run(*args, **kwargs):
        raise ZeroDivisionError

    monkeypatch.setattr(workflow, "run_workflow", run)
    refused = _refused()
    assert workflow._remedy_tried(refused, load_robot("panda"), None, None, WorkflowOptions(), None) is refused


def _trend(name: str) -> Finding:
    return Finding(f"trend {name}", True, f"samples.csv: rows 21-40, field 'fixture': the residual at fixture {name} "
                   "moves 6 mm with recording order", {"trend": True})


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


def test_a_written_calibration_keeps_its_drifting_fixture_and_advises_no_exclusion() -> None:
    check = SelfCheck((Finding("residual level", True, "residual 0.3 mm per axis"), _trend("P2")), 3e-4, 3e-4)
    check.raise_if_inconsistent()  # consistent: nothing raised
    assert check._refusal() == ("", ())
    (warning,) = check.warnings
    assert warning.endswith("so it is kept (calibrate --exclude-fixture P2 leaves it out)")
    assert "leave it out" not in warning
