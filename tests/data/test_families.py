"""Trainee families: each deficit is measurably present in its trajectories; subjects mix families by level."""

import numpy as np
import pytest
from typer.testing import CliRunner

import fastrl
from fastrl.assess.kinematic import path_length
from fastrl.assess.scoring import Scorer
from fastrl.cli import app
from fastrl.data import load_trajectories
from fastrl.data.cohort import make_cohort, with_overlays
from fastrl.data.families import FAMILIES, draw_mix, family_names, mixed_profile
from fastrl.data.replay import expert_trajectories
from fastrl.data.skill import SkillProfile
from fastrl.data.trainee import Trainee

from ..conftest import spec_file

SEEDS = (0, 1, 2)


def signs(env, profile: SkillProfile, seed: int) -> dict:
    """Kinematic signs of one episode of a trainee: stillness, reversals, cue errors, contacts, path and time."""
    u = env.unwrapped
    trainee = Trainee(env, profile, seed)
    env.reset(seed=seed)
    trainee.reset()
    q, tips, centring, horizon, depth, contacts, done = [u.portal_coordinates()], [], [], [], [], 0, False
    while not done:
        _, _, term, trunc, info = env.step(trainee.act())
        s = u.state
        q.append(u.portal_coordinates())
        tips.append(np.array(s.tip_pos))
        centring.append(s.centring > s.tol_centring)
        horizon.append(s.horizon)
        depth.append(abs(s.distance_error))
        contacts += bool(s.contacts)
        done = term or trunc
    dq = np.diff(np.array(q), axis=0)
    still = np.abs(dq).max(axis=1) < 1e-4
    runs = np.diff(np.flatnonzero(np.diff(np.r_[0, still.astype(int), 0])))[::2]  # lengths of still stretches
    signs_ = np.sign(dq[:, :2])
    reversals = int(((signs_[1:] * signs_[:-1]) < 0).sum())
    return {
        "time": info["time"],
        "long_pauses": int((runs >= 10).sum()),
        "reversals_per_s": reversals / info["time"],
        "held_off_centre": int((np.array(centring) & still).sum()),  # steps the view is held still off-centre
        "horizon": float(np.mean(horizon)),
        "out_of_band": float(np.mean(np.array(depth) > 1e-9)),
        "contacts": contacts,
        "path": path_length(np.array(tips)),
        "subtasks": info["subtask"],
    }


ACTED = [f for f in FAMILIES if FAMILIES[f].overlay is None]
OVERLAID = [f for f in FAMILIES if FAMILIES[f].overlay is not None]


@pytest.fixture(scope="module")
def measured():
    """The mean signs of the expert and of each acted family at novice severity, TraceLines seeds 0-2."""
    env = fastrl.make(spec_file("tracelines"))
    out = {}
    for name, profile in {"expert": SkillProfile(), **{f: FAMILIES[f].novice for f in ACTED}}.items():
        rows = [signs(env, profile, seed) for seed in SEEDS]
        out[name] = {k: float(np.mean([r[k] for r in rows])) for k in rows[0]}
    return out


# What each family's deficit must show against the expert: (sign, ratio or margin it must exceed).
PRESENT = {
    "flow": lambda f, e: f["long_pauses"] >= 3 and e["long_pauses"] == 0,
    "speed": lambda f, e: f["time"] > 1.5 * e["time"] and f["path"] < 1.5 * e["path"],
    "depth": lambda f, e: f["out_of_band"] > 2 * e["out_of_band"] + 0.05,
    "field_of_view": lambda f, e: f["held_off_centre"] >= 20 and f["held_off_centre"] > 3 * e["held_off_centre"],
    "horizon": lambda f, e: f["horizon"] > 1.5 * e["horizon"],
    "economy": lambda f, e: f["path"] > 1.5 * e["path"],
    "corrections": lambda f, e: f["reversals_per_s"] > 2 * e["reversals_per_s"] + 0.5,
    "safety": lambda f, e: f["contacts"] >= 3 and e["contacts"] == 0,
    "classic": lambda f, e: f["subtasks"] < e["subtasks"] and f["time"] > e["time"],
}


def test_every_family_has_its_sign():
    assert set(PRESENT) == set(ACTED) and set(OVERLAID) == {"slowed", "jitter", "drift", "paused", "retraced"}


@pytest.mark.parametrize("family", ACTED)
def test_family_deficit_is_present_in_its_trajectories(family, measured):
    f, e = measured[family], measured["expert"]
    assert PRESENT[family](f, e), (family, f, e)


def band_power(q: np.ndarray, hz: float, lo: float, hi: float) -> float:
    """Power of pitch and yaw inside [lo, hi] Hz."""
    f = np.fft.rfftfreq(len(q), 1 / hz)
    spectrum = np.abs(np.fft.rfft(q[:, :2] - q[:, :2].mean(0), axis=0)) ** 2
    return float(spectrum[(f >= lo) & (f <= hi)].sum())


