"""Scoring (`fastrl score`): files scored with a run's networks, a forked helper or Ray, videos as inputs."""
