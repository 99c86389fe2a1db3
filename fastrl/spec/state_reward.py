"""The spec's observation (the paper's state, named terms) and reward (w . phi(s) over named features) sections."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, model_validator

from ..terms import OBSERVATION_TERMS, REWARD_FEATURES
from .base import Strict, _raise
from .images import Image


class Observation(Strict):
    """The paper's state, with options; `extra` adds registered terms by name."""

    state: Literal["full", "camera_position"] = Field(
        "full",
        description="camera_position: the paper's liver-tour state, the camera position in R^3, then the `extra` terms "
        "(the liver spec adds the cue for its policy and keeps them from the reward with irl.discriminator.ignore)",
    )
    velocities: bool = True
    goal: bool = True
    egocentric: bool = False
    extra: list[str] = []
    stack: int = Field(1, ge=1, le=16)
    image: Image | None = Field(None, description="endoscope frames as the observation (none: the state alone)")

    @model_validator(mode="after")
    def _known(self):
        _raise(
            [
                (("extra", i), f"unknown observation term '{name}' (known: {', '.join(OBSERVATION_TERMS)})", name)
                for i, name in enumerate(self.extra)
                if name not in OBSERVATION_TERMS
            ]
        )
        return self

    def terms(self) -> list[str]:
        """Observation term names in order."""
        if self.state == "camera_position":
            return ["camera_position"] + [n for n in self.extra if n != "camera_position"]
        names = ["tip_pos", "tip_quat"]
        names += ["tip_vel", "tip_quat_rate"] if self.velocities else []
        names += ["target_pos", "target_quat"] if self.goal else []
        names += ["alignment"]
        if self.egocentric:
            names += ["target_in_camera", "horizon_error", "distance_error", "dwell", "portal", "subtask_fraction"]
        return names + [n for n in self.extra if n not in names]


class Feature(Strict):
    """One reward feature's weight and parameters."""

    weight: float
    params: dict[str, Any] = {}


class Reward(Strict):
    """r = w . phi(s) over registered features."""

    gamma: float = Field(0.99, gt=0, le=1, description="discount used by the shaping feature")
    features: dict[str, Feature] = Field(min_length=1)

    @model_validator(mode="after")
    def _known(self):
        errors = []
        for name, f in self.features.items():
            if name not in REWARD_FEATURES:
                known = ", ".join(REWARD_FEATURES)
                errors.append((("features", name), f"unknown reward feature '{name}' (known: {known})", name))
                continue
            for key, problem in REWARD_FEATURES[name].check_params(f.params):
                errors.append((("features", name, "params", key), problem, f.params[key]))
        _raise(errors)
        return self
