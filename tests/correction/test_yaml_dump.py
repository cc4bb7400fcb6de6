"""Robot and fixtures files are written through libyaml's emitter: the same text as PyYAML's own."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import yaml

from spherecal.correction import load_robot, perturb
from spherecal.correction.files.robot_file import dump_robot, robot_to_dict
from spherecal.correction.files.yaml_safe import dump_yaml

AWKWARD = {
    "name": "arm: x", "lines": "line1\nline2", "unicode": "Zlajpah \u017e \u00e9", "quotes": "it's \"q\"",
    "lead": " space", "empty": "", "hash": "a #b", "number": "1.5", "yes": "yes", "none": None,
    "nan": float("nan"), "inf": float("-inf"), "tiny": 5e-324, "long": "x" * 1500, "tab": "a\tb",
    "nested": {"a": [1, 2.5, [3, {"b": "c"}]], "e": [], "f": {}}, "dash": "- a", "star": "*a", "true": True,
}


def test_dump_yaml_writes_what_pyyaml_s_own_emitter_writes() -> None:
    for flow in (None, False):
        options = {"sort_keys": False, "default_flow_style": flow, "width": 1000}
        assert dump_yaml(AWKWARD, **options) == yaml.safe_dump(AWKWARD, **options)
    arm = perturb(load_robot("panda"), np.random.default_rng(0))
    block = {"covariance": np.random.default_rng(1).normal(size=(20, 20)).tolist(), **AWKWARD}
    arm = replace(arm, extras={**arm.extras, "calibration": block})  # a copy: load_robot's model is shared
    reference = yaml.safe_dump(robot_to_dict(arm), sort_keys=False, default_flow_style=None, width=1000)
    assert dump_robot(arm).endswith(reference)
    assert yaml.safe_load(dump_robot(arm))["calibration"]["covariance"] == arm.extras["calibration"]["covariance"]
