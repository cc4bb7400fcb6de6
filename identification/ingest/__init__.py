"""Recordings in: MUKCa folders, joint CSV files and ROS bags, segmented into fixtures.
"""
