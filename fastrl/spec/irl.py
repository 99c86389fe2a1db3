"""The irl section: learn from demonstrations (GAIL, AIRL, behavioural cloning) instead of the heuristic reward."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from .base import Strict
from .training import PPOParams, Train

Degradation = Literal["slowed", "jitter", "drift", "paused", "retraced"]  # fastrl.data.overlays.OVERLAYS
DEGRADED_DEFAULT = ("drift", "jitter", "slowed")  # what `ranking_degraded: true` lays on the copies


class Demonstrations(Strict):
    """Where demonstrations come from: a directory of trajectory files, or the scripted expert."""

    path: str | None = Field(None, description="directory of trajectory files (.npz); else the scripted expert")
    expert: int = Field(20, ge=1, description="how many scripted-expert demonstrations to write into the run")
    seed: int = Field(0, ge=0, description="seed of the first scripted-expert demonstration")
    others: str | None = Field(
        None,
        description="directory of the cohort's recordings not learned from (`fastrl assess` writes it, a study "
        "points at its whole cohort, where `generator.recorded_starts` asks); only their states are used, as "
        "training starts",
    )


class DiscriminatorSettings(Strict):
    """The discriminator network and how it is trained."""

    hidden: list[int] = [64, 64]
    learning_rate: float = Field(3e-4, gt=0)
    epochs: int = Field(2, ge=1, description="on-policy (PPO): passes over each rollout")
    steps: int = Field(4, ge=1, description="off-policy (SAC): gradient steps after each rollout")
    every: int = Field(
        0,
        ge=0,
        description="off-policy: env steps (all envs) between discriminator fits, on the "
        "samples since the last fit; 0: after every rollout",
    )
    spectral_norm: bool = Field(False, description="spectrally normalise every layer")
    gradient_penalty: float = Field(
        0.0,
        ge=0,
        description="weight of the WGAN-GP penalty (|grad logit| - 1)^2 at "
        "points between policy and expert inputs; 0: none",
    )
    current_rollout: bool = Field(True, description="off-policy: train only on the latest rollout's samples")
    history: int = Field(
        0,
        ge=0,
        description="on-policy (PPO): keep a uniform sample of this many earlier policy "
        "transitions and add as many of them as the rollout has to each fit's policy side, so the "
        "learned reward keeps rating what earlier policies did low; 0: the rollout alone",
    )
    absorbing: bool = Field(True, description="terminated episodes continue in an absorbing state")
    ignore: list[str] | None = Field(
        None,
        description="observation terms the discriminator does not see (the "
        "policy still does). null: resolved when the spec is loaded, GAIL ignores `elapsed` (if observed), "
        "AIRL sees all. "
        "With the clock in its input, GAIL's non-negative reward is about 0 on every "
        "state later than the expert's, however far the task has come",
    )
    reward_ignore: list[str] = Field(
        [],
        description="shaped AIRL: terms the reward r_psi also leaves out, while "
        "the potential h sees them (`[elapsed]`: the clock in the shaping only). "
        "Off by default: without the clock r_psi no longer ranks ImageCentring trainees",
    )
    ranking: float = Field(
        0.0,
        ge=0,
        description="shaped AIRL on PPO: weight of a ranking loss on r_psi (D-REX): "
        "over snippets of the scripted expert (with `demonstrations.path`: of a policy cloned from those "
        "recordings) whose actions are random at `ranking_noise` rates, "
        "less noise must sum higher; 0: none (GAIL and a SAC generator go without it)",
    )
    ranking_noise: list[Annotated[float, Field(ge=0, le=1)]] = Field(
        [0.0, 0.25, 0.5, 0.75, 1.0], min_length=2, description="random-action rates of the ranking rollouts"
    )
    ranking_episodes: int = Field(4, ge=1, description="ranking rollouts per noise rate")
    ranking_repeat: int = Field(1, ge=1, description="steps each random action of the ranking rollouts is held")
    ranking_degraded: bool | list[Degradation] = Field(
        False,
        description="also rank copies of the demonstrations degraded at each `ranking_noise` rate by these "
        "kinematic overlays (fastrl.data.overlays), pairs of the same source only; true: drift, jitter, slowed",
    )
    ranking_support: float = Field(
        0.0,
        ge=0,
        le=10,
        description="shaped AIRL on PPO, with `ranking`: r_psi must also rate each demonstrated state above a copy "
        "with Gaussian noise of this spread on its normalised observation (a support prior: what the "
        "demonstrations never do ranks below what they do nearby; normalised observations are clipped at 10); 0: none",
    )
    motion: float = Field(
        0.0,
        ge=0,
        le=10,
        description="on a task that observes the camera's velocities, with a PPO generator: the learned reward "
        "scored adds this weight times each step's motion log-density below the demonstrations' best (the density "
        "of their steps' speed, turn rate and its change: fastrl.assess.motion), in units of the generator's reward "
        "spread over its last rollout, and the learned value scored adds the same term discounted over the "
        "trainee's own steps from each state on; the generator learns from the discriminator alone (trained with the "
        "term, the value lost 0.20 on tremor: RESULTS, the motion in the learned reward; the value's term: RESULTS, "
        "the motion in the learned value); 0: none",
    )
    average_every: int = Field(
        50000,
        ge=0,
        description="shaped AIRL: copy r_psi and h every this many environment "
        "steps; the saved reward is the mean of the copies and the final networks (adversarial "
        "training converges in the average of its iterates); 0: the final networks alone",
    )
    shaped: bool = Field(True, description="AIRL: f = r_psi(s) + gamma h(s') - h(s); false: the standard f(s, s')")
    policy_term: bool | None = Field(
        None,
        description="AIRL: D's logit is f - log pi(a|s); false: f alone. null: "
        "resolved when the spec is loaded, on for PPO, off for SAC, whose squashed Gaussian gives the expert's "
        "saturated actions a log pi of hundreds, which decides D on its own",
    )
    scale_reward: bool | None = Field(
        None,
        description="on-policy (PPO): divide the generator's learned reward by "
        "the running std of its discounted return (VecNormalize's reward scaling), so "
        "the critic's targets stay in range as the discriminator sharpens. null: "
        "resolved when the spec is loaded, on for AIRL (3-5x fewer steps), off for GAIL (measured slower)",
    )

    @property
    def degraded_overlays(self) -> tuple[str, ...]:
        """The overlays the ranking's degraded copies of the demonstrations carry (none: no copies)."""
        return DEGRADED_DEFAULT if self.ranking_degraded is True else tuple(self.ranking_degraded or ())


