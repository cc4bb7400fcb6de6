"""Experiment planning: candidate fixtures, their ranking, and predicted against measured accuracy.
"""
