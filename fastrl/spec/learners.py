"""What differs between the forward-RL learners (PPO, SAC), decided once from `train.algo`."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class LearnerKind:
    """One learner's traits: the rest of fastrl asks these instead of testing the algorithm's name."""

    name: str  # the stable-baselines3 class, and the train section of its hyperparameters (lower case)
    off_policy: bool  # a replay buffer (the discriminator is trained on its latest samples)
    discrete: bool  # can act in a discrete action space
    critic: str  # the critic's key in SB3's policy_kwargs net_arch
    normalize_reward: bool  # default of train.normalize.reward
    policy_term: bool  # default of irl.discriminator.policy_term (AIRL's logit keeps -log pi)


LEARNERS = {
    "PPO": LearnerKind("PPO", off_policy=False, discrete=True, critic="vf", normalize_reward=True, policy_term=True),
    # SAC: a moving reward scale fights its entropy temperature; its squashed Gaussian gives the expert's saturated
    # actions a log pi of hundreds, which would decide AIRL's discriminator on its own.
    "SAC": LearnerKind("SAC", off_policy=True, discrete=False, critic="qf", normalize_reward=False, policy_term=False),
}
