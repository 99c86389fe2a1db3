"""Rerun's native viewer decodes H.264 only through an ffmpeg executable: `fastrl view` brings one."""

import os
import subprocess

from fastrl.log.video import viewer_env


def test_viewer_env_puts_a_working_ffmpeg_on_a_path_without_one(tmp_path, monkeypatch):
    monkeypatch.setenv("FASTRL_CACHE", str(tmp_path / "cache"))
    bare = {"PATH": str(tmp_path / "empty"), "HOME": os.environ.get("HOME", "")}
    env = viewer_env(bare)
    first = env["PATH"].split(os.pathsep)[0]
    assert first == str(tmp_path / "cache" / "bin") and env["PATH"].endswith(bare["PATH"])
    res = subprocess.run(["ffmpeg", "-hide_banner", "-decoders"], env=env, capture_output=True, text=True, timeout=60)
    assert res.returncode == 0 and " h264 " in res.stdout  # it decodes H.264
    assert viewer_env(env) == env  # already there: nothing added twice


def test_viewer_env_keeps_an_ffmpeg_already_on_path(tmp_path):
    own = tmp_path / "bin"
    own.mkdir()
    (own / "ffmpeg").write_text("#!/bin/sh\n")
    (own / "ffmpeg").chmod(0o755)
    env = viewer_env({"PATH": str(own)})
    assert env == {"PATH": str(own)}
