"""A uniform sample of every earlier policy transition, so the discriminator keeps rating old mistakes low."""

from __future__ import annotations

import numpy as np

from .fitting import Transitions


class PolicyHistory:
    """Reservoir sampling over all transitions added: each one seen is kept with probability capacity / seen."""

    def __init__(self, capacity: int, seed: int = 0):
        self.capacity, self.seen = capacity, 0
        self.rng = np.random.default_rng(seed)
        self.data: Transitions | None = None
        self.size = 0

    def __len__(self) -> int:
        return self.size

    def add(self, new: Transitions) -> None:
        """Offer every row of `new` to the reservoir."""
        n = len(new)
        if self.data is None:
            self.data = Transitions(
                *(
                    np.zeros((self.capacity, *x.shape[1:]), x.dtype)
                    for x in (new.obs, new.next_obs, new.terminal, new.actions)
                )
            )
        free = min(n, self.capacity - self.size)
        slots = np.arange(self.size, self.size + free)
        seen_at = self.seen + np.arange(free + 1, n + 1)  # how many rows had been offered when each later row came
        draw = (self.rng.random(n - free) * seen_at).astype(np.int64)
        keep = draw < self.capacity
        rows = np.concatenate([np.arange(free), free + np.flatnonzero(keep)])
        slots = np.concatenate([slots, draw[keep]])
        for mine, theirs in zip(
            (self.data.obs, self.data.next_obs, self.data.terminal, self.data.actions),
            (new.obs, new.next_obs, new.terminal, new.actions),
        ):
            mine[slots] = theirs[rows]  # a slot drawn twice keeps the later row, as sequential sampling would
        self.size += free
        self.seen += n

    def sample(self, k: int) -> Transitions:
        """k rows drawn uniformly with replacement."""
        if not self.size:
            raise ValueError("the history is empty")
        return self.data.take(self.rng.integers(0, self.size, k))
