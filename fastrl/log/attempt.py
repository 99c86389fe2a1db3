"""One trainee attempt in Rerun: the replayed episode, suggested paths, the value cue and the feedback."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from ..data.episode import EpisodeRecord
from ..model.compiler import CompiledTask
from .episode import log_episode
from .layout import BACKGROUND
from .scene import default_eye, log_scene
from .stream import saved_stream

WORLD, METRICS = "world/attempt", "metrics/attempt"
TIP, AIM, MISSED = (255, 30, 230), (0, 215, 240), (150, 150, 150)  # as in the viewer; grey: does not reach


def log_attempt(
    path: Path,
    recording_id: str,
    task: CompiledTask,
    ep: EpisodeRecord,
    cue: np.ndarray | None = None,
    cue_colours: np.ndarray | None = None,
    suggestions: list | None = None,
    feedback: str | None = None,
    cue_kind: str = "value",
) -> Path:
    """Write an .rrd: scene, episode, suggested tip and view-centre paths at their steps, cue series, feedback."""
    rec = saved_stream(path, recording_id)
    try:
        log_scene(rec, task, root="world")
        log_episode(rec, ep, task, task.spec.scope.fov_deg, world=WORLD, metrics=METRICS)
        index = [
            rr.TimeColumn("step", sequence=np.arange(len(ep.time))),
            rr.TimeColumn("sim_time", duration=np.asarray(ep.time, float)),
        ]
        if cue is not None:
            rec.log(f"{METRICS}/cue/{cue_kind}", rr.SeriesLines(names=cue_kind), static=True)
            rec.send_columns(f"{METRICS}/cue/{cue_kind}", indexes=index, columns=rr.Scalars.columns(scalars=cue))
        if cue_colours is not None:
            n = len(ep.time)
            rec.send_columns(
                f"{WORLD}/value_cue",
                indexes=index,
                columns=rr.Points3D.columns(positions=ep.tip_pos, colors=cue_colours, radii=np.full(n, 0.003)),
            )
        for step, sg, uv_tip, uv_aim in suggestions or []:
            rec.set_time("step", sequence=int(step))
            rec.set_time("sim_time", duration=float(ep.time[step]))
            colour = TIP if sg.reached else MISSED
            aim = sg.aim[np.isfinite(sg.aim).all(axis=1)]
            rec.log(f"{WORLD}/suggestion/tip", rr.LineStrips3D([sg.tip], colors=[colour], radii=0.0006))
            rec.log(f"{WORLD}/suggestion/view_centre", rr.LineStrips3D([aim], colors=[AIM], radii=0.0005))
            for name, uv, c in (("tip", uv_tip, colour), ("view_centre", uv_aim, AIM)):
                rec.log(
                    f"{WORLD}/camera/image/suggestion/{name}",
                    rr.LineStrips2D([uv] if uv is not None else [], colors=[c], radii=1.0),
                )
            rec.log(f"{METRICS}/suggestion/reached", rr.Scalars(float(sg.reached)))
            rec.log(f"{METRICS}/suggestion/ms", rr.Scalars(sg.ms))
        if feedback:
            rec.log("summary", rr.TextDocument(feedback, media_type=rr.MediaType.MARKDOWN), static=True)
        rec.send_blueprint(attempt_blueprint(task, cue_kind))
    finally:
        rec.flush()
        rec.disconnect()
    return Path(path)


def attempt_blueprint(task: CompiledTask, cue_kind: str) -> rrb.Blueprint:
    """3D scene with the attempt and suggestions; endoscope image; cue and reward curves; feedback."""
    eye = default_eye(task)
    scene = rrb.Spatial3DView(
        origin="/world",
        name="attempt + suggested paths",
        background=BACKGROUND,
        eye_controls=rrb.EyeControls3D(position=eye[0], look_target=eye[1], eye_up=(0.0, 0.0, 1.0)),
    )
    image = rrb.Spatial2DView(origin=f"/{WORLD}/camera/image", name="endoscope + suggestion")
    curves = rrb.Vertical(
        rrb.TimeSeriesView(origin=f"/{METRICS}/cue", name=f"{cue_kind} cue"),
        rrb.TimeSeriesView(
            origin=f"/{METRICS}", contents=[f"+ /{METRICS}/reward", f"+ /{METRICS}/subtask"], name="reward, subtask"
        ),
    )
    root = rrb.Horizontal(
        rrb.Vertical(
            scene, rrb.Horizontal(image, rrb.TextDocumentView(origin="/summary", name="feedback")), row_shares=[3, 2]
        ),
        curves,
        column_shares=[3, 1],
    )
    return rrb.Blueprint(
        root,
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline="step"),
        auto_layout=False,
        auto_views=False,
    )
