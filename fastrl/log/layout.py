"""The viewer layout of a run: 3D scene, endoscope image, curves and summary side by side."""

from __future__ import annotations

import rerun.blueprint as rrb


def episode_name(index: int) -> str:
    """Entity name of an evaluation episode."""
    return f"ep_{index:02d}"


def run_blueprint(n_episodes: int, focus: int = 0, eye: tuple | None = None, timeline: str = "step") -> rrb.Blueprint:
    """3D view of the scene and one episode, its endoscope image and features, training curves, summary."""
    ep = episode_name(focus)
    world = ["+ /world", "+ /world/scene/**"]
    if n_episodes > 0:
        world.append(f"+ /world/eval/{ep}/**")
    eye_controls = None
    if eye is not None:
        position, target = eye
        eye_controls = rrb.EyeControls3D(position=position, look_target=target, eye_up=(0.0, 0.0, 1.0))
    scene = rrb.Spatial3DView(origin="/world", contents=world, name=f"scene + {ep}" if n_episodes else "scene",
                              eye_controls=eye_controls, background=(40, 42, 48))
    image = rrb.Spatial2DView(origin=f"/world/eval/{ep}/camera/image", name=f"endoscope {ep}")
    reward = rrb.TimeSeriesView(origin=f"/metrics/eval/{ep}", name=f"reward {ep} (timeline: step)",
                                contents=[f"+ /metrics/eval/{ep}/reward"], plot_legend=rrb.PlotLegend(visible=False))
    features = rrb.TimeSeriesView(origin=f"/metrics/eval/{ep}/features", name=f"reward features {ep}",
                                  plot_legend=rrb.Corner2D.LeftTop)
    training = rrb.TimeSeriesView(origin="/metrics/train", name="training (select timeline: timesteps)",
                                  plot_legend=rrb.Corner2D.LeftTop)
    summary = rrb.TextDocumentView(origin="/summary", name="summary")
    left = rrb.Vertical(scene, rrb.Horizontal(image, summary, column_shares=[1, 1]), row_shares=[2, 1])
    right = rrb.Vertical(reward, features, training, row_shares=[3, 6, 4])
    return rrb.Blueprint(
        rrb.Horizontal(left, right, column_shares=[3, 2]),
        rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline=timeline),
        auto_layout=False, auto_views=False)
