"""Pixel observations on a 2-core CPU: renderer options per size, env steps/s with images, the encoder's cost.

    python bench/pixel_throughput.py [--sizes 32,48,64] [--seconds S] [--json OUT]

In one run, on TraceLines states along a seeded random walk (the same states for every option):
  renderers   frames/s of each way to make the policy's frame, one process:
              gl-full     mujoco.Renderer on the whole scene (the compiled model's lean visual settings)
              gl-culled   the shipped renderer (fastrl.env.images): geoms off the view cone not drawn, rgb
              gl-depth, gl-segmentation   the shipped renderer's other kinds
              rangefinder MuJoCo's per-pixel rangefinder on the endoscope camera (depth without GL; the tip
                          geom around the lens removed from the bench's copy of the model, else every ray hits it)
              multiray    mj_multiRay, one ray per pixel (the scope's shaft body and group 3 excluded)
              with each ray option's largest difference from GL depth (mm) as its faithfulness;
  2 cores     the shipped renderer in 2 processes at once: frames/s across both (the target: >= 2,000);
  env         steps/s of 16 envs stepped by 2 processes (fastrl's vectorised env) with random actions:
              kinematic state against rgb frames per size (stack 2);
  encoder     fastrl's CNN (PixelEncoder) forward + backward on a batch of 256 per size and stack, against
              SB3's NatureCNN at the sizes it takes (>= 36 px), one torch thread (as training uses).
The machine, its load before and after, and the versions are printed beside the figures.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # before anything imports mujoco

import argparse
import json
import multiprocessing as mp
import time
from pathlib import Path

import mujoco
import numpy as np
from common import cpu_model, load_average, load_figures, utc_stamp

ROOT = Path(__file__).resolve().parent.parent
SPEC = ROOT / "specs" / "tracelines.yaml"
N_STATES = 300


def machine() -> dict:
    """CPU model, cores, load average, versions, UTC date."""
    import stable_baselines3
    import torch

    return {
        "date_utc": utc_stamp(),
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "load": load_figures(),
        "mujoco": mujoco.__version__,
        "torch": torch.__version__,
        "sb3": stable_baselines3.__version__,
        "mujoco_gl": os.environ.get("MUJOCO_GL"),
    }


def walk(n: int = N_STATES, seed: int = 0) -> tuple:
    """The kinematic env and the qpos of n states along a seeded random walk (resetting on episode ends)."""
    from fastrl.env.fast_env import FastEnv
    from fastrl.spec import load_spec

    env = FastEnv(load_spec(SPEC))
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    states = []
    for a in rng.integers(0, 11, n):
        _, _, term, trunc, _ = env.step(int(a))
        states.append(env.data.qpos.copy())
        if term or trunc:
            env.reset()
    return env, states


def timed(env, states, render, seconds: float) -> tuple[float, list]:
    """Frames/s of render(data) over the states (kinematics outside the clock), cycling until `seconds`."""
    m, d = env.model, env.data
    spent, frames, out = 0.0, 0, []
    while spent < seconds or frames < len(states):
        q = states[frames % len(states)]
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_camlight(m, d)
        t = time.perf_counter()
        img = render(d)
        spent += time.perf_counter() - t
        if frames < len(states):
            out.append(np.array(img, copy=True))
        frames += 1
    return frames / spent, out


def gl_options(env, size: int) -> dict:
    """The GL renderers at one size: render(data) callables."""
    from fastrl.env.images import _OPTION, EndoscopeFrames
    from fastrl.spec.images import Image

    full = mujoco.Renderer(env.model, size, size)

    def gl_full(d):
        full.update_scene(d, camera=env.task.camera, scene_option=_OPTION)
        return full.render()

    opts = {"gl-full": gl_full}
    for kind in ("rgb", "depth", "segmentation"):
        frames = EndoscopeFrames(task=env.task, model=env.model, image=Image(size=size, kind=kind))
        name = "gl-culled" if kind == "rgb" else f"gl-{kind}"
        opts[name] = lambda d, f=frames: f.frame(d, 0)
    return opts


def rangefinder(size: int, env):
    """A copy of the model with a per-pixel rangefinder on the endoscope; render(data) gives depth in mm."""
    from fastrl.model.compiler import build_mjspec

    ms, _ = build_mjspec(env.task_spec)
    ms.camera("endoscope").resolution = [size, size]
    ms.delete(ms.geom("tip"))  # the camera sits inside it: every ray would stop there
    sensor = ms.add_sensor(
        name="depth",
        type=mujoco.mjtSensor.mjSENS_RANGEFINDER,
        objtype=mujoco.mjtObj.mjOBJ_CAMERA,
        objname="endoscope",
    )
    sensor.intprm[0] = 1 << int(mujoco.mjtRayDataField.mjRAYDATA_DEPTH)
    m = ms.compile()
    d = mujoco.MjData(m)
    m.geom_rgba[:] = np.delete(env.model.geom_rgba, env.task.tip_geom, axis=0)  # the cue colours (alpha 0: unseen)

    def render(src):
        d.qpos[:] = src.qpos
        mujoco.mj_kinematics(m, d)
        mujoco.mj_camlight(m, d)
        t = time.perf_counter()
        mujoco.mj_sensorPos(m, d)
        render.spent += time.perf_counter() - t
        return d.sensordata.reshape(size, size) * 1000.0

    render.spent = 0.0
    return render


def multiray(size: int, env):
    """mj_multiRay through every pixel centre; render(data) gives depth along the optical axis in mm."""
    m, cam = env.model, env.task.camera
    f = 0.5 * size / np.tan(0.5 * np.radians(m.cam_fovy[cam]))
    u, v = np.meshgrid(np.arange(size) + 0.5 - size / 2, -(np.arange(size) + 0.5 - size / 2))
    local = np.stack([u / f, v / f, -np.ones_like(u)], -1).reshape(-1, 3)
    unit = local / np.linalg.norm(local, axis=1, keepdims=True)
    groups = np.array([1, 1, 1, 0, 1, 1], np.uint8)
    exclude = m.body("scope_shaft").id
    geomid, dist = np.zeros(size * size, np.int32), np.zeros(size * size)

    def render(d):
        rot = d.cam_xmat[cam].reshape(3, 3)
        vec = unit @ rot.T
        mujoco.mj_multiRay(m, d, d.cam_xpos[cam], vec.ravel(), groups, 1, exclude, geomid, dist, None, size * size, 1.0)
        return (dist * -unit[:, 2]).reshape(size, size) * 1000.0  # ray length -> depth along the axis

    return render


def renderers(sizes, seconds: float) -> list[dict]:
    """Frames/s of every option per size, with the ray options' largest depth difference from GL (mm)."""
    env, states = walk()
    rows = []
    for size in sizes:
        gl = gl_options(env, size)
        results = {}
        for name, fn in gl.items():
            fps, out = timed(env, states, fn, seconds)
            results[name] = (fps, out)
        reference = np.stack(results["gl-depth"][1])[..., 0].astype(float)
        full, culled = np.stack(results["gl-full"][1]), np.stack(results["gl-culled"][1])
        for name, fps_out in results.items():
            row = {"size": size, "option": name, "frames_per_s": round(fps_out[0], 1)}
            if name == "gl-culled":
                row["pixels_equal_gl_full"] = bool(np.array_equal(full, culled))
            rows.append(row)
        for name, make in (("rangefinder", rangefinder), ("multiray", multiray)):
            fn = make(size, env)
            fps, out = timed(env, states, fn, seconds)
            if name == "rangefinder":  # only the sensor's own time: the bench's copy redoes the kinematics
                fps = len(states) / fn.spent if fn.spent else fps
            depth = np.clip(np.rint(np.stack(out)), 0, 255)
            diff = np.abs(depth - reference)
            rows.append(
                {
                    "size": size,
                    "option": name,
                    "frames_per_s": round(fps, 1),
                    "depth_diff_mm_p99": float(np.percentile(diff, 99)),
                    "depth_diff_mm_max": float(diff.max()),
                }
            )
    return rows


