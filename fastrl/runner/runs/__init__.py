"""Run folders: naming, resolved spec, metadata, checkpoints; reading them; loading what a run saved; stops."""
