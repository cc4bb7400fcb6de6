"""File formats and safe I/O: robot files (YAML), URDF read/convert/write, samples and fixtures
files, bounded readers, staged outputs.

No model maths here: the model lives in :mod:`spherecal.correction`.
"""
