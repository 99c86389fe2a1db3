"""Teleoperation: a person drives the scope in the MuJoCo viewer; attempts are recorded as trajectories."""
