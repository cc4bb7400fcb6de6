"""Validation: simulated motion capture, nominal vs calibrated comparison, Rerun, demo."""
