"""Env throughput of the bundled FAST tasks: env step vs raw MuJoCo physics vs gymnasium.make.

    python bench/env_throughput.py [--seconds S] [--rounds R] [--tasks a,b] [--json OUT]
    python bench/env_throughput.py --profile tracelines     # cProfile of the env step

For each task this times, in interleaved rounds of equal work (median and min reported):
  env       fastrl.make("specs/<task>.yaml").step on a fixed, seeded random action sequence,
            resetting on termination/truncation (resets are inside the timed loop);
  physics   mujoco.mj_step(model, data, nstep=substeps) on the SAME compiled model with a fresh
            MjData, replaying the ctrl sequence the env produced for those actions (and the
            env's states at its resets), so both walk the same trajectory with the same contacts;
  gym       the same loop through gymnasium.make("fastrl/<Id>-v0") (its wrappers included);
then one reset() and one 128x128 endoscope render(). Targets are reported, never asserted.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # before anything imports mujoco

import argparse
import cProfile
import json
import platform
import pstats
import statistics
import sys
import time
from pathlib import Path

import gymnasium
import mujoco
import numpy as np
from common import cpu_model, cpuinfo, git_commit, load_figures, utc_stamp

import fastrl  # (registers the fastrl/<Id>-v0 ids)

ROOT = Path(__file__).resolve().parent.parent
TASKS = ("imagecentring", "periscoping", "tracelines")
GYM_IDS = {name: f"fastrl/{task_id}-v0" for task_id, name in fastrl.TASK_IDS.items()}
TARGET_STEPS_PER_S = 5000.0  # env steps/s per task, single env
TARGET_OVERHEAD_RATIO = 1.0  # env overhead <= physics time
STATE = mujoco.mjtState.mjSTATE_INTEGRATION
N_ACTIONS = 20_000  # pre-drawn actions, cycled
N_RECORD = 4_000  # env steps recorded (ctrl + reset states) for the physics replay; also warm-up
N_RESETS, N_RENDERS = 30, 30


# ---- machine -------------------------------------------------------------------------------
def machine_info() -> dict:
    """CPU, cores, load, library versions, git commit and UTC date."""
    mhz = cpuinfo("cpu MHz")
    return {
        "date_utc": utc_stamp(),
        "cpu": cpu_model(),
        "cpu_mhz": float(mhz) if mhz else None,
        "cores": os.cpu_count(),
        "cores_usable": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "loadavg": load_figures(),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "mujoco": mujoco.__version__,
        "gymnasium": gymnasium.__version__,
        "fastrl": fastrl.__version__,
        "git_commit": git_commit(),
        "mujoco_gl": os.environ.get("MUJOCO_GL"),
    }


# ---- timed loops ---------------------------------------------------------------------------
def draw_actions(space, seed: int, n: int = N_ACTIONS) -> list:
    """A fixed action sequence from a seeded numpy RNG (ints for Discrete, arrays for Box)."""
    rng = np.random.default_rng(seed)
    if isinstance(space, gymnasium.spaces.Discrete):
        return (int(space.start) + rng.integers(0, int(space.n), n)).tolist()
    return list(rng.uniform(space.low, space.high, (n, *space.shape)).astype(space.dtype))


def env_loop(env, actions: list, start: int, n: int) -> tuple[float, int]:
    """Step n actions from index start, resetting at episode ends; return (seconds, resets)."""
    step, reset, count, resets = env.step, env.reset, len(actions), 0
    t0 = time.perf_counter()
    for k in range(start, start + n):
        _, _, terminated, truncated, _ = step(actions[k % count])
        if terminated or truncated:
            reset()
            resets += 1
    return time.perf_counter() - t0, resets


def physics_loop(model, data, ctrls: list, states: dict, substeps: int, start: int, n: int) -> float:
    """Replay recorded ctrl (and reset states) through mj_step(nstep=substeps); return seconds."""
    step, set_state, get, ctrl, count = mujoco.mj_step, mujoco.mj_setState, states.get, data.ctrl, len(ctrls)
    t0 = time.perf_counter()
    for k in range(start, start + n):
        j = k % count
        state = get(j)
        if state is not None:
            set_state(model, data, state, STATE)
        ctrl[:] = ctrls[j]
        step(model, data, nstep=substeps)
    return time.perf_counter() - t0


def record(env, actions: list, seed: int, n: int = N_RECORD):
    """Run the env n steps (the warm-up); keep ctrl per step, state at resets, µs/step, contacts."""
    env.reset(seed=seed)
    model, data = env.unwrapped.model, env.unwrapped.data
    buf = np.empty(mujoco.mj_stateSize(model, STATE))
    mujoco.mj_getState(model, data, buf, STATE)
    states, ctrls, ncon = {0: buf.copy()}, [], 0
    t0 = time.perf_counter()
    for k in range(n):
        _, _, terminated, truncated, _ = env.step(actions[k % len(actions)])
        ctrls.append(data.ctrl.copy())
        ncon += data.ncon
        if terminated or truncated:
            env.reset()
            mujoco.mj_getState(model, data, buf, STATE)
            states[k + 1] = buf.copy()
    return ctrls, states, 1e6 * (time.perf_counter() - t0) / n, ncon / n


def wrapper_cost(genv, n: int = 100_000) -> float:
    """µs per step of gymnasium's wrapper chain alone: the inner step replaced by a canned reply."""
    inner = genv.unwrapped
    reply = (np.zeros(inner.observation_space.shape, np.float32), 0.0, False, False, {})

    def stub(action):
        return reply

    inner.step = stub  # instance attribute shadows FastEnv.step; removed below
    try:
        t0 = time.perf_counter()
        for _ in range(n):
            genv.step(0)
        wrapped = time.perf_counter() - t0
        t0 = time.perf_counter()
        for _ in range(n):
            inner.step(0)
        bare = time.perf_counter() - t0
    finally:
        del inner.step
    return 1e6 * (wrapped - bare) / n


