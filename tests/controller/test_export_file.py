"""controller.export_file: `spherecal export` as one library call (check, load, build, write)."""

import numpy as np
import pytest

from spherecal.controller.export_file import ExportConfig, export_file
from spherecal.correction import load_robot, perturb, save_robot, tool_point
from spherecal.correction.files.outputs import OutputError, OutputSet
from spherecal.correction.files.urdf_write import ExportError


@pytest.fixture
def calibrated(tmp_path, panda):
    path = tmp_path / "cal.yaml"
    save_robot(perturb(panda, np.random.default_rng(6)), path)
    return str(path)


@pytest.mark.parametrize("output_format, name", [("yaml", "out.yaml"), ("urdf", "out.urdf")])
def test_the_written_file_loads_as_the_same_arm(calibrated, tmp_path, panda, output_format, name):
    out = tmp_path / name
    result = export_file(ExportConfig(robot=calibrated, output_format=output_format, out=str(out)),
                         OutputSet({"--out": str(out)}))
    assert result.path == out and result.model.name == "franka_panda"
    # the exported file, read back by the robot loader (URDF: through its own converter), puts the tool
    # point where the calibrated model does (a rigid model: the URDF carries it exactly)
    q = panda.random_configurations(20, np.random.default_rng(1))
    back = load_robot(str(out))
    assert np.abs(tool_point(back, q) - tool_point(load_robot(calibrated), q)).max() < 1e-9


@pytest.mark.parametrize("config, error, message", [
    ({"output_format": "urdf", "out": "x.yaml"}, OutputError, "would be read as YAML"),
    ({"output_format": "urdf", "out": "x.urdf", "effort": "1,x"}, ExportError, "field '--effort': expected"),
    ({"output_format": "yaml", "out": "x.yaml", "velocity": "1,2,3,4,5,6,7"}, ExportError, "only the urdf format"),
])
def test_refusals_write_nothing(calibrated, tmp_path, monkeypatch, config, error, message):
    monkeypatch.chdir(tmp_path)
    before = sorted(tmp_path.iterdir())
    with pytest.raises(error, match=message):
        export_file(ExportConfig(robot=calibrated, **config), OutputSet({"--out": config["out"]}))
    assert sorted(tmp_path.iterdir()) == before