class Generator(Strict):
    """GAIL and AIRL's PPO generator: its own envs and hyperparameters, apart from forward RL's `train.ppo`."""

    n_envs: int | None = Field(None, ge=1, le=256, description="parallel envs of the generator; null: train.n_envs")
    ppo: PPOParams | None = Field(
        None,
        description="the generator's PPO hyperparameters; null: train.ppo. Forward RL's are tuned for speed on the "
        "heuristic reward, and an adversarial reward that moves with every rollout needs gentler steps",
    )
    cloned: bool = Field(
        False,
        description="start from the behavioural clone of the demonstrations (irl.bc's settings) with the "
        "observation normalisation fixed to theirs, so the discriminator meets a generator near the task from the "
        "first rollout",
    )
    anchor: int = Field(
        0,
        ge=0,
        description="with `cloned`: minibatches of behavioural cloning on the demonstrations after every PPO update "
        "(as DAPG), so the adversarial reward cannot lead the clone away from the task; 0: none",
    )
    min_steps: int = Field(
        0,
        ge=0,
        description="steps the PPO generator trains before an evaluation may stop it (evaluate.stop_at_subtasks): "
        "its critic is the learned value that scores trainees, and an anchored clone that completes the task at the "
        "first evaluations left it too few (RESULTS: validity); 0: any evaluation may stop it",
    )
    stop_at_subtasks: float | None = Field(
        None,
        gt=0,
        le=1,
        description="the share of subtasks at which an evaluation (after min_steps) stops the PPO generator; null: "
        "evaluate.stop_at_subtasks, forward RL's",
    )
    late_starts: float = Field(
        0.0,
        ge=0,
        lt=1,
        description="every training episode after an env's first starts with a random share of the time limit, up "
        "to this, already gone (the pose as usual), so the critic, whose value scores trainees, also meets the late "
        "clock that slow trainees reach; 0: every episode at 0 s",
    )
    recorded_starts: float = Field(
        0.0,
        ge=0,
        lt=1,
        description="this share of every env's training episodes after its first starts at a random state of a "
        "recording (the demonstrations and, with `fastrl assess` or a study, the cohort's others), so the critic, "
        "whose value scores trainees, and the discriminator meet the states trainees visit; 0: none",
    )
    value_ignore: list[str] = Field(
        [],
        description="observation terms the PPO generator's critic (whose value scores trainees) leaves out while the "
        "policy sees them, e.g. where in the dome the scope and target are, so the value rests on what the view "
        "shows (RESULTS: validity); default: none",
    )


