"""Sweeps: a plan of configurations x seeds, each trial an ordinary run, on Ray Tune; the results table."""
