"""Inverse RL on stable-baselines3: GAIL and AIRL discriminators, on-policy (PPO) and off-policy (SAC) loops."""

from .adversarial import AdversarialCallback
from .discriminator import Discriminator
from .fitting import DiscriminatorFit, Transitions
from .offpolicy import OffPolicyAdversarialCallback, RelabelingReplayBuffer

__all__ = [
    "AdversarialCallback",
    "Discriminator",
    "DiscriminatorFit",
    "OffPolicyAdversarialCallback",
    "RelabelingReplayBuffer",
    "Transitions",
]