def stats(seconds: list[float], n: int) -> dict:
    """Median, min and max of per-step microseconds over the rounds."""
    us = [1e6 * s / n for s in seconds]
    return {"median_us": statistics.median(us), "min_us": min(us), "max_us": max(us), "rounds_us": us}


# ---- one task ------------------------------------------------------------------------------
def bench_task(name: str, seconds: float, rounds: int, seed: int, log) -> dict:
    """All figures of one task."""
    t_setup = time.perf_counter()
    env = fastrl.make(str(ROOT / "specs" / f"{name}.yaml"))
    model, substeps = env.unwrapped.model, int(env.unwrapped.substeps)
    actions = draw_actions(env.action_space, seed)
    ctrls, states, _, ncon = record(env, actions, seed)
    gym_id = GYM_IDS.get(name)
    genv = gymnasium.make(gym_id) if gym_id in gymnasium.registry else None
    data = mujoco.MjData(model)
    setup_s = time.perf_counter() - t_setup

    env.reset(seed=seed)
    calib_s, _ = env_loop(env, actions, 0, 300)  # the record pass is slower (copies, first steps)
    n = max(200, int(seconds * 300 / calib_s))  # equal work in every round, about `seconds` long
    env.reset(seed=seed)
    wrapper_us = None
    if genv is not None:
        genv.reset(seed=seed)
        env_loop(genv, actions, 0, 300)  # warm-up (and the passive checker's first step)
        wrapper_us = wrapper_cost(genv)
        genv.reset(seed=seed)
    physics_loop(model, data, ctrls, states, substeps, 0, 300)
    log(f"[dim]{name}: setup {setup_s:.1f} s, {rounds} rounds x {n} steps per measurement[/dim]")

    runs = {"env": [], "physics": [], "gym": []}
    resets = {"env": 0, "gym": 0}
    cursor = {"env": 0, "physics": 0, "gym": 0}
    kinds = ["env", "physics"] + (["gym"] if genv is not None else [])
    for r in range(rounds):
        for kind in kinds[r % len(kinds) :] + kinds[: r % len(kinds)]:  # rotate the order each round
            if kind == "physics":
                secs = physics_loop(model, data, ctrls, states, substeps, cursor[kind], n)
            else:
                secs, count = env_loop(env if kind == "env" else genv, actions, cursor[kind], n)
                resets[kind] += count
            cursor[kind] += n
            runs[kind].append(secs)

    reset_ms = []
    for i in range(N_RESETS):
        t0 = time.perf_counter()
        env.reset(seed=seed + 1 + i)
        reset_ms.append(1e3 * (time.perf_counter() - t0))
    render = {}
    try:
        t0 = time.perf_counter()
        image = env.render()
        render["first_ms"] = 1e3 * (time.perf_counter() - t0)
        render["shape"] = list(image.shape)
        times = []
        for i in range(N_RENDERS):
            env.step(actions[i])
            t0 = time.perf_counter()
            env.render()
            times.append(1e3 * (time.perf_counter() - t0))
        render.update(median_ms=statistics.median(times), min_ms=min(times))
    except Exception as exc:  # noqa: BLE001 - no GL on this machine is a result, not a crash
        render["error"] = f"{type(exc).__name__}: {exc}"
    env.close()
    if genv is not None:
        genv.close()

    out = {
        "substeps": substeps,
        "timestep_s": float(model.opt.timestep),
        "steps_per_round": n,
        "rounds": rounds,
        "setup_s": setup_s,
        "mean_contacts": ncon,
        "env": stats(runs["env"], n),
        "physics": stats(runs["physics"], n),
        "env_resets": resets["env"],
        "env_steps": n * rounds,
        "reset_ms": {"median": statistics.median(reset_ms), "min": min(reset_ms)},
        "render": render,
    }
    env_us, phys_us = out["env"]["median_us"], out["physics"]["median_us"]
    out["env"]["steps_per_s"] = 1e6 / env_us
    out["env"]["best_steps_per_s"] = 1e6 / out["env"]["min_us"]
    out["physics"]["steps_per_s"] = 1e6 / phys_us
    out["physics"]["best_steps_per_s"] = 1e6 / out["physics"]["min_us"]
    out["physics"]["us_per_substep"] = phys_us / substeps
    out["overhead_us"] = env_us - phys_us
    out["overhead_ratio"] = (env_us - phys_us) / phys_us
    out["overhead_min_us"] = out["env"]["min_us"] - out["physics"]["min_us"]
    if genv is not None:
        out["gym"] = stats(runs["gym"], n)
        out["gym"]["id"] = gym_id
        out["gym"]["steps_per_s"] = 1e6 / out["gym"]["median_us"]
        out["gym"]["wrapper_us"] = out["gym"]["median_us"] - env_us
        out["gym"]["wrapper_isolated_us"] = wrapper_us
        out["gym_resets"] = resets["gym"]
    out["pass_steps_per_s"] = out["env"]["steps_per_s"] >= TARGET_STEPS_PER_S
    out["pass_overhead"] = out["overhead_ratio"] <= TARGET_OVERHEAD_RATIO
    return out


