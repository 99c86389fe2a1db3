"""Expert transitions for a discriminator: demonstrations replayed in the compiled task."""

from __future__ import annotations

import numpy as np

from ..data.replay import replay_demonstrations
from ..data.trajectory import Trajectory
from .fitting import Transitions


def expert_transitions(env, trajectories: list[Trajectory]) -> Transitions:
    """Transitions (s, s', terminal, a) of demonstrations for a discriminator, recomputed by replay."""
    obs, nxt, term, acts = [], [], [], []
    for o, success, actions in replay_demonstrations(env, trajectories):
        obs.append(o[:-1])
        nxt.append(o[1:])
        t = np.zeros(len(actions), np.float32)
        t[-1] = 1.0 if success else 0.0
        term.append(t)
        acts.append(actions)
    return Transitions(np.concatenate(obs), np.concatenate(nxt), np.concatenate(term), np.concatenate(acts))
