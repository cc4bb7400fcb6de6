"""spherecal: kinematic calibration of a serial arm from spherical-joint self-motion.

Subpackages (imported as ``spherecal.<name>``; in the source tree they are the folders at the
repository root, mapped into this package by ``pyproject.toml``):

* :mod:`spherecal.correction`: the kinematic model, parameter layout, robot and data files (the base
  layer; imports nothing else of spherecal).
* :mod:`spherecal.identification`: samples in, calibrated parameters out.
* :mod:`spherecal.controller`: MuJoCo plant, QP differential IK, null-space self-motion, compensation.
* :mod:`spherecal.validation`: simulated motion capture, comparisons, campaigns, Rerun, planning.
* :mod:`spherecal.cli`: the ``spherecal`` command line (library code never imports it).
"""

from __future__ import annotations

import os as _os

# Installed (``pip install .``) the subpackages are copied into this folder. In a source checkout
# whose root is on ``sys.path`` (``python -m pytest`` or ``python -c`` run there) this folder is found
# before the editable install's mapping and holds only this file and the CLI: the subpackages are then
# its siblings, so the repository root joins the package path. Nothing changes for an installed copy.
_HERE = _os.path.dirname(_os.path.abspath(__file__))
if not _os.path.isdir(_os.path.join(_HERE, "correction")):
    __path__.append(_os.path.dirname(_HERE))  # type: ignore[name-defined]  # noqa: F821
