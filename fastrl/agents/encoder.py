"""A small CNN for endoscope frames, with DrQ's random shift while training, and the state beside it."""

from __future__ import annotations

import torch
from gymnasium import spaces
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn
from torch.nn import functional as F


def random_shift(x: torch.Tensor, pad: int) -> torch.Tensor:
    """Each image moved by a random whole number of pixels up to `pad` each way, edges repeated (DrQ)."""
    n, _, h, w = x.shape
    padded = F.pad(x, (pad, pad, pad, pad), mode="replicate")
    offsets = torch.randint(0, 2 * pad + 1, (n, 2)).tolist()  # slices: 2x faster than one gather on a CPU
    return torch.stack([padded[i, :, dy : dy + h, dx : dx + w] for i, (dy, dx) in enumerate(offsets)])


def conv_stack(channels: int) -> nn.Sequential:
    """A 5x5 stride-3 and a 3x3 stride-2 convolution, 32 filters each: a 48 px frame becomes 32 x 8 x 8.

    On one CPU thread its forward and backward cost a third of three stride-2 3x3 layers' (bench/pixel_throughput.py).
    """
    return nn.Sequential(
        nn.Conv2d(channels, 32, 5, stride=3, padding=1),
        nn.ReLU(),
        nn.Conv2d(32, 32, 3, stride=2, padding=1),
        nn.ReLU(),
        nn.Flatten(),
    )


class PixelEncoder(BaseFeaturesExtractor):
    """Frames (channels first, scaled to [0, 1] by SB3) through a small CNN; a Dict's state is appended as is."""

    def __init__(self, observation_space: spaces.Space, *, features: int = 64, shift: int = 4):
        image = observation_space["image"] if isinstance(observation_space, spaces.Dict) else observation_space
        state = observation_space["state"].shape[0] if isinstance(observation_space, spaces.Dict) else 0
        c, h, w = image.shape
        convs = conv_stack(c)
        with torch.no_grad():
            flat = convs(torch.zeros(1, c, h, w)).shape[1]
        super().__init__(observation_space, features + state)
        self.cnn = nn.Sequential(convs, nn.Linear(flat, features), nn.LayerNorm(features), nn.Tanh())
        self.shift, self.dict = shift, isinstance(observation_space, spaces.Dict)

    def forward(self, obs) -> torch.Tensor:
        """Features of a batch; frames are shifted at random only in training mode (SB3's gradient steps)."""
        x = obs["image"] if self.dict else obs
        if self.training and self.shift:
            x = random_shift(x, self.shift)
        z = self.cnn(x)
        return torch.cat([z, obs["state"].flatten(1)], dim=1) if self.dict else z