@pytest.mark.parametrize("family", OVERLAID)
def test_kinematic_overlay_deforms_the_recording_as_named(family):
    spec = fastrl.make(spec_file("tracelines")).unwrapped.task_spec
    scorer = Scorer(spec)
    cohort = list(make_cohort(spec, 2, 1, seed=0, env=scorer.env, families=(family,)))
    assert cohort[0].actions is None and cohort[0].meta["overlays"] == {FAMILIES[family].overlay: 1.0}
    assert "overlays" not in cohort[1].meta and cohort[1].actions is not None  # the top level: the expert as acted
    hz = spec.episode.control_hz
    for seed, e in zip((0, 1), expert_trajectories(scorer.env, [0, 1])):
        n = with_overlays(scorer.env, e, {FAMILIES[family].overlay: 1.0}, seed)
        assert n.range_problem(scorer.env.task.ranges) is None and np.allclose(np.diff(n.time), 1 / hz)
        if family == "slowed":  # the same path, later
            assert (
                len(n.time) > 1.5 * len(e.time)
                and scorer.score(n).scores["time"] > 1.5 * scorer.score(e).scores["time"]
            )
            np.testing.assert_allclose(n.portal[-1], e.portal[-1])
        elif family == "jitter":  # a shake in the tremor band
            gap = n.portal[:, :2] - e.portal[:, :2]
            assert np.sqrt((gap**2).mean()) > np.radians(0.5)
            assert band_power(gap, hz, 3, 8) > 10 * band_power(gap, hz, 0, 2)
        elif family == "paused":  # the same samples in the same order, with still stretches between them
            moving = n.portal[np.r_[True, np.abs(np.diff(n.portal, axis=0)).max(1) > 0]]
            assert np.array_equal(moving, e.portal[np.r_[True, np.abs(np.diff(e.portal, axis=0)).max(1) > 0]])
            still = np.abs(np.diff(n.portal, axis=0)).max(1) == 0
            assert still.sum() - (np.abs(np.diff(e.portal, axis=0)).max(1) == 0).sum() >= 0.4 * hz
        elif family == "retraced":  # recorded poses only, gone over again: a longer path to the same end
            assert np.isin(n.portal.view([("", n.portal.dtype)] * 5), e.portal.view([("", e.portal.dtype)] * 5)).all()
            assert scorer.score(n).scores["path_length"] > 1.1 * scorer.score(e).scores["path_length"]
            np.testing.assert_allclose(n.portal[-1], e.portal[-1])
        else:  # drift: slow deviations from the recorded path, not a shake
            gap = n.portal[:, :2] - e.portal[:, :2]
            assert np.sqrt((gap**2).mean()) > np.radians(1.0)
            assert band_power(gap, hz, 0, 1) > 5 * band_power(gap, hz, 3, 10)


def test_a_subject_mixes_families_in_shares_and_the_level_sets_the_total():
    mixes = [draw_mix(tuple(FAMILIES), seed) for seed in range(200)]
    assert all(abs(sum(m.values()) - 1.0) < 1e-9 and 1 <= len(m) <= 3 for m in mixes)
    assert {f for m in mixes for f in m} == set(FAMILIES)  # every family drawn somewhere
    assert len({tuple(sorted(m)) for m in mixes}) > 20  # many different mixes
    assert draw_mix(tuple(FAMILIES), 7) == draw_mix(tuple(FAMILIES), 7)
    mix = {"speed": 0.25, "economy": 0.75}
    assert mixed_profile(mix, 5, 5) == SkillProfile()  # the top level is the expert
    novice, middle = mixed_profile(mix, 1, 5), mixed_profile(mix, 3, 5)
    assert novice.slowness == pytest.approx(0.25 * FAMILIES["speed"].novice.slowness)
    assert novice.detour == pytest.approx(2 * middle.detour) and novice.dither == 0.0


def test_family_names_are_checked():
    assert family_names("all") == tuple(FAMILIES)
    assert family_names("speed, depth") == ("speed", "depth")
    with pytest.raises(ValueError, match="choose from"):
        family_names("speed,sloppiness")


def test_mixed_cohort_labels_each_subject_with_its_mix(tmp_path):
    spec = fastrl.make(spec_file("tracelines")).unwrapped.task_spec
    trajs = list(make_cohort(spec, 2, 3, seed=0, families=("speed", "depth", "economy")))
    assert [t.meta["skill"] for t in trajs] == [1, 1, 1, 2, 2, 2]
    assert all(set(t.meta["families"]) <= {"speed", "depth", "economy"} for t in trajs)
    assert all(v == 0.0 for t in trajs if t.meta["skill"] == 2 for v in t.meta["profile"].values())
    res = CliRunner().invoke(
        app,
        [
            "cohort",
            str(spec_file("tracelines")),
            "--levels",
            "2",
            "--per-level",
            "1",
            "--families",
            "flow,speed",
            "-o",
            str(tmp_path / "c"),
            "--no-progress",
        ],
    )
    assert res.exit_code == 0, res.output
    written, problems = load_trajectories([tmp_path / "c"])
    assert not problems and len(written) == 2 and all(set(t.meta["families"]) <= {"flow", "speed"} for t in written)
    bad = CliRunner().invoke(app, ["cohort", str(spec_file("tracelines")), "--families", "sloppy", "-o", str(tmp_path)])
    assert bad.exit_code == 2 and "Traceback" not in bad.output


def test_tasks_with_instruments_take_the_families_their_trainee_acts_out(tmp_path):
    spec = fastrl.make(spec_file("triangulation")).unwrapped.task_spec
    with pytest.raises(ValueError, match="deviates the scope alone"):
        next(make_cohort(spec, 2, 1, families=("depth",)))
    res = CliRunner().invoke(
        app, ["cohort", str(spec_file("triangulation")), "--families", "all", "-o", str(tmp_path), "--no-progress"]
    )
    assert res.exit_code == 2 and "two-handed tasks take classic, flow, speed, corrections" in res.output
    assert not list(tmp_path.glob("*.npz"))