# ---- report --------------------------------------------------------------------------------
def _verdict(ok: bool) -> str:
    return "[bold green]PASS[/]" if ok else "[bold red]FAIL[/]"


def print_report(console, info: dict, results: dict, elapsed: float) -> None:
    """Machine header, one column per task, targets with pass/fail."""
    from rich.table import Table

    console.print(f"[bold]fastrl env throughput[/]  {info['date_utc']}  (git {info['git_commit']})")
    console.print(
        f"CPU: {info['cpu']} @ {info['cpu_mhz']} MHz, {info['cores']} cores "
        f"({info['cores_usable']} usable), load avg {' '.join(info['loadavg'])}"
    )
    console.print(
        f"Python {info['python']}, numpy {info['numpy']}, mujoco {info['mujoco']}, "
        f"gymnasium {info['gymnasium']}, fastrl {info['fastrl']}, "
        f"MUJOCO_GL={info['mujoco_gl']}"
    )
    names = list(results)
    console.print(
        "Single env, state observation, the spec's action mode; times are medians "
        "over rounds, \\[min | max] in brackets."
    )
    table = Table()
    table.add_column("metric", style="bold")
    for name in names:
        table.add_column(name, justify="right")

    def row(label, fn):
        cells = []
        for name in names:
            try:
                cells.append(fn(results[name]))
            except KeyError:
                cells.append("n/a")
        table.add_row(label, *cells)

    def spread(s):
        return f"{s['median_us']:.0f} [{s['min_us']:.0f} | {s['max_us']:.0f}]"

    row("substeps x timestep", lambda r: f"{r['substeps']} x {1e3 * r['timestep_s']:.1f} ms")
    row("rounds x steps", lambda r: f"{r['rounds']} x {r['steps_per_round']}")
    row("env steps/s (best)", lambda r: f"{r['env']['steps_per_s']:,.0f} ({r['env']['best_steps_per_s']:,.0f})")
    row("env µs/step", lambda r: spread(r["env"]))
    row("  resets in timed steps", lambda r: f"{r['env_resets']} / {r['env_steps']:,}")
    row(
        "physics-only env steps/s (best)",
        lambda r: f"{r['physics']['steps_per_s']:,.0f} ({r['physics']['best_steps_per_s']:,.0f})",
    )
    row("physics µs/env step", lambda r: spread(r["physics"]))
    row("  physics µs/substep", lambda r: f"{r['physics']['us_per_substep']:.1f}")
    row("  contacts per step (mean)", lambda r: f"{r['mean_contacts']:.2f}")
    row("env overhead µs/step", lambda r: f"{r['overhead_us']:.0f} (mins: {r['overhead_min_us']:.0f})")
    row("overhead / physics", lambda r: f"{r['overhead_ratio']:.2f}")
    row("gym.make env steps/s", lambda r: f"{r['gym']['steps_per_s']:,.0f}")
    row("gym.make µs/step", lambda r: spread(r["gym"]))
    row("  gym - env µs/step", lambda r: f"{r['gym']['wrapper_us']:+.1f}")
    row("  wrappers alone µs/step", lambda r: f"{r['gym']['wrapper_isolated_us']:.2f}")
    row("reset() ms (min)", lambda r: f"{r['reset_ms']['median']:.2f} ({r['reset_ms']['min']:.2f})")
    row(
        "render() ms (min)",
        lambda r: (
            f"{r['render']['median_ms']:.2f} ({r['render']['min_ms']:.2f})"
            if "median_ms" in r["render"]
            else r["render"]["error"][:40]
        ),
    )
    row("  first render() ms", lambda r: f"{r['render']['first_ms']:.0f} {'x'.join(map(str, r['render']['shape']))}")
    row(f"≥ {TARGET_STEPS_PER_S:,.0f} env steps/s", lambda r: _verdict(r["pass_steps_per_s"]))
    row("overhead ≤ physics", lambda r: _verdict(r["pass_overhead"]))
    console.print(table)
    console.print(
        f"Targets: ≥ {TARGET_STEPS_PER_S:,.0f} env steps/s per task (single env, median), "
        "env overhead ≤ physics time. Reported, not asserted."
    )
    for name, r in results.items():
        if r["physics"]["steps_per_s"] < TARGET_STEPS_PER_S:
            console.print(
                f"  {name}: physics alone allows {r['physics']['steps_per_s']:,.0f} "
                f"steps/s < {TARGET_STEPS_PER_S:,.0f}: the model must get cheaper."
            )
    loads = [float(x) for x in info["loadavg"][:1] + info.get("loadavg_end", [])[:1]]
    busy = bool(loads) and max(loads) > (info["cores_usable"] or info["cores"] or 1)
    console.print(
        f"Load average {' '.join(info['loadavg'])} at the start, "
        f"{' '.join(info.get('loadavg_end', []))} at the end"
        + (": other jobs shared the CPU, figures are pessimistic." if busy else ".")
    )
    console.print(
        f"[dim]Overhead = env µs/step - physics µs/step (medians); physics replays the "
        f"env's own ctrl trajectory. Total time {elapsed:.0f} s.[/dim]"
    )