class BehaviourCloning(Strict):
    """Behavioural cloning of the demonstrated actions into the PPO policy of `irl.generator` (else `train.ppo`)."""

    epochs: int = Field(20, ge=1)
    learning_rate: float = Field(1e-3, gt=0)
    batch_size: int = Field(256, ge=2)


class IRL(Strict):
    """Which learner from demonstrations (none: forward RL on the spec's reward), and its settings."""

    algorithm: Literal["none", "gail", "airl", "bc"] = "none"
    demonstrations: Demonstrations = Demonstrations()
    discriminator: DiscriminatorSettings = DiscriminatorSettings()
    generator: Generator | None = Field(None, description="GAIL/AIRL on PPO: the generator's settings; null: train's")
    bc: BehaviourCloning = BehaviourCloning()

    @property
    def enabled(self) -> bool:
        """Whether runs learn from demonstrations."""
        return self.algorithm != "none"


def unobserved_terms(irl: IRL, observed: list[str]) -> list[tuple]:
    """(location, message, value) of each term the discriminator or the critic ignores that is not observed."""
    listed = [
        (("irl", "discriminator", field, i), name)
        for field in ("ignore", "reward_ignore")
        for i, name in enumerate(getattr(irl.discriminator, field) or [])
    ]
    listed += [
        (("irl", "generator", "value_ignore", i), name)
        for i, name in enumerate(irl.generator.value_ignore if irl.generator else [])
    ]
    shown = ", ".join(observed)
    return [
        (loc, f"'{name}' is not observed (observation terms: {shown})", name)
        for loc, name in listed
        if name not in observed
    ]


def ppo_generator(train: Train, irl: IRL) -> Generator | None:
    """The `irl.generator` settings this run learns with: GAIL or AIRL on PPO only (None otherwise, or unset)."""
    return irl.generator if irl.algorithm in ("gail", "airl") and train.algo == "PPO" else None


def starts_cloned(train: Train, irl: IRL) -> bool:
    """Whether the run's PPO generator starts from the demonstrations' behavioural clone (`irl.generator.cloned`)."""
    gen = ppo_generator(train, irl)
    return gen is not None and gen.cloned


def min_steps(train: Train, irl: IRL) -> int:
    """Steps the PPO generator trains before an evaluation may stop it (`irl.generator.min_steps`; 0 otherwise)."""
    gen = ppo_generator(train, irl)
    return gen.min_steps if gen is not None else 0


def stop_at_subtasks(train: Train, irl: IRL, evaluate_at: float | None) -> float | None:
    """The share of subtasks at which an evaluation stops training: the PPO generator's own where it has one
    (`irl.generator.stop_at_subtasks`), else `evaluate_at` (`evaluate.stop_at_subtasks`)."""
    gen = ppo_generator(train, irl)
    return gen.stop_at_subtasks if gen is not None and gen.stop_at_subtasks is not None else evaluate_at


def late_starts(train: Train, irl: IRL) -> float:
    """Up to what share of the time limit the PPO generator's training episodes start late (`irl.generator`)."""
    gen = ppo_generator(train, irl)
    return gen.late_starts if gen is not None else 0.0


def recorded_starts(train: Train, irl: IRL) -> float:
    """The share of the PPO generator's training episodes that start at a recorded state (`irl.generator`)."""
    gen = ppo_generator(train, irl)
    return gen.recorded_starts if gen is not None else 0.0


def learning_train(train: Train, irl: IRL) -> Train:
    """The train settings a run learns with: `train`, except that GAIL and AIRL on PPO take `irl.generator`'s, and
    so does BC: it fits the network such a generator starts from, not forward RL's (tuned for the heuristic reward)."""
    gen = irl.generator if irl.algorithm == "bc" else ppo_generator(train, irl)
    if gen is None:
        return train
    update = {k: v for k, v in (("n_envs", gen.n_envs), ("ppo", gen.ppo)) if v is not None}
    return train.model_copy(update=update)
