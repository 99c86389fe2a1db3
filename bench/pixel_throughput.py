"""Pixel observations on a 2-core CPU: renderer options per size, env steps/s with images, the encoder's cost.

    python bench/pixel_throughput.py [--sizes 32,48,64] [--rounds R] [--seconds S] [--json OUT]

In one run, on TraceLines states along a seeded random walk (the same states for every option):
  processes   frames/s of the renderer as built (mujoco.Renderer on the compiled model, geoms off the view cone
              not drawn) against the lean one (fastrl.env.lean_scene: the fixed geoms as meshes; the shipped
              default), rgb, per size, in 1 and in 2 processes at once (the target: >= 2,000 frames/s on 2 cores),
              each process rendering every state by both in turn (so both meet the same load); then the same at
              the policy's size with llvmpipe's LP_NUM_THREADS=0 (draws in the calling thread) and =1;
  renderers   one process, every option interleaved frame by frame (the same load for each), frames/s:
              gl-full            mujoco.Renderer on the whole scene (the compiled model's lean visual settings)
              built-KIND         the former renderer (the cull alone) for rgb, depth, segmentation
              lean-KIND          the shipped renderer, with its faithfulness: the share of pixels that differ
                                 from built-KIND, and of those more than 8 levels apart
              rangefinder MuJoCo's per-pixel rangefinder on the endoscope camera (depth without GL; the tip
                          geom around the lens removed from the bench's copy of the model, else every ray hits it)
              multiray    mj_multiRay, one ray per pixel (the scope's shaft body and group 3 excluded)
              with each ray option's largest difference from GL depth (mm) as its faithfulness;
  env         steps/s of 16 envs stepped by 2 processes (fastrl's vectorised env) with random actions:
              kinematic state against rgb frames per size (stack 2), the shipped renderer;
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
        for lean in (False, True):
            frames = EndoscopeFrames(task=env.task, model=env.model, image=Image(size=size, kind=kind), lean=lean)
            frames.frame(env.data, 0)  # the lean model is built (once per process) outside the clock
            opts[f"{'lean' if lean else 'built'}-{kind}"] = lambda d, f=frames: f.frame(d, 0)
    return opts


def interleaved(env, states, options: dict, rounds: int) -> tuple[dict, dict]:
    """Frames/s of each option, the options taking turns on every state (so each meets the same load); frames."""
    m, d = env.model, env.data
    spent, out, names = dict.fromkeys(options, 0.0), {k: [] for k in options}, list(options)
    for r in range(rounds):
        for i, q in enumerate(states):
            d.qpos[:] = q
            mujoco.mj_kinematics(m, d)
            mujoco.mj_camlight(m, d)
            k = (i + r) % len(names)
            for name in names[k:] + names[:k]:
                t = time.perf_counter()
                img = options[name](d)
                spent[name] += time.perf_counter() - t
                if r == 0:
                    out[name].append(np.array(img, copy=True))
    return {k: rounds * len(states) / v for k, v in spent.items()}, out


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


def renderers(sizes, rounds: int) -> list[dict]:
    """Frames/s of every option per size, with the lean and ray options' faithfulness."""
    env, states = walk()
    rows = []
    for size in sizes:
        fps, out = interleaved(env, states, gl_options(env, size), rounds)
        frames = {k: np.stack(v).astype(int) for k, v in out.items()}
        for name, rate in fps.items():
            row = {"size": size, "option": name, "frames_per_s": round(rate, 1)}
            if name == "built-rgb":
                row["pixels_equal_gl_full"] = bool(np.array_equal(frames["gl-full"], frames[name]))
            if name.startswith("lean"):
                diff = np.abs(frames[name] - frames[name.replace("lean", "built")]).max(axis=-1)
                row["pixels_differing_pct"] = round(100 * float((diff > 0).mean()), 4)
                row["pixels_over_8_levels_pct"] = round(100 * float((diff > 8).mean()), 4)
            rows.append(row)
        reference = frames["built-depth"][..., 0].astype(float)
        for name, make in (("rangefinder", rangefinder), ("multiray", multiray)):
            fn = make(size, env)
            rate, out = timed(env, states, fn, 0.0)
            if name == "rangefinder":  # only the sensor's own time: the bench's copy redoes the kinematics
                rate = len(states) / fn.spent if fn.spent else rate
            depth = np.clip(np.rint(np.stack(out)), 0, 255)
            diff = np.abs(depth - reference)
            rows.append(
                {
                    "size": size,
                    "option": name,
                    "frames_per_s": round(rate, 1),
                    "depth_diff_mm_p99": float(np.percentile(diff, 99)),
                    "depth_diff_mm_max": float(diff.max()),
                }
            )
    return rows


def _render_worker(size: int, rounds: int, threads: str | None, queue) -> None:
    """One process rendering rgb frames by the built and the lean renderer in turn: frames/s of each."""
    if threads is not None:
        os.environ["LP_NUM_THREADS"] = threads  # read when this process makes its first GL context
    env, states = walk()
    from fastrl.env.images import EndoscopeFrames
    from fastrl.spec.images import Image

    options = {}
    for lean in (False, True):
        frames = EndoscopeFrames(task=env.task, model=env.model, image=Image(size=size), lean=lean)
        frames.frame(env.data, 0)  # the lean model is built outside the clock
        options["lean" if lean else "built"] = lambda d, f=frames: f.frame(d, 0)
    queue.put(interleaved(env, states, options, rounds)[0])


def processes(n: int, size: int, rounds: int, threads: str | None = None) -> dict:
    """Frames/s of the built and the lean renderer (taking turns frame by frame) in n processes at once."""
    ctx = mp.get_context("fork")  # before this process makes a GL context: each child makes its own
    queue = ctx.Queue()
    procs = [ctx.Process(target=_render_worker, args=(size, rounds, threads, queue)) for _ in range(n)]
    for p in procs:
        p.start()
    fps = [queue.get() for _ in procs]
    for p in procs:
        p.join()
    row = {"size": size, "processes": n, "LP_NUM_THREADS": threads or os.environ.get("LP_NUM_THREADS", "default")}
    for name in ("built", "lean"):
        row[f"{name}_frames_per_s"] = round(sum(f[name] for f in fps), 1)
        row[f"{name}_per_process"] = [round(f[name], 1) for f in fps]
    row["speedup"] = round(row["lean_frames_per_s"] / row["built_frames_per_s"], 2)
    return row


def process_table(sizes, policy_size: int, rounds: int) -> list[dict]:
    """Both renderers per size in 1 and 2 processes, then at the policy's size per llvmpipe thread setting."""
    rows = []
    for size in sizes:
        for n in (1, 2):
            rows.append(processes(n, size, rounds))
            print("processes", rows[-1])
    for threads in ("0", "1"):
        for n in (1, 2):
            rows.append(processes(n, policy_size, rounds, threads))
            print("processes", rows[-1])
    return rows


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
    parser.add_argument("--seconds", type=float, default=2.0, help="half of each env steps/s measurement")
    parser.add_argument("--rounds", type=int, default=2, help="passes over the 300 states per GL renderer")
    parser.add_argument("--policy-size", type=int, default=48, help="the size the shipped pixel spec uses")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    out = {"machine": machine()}
    print(json.dumps(out["machine"]))
    # processes first: they fork before this process holds GL (the target: >= 2,000 frames/s on 2 cores)
    out["processes"] = process_table(sizes, args.policy_size, args.rounds)
    out["env"] = env_steps(sizes, 2 * args.seconds)  # forks its worker: before this process holds GL too
    for row in out["env"]:
        print("env", row)
    out["renderers"] = renderers(sizes, args.rounds)
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
