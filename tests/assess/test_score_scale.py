"""Scoring archives: the journal resumes after a real SIGINT, bad files and torn lines, the sampled pictures'
report equal to the whole one, and Ray's scores equal to this process's."""

import io
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import psutil
import pytest
import yaml
from rich.console import Console

from fastrl.assess.journal import Journal
from fastrl.assess.references import reference_scores
from fastrl.assess.report import build_report, score_files
from fastrl.assess.scoring import Scorer, normalise
from fastrl.runner.chosen import rank_recordings
from fastrl.runner.score import archive, assessment
from fastrl.runner.score.archive import sample_indices
from fastrl.runner.score.assessment import assess

from ..conftest import spec_file
from .test_assess import _spec, airl_run, degraded  # noqa: F401 (airl_run: the tiny real AIRL run, a fixture)


@pytest.fixture(scope="module")
def cohort(tmp_path_factory):
    """Six short trajectories at two skill levels, a copy of each under another name, and the spec file."""
    root = tmp_path_factory.mktemp("cohort")
    scorer = Scorer(_spec())
    for i, (level, noise) in enumerate(((2, 0.0), (1, 0.7), (2, 0.1), (1, 0.5), (2, 0.05), (1, 0.9))):
        degraded(scorer, 30 + i, noise, level).save(root / "in" / f"t{i}.npz")
    spec = root / "spec.yaml"
    spec.write_text(yaml.safe_dump(scorer.spec.model_dump(mode="json")))
    return root / "in", spec


def without_seconds(report: dict) -> dict:
    """A report less its timings and its note on the pictures' sample."""
    return {k: v for k, v in report.items() if k not in ("seconds", "pictures_sample")}


def journaled(path) -> list[str]:
    """The files named by a journal's whole lines, in order (the header and a torn line left out)."""
    out = []
    for line in path.read_text().splitlines()[1:]:
        try:
            out.append(json.loads(line)["file"])
        except json.JSONDecodeError:
            pass
    return out


def test_sample_is_every_file_up_to_the_limit_then_evenly_spaced_from_first_to_last():
    assert sample_indices(5, 10) == set(range(5))
    picked = sample_indices(1000, 5)
    assert picked == {0, 250, 500, 749, 999} and sample_indices(1000, 5) == picked


def test_a_rerun_after_sigint_scores_only_the_files_not_journaled(cohort, tmp_path):
    folder, spec = cohort
    many = tmp_path / "many"
    many.mkdir()
    for k in range(12):  # 72 files: long enough to be stopped part way
        for f in sorted(folder.glob("*.npz")):
            shutil.copy(f, many / f"{f.stem}_{k:02d}.npz")
    out = tmp_path / "out" / "scores.json"
    journal = out.parent / "scores.journal.jsonl"
    cmd = [sys.executable, "-m", "fastrl.cli", "score", "--spec", str(spec), str(many), "-o", str(out)]
    cmd += ["--references", "1", "--no-pictures", "--no-progress"]
    reset = lambda: signal.signal(signal.SIGINT, signal.SIG_DFL)  # noqa: E731 (a job run with & ignores SIGINT)
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=reset)
    deadline = time.monotonic() + 600
    while proc.poll() is None and (not journal.exists() or len(journaled(journal)) < 5):
        assert time.monotonic() < deadline
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 130, err
    assert "interrupted" in err and str(journal) in err and "run the same command again" in err
    first = journaled(journal)
    assert 5 <= len(first) < 72 and len(set(first)) == len(first)
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert f"scored 72 trajectories ({len(first)} read from the journal)" in res.stdout
    assert f"resuming: {len(first)} of 72 files already scored" in res.stderr
    lines = journaled(journal)
    assert lines[: len(first)] == first and sorted(lines) == sorted(map(str, many.glob("*.npz")))  # each once
    whole = tmp_path / "whole" / "scores.json"
    assess([many], spec_path=spec, output=whole, reference_episodes=1, pictures=False, progress=False)
    assert without_seconds(json.loads(out.read_text())) == without_seconds(json.loads(whole.read_text()))


