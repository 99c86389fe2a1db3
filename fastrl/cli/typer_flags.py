"""typer's --help without a type beside flags: typer 0.29 prints `<bool>` as if a flag took a value."""

import typer.core

_value_type = getattr(typer.core.TyperOption, "display_type_rich", None)


def _flag_has_no_value(self, ctx):
    """Type column of --help: none for flags (--json, --progress/--no-progress, --help take no value)."""
    return None if self.is_flag else _value_type(self, ctx)


# this covers the commands of every module and typer's own --help
if _value_type is not None:  # a typer without it prints no type column to fix
    typer.core.TyperOption.display_type_rich = _flag_has_no_value
