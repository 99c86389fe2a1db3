"""What a run trains: forward RL on the spec's reward, or GAIL / AIRL / behavioural cloning from demonstrations."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, partial
from math import isnan, nan
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.markup import escape
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecEnv, VecNormalize

from ...agents.anchor import CloneAnchor
from ...agents.bc import action_accuracy, behaviour_clone
from ...agents.sb3 import build_model, make_vec_env
from ...assess.motion import MotionModel, motion_columns, step_motion, transition_motion
from ...data.inverse import to_control_rate
from ...data.recordings import load_recordings, with_actions
from ...data.replay import demonstration_pairs, replay_arrays
from ...data.trajectory import Trajectory
from ...env.fast_env import FastEnv
from ...irl import (
    AdversarialCallback,
    Discriminator,
    DiscriminatorForm,
    OffPolicyAdversarialCallback,
    RelabelingReplayBuffer,
)
from ...irl.averaging import RewardAveraging
from ...irl.demonstrations import expert_transitions
from ...irl.fitting import DiscriminatorFit, Transitions
from ...irl.ranking import RankedRollouts
from ...model.scope import joint_ranges
from ...spec.columns import discriminator_inputs, reward_inputs
from ...spec.models import TaskSpec
from ..runs.rundir import update_meta
from .cloned import cloned_actor
from .demos import write_demos


@dataclass
class Learner:
    """A model on its vectorised env, the callbacks it learns with (an adversarial one first), and their state."""

    spec: TaskSpec
    venv: VecEnv
    model: BaseAlgorithm
    callbacks: list[BaseCallback] = field(default_factory=list)
    disc: Discriminator | None = None
    demos: list[Trajectory] = field(default_factory=list)
    averaging: RewardAveraging | None = None
    console: Console | None = None
    motion: MotionModel | None = None  # the demonstrations' motion density (tasks observing camera velocities)

    @property
    def learned_motion(self) -> MotionModel | None:
        """The motion density, weighed in the learned reward by irl.discriminator.motion in units of the generator's
        reward spread over its last rollout, and in the learned value in the units its critic learned (unweighed where
        the spec does not ask or the run has no PPO generator)."""
        cb, weight = self.adversarial, self.spec.irl.discriminator.motion
        if self.motion is None or not weight or not isinstance(cb, AdversarialCallback):
            return self.motion
        reward_weight = weight * cb.motion_scale()
        return self.motion.weighing(reward_weight, reward_weight * cb.value_units())

    @property
    def adversarial(self) -> BaseCallback | None:
        """The callback that fits the discriminator (the first), None without one."""
        return self.callbacks[0] if self.disc is not None else None

    @property
    def parts(self) -> dict:
        """Extra state saved in checkpoints: the discriminator and its optimizer, the reward's snapshots."""
        parts = {"discriminator": self.adversarial.fit} if self.adversarial else {}
        return parts | ({"reward_average": self.averaging} if self.averaging is not None else {})

    @property
    def snapshots(self) -> list | None:
        """Shaped AIRL's r_psi and h copied during training, to save as an averaged reward; None: no averaging."""
        return None if self.averaging is None else self.averaging.snapshots

    @property
    def demonstrated(self) -> Transitions | None:
        """The demonstrations' transitions the discriminator learns from; None without one."""
        return self.adversarial.expert if self.adversarial else None

    def stats(self) -> dict[str, float]:
        """The latest discriminator statistics, for the training curves."""
        return dict(self.adversarial.stats) if self.adversarial else {}

    def learn(self, timesteps: int, monitor: BaseCallback) -> None:
        """Train for `timesteps` more steps (behavioural cloning: fit the demonstrations once; a cloned generator
        is fitted to them before its first step)."""
        if self.model.num_timesteps == 0 and (self.spec.irl.algorithm == "bc" or self.spec.cloned_generator):
            accuracy = self.clone()
            if self.spec.cloned_generator and self.console is not None:
                matched = "" if isnan(accuracy) else f", action accuracy {accuracy:.2f}"
                self.console.print(f"generator: cloned from {len(self.demos)} demonstrations{matched}")
        if self.spec.irl.algorithm == "bc":
            return
        self.model.learn(timesteps, callback=[*self.callbacks, monitor], reset_num_timesteps=False)

    @cached_property
    def pairs(self) -> tuple:
        """The demonstrations' (observations, actions), replayed once for the clone and the anchor."""
        return demonstration_pairs(FastEnv(self.spec), self.demos)

    def clone(self) -> float:
        """Fit the policy to the demonstrated actions (irl.bc's settings); return its action accuracy on them."""
        bc = self.spec.irl.bc
        obs, actions = self.pairs
        behaviour_clone(
            self.model, self.venv, obs, actions, bc.epochs, bc.batch_size, bc.learning_rate, self.spec.train.seed
        )
        return action_accuracy(self.model, self.venv, obs, actions) if self.model.action_space.shape == () else nan