def _render_worker(size: int, seconds: float, queue) -> None:
    """One process rendering the shipped rgb frames for `seconds`: its frame count and time."""
    env, states = walk()
    from fastrl.env.images import EndoscopeFrames
    from fastrl.spec.images import Image

    frames = EndoscopeFrames(task=env.task, model=env.model, image=Image(size=size))
    fps, _ = timed(env, states, lambda d: frames.frame(d, 0), seconds)
    queue.put(fps)


def two_cores(size: int, seconds: float) -> dict:
    """The shipped renderer in two processes at once."""
    ctx = mp.get_context("fork")  # before this process makes a GL context: each child makes its own
    queue = ctx.Queue()
    procs = [ctx.Process(target=_render_worker, args=(size, seconds, queue)) for _ in range(2)]
    for p in procs:
        p.start()
    fps = [queue.get() for _ in procs]
    for p in procs:
        p.join()
    return {"size": size, "processes": 2, "frames_per_s_total": round(sum(fps), 1), "per_process": fps}


def env_steps(sizes, seconds: float) -> list[dict]:
    """Steps/s of 16 envs on 2 processes with random actions: kinematic, then rgb frames per size."""
    from fastrl.agents.sb3 import make_vec_env
    from fastrl.spec import load_spec

    rows = []
    for size in [None, *sizes]:
        sets = [] if size is None else [f"observation.image.size={size}", "observation.image.stack=2"]
        spec = load_spec(SPEC, sets)
        venv = make_vec_env(spec, 16, 0, workers=2)
        venv.reset()
        rng = np.random.default_rng(0)
        steps, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            venv.step(rng.integers(0, 11, 16))
            steps += 16
        rows.append(
            {
                "observation": "state" if size is None else f"rgb {size}px x2",
                "steps_per_s": round(steps / (time.perf_counter() - t0), 1),
            }
        )
        venv.close()
    return rows


