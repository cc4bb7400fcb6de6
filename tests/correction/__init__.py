"""Tests of spherecal.correction."""