def demonstrations(spec: TaskSpec, run: Path, console: Console, progress: bool) -> list[Trajectory]:
    """The spec's demonstrations: its directory of trajectories, or scripted-expert ones written into the run."""
    cfg = spec.irl.demonstrations
    if cfg.path is not None:
        folder = Path(cfg.path)
        if not folder.exists():
            raise FileNotFoundError(f"irl.demonstrations.path: {folder} does not exist")
    else:
        folder = run / "demos"
        if len(list(folder.glob("*.npz"))) < cfg.expert:
            write_demos(folder, cfg.expert, cfg.seed, expert_spec=spec, progress=progress)
    named, errors = load_recordings([folder], joint_ranges(spec.scope))
    prepared = with_actions(FastEnv(spec), [(str(f), t) for f, t in named])
    for message in errors + prepared.errors:
        console.print(f"[yellow]skipped[/yellow] {escape(message)}", highlight=False)
    for note in prepared.notes(spec.actions.mode):
        console.print(note, markup=False, highlight=False)
    if not prepared.trajectories:
        raise FileNotFoundError(f"no usable demonstrations in {folder}")
    return prepared.trajectories


def recorded_states(spec: TaskSpec) -> tuple:
    """(seed, portal) of the recordings the generator's training episodes may start in (`recorded_starts`): the
    demonstrations' folder and the cohort's others; () where it does not ask."""
    if not spec.generator_recorded_starts:
        return ()
    cfg = spec.irl.demonstrations
    folders = [Path(f) for f in (cfg.path, cfg.others) if f is not None]
    if not folders:  # reported as a missing file, in one line, before any training
        raise FileNotFoundError(
            "irl.generator.recorded_starts: no recordings to start from: set irl.demonstrations.path "
            "(fastrl assess and a study set it)"
        )
    named, _ = load_recordings(folders, joint_ranges(spec.scope))
    hz = spec.episode.control_hz
    return tuple((t.seed, to_control_rate(t, hz).portal) for _, t in named)


def log_generator(spec: TaskSpec, run: Path, console: Console) -> None:
    """Print the PPO generator's (or BC's) envs and hyperparameters and where they come from; keep them in meta.json."""
    train = spec.learning()
    gen = spec.irl.generator
    source = "irl.generator" if gen is not None and (gen.n_envs, gen.ppo) != (None, None) else "train"
    ppo = train.ppo.model_dump()
    who = "BC into" if spec.irl.algorithm == "bc" else "generator:"
    console.print(
        f"{who} PPO on {train.n_envs} envs ({source}): " + ", ".join(f"{k} {v}" for k, v in ppo.items()),
        markup=False,
        highlight=False,
    )
    cloned = spec.cloned_generator
    anchor = gen.anchor if cloned else 0
    if cloned:
        held = f", held near them by {anchor} cloning steps after each update (irl.generator.anchor)" if anchor else ""
        console.print(f"generator: starts from the demonstrations' behavioural clone (irl.generator.cloned){held}")
    late = spec.generator_late_starts
    if late:
        console.print(
            f"generator: episodes after the first start up to {late:.0%} of the time limit late "
            "(irl.generator.late_starts)"
        )
    meta = {
        "source": source,
        "n_envs": train.n_envs,
        "ppo": ppo,
        "cloned": cloned,
        "anchor": anchor,
        "late_starts": late,
        "recorded_starts": spec.generator_recorded_starts,
    }
    update_meta(run, generator=meta)


def below_best(model: MotionModel, columns, obs: np.ndarray, next_obs: np.ndarray) -> np.ndarray:
    """Each transition's motion log-density below the best of the demonstrations' (raw observations)."""
    return model.log_density(transition_motion(obs, next_obs, columns)) - model.ceiling


