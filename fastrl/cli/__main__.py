"""`python -m fastrl.cli`."""

from . import app

app()
