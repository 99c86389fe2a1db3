"""The viewer layout of a run: 3D scene, endoscope image, curves and summary side by side."""

from __future__ import annotations

import rerun.blueprint as rrb

BACKGROUND = (40, 42, 48)


def episode_name(index: int) -> str:
    """Entity name of an evaluation episode."""
    return f"ep_{index:02d}"


def training_views(irl: bool = False) -> rrb.Tabs:
    """Training curves in tabs: episodes, evaluations during training, (discriminator, learned reward), all."""

    def series(origin: str, name: str, contents=None) -> rrb.TimeSeriesView:
        return rrb.TimeSeriesView(
            origin=origin, contents=contents or ["$origin/**"], name=name, plot_legend=rrb.Corner2D.LeftTop
        )

    tabs = [
        series("/metrics/train/episode", "training episodes"),
        series("/metrics/train/eval", "evaluation during training"),
    ]
    if irl:
        tabs += [
            series("/metrics/train/irl", "discriminator", ["+ $origin/disc_accuracy", "+ $origin/disc_loss"]),
            series("/metrics/train/irl", "learned reward", ["+ $origin/reward_expert", "+ $origin/reward_policy"]),
        ]
    tabs.append(series("/metrics/train", "all curves (timeline: timesteps)"))
    return rrb.Tabs(*tabs, active_tab=2 if irl else 0)


def run_blueprint(
    n_episodes: int, focus: int = 0, eye: tuple | None = None, timeline: str | None = None, irl: bool = False
) -> rrb.Blueprint:
    """3D scene + episode `focus`, its endoscope image and reward features, training, summary."""
    # Other episodes stay in the recording, hidden from the 3D view. Time series views plot
    # against the time panel's timeline (rerun 0.41 has no per-view timeline): `step` shows
    # the episode, `timesteps` the training curves.
    eye_controls = None
    if eye is not None:
        eye_controls = rrb.EyeControls3D(position=eye[0], look_target=eye[1], eye_up=(0.0, 0.0, 1.0))
    training = training_views(irl)
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
    reward = rrb.TimeSeriesView(
        origin=f"/metrics/eval/{ep}",
        contents=[f"+ /metrics/eval/{ep}/reward"],
        name=f"reward {ep} (timeline: step)",
        plot_legend=rrb.PlotLegend(visible=False),
    )
    features = rrb.TimeSeriesView(
        origin=f"/metrics/eval/{ep}/features",
        name=f"reward features {ep}",
        plot_legend=rrb.Corner2D.LeftTop,
    )
    left = rrb.Vertical(scene, rrb.Horizontal(image, summary), row_shares=[2, 1])
    right = rrb.Vertical(reward, features, training, row_shares=[3, 6, 4])
    return _blueprint(rrb.Horizontal(left, right, column_shares=[3, 2]), timeline or "step")


def _blueprint(root, timeline: str) -> rrb.Blueprint:
    """The layout with side panels collapsed and the time panel on `timeline`."""
    return rrb.Blueprint(
        root,
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline=timeline),
        auto_layout=False,
        auto_views=False,
    )
