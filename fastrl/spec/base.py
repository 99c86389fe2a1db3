"""Building blocks of the spec models: the strict base model, positive types, errors at their locations."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError
from pydantic_core import InitErrorDetails, PydanticCustomError


def _raise(errors: list[tuple[tuple, str, Any]]) -> None:
    """Raise one ValidationError carrying every (loc, message, input) with its own location."""
    if errors:
        raise ValidationError.from_exception_data(
            "TaskSpec",
            [
                InitErrorDetails(type=PydanticCustomError("spec", msg), loc=loc, input=value)
                for loc, msg, value in errors
            ],
        )


def _fail(dotted: str, msg: str) -> None:
    """Raise a ValidationError at a dotted location."""
    loc = tuple(int(k) if k.isdigit() else k for k in dotted.split("."))
    _raise([(loc, msg, None)])


Pos = Annotated[float, Field(gt=0)]
NonNeg = Annotated[float, Field(ge=0)]


class Strict(BaseModel):
    """Base: frozen, unknown keys are errors."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)