# ---- profile -------------------------------------------------------------------------------
def profile_task(name: str, seconds: float, seed: int, top: int, console) -> dict:
    """cProfile the env step loop; print the top functions in µs per env step (tottime)."""
    env = fastrl.make(str(ROOT / "specs" / f"{name}.yaml"))
    actions = draw_actions(env.action_space, seed)
    env.reset(seed=seed)
    _, _, warm_us, _ = record(env, actions, seed, n=1000)
    n = max(500, int(seconds / (warm_us * 1e-6)))
    env.reset(seed=seed)
    prof = cProfile.Profile()
    prof.enable()
    env_loop(env, actions, 0, n)
    prof.disable()
    st = pstats.Stats(prof)
    rows = []
    for (file, line, func), (_, ncalls, tottime, cumtime, _) in st.stats.items():
        where = f"{Path(file).name}:{line}({func})" if line else func
        rows.append(
            {
                "function": where,
                "calls_per_step": ncalls / n,
                "tottime_us_per_step": 1e6 * tottime / n,
                "cumtime_us_per_step": 1e6 * cumtime / n,
            }
        )
    rows.sort(key=lambda r: -r["tottime_us_per_step"])
    total = sum(r["tottime_us_per_step"] for r in rows)
    console.print(
        f"[bold]cProfile of {name}.step[/], {n} steps: {total:.0f} µs/step under "
        "the profiler (it inflates Python calls)"
    )
    console.print("   self µs     cum µs  calls/step  function")
    for r in rows[:top]:
        console.print(
            f"{r['tottime_us_per_step']:10.1f} {r['cumtime_us_per_step']:10.1f} "
            f"{r['calls_per_step']:11.1f}  {r['function']}"
        )
    return {"task": name, "steps": n, "total_us_per_step": total, "top": rows[:top]}


