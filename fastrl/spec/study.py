"""The study section: the paper's laparoscopic study (Table 3), run by `fastrl run` instead of one training."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from .base import Strict


class Study(Strict):
    """Cohort of graded procedures -> inverse RL on the best by the heuristic -> learned scores vs ground truth."""

    enabled: bool = Field(False, description="`fastrl run` runs this study instead of one training")
    levels: int = Field(5, ge=2, le=20, description="skill levels of the synthetic cohort")
    per_level: int = Field(20, ge=1, le=1000, description="procedures per level")
    seed: int = Field(0, ge=0, description="seed of the first procedure")
    best: int = Field(10, ge=1, description="procedures rated best by the heuristic score: the demonstrations")
    algorithms: list[Literal["gail", "airl"]] = Field(["gail", "airl"], min_length=1)
    timesteps: int = Field(300_000, ge=1, description="generator steps of each inverse-RL training")

    @model_validator(mode="after")
    def _enough(self):
        if self.best > self.levels * self.per_level:
            raise ValueError(f"best ({self.best}) is more than the cohort ({self.levels * self.per_level})")
        return self
