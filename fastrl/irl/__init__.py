"""Inverse RL on stable-baselines3: GAIL and AIRL discriminators and the on-policy adversarial loop."""

from .adversarial import AdversarialCallback, Transitions
from .discriminator import Discriminator

__all__ = ["AdversarialCallback", "Discriminator", "Transitions"]
