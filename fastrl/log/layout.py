"""The viewer layout of a run: 3D scene, endoscope image, curves and summary side by side."""

from __future__ import annotations

import rerun.blueprint as rrb

BACKGROUND = (40, 42, 48)
# Rerun plots a sequence timeline spanning more than 2,000 ticks only around the time cursor
# (+-1,000) unless the view sets its range: training curves span 10^5-10^7 timesteps.
WHOLE_TIMELINE = rrb.TimeAxis(
    view_range=rrb.TimeRange(start=rrb.TimeRangeBoundary.infinite(), end=rrb.TimeRangeBoundary.infinite())
)


def episode_name(index: int) -> str:
    """Entity name of an evaluation episode."""
    return f"ep_{index:02d}"


def _series(origin: str, name: str, contents=None, legend=rrb.Corner2D.LeftTop) -> rrb.TimeSeriesView:
    """A time series view over the whole timeline."""
    if not isinstance(legend, rrb.PlotLegend):
        legend = rrb.PlotLegend(corner=legend)
    return rrb.TimeSeriesView(
        origin=origin, contents=contents or ["$origin/**"], name=name, plot_legend=legend, axis_x=WHOLE_TIMELINE
    )


def training_views(irl: bool = False, warm: bool = False) -> rrb.Tabs:
    """Training curves in tabs: episodes, evaluations during training, (discriminator, learned reward), (the warm
    start's rounds), all."""
    tabs = [
        _series("/metrics/train/episode", "training episodes"),
        _series("/metrics/train/eval", "evaluation during training"),
    ]
    if irl:
        tabs += [
            _series("/metrics/train/irl", "discriminator", ["+ $origin/disc_accuracy", "+ $origin/disc_loss"]),
            _series("/metrics/train/irl", "learned reward", ["+ $origin/reward_expert", "+ $origin/reward_policy"]),
        ]
    if warm:
        tabs.append(_series("/metrics/warm_start", "warm start (DAgger rounds)"))
    tabs.append(_series("/metrics/train", "all curves"))
    return rrb.Tabs(*tabs, active_tab=2 if irl else 0)


def run_blueprint(
    n_episodes: int,
    focus: int = 0,
    eye: tuple | None = None,
    timeline: str | None = None,
    irl: bool = False,
    curves: bool = True,
    pixels: bool = False,
    warm: bool = False,
) -> rrb.Blueprint:
    """3D scene + episode `focus`, its endoscope image and reward features, training, summary.

    The viewer opens on the `timesteps` timeline (on `step` for a run without training curves),
    at its end: the curves in full, and the episode's final state, which the recorder places at
    the policy's training timesteps. Rerun 0.41 plots every view against the one timeline of the
    time panel, so the reward views hold the training figures (timesteps) beside the episode's
    per-step ones (step): switching the timeline to `step` replays the episode.
    """
    eye_controls = None
    if eye is not None:
        eye_controls = rrb.EyeControls3D(position=eye[0], look_target=eye[1], eye_up=(0.0, 0.0, 1.0))
    training = training_views(irl, warm)
    summary = rrb.TextDocumentView(origin="/summary", name="summary")
    if n_episodes <= 0:
        scene = rrb.Spatial3DView(
            origin="/world",
            contents=["+ /world", "+ /world/scene/**"],
            name="scene",
            eye_controls=eye_controls,
            background=BACKGROUND,
        )
        root = rrb.Horizontal(scene, rrb.Vertical(training, summary), column_shares=[3, 2])
        return _blueprint(root, timeline or "timesteps")
    ep = episode_name(focus)
    scene = rrb.Spatial3DView(
        origin="/world",
        contents=["+ /world", "+ /world/scene/**", f"+ /world/eval/{ep}/**"],
        name=f"scene + {ep}",
        eye_controls=eye_controls,
        background=BACKGROUND,
    )
    image = rrb.Spatial2DView(origin=f"/world/eval/{ep}/camera/image", name=f"endoscope {ep}")
    reward = _series(
        f"/metrics/eval/{ep}",
        f"reward: {ep} (step), training (timesteps)",
        [f"+ /metrics/eval/{ep}/reward", "+ /metrics/train/episode/return"],
        legend=rrb.PlotLegend(visible=False),
    )
    features = _series(
        f"/metrics/eval/{ep}/features",
        f"reward features: {ep} (step), training (timesteps)",
        ["+ $origin/**", "+ /metrics/train/features/**"],
    )
    below = (
        [image, rrb.Spatial2DView(origin=f"/world/eval/{ep}/policy", name=f"policy frames {ep}")] if pixels else [image]
    )
    left = rrb.Vertical(scene, rrb.Horizontal(*below, summary), row_shares=[2, 1])
    right = rrb.Vertical(reward, features, training, row_shares=[3, 6, 4])
    default = "timesteps" if curves else "step"
    return _blueprint(rrb.Horizontal(left, right, column_shares=[3, 2]), timeline or default)


def _blueprint(root, timeline: str) -> rrb.Blueprint:
    """The layout with side panels collapsed and the time panel on `timeline`, following its end."""
    return rrb.Blueprint(
        root,
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline=timeline, play_state="following"),
        auto_layout=False,
        auto_views=False,
    )
