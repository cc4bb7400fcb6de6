"""validation.experiments.simulation: `spherecal simulate` as one library call."""

import numpy as np
import pytest

from spherecal.correction import load_robot, tool_point
from spherecal.correction.files.fixtures import read_fixtures
from spherecal.correction.files.samples_csv import read_samples
from spherecal.validation.experiments.experiment import ExperimentError, joint_stiffness
from spherecal.validation.experiments.simulation import SimulationConfig, simulate_to_folder


def test_library_call_writes_a_simulation_the_truth_explains(tmp_path):
    config = SimulationConfig(out=tmp_path, seed=4, seconds=0.3, samples=20, noise=0.0, known_distances=True)
    result = simulate_to_folder(config)
    assert [p.name for p in result.files] == ["samples.csv", "fixtures.yaml", "truth.yaml"]
    truth = load_robot(str(tmp_path / "truth.yaml"))
    data = read_samples(tmp_path / "samples.csv", truth)
    spec = read_fixtures(tmp_path / "fixtures.yaml")
    centres = truth.extras["simulation"]["fixtures"]
    assert len(data.q) == 20 * len(centres) and len(spec.distances) == 3
    # the true robot puts every sample on its fixture's recorded centre (noise 0: the controller's tracking only)
    for name in data.fixture_names:
        assert np.abs(tool_point(truth, data.for_fixture(name)) - centres[name]).max() < 1e-3
    for a, b, distance in spec.distances:  # the written distances are those of the recorded centres
        assert distance == pytest.approx(np.linalg.norm(np.subtract(centres[a], centres[b])), abs=1e-15)


def test_joint_stiffness():
    assert joint_stiffness(None, 7) is None and joint_stiffness("3e4", 3) == [3e4] * 3
    assert joint_stiffness("0,1,2", 3) == [0.0, 1.0, 2.0]
    for bad in ("1,2", "-5", "x", "nan"):
        with pytest.raises(ExperimentError, match="--stiffness"):
            joint_stiffness(bad, 3)


def test_an_elastic_robot_file_simulates_again(tmp_path):
    # a simulation's elastic truth.yaml given as the robot: its controller crashed (the MuJoCo plant of an elastic
    # model has a motor and a link hinge per joint, 14 columns of Jacobian for 7 joints); the controller commands
    # the rigid chain, and the true arm the samples come from is elastic, as the truth file records
    first = simulate_to_folder(SimulationConfig(out=tmp_path / "a", seed=1, seconds=0.3, samples=20, noise=0.0,
                                                stiffness="3e4"))
    assert first.files
    elastic = load_robot(str(tmp_path / "a" / "truth.yaml"))
    assert np.any(elastic.extras["compliance"])
    simulate_to_folder(SimulationConfig(out=tmp_path / "b", seed=2, seconds=0.3, samples=20, noise=0.0,
                                        robot=str(tmp_path / "a" / "truth.yaml")))
    truth = load_robot(str(tmp_path / "b" / "truth.yaml"))
    assert np.any(truth.extras["compliance"])
    data = read_samples(tmp_path / "b" / "samples.csv", truth)
    centres = truth.extras["simulation"]["fixtures"]
    for name in data.fixture_names:  # the elastic truth puts every sample on its fixture
        assert np.abs(tool_point(truth, data.for_fixture(name)) - centres[name]).max() < 1e-3