def motion_density(spec: TaskSpec, env: FastEnv, demos: list[Trajectory]) -> MotionModel | None:
    """The density of the demonstrations' motion as scoring replays their poses (fastrl.assess.motion), their own
    steps only; None where the task observes no camera velocities."""
    columns = motion_columns(spec)
    if columns is None:
        return None
    hz = spec.episode.control_hz
    replays = [(replay_arrays(env, t).observations, len(t.time)) for t in (to_control_rate(d, hz) for d in demos)]
    return MotionModel.fit([step_motion(obs, columns)[:own] for obs, own in replays])


def build_learner(spec: TaskSpec, run: Path, console: Console, progress: bool = True) -> Learner:
    """The model (and, learning from demonstrations, the discriminator and its callback) for a run."""
    train = spec.learning()
    venv = make_vec_env(
        spec,
        train.n_envs,
        train.seed,
        train.workers,
        spec.generator_late_starts,
        spec.training_later_subtasks,
        recorded=recorded_states(spec),
        recorded_starts=spec.generator_recorded_starts,
    )
    irl = spec.irl
    if irl.algorithm in ("none", "bc"):
        learner = Learner(spec, venv, build_model(spec, venv))
        if irl.algorithm == "bc":
            log_generator(spec, run, console)
            learner.demos = demonstrations(spec, run, console, progress)
        return learner
    off_policy = spec.train.kind.off_policy
    if not off_policy:
        log_generator(spec, run, console)
    model = build_model(spec, venv, replay_buffer_class=RelabelingReplayBuffer if off_policy else None)
    demos = demonstrations(spec, run, console, progress)
    if spec.cloned_generator and isinstance(venv, VecNormalize):
        venv.training = False  # the clone's normalisation (set when it is fitted, or restored on resume) stays
    d = irl.discriminator
    obs_dim = venv.observation_space.shape[0]
    disc = Discriminator(
        obs_dim,
        DiscriminatorForm(
            kind=irl.algorithm,
            gamma=train.params().gamma,
            hidden=tuple(d.hidden),
            spectral=d.spectral_norm,
            absorbing=d.absorbing,
            shaped=d.shaped,
            policy_term=d.policy_term,
        ),
        inputs=discriminator_inputs(spec),
        reward_inputs=reward_inputs(spec),
    )
    env = FastEnv(spec)
    transitions = expert_transitions(env, demos)
    motion = motion_density(spec, env, demos)
    if d.motion and (motion is None or off_policy):
        console.print(
            "[dim]irl.discriminator.motion: the motion term is for PPO on a task that observes the camera's "
            "velocities; this run goes without it[/]"
        )
    ranked = None
    if d.ranking and disc.shaped and not off_policy:
        actor = None if irl.demonstrations.path is None else cloned_actor(spec, demos)  # D-REX: no expert
        ranked = RankedRollouts(
            env,
            d,
            actor=actor,
            recordings=demos,
            envs=[] if actor is None else [FastEnv(spec) for _ in range(len(d.ranking_noise) * d.ranking_episodes)],
        )
    elif d.ranking and irl.algorithm == "airl":  # GAIL has no r_psi to rank, so it goes without a word
        console.print(
            "[dim]irl.discriminator.ranking: the ranking prior is for shaped AIRL on PPO; this run goes without it[/]"
        )
    fit = DiscriminatorFit(disc, lr=d.learning_rate, seed=spec.train.seed, gradient_penalty=d.gradient_penalty)
    if off_policy:
        cb = OffPolicyAdversarialCallback(
            fit, transitions, current_rollout=d.current_rollout, steps=d.steps, every=d.every
        )
    else:
        cb = AdversarialCallback(
            fit,
            transitions,
            epochs=d.epochs,
            seed=spec.train.seed,
            history=d.history,
            scale_reward=d.scale_reward,
            ranked=ranked,
            ranking_weight=d.ranking,
            support_spread=d.ranking_support,
            motion=partial(below_best, motion, motion_columns(spec)) if motion and d.motion else None,
        )
    averaging = RewardAveraging(disc, d.average_every) if d.average_every and disc.shaped else None
    callbacks = [cb, *([averaging] if averaging else [])]
    learner = Learner(spec, venv, model, callbacks, disc, demos, averaging, console, motion)
    if spec.cloned_generator and irl.generator.anchor:
        learner.callbacks.append(CloneAnchor(*learner.pairs, steps=irl.generator.anchor, seed=spec.train.seed))
    return learner
