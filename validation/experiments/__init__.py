"""Simulated experiments: the shared steps, campaigns and the demo.
"""
