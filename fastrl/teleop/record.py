"""`fastrl record`: an attempt in the viewer, saved as it goes, then scored and recorded in Rerun."""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

from ..agents.expert import ScriptedExpert
from ..assess.scoring import Scorer
from ..assist import Suggester, ValueCue
from ..assist.feedback import attempt_feedback, feedback_text
from ..data.trajectory import Trajectory
from ..env.fast_env import FastEnv
from ..spec.models import TaskSpec
from .offline import attempt_recording, load_networks_of, spec_of_run
from .session import Assistance, Session


def load_assistance(run: Path | None, spec: TaskSpec, horizon_s: float = 3.0, seed: int = 0) -> Assistance:
    """The run's policy as a suggester and its value as the cue (heuristic potential cue without a run)."""
    env = FastEnv(spec)
    expert = ScriptedExpert(env)
    if run is None:
        cue = ValueCue()
        cue.calibrate(env, {"expert": lambda _o: expert.act()}, seed)
        return Assistance(cue=cue)
    theirs = spec_of_run(run)
    for part in ("observation", "actions"):
        if getattr(theirs, part) != getattr(spec, part):
            raise ValueError(f"{run}: its policy was trained with another `{part}` section than this spec's")
    nets = load_networks_of(run)
    cue = ValueCue(nets)
    cue.calibrate(env, {"expert": lambda _o: expert.act()}, seed)
    return Assistance(Suggester(spec, nets.policy, horizon_s), cue, str(run))


def attempt_path(out_dir: Path, subject: str) -> Path:
    """A new file name for an attempt: SUBJECT-UTCSTAMP.npz."""
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in subject) or "trainee"
    return Path(out_dir) / f"{safe}-{time.strftime('%Y%m%dT%H%M%SZ', time.gmtime())}.npz"


def record(
    spec: TaskSpec,
    subject: str,
    out_dir: Path,
    run: Path | None = None,
    seed: int = 0,
    viewer: bool = True,
    linger: float = -1.0,
    max_seconds: float | None = None,
    feedback: bool = True,
    suggest_every: float | None = None,
    say=print,
) -> dict:
    """Record one attempt; returns what was written and the feedback. Saved every second and on any exit."""
    assistance = load_assistance(run, spec, seed=seed)
    path = attempt_path(out_dir, subject)
    assistance.suggest_every = round(suggest_every * spec.episode.control_hz) if suggest_every else None
    session = Session(spec, subject, path, seed=seed, assist=assistance)
    session.writer.meta["task_spec"] = spec.model_dump(mode="json")
    display = None
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}

    def stop(signum, _frame):
        session.stop = session.stop or f"interrupted ({signal.Signals(signum).name})"

    for s in previous:
        signal.signal(s, stop)
    try:
        session.start()
        if viewer:
            from .display import Display

            display = Display(session.env, session.on_key)
        say(f"recording {path} (Esc finishes, closing the window or Ctrl+C saves too)")
        session.run(display, max_seconds)
    finally:
        saved = session.finish()
        for s, handler in previous.items():
            signal.signal(s, handler)
    result = {"path": saved, "end": session.stop, "timing": session.timing(), "suggestions": session.suggestions}
    if saved is None:
        say("nothing recorded (fewer than two samples)")
        if display is not None:
            display.close()
        return result
    if feedback:
        if display is not None:
            display.message("scoring the attempt ...")
        traj = Trajectory.load(saved)
        nets = load_networks_of(run) if run is not None else None
        scorer = Scorer(spec, nets)
        fb = attempt_feedback(
            scorer,
            traj,
            Path(out_dir) / f"references-{traj.meta['task_hash']}.json",
            policy=nets.policy if nets is not None else None,
        )
        text = feedback_text(fb)
        session.writer.flush(feedback={k: v for k, v in fb.items() if k != "deviation_mm"})
        (saved.with_suffix(".feedback.json")).write_text(json.dumps(fb, indent=2, default=float))
        result["feedback"], result["feedback_text"] = fb, text
        result["rrd"] = attempt_recording(
            spec,
            Trajectory.load(saved),
            saved.with_suffix(".rrd"),
            run,
            feedback_md=markdown_feedback(fb),
            assistance=assistance,
        )
        say(text)
        if display is not None:
            display.linger(text, linger)
    if display is not None:
        display.close()
    return result


def markdown_feedback(fb: dict) -> str:
    """The feedback as a markdown list (for the Rerun recording)."""
    return "## Feedback\n\n" + "\n".join(f"- {line.strip()}" for line in feedback_text(fb).splitlines())
