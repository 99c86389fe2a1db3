"""The spec's endoscope-image observation: frame size, kind, stacked frames, and the state beside them or not."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from .base import Strict

DEPTH_MM_PER_LEVEL = 1.0  # depth frames: one uint8 level per millimetre from the lens, 255 = 255 mm or farther
SEGMENTATION_CLASSES = (  # segmentation frames: class k is the level k * SEGMENTATION_STEP
    "nothing",
    "plate",
    "shell",
    "line",
    "active avatar",
    "active avatar's up mark",
    "other avatar",
    "instrument",
)
SEGMENTATION_STEP = 32


class Looks(Strict):
    """Randomised looks, drawn per episode: so a pixel policy survives a dome that looks different."""

    colour: float = Field(
        0.0, ge=0, le=1, description="each RGB channel of plate, shell and line moves by up to this (0: as compiled)"
    )
    light: float = Field(0.0, ge=0, lt=1, description="headlight and scope light scaled by 1 +- up to this")
    noise: float = Field(0.0, ge=0, le=64, description="standard deviation of Gaussian pixel noise, in levels")
    blur: float = Field(0.0, ge=0, le=1, description="share of episodes whose frames are blurred (3 x 3 box)")


class Image(Strict):
    """Endoscope frames as the observation: uint8 height x width x channels, rendered where the env steps."""

    size: int = Field(48, ge=32, le=128, description="width and height of the frames in pixels")
    kind: Literal["rgb", "depth", "segmentation"] = Field(
        "rgb",
        description="rgb: 3 channels; depth: 1 channel, 1 level per mm from the lens (255: 255 mm or farther); "
        "segmentation: 1 channel, class k at level 32 k (0 nothing, 1 plate, 2 shell, 3 line, 4 active avatar, "
        "5 its up mark, 6 other avatars, 7 instruments)",
    )
    stack: int = Field(1, ge=1, le=8, description="the last frames stacked along the channels, newest last")
    looks: Looks | None = Field(None, description="randomised colours, lighting, noise and blur (none: as compiled)")
    state: bool = Field(
        False,
        description="true: a Dict of `image` and the kinematic `state` (the terms above, not normalised); "
        "false: the image alone",
    )

    @property
    def channels(self) -> int:
        """Channels of one frame."""
        return 3 if self.kind == "rgb" else 1