def encoder_cost(sizes, batch: int = 256, repeats: int = 5) -> list[dict]:
    """Seconds per forward + backward of a batch: fastrl's PixelEncoder and SB3's NatureCNN, one thread."""
    import torch
    from gymnasium import spaces
    from stable_baselines3.common.torch_layers import NatureCNN

    from fastrl.agents.encoder import PixelEncoder

    torch.set_num_threads(1)
    rows = []
    for size in sizes:
        for channels in (3, 6, 9):
            space = spaces.Box(0, 255, (channels, size, size), np.uint8)
            nets = {"fastrl PixelEncoder (shift 4)": PixelEncoder(space)}
            if size >= 36:
                nets["SB3 NatureCNN"] = NatureCNN(space, features_dim=64)
            x = torch.rand(batch, channels, size, size)
            for name, net in nets.items():
                net.train()
                net(x).sum().backward()
                t = time.perf_counter()
                for _ in range(repeats):
                    net.zero_grad()
                    net(x).sum().backward()
                s = (time.perf_counter() - t) / repeats
                rows.append({"size": size, "channels": channels, "encoder": name, "seconds_per_batch": round(s, 4)})
    return rows


def main() -> None:
    """Run every measurement and print it with the machine and load."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="32,48,64")
    parser.add_argument("--seconds", type=float, default=2.0, help="per timed option")
    parser.add_argument("--policy-size", type=int, default=48, help="the size the shipped pixel spec uses")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    out = {"machine": machine()}
    print(json.dumps(out["machine"]))
    out["two_cores"] = two_cores(args.policy_size, 2 * args.seconds)  # first: before this process holds GL
    print("2 cores, shipped renderer:", out["two_cores"], "(target >= 2000 frames/s)")
    out["env"] = env_steps(sizes, 2 * args.seconds)  # forks its worker: before this process holds GL too
    for row in out["env"]:
        print("env", row)
    out["renderers"] = renderers(sizes, args.seconds)
    for row in out["renderers"]:
        print("renderer", row)
    out["encoder"] = encoder_cost(sizes)
    for row in out["encoder"]:
        print("encoder", row)
    out["load_after"] = load_figures()
    print("load before", " ".join(out["machine"]["load"]), "after", load_average())
    if args.json:
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
