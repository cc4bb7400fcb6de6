"""Tests of spherecal.identification."""