# ---- main ----------------------------------------------------------------------------------
def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=1.2, help="seconds per measurement per round")
    p.add_argument("--rounds", type=int, default=5, help="interleaved rounds (median and min reported)")
    p.add_argument("--tasks", default=",".join(TASKS), help="comma-separated spec names in specs/")
    p.add_argument("--seed", type=int, default=0, help="seed of the action sequence and resets")
    p.add_argument("--json", type=Path, default=None, help="write all figures to this JSON file")
    p.add_argument(
        "--profile",
        metavar="TASK",
        default=None,
        help="instead of the benchmark, cProfile TASK's env step and list the top costs",
    )
    p.add_argument("--top", type=int, default=15, help="rows of the --profile listing")
    args = p.parse_args(argv)

    from rich.console import Console

    console = Console(width=None if sys.stdout.isatty() else 120)
    info = machine_info()
    if args.profile:
        out = {"machine": info, "profile": profile_task(args.profile, 3 * args.seconds, args.seed, args.top, console)}
        if args.json:
            args.json.write_text(json.dumps(out, indent=2))
        return 0

    tasks = [t.strip() for t in args.tasks.split(",") if t.strip()]
    missing = [t for t in tasks if not (ROOT / "specs" / f"{t}.yaml").exists()]
    if missing:
        p.error(f"no spec for {missing} in {ROOT / 'specs'}")
    t0 = time.perf_counter()
    results = {}
    for name in tasks:
        results[name] = bench_task(name, args.seconds, args.rounds, args.seed, console.print)
    elapsed = time.perf_counter() - t0
    info["loadavg_end"] = load_figures()
    print_report(console, info, results, elapsed)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        config = {
            "seconds": args.seconds,
            "rounds": args.rounds,
            "seed": args.seed,
            "targets": {"env_steps_per_s": TARGET_STEPS_PER_S, "overhead_over_physics": TARGET_OVERHEAD_RATIO},
        }
        args.json.write_text(
            json.dumps({"machine": info, "config": config, "elapsed_s": elapsed, "tasks": results}, indent=2)
        )
        console.print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
