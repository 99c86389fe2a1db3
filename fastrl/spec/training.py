"""The train and evaluate sections: algorithm, hyperparameters checked per algorithm, budgets."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from .base import Strict
from .learners import LEARNERS, LearnerKind


class Params(Strict):
    """Base for hyperparameter sets: unknown names are errors."""


class PPOParams(Params):
    """stable-baselines3 PPO hyperparameters (same names), plus the network."""

    learning_rate: float = Field(3e-4, gt=0)
    n_steps: int = Field(256, ge=2)
    batch_size: int = Field(512, ge=2)
    n_epochs: int = Field(5, ge=1)
    gamma: float = Field(0.99, gt=0, le=1)
    gae_lambda: float = Field(0.95, ge=0, le=1)
    clip_range: float = Field(0.2, gt=0)
    ent_coef: float = Field(0.0, ge=0)
    vf_coef: float = Field(0.5, ge=0)
    max_grad_norm: float = Field(0.5, gt=0)
    target_kl: float | None = Field(None, gt=0)
    normalize_advantage: bool = True
    net_arch: list[int] = [128, 128]
    activation: Literal["tanh", "relu"] = "tanh"


class SACParams(Params):
    """stable-baselines3 SAC hyperparameters (same names), plus the network."""

    learning_rate: float = Field(3e-4, gt=0)
    buffer_size: int = Field(300_000, ge=1000)
    learning_starts: int = Field(5_000, ge=0)
    batch_size: int = Field(
        128,
        ge=2,
        description="SB3's default is 256; 128 with [128, 128] trains 2.8x faster "
        "to the same result (bench/sac_schedules.py)",
    )
    tau: float = Field(0.005, gt=0, le=1)
    gamma: float = Field(0.99, gt=0, le=1)
    train_freq: int = Field(1, ge=1)
    gradient_steps: int = Field(1, ge=-1)
    ent_coef: float | Literal["auto"] = "auto"
    target_entropy: float | Literal["auto"] = "auto"
    net_arch: list[int] = Field([128, 128], description="SB3's default is [256, 256]")
    activation: Literal["tanh", "relu"] = "relu"
    lean_update: bool = Field(
        True,
        description="fastrl's leaner gradient step (same maths as SB3's, tested "
        "equal); false: stable-baselines3's own SAC.train",
    )
    periodic_every: int | None = Field(
        None,
        ge=1,
        description="timesteps between evaluations during training, in place of evaluate.periodic_every "
        "(null: that one): SAC trains an order of magnitude fewer steps per second than PPO, and its "
        "deterministic policy's subtasks swing between evaluations",
    )


class Normalize(Strict):
    """Running normalisation of observations and rewards (VecNormalize)."""

    obs: bool = True
    reward: bool | None = Field(
        None,
        description="normalise rewards by the running return scale (never when learning from demonstrations); "
        "null: resolved when the spec is loaded, on for PPO, off for SAC, whose entropy temperature is tuned "
        "to the reward's scale",
    )


class Encoder(Strict):
    """The CNN that reads observation.image: its output width and DrQ's random shift while training."""

    features: int = Field(64, ge=8, le=1024, description="width of the CNN's output (the state is appended to it)")
    shift: int = Field(
        4, ge=0, le=16, description="pixels each frame moves at random in gradient steps (DrQ; 0: no augmentation)"
    )
    critic_cnn: bool = Field(
        False,
        description="the value function reads the frames through a CNN of its own (false: the policy's), so its "
        "loss cannot move a warm-started policy's features",
    )


