"""``spherecal plan`` as library calls, files in and files out: a plan from scratch over candidate positions
(:func:`plan_files`), what to record next on a real arm (:func:`guide_files`) and the predicted accuracy of a
data set (:func:`predict_files`)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

from spherecal.correction.files.earlier_run import refuse_unless_own, written_by
from spherecal.correction.files.fixtures import FixtureSpec, format_fixtures, read_fixtures
from spherecal.correction.files.outputs import OutputSet
from spherecal.correction.files.provenance import comment_block, provenance
from spherecal.correction.files.robots import load_robot
from spherecal.correction.files.samples_csv import read_samples
from spherecal.identification.prediction import Prediction, predict_accuracy

from ..parallel import executor
from .candidates import CandidateError, auto_grid, grid_candidates, read_candidates
from .guidance import Guidance, recording_guidance
from .guidance_report import guidance_json, write_guidance_recording
from .placements import read_placements
from .plan import Plan, plan
from .plan_report import write_recording

#: The box grid's syntax, for the refusals [m].
GRID = "'xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz'"


def refuse_foreign_outputs(outputs: dict[str, str | None]) -> None:
    """Refuse to replace an existing file a plan would write (``--out``, ``--analysis``, ``--rrd``) that an earlier
    ``spherecal plan`` did not write, as ``simulate`` and ``demo`` do (a review: a user's file at ``--out`` was
    overwritten). A report or analysis is the plan's by its provenance line; a recording by its ``tables/plan``
    panel.

    Raises:
        OutputError: one line naming the file and the option.
    """
    for option, path in outputs.items():
        if path is not None:
            refuse_unless_own([path], option, "spherecal plan", _plan_own)


def _plan_own(path: Path) -> bool:
    if path.suffix != ".rrd":
        return written_by(path, "spherecal plan")
    from spherecal.validation.viewer.recording import read_entity_rows  # rerun: only for an existing --rrd

    try:
        return "tables/plan" in read_entity_rows(path)
    except Exception:  # noqa: BLE001 - not a readable recording: not the plan's
        return False


def predict_files(robot: str, samples: str, fixtures: str | None, noise: float, **links) -> Prediction:
    """The accuracy a calibration from the data set ``samples`` (and its ``fixtures``) will reach.

    Args:
        robot: a robot file, a URDF or an embedded arm's name; ``links``: :func:`correction.load_robot`'s
            ``tip_link``, ``base_link``, ``inertials``, ``report``.
        samples, fixtures: samples.csv and fixtures.yaml (None: nothing known of the fixtures).
        noise: fixture noise std per axis [m].
    """
    model = load_robot(robot, **links)
    dataset = read_samples(samples, model)
    spec = read_fixtures(fixtures) if fixtures else None
    return predict_accuracy(model, dataset, spec, noise=noise)


def guide_files(robot: str, samples: str, fixtures: str | None, candidates: str | None, plate_grid: str | None,
                orientations: int, per_socket: int | None, min_gain: float, noise: float, seed: int,
                inputs: dict, out: str | None = None, rrd: str | None = None, outputs: OutputSet | None = None,
                grid: str | None = None, show: Callable[[Guidance], None] | None = None, **links) -> Guidance:
    """What to record next: rank the candidate placements given the recording so far, write the ranking.

    Args:
        robot, links: as :func:`predict_files`.
        samples, fixtures: the recording so far (samples.csv, fixtures.yaml or None).
        candidates: YAML of candidate placements (:func:`.placements.read_placements`), or None.
        plate_grid: the recorded plate centred over a box grid [m] or ``"auto"`` (:func:`.guidance.recording_guidance`).
        orientations: turns of the plate per grid point.
        per_socket: configurations per candidate socket (None: as recorded).
        min_gain: smallest gain worth another placement [m].
        noise: expected fixture noise [m].
        seed: seeds everything random.
        inputs: the options of the run as the provenance records them.
        out: plan.json to write (ranking best first, predicted error [m]), or None.
        rrd: Rerun recording to write, or None.
        outputs: the staged outputs holding ``out`` and ``rrd`` (checked by the caller); None: made here.
        grid: a box grid of single fixtures (the plan from scratch's): refused here, it names no plate.
        show: called with the guidance before the files are written.

    Raises:
        CandidateError: ``grid`` given, neither ``candidates`` nor ``plate_grid``, or nothing recordable.
    """
    model = load_robot(robot, **links)
    if grid is not None:
        raise CandidateError("field '--grid': places single fixtures for a plan from scratch; with --samples give "
                             "--plate-grid")
    if candidates is None and plate_grid is None:
        raise CandidateError(f"field '--candidates': with --samples give --candidates C.yaml or --plate-grid {GRID}")
    dataset = read_samples(samples, model)
    spec = read_fixtures(fixtures) if fixtures else None
    placements = read_placements(candidates) if candidates else []
    guidance = recording_guidance(model, dataset, spec, np.random.default_rng(seed), placements, plate_grid,
                                  orientations, per_socket, min_gain, noise)
    if show is not None:
        show(guidance)
    info = provenance(seed, inputs)
    outputs = OutputSet({"--out": out, "--rrd": rrd}) if outputs is None else outputs
    with outputs:  # staged: every output appears, or none
        if out:
            outputs.stage(out).write_text(json.dumps(guidance_json(guidance, info), indent=2) + "\n")
        if rrd:
            write_guidance_recording(outputs.stage(rrd), guidance, info)
    return guidance


def plan_files(robot: str, candidates: str | None, grid: str | None, fixture_count: int, seed: int, noise: float,
               per_fixture: int, motion: str, seconds: float, inputs: dict, workers: int = 2,
               scheduler: str | None = None, rrd: str | None = None, outputs: OutputSet | None = None,
               show: Callable[[Plan], None] | None = None, fixtures_out: str | None = None, **links) -> Plan:
    """A plan from scratch: survey the candidate fixture positions, choose ``fixture_count`` of them, record it.

    Args:
        robot, links: as :func:`predict_files`.
        candidates: YAML of candidate positions (:func:`.candidates.read_candidates`), or None.
        grid: box grid ``"xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz"`` of candidate positions [m], ``"auto"`` (over the
            arm's reach in front of its base, :func:`.candidates.auto_grid`), or None.
        fixture_count: fixtures wanted, 1..4.
        seed: seeds each candidate's survey (by its name) and the workspace.
        noise: fixture noise std per axis [m].
        per_fixture: samples to be recorded per fixture.
        motion: ``"kinematic"`` or ``"controller"`` self-motion at a candidate.
        seconds: controller self-motion per candidate [s].
        inputs: the options of the run as the provenance records them.
        workers, scheduler: where the surveys run (:func:`validation.parallel.executor`).
        rrd: Rerun recording of the candidates coloured by score, and the arm reaching the best one, to write, or
            None.
        outputs: the staged outputs holding ``rrd`` (checked by the caller); None: made here.
        show: called with the plan before a refusal or the recording.
        fixtures_out: fixtures.yaml of the chosen set to write (:func:`chosen_fixtures`), or None.

    Raises:
        CandidateError: neither ``candidates`` nor ``grid``, ``fixture_count`` outside 1..4, fewer reachable
            candidates than fixtures wanted (after ``show``).
    """
    model = load_robot(robot, **links)
    if candidates is None and grid is None:
        raise CandidateError(f"field '--candidates': give --candidates C.yaml or --grid {GRID} [m] (or --grid auto: "
                             "5 x 5 x 5 over the arm's reach in front of and above its base)")
    if candidates:
        found = read_candidates(candidates, model.n_joints)
    elif grid == "auto":  # its own generator: the surveys' seeds are the candidates' names, as for any grid
        found = auto_grid(model, np.random.default_rng([seed, 2]))
    else:
        found = grid_candidates(grid)
    if not 1 <= fixture_count <= 4:
        raise CandidateError(f"field '--fixture-count': expected an integer in 1..4, got {fixture_count}")
    with executor(workers, scheduler) as pool:  # each candidate's survey a task, seeded by its name
        result = plan(model, found, fixture_count, seed, noise, per_fixture, motion, seconds, executor=pool)
    if show is not None:
        show(result)
    if result.best is None:  # the table shown says which candidates failed; the refusal is one line
        reachable = sum(s.reachable for s in result.surveys)
        raise CandidateError(f"no plan: {reachable} of {len(result.surveys)} candidates reachable, fewer than the "
                             f"{fixture_count} fixtures wanted (--fixture-count)")
    if rrd or fixtures_out:
        outputs = OutputSet({"--rrd": rrd, "--fixtures-out": fixtures_out}) if outputs is None else outputs
        with outputs:  # staged, renamed into place once Rerun has written it all
            info = provenance(seed, inputs, workers=result.workers)
            if rrd:
                write_recording(outputs.stage(rrd), result, info, model)
            if fixtures_out:
                outputs.write_text(fixtures_out, chosen_fixtures(result, info))
    return result


def chosen_fixtures(result: Plan, info: dict) -> str:
    """fixtures.yaml text of the plan's chosen set: each fixture's position [m] (what ``simulate --fixtures`` takes as
    the true centres), and under ``plan:`` the distances worth measuring (their planned values [m]: measure them on
    the plate and give them under ``distances:``), the predicted error [m]; the provenance as the leading comment (by
    which a later plan knows the file for its own). Not a real recording's fixtures.yaml: calibrate takes a position
    for a measured centre."""
    best = result.best
    position = {s.candidate.name: s.candidate.position for s in result.surveys}
    measure = [[a, b, round(float(np.linalg.norm(position[a] - position[b])), 6)] for a, b in best.distances]
    predicted = {"mean": float(best.prediction.mean), "p95": float(best.prediction.p95)}
    spec = FixtureSpec(names=best.names, positions={name: position[name] for name in best.names},
                       extras={"plan": {"measure_distances": measure, "predicted_error_m": predicted}})
    return "".join(f"# {line}\n" for line in comment_block(info).splitlines()) + format_fixtures(spec)
