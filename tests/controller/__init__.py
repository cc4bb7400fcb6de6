"""Tests of spherecal.controller."""
