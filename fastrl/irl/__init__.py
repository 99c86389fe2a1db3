"""Inverse RL on stable-baselines3: GAIL and AIRL discriminators, on-policy (PPO) and off-policy (SAC) loops."""

from importlib import import_module

_FROM = {
    "AdversarialCallback": ".adversarial",
    "Discriminator": ".discriminator",
    "DiscriminatorForm": ".discriminator",
    "DiscriminatorFit": ".fitting",
    "OffPolicyAdversarialCallback": ".offpolicy",
    "RelabelingReplayBuffer": ".offpolicy",
    "Transitions": ".fitting",
}
__all__ = sorted(_FROM)


def __getattr__(name: str):
    """Import the training side (stable-baselines3) on first use: loading exported networks needs only torch."""
    if name in _FROM:
        return getattr(import_module(_FROM[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