def test_after_a_kill_the_helper_stops_and_a_rerun_scores_only_the_files_not_journaled(cohort, tmp_path):
    folder, spec = cohort
    many = tmp_path / "many"
    many.mkdir()
    for k in range(12):
        for f in sorted(folder.glob("*.npz")):
            shutil.copy(f, many / f"{f.stem}_{k:02d}.npz")
    out = tmp_path / "out" / "scores.json"
    journal = out.parent / "scores.journal.jsonl"
    cmd = [sys.executable, "-m", "fastrl.cli", "score", "--spec", str(spec), str(many), "-o", str(out)]
    cmd += ["--references", "1", "--no-pictures", "--no-progress"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 600
    while proc.poll() is None and (not journal.exists() or len(journaled(journal)) < 5):
        assert time.monotonic() < deadline
        time.sleep(0.05)
    helpers = psutil.Process(proc.pid).children()
    assert len(helpers) == 1  # 72 files: the forked helper shares the work
    proc.kill()
    proc.wait()
    psutil.wait_procs(helpers, timeout=60)  # it stops after the file in hand, not at the last file
    assert not any(h.is_running() and h.status() != psutil.STATUS_ZOMBIE for h in helpers)
    first = journaled(journal)
    assert 5 <= len(first) < 72
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert f"scored 72 trajectories ({len(first)} read from the journal)" in res.stdout
    assert sorted(journaled(journal)) == sorted(map(str, many.glob("*.npz")))  # each file once


IDLE_HELPER = """
import os, signal, sys
from fastrl.assess.scoring import Scorer
from fastrl.runner.score.helper import Helper
from fastrl.spec import load_spec
helper = Helper(Scorer(load_spec(sys.argv[1])))
print(helper.submit(os.getpid).result(), flush=True)  # the worker's pid; it then waits for its next task
os.kill(os.getpid(), signal.SIGKILL)
"""


def test_a_scoring_helper_left_idle_by_a_killed_parent_exits(tmp_path):
    out = tmp_path / "pid.txt"
    with open(out, "w") as f:
        cmd = [sys.executable, "-c", IDLE_HELPER, str(spec_file("tracelines"))]
        assert subprocess.run(cmd, stdout=f, stderr=subprocess.DEVNULL, timeout=120).returncode == -signal.SIGKILL
    try:  # it watches its parent: no task will ever come
        _, alive = psutil.wait_procs([psutil.Process(int(out.read_text()))], timeout=10)
    except psutil.NoSuchProcess:
        alive = []
    assert all(p.status() == psutil.STATUS_ZOMBIE for p in alive)


def test_a_corrupt_file_is_named_a_torn_line_rescored_and_another_scorers_journal_replaced(cohort, tmp_path):
    folder, spec = cohort
    files = tmp_path / "in"
    shutil.copytree(folder, files)
    (files / "t2b.npz").write_bytes(b"not an archive")
    out = tmp_path / "out" / "scores.json"
    run = dict(spec_path=spec, output=out, reference_episodes=1, pictures=False, progress=False)
    first = assess([files], **run)
    assert len(first.report["trajectories"]) == 6 and len(first.report["problems"]) == 1
    assert "t2b.npz" in first.report["problems"][0]
    journal = out.parent / "scores.journal.jsonl"
    text = journal.read_text()
    journal.write_text(text[: text.rindex("t5.npz") + 20])  # killed half way through t5's line
    again = assess([files], **run)
    assert again.resumed == 6 and without_seconds(again.report) == without_seconds(first.report)
    assert journaled(journal).count(str(files / "t5.npz")) == 1  # the torn line is dropped, t5 scored again
    os.utime(files / "t1.npz")  # a file touched since is scored again
    assert assess([files], **run).resumed == 6
    header = json.loads(journal.read_text().splitlines()[0])
    journal.write_text(json.dumps({**header, "identity": "another scorer"}) + "\n" + "\n".join(text.splitlines()[1:]))
    said = io.StringIO()
    replaced = assess([files], **run, console=Console(file=said, width=300))
    assert "written by another scorer" in said.getvalue() and str(journal) in said.getvalue()
    assert replaced.resumed == 0 and without_seconds(replaced.report) == without_seconds(first.report)
    assert Journal(path=journal, identity=header["identity"]).lines()  # rewritten under this scorer


def test_the_report_with_a_sample_of_pictures_equals_the_one_scored_in_memory(cohort, tmp_path, monkeypatch):
    folder, spec = cohort
    scorer = Scorer(_spec())
    files = sorted(folder.glob("*.npz"))
    references = reference_scores(scorer, 1)
    scored, problems = score_files(scorer, files)
    normalise(scored, references)
    in_memory = build_report(scored, references, problems, learned=False)
    monkeypatch.setattr(archive, "SAMPLE", 3)
    monkeypatch.setattr(assessment, "SAMPLE", 3)
    for parallel in (False, True):
        out = tmp_path / f"out-{parallel}" / "scores.json"
        result = assess([folder], spec_path=spec, output=out, reference_episodes=1, progress=False, parallel=parallel)
        report = json.loads(out.read_text())
        assert without_seconds(report) == json.loads(json.dumps(in_memory))
        assert "draw 3 of the 6 trajectories" in report["pictures_sample"]
        assert {"paths", "deviation", "distributions", "rrd"} <= set(result.files)
        assert (out.parent / "scores_paths.png").stat().st_size > 10_000


def test_scores_on_a_local_ray_equal_those_scored_here(airl_run, cohort, tmp_path):  # noqa: F811
    folder, _ = cohort
    here = tmp_path / "here" / "scores.json"
    assess([folder], run=airl_run, output=here, reference_episodes=1, pictures=False, progress=False, parallel=False)
    ray = tmp_path / "ray" / "scores.json"
    result = assess([folder], run=airl_run, output=ray, reference_episodes=1, progress=False, address="local")
    reports = [without_seconds(json.loads(p.read_text())) for p in (here, ray)]
    assert reports[0] == reports[1] and all(r["reward_raw"] is not None for r in reports[1]["trajectories"])
    assert sorted(journaled(ray.parent / "scores.journal.jsonl")) == sorted(map(str, folder.glob("*.npz")))
    assert (ray.parent / "scores_paths.png").stat().st_size > 10_000 and "rrd" in result.files


def test_recordings_ranked_one_at_a_time_keep_only_the_best_trajectories(cohort):
    folder, _ = cohort
    (folder.parent / "bad").mkdir(exist_ok=True)
    (folder.parent / "bad" / "x.npz").write_bytes(b"broken")
    everything, skipped = rank_recordings(_spec(), [folder, folder.parent / "bad"], "heuristic")
    bounded, skipped_too = rank_recordings(_spec(), [folder, folder.parent / "bad"], "heuristic", top=2)
    assert skipped == skipped_too and "x.npz" in skipped[0]
    assert [(s.name, s.scores["heuristic"]) for s, _ in bounded] == [
        (s.name, s.scores["heuristic"]) for s, _ in everything
    ]
    assert [t is not None for _, t in bounded] == [True, True, False, False, False, False]
    np.testing.assert_array_equal(bounded[1][1].portal, everything[1][1].portal)
    assert all(len(s.tip) == 0 for s, _ in bounded) and all(len(s.tip) > 0 for s, _ in everything)
