"""Tests of spherecal.validation."""