class WarmStart(Strict):
    """Before PPO's first step: clone the scripted expert's episodes into the policy, then DAgger rounds in which
    the expert labels the states the policy itself visits (from the kinematic state the env computes anyway)."""

    demonstrations: int = Field(40, ge=1, description="scripted-expert episodes cloned first")
    rounds: int = Field(4, ge=0, description="DAgger rounds after the clone (0: behavioural cloning alone)")
    episodes: int = Field(8, ge=1, description="the policy's episodes per round, every step labelled by the expert")
    expert_share: float = Field(
        0.5,
        ge=0,
        le=1,
        description="in round k the expert's action is taken at this ** k of the steps (DAgger's beta), so the "
        "early rounds still reach the later subtasks",
    )
    epochs: int = Field(25, ge=1, description="passes over all the labelled data after each round")
    batch_size: int = Field(256, ge=2)
    learning_rate: float = Field(1e-3, gt=0)
    anchor: int = Field(
        0,
        ge=0,
        description="minibatches of cloning on all the labelled data after every PPO update (as DAPG), so PPO "
        "improves on the clone without leaving it; 0: none",
    )


class Train(Strict):
    """Which algorithm, its hyperparameters (one section per algorithm), budget, parallel envs, seed."""

    algo: Literal["PPO", "SAC"] = "PPO"
    timesteps: int = Field(500_000, ge=1)
    n_envs: int = Field(8, ge=1, le=256)
    seed: int = Field(0, ge=0)
    workers: int = Field(
        2,
        ge=1,
        le=64,
        description="processes stepping the envs in batches, this one included (at most one per CPU and env); "
        "the trajectories do not depend on it",
    )
    ppo: PPOParams = PPOParams()
    sac: SACParams = SACParams()
    encoder: Encoder | None = Field(None, description="observation.image's CNN (null: its defaults)")
    warm_start: WarmStart | None = Field(
        None,
        description="PPO from the spec's reward, starting from the scripted expert's clone refined by DAgger (null: "
        "from scratch); episode seeds from 100,000 x train.seed",
    )
    later_subtasks: float = Field(
        0.0,
        ge=0,
        le=1,
        description="forward RL: this share of each training env's episodes after its first start at a random later "
        "subtask, the earlier ones done, so every subtask is practised from the start (evaluation always starts at "
        "the first; GAIL, AIRL and BC never do: their demonstrations start there); 0: every episode at the first",
    )
    normalize: Normalize = Normalize()
    checkpoint_every: int = Field(100_000, ge=1, description="timesteps between checkpoints")
    log_every: int = Field(10_000, ge=1, description="timesteps between training-curve points")
    keep_checkpoints: int = Field(3, ge=1, description="how many of the newest checkpoints to keep")

    @property
    def kind(self) -> LearnerKind:
        """What the chosen algorithm is: on- or off-policy, its defaults, its SB3 names."""
        return LEARNERS[self.algo]

    def params(self) -> Params:
        """The hyperparameters of the chosen algorithm."""
        return getattr(self, self.kind.name.lower())

    def sb3_params(self) -> dict:
        """The chosen algorithm's hyperparameters that go to stable-baselines3 (and the network)."""
        return self.params().model_dump(exclude={"periodic_every"})


class Evaluate(Strict):
    """Evaluation episodes after training (and during it), and what of them goes into the recording."""

    episodes: int = Field(20, ge=1)
    seed: int = Field(10_000, ge=0)
    sampled: bool = Field(
        False,
        description="act with actions sampled from the policy, as it trains (random draws seeded by `seed`), "
        "not its most likely ones",
    )
    image_every: int = Field(4, ge=0, description="log the endoscope image every k steps (0: never)")
    image_size: tuple[int, int] = Field((128, 128), description="width, height of logged endoscope images")
    record_episodes: int = Field(20, ge=0, description="how many evaluation episodes go into the recording")
    expert: bool = Field(True, description="also evaluate the scripted expert on the same seeds, for reference")
    periodic_every: int = Field(0, ge=0, description="timesteps between evaluations during training (0: none)")
    periodic_episodes: int = Field(10, ge=1, description="episodes per evaluation during training")
    stop_at_subtasks: float | None = Field(
        None,
        gt=0,
        le=1,
        description="stop training once an evaluation during training completes this share of subtasks",
    )

    @property
    def sampling_seed(self) -> int | None:
        """The seed of the evaluation's sampled actions (None: the most likely actions)."""
        return self.seed if self.sampled else None
