"""Identification: spherical-joint samples in, calibrated robot parameters out."""
