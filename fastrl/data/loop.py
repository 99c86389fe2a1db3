"""The one episode loop (a policy stepping the env, or recorded coordinates replayed in it) and its recorder.

Evaluation, demonstrations, replay and assessment all run their episodes through `episode_steps`."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np

from .episode import EpisodeRecord


def episode_steps(
    env,
    seed: int,
    *,
    policy: Callable | None = None,
    portal: np.ndarray | None = None,
    on_reset: Callable | None = None,
    instruments: np.ndarray | None = None,
    bodies: np.ndarray | None = None,
    read_past: bool = False,
) -> Iterator[tuple[np.ndarray, float, dict, object]]:
    """Yield (observation, reward, info, action) at the reset state (reward 0, action None) and after each step.

    With `policy` (observation -> action) the env steps until the episode terminates or is truncated; else the
    recorded `portal` coordinates are replayed (the first is the reset pose) until the task terminates or they end,
    with the `instruments`' coordinates and the loose `bodies`' poses beside them where recorded; `read_past`:
    measured poses, read with Task.read_past. `on_reset()` is called right after the reset."""
    u = env.unwrapped
    if policy is not None:
        obs, info = env.reset(seed=seed)
    else:
        options = {"portal": portal[0], "read_past": read_past}
        if instruments is not None:
            options["instruments"] = instruments[0]
        if bodies is not None:
            options["bodies"] = bodies[0]
        obs, info = u.reset(seed=seed, options=options)
    if on_reset is not None:
        on_reset()
    yield obs, 0.0, info, None
    if policy is not None:
        done = False
        while not done:
            action = policy(obs)
            obs, reward, term, trunc, info = env.step(action)
            yield obs, reward, info, action
            done = term or trunc
        return
    for i, q in enumerate(portal[1:], 1):
        tools = None if instruments is None else instruments[i]
        obs, reward, term, _, info = u.replay_step(q, tools, None if bodies is None else bodies[i])
        yield obs, reward, info, None
        if term:
            break


class EpisodeRecorder:
    """Poses, rewards, features, cues and every k-th image of an episode's states, made into an EpisodeRecord."""

    def __init__(self, env, *, image_every: int = 0, image: Callable | None = None):
        self.u = env.unwrapped
        self.shaft = self.u.model.body("scope_shaft").id
        self.length = self.u.task_spec.scope.shaft_length
        self.image_every, self.image = image_every, image
        self.rows: list[tuple] = []
        self.tools: list[np.ndarray] = []
        self.tool_ends = [(t.tip_body, t.spec.shaft_length) for t in self.u.task.instruments]
        self.bodies: list[np.ndarray] = []
        self.images: dict[int, np.ndarray] = {}
        self.frames: dict[int, np.ndarray] = {}  # what a pixel policy saw, at the same steps as the images

    def snapshot(self, reward: float, info: dict) -> int:
        """Keep the env's current state; return its step index."""
        u, s = self.u, self.u.state
        axis = u.data.xmat[self.shaft].reshape(3, 3)[:, 2]
        self.rows.append(
            (
                s.time,
                s.portal,
                s.tip_pos,
                s.tip_quat,
                u.data.xpos[self.shaft] - self.length * axis,
                reward,
                list(info["features"].values()),
                info["subtask"],
                info["cue"]["green"],
                info["contacts"],
            )
        )
        if self.tool_ends:
            d = u.data
            self.tools.append(
                np.array([[d.xpos[b], d.xpos[b] - n * d.xmat[b].reshape(3, 3)[:, 2]] for b, n in self.tool_ends])
            )
        if u.loose is not None:
            self.bodies.append(u.data.xpos[u.loose.bodies].copy())
        step = len(self.rows) - 1
        if self.image_every and step % self.image_every == 0:
            self.images[step] = self.image(u)
            if getattr(u, "frames", None) is not None:
                self.frames[step] = policy_strip(u.frames.frames, u.task_spec.observation.image.channels)
        return step

    def record(self, seed: int, actions: np.ndarray | None, info: dict) -> EpisodeRecord:
        """The kept states as an EpisodeRecord (`info`: the last step's)."""
        cols = list(zip(*self.rows))
        names = self.u.feature_names
        feats = np.array(cols[6], float).reshape(len(self.rows), len(names))
        return EpisodeRecord(
            seed=seed,
            time=np.array(cols[0]),
            portal=np.array(cols[1]),
            tip_pos=np.array(cols[2]),
            tip_quat=np.array(cols[3]),
            shaft_end=np.array(cols[4]),
            reward=np.array(cols[5]),
            features={n: feats[:, i] for i, n in enumerate(names)},
            subtask=np.array(cols[7]),
            green=np.array(cols[8], bool),
            contacts=np.array(cols[9]),
            actions=actions,
            images=self.images,
            frames=self.frames,
            subtasks_total=info["subtasks_total"],
            success=bool(info["success"]),
            tools=np.array(self.tools) if self.tools else None,
            bodies=np.array(self.bodies) if self.bodies else None,
        )


def policy_strip(stack: np.ndarray, channels: int) -> np.ndarray:
    """A frame stack (H, W, C * k) as its k frames side by side, oldest first: (H, k * W, C), or (H, k * W) grey."""
    h, w, total = stack.shape
    k = total // channels
    strip = stack.reshape(h, w, k, channels).transpose(0, 2, 1, 3).reshape(h, k * w, channels)
    return strip[:, :, 0].copy() if channels == 1 else strip
