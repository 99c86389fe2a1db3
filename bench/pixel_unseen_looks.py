"""A pixel policy on domes it never saw: colours and lighting outside the draws of the looks it trained with.

    python bench/pixel_unseen_looks.py RUN [RUN ...] [--json OUT] [--pictures PNG]

Each run's final policy plays its spec's evaluation seeds (acting as the spec says: sampled for
tracelines_pixels) on the looks it trained with (drawn per episode from the evaluation seeds), on the dome as
compiled, and on each dome of DOMES: plate, shell and line recoloured and every light scaled, with no draws. A dome
counts as unseen when every recoloured surface has a channel further from its compiled colour than the run's
`looks.colour` and its light lies outside 1 +- `looks.light`; the bench prints whether it does. Printed per run
and dome: the share of subtasks completed and the success rate. `--pictures` saves the first frame each dome gives.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402
from common import machine_line, utc_stamp  # noqa: E402

from fastrl.env import FastEnv  # noqa: E402
from fastrl.env.images import segmentation_classes  # noqa: E402
from fastrl.runner.runs.runfiles import read_run_spec  # noqa: E402
from fastrl.runner.runs.saved import checkpoint_policy  # noqa: E402
from fastrl.runner.train.evaluate import evaluate  # noqa: E402
from fastrl.spec.images import SEGMENTATION_CLASSES  # noqa: E402

# Held-out domes: RGB of each recoloured surface (the rest as compiled) and the scale of every light.
GREEN_RED = {"plate": (0.45, 0.8, 0.45), "shell": (0.6, 0.75, 0.95), "line": (0.75, 0.1, 0.1)}
PINK_GREEN = {"plate": (0.95, 0.5, 0.6), "shell": (0.5, 0.55, 0.6), "line": (0.1, 0.6, 0.2)}
DARK_YELLOW = {"plate": (0.35, 0.3, 0.3), "shell": (0.5, 0.45, 0.4), "line": (0.9, 0.9, 0.3)}
DOMES = {
    "green plate, red line, dim": (GREEN_RED, 0.6),
    "as compiled, dim": ({}, 0.5),
    "as compiled, bright": ({}, 1.6),
    "pink plate, green line, bright": (PINK_GREEN, 1.5),
    "dark plate, yellow line": (DARK_YELLOW, 1.0),
}


class Dome:
    """Recolours an env's plate, shell and line and scales its lights: a fixed look, the same every episode."""

    def __init__(self, env: FastEnv):
        self.model = m = env.model
        self.classes = segmentation_classes(m, env.task)
        self.rgba = m.geom_rgba.copy()
        self.lights = (m.vis.headlight.ambient.copy(), m.vis.headlight.diffuse.copy(), m.light_diffuse.copy())

    def surface(self, name: str) -> np.ndarray:
        """The geoms of one surface class."""
        return self.classes == SEGMENTATION_CLASSES.index(name)

    def apply(self, colours: dict, light: float) -> None:
        """Set the dome's colours and light scale in the env's model (the renderer copies them every frame)."""
        m = self.model
        m.geom_rgba[:] = self.rgba
        for name, rgb in colours.items():
            m.geom_rgba[self.surface(name), :3] = rgb
        m.vis.headlight.ambient[:] = self.lights[0] * light
        m.vis.headlight.diffuse[:] = self.lights[1] * light
        m.light_diffuse[:] = self.lights[2] * light

    def unseen(self, colours: dict, light: float, looks) -> bool:
        """Whether every recoloured surface and the light lie outside the training draws of `looks`."""
        far = looks.colour if looks else 0.0
        for name, rgb in colours.items():
            offset = np.abs(self.rgba[self.surface(name), :3] - np.asarray(rgb)).max(axis=1)
            if not (offset > far).all():
                return False
        return abs(light - 1.0) > (looks.light if looks else 0.0)


def on_domes(run: Path, pictures: list | None) -> dict:
    """The run's final policy on its trained looks, the compiled dome and every held-out dome."""
    spec = read_run_spec(run)
    looks = spec.observation.image.looks
    seeds = [spec.evaluate.seed + i for i in range(spec.evaluate.episodes)]
    image = spec.observation.image.model_copy(update={"looks": None})
    plain = spec.model_copy(update={"observation": spec.observation.model_copy(update={"image": image})})
    cases = {"trained looks": None, "as compiled": ({}, 1.0), **DOMES}
    out = {}
    for name, dome in cases.items():
        env, t0 = FastEnv(spec if dome is None else plain), time.perf_counter()
        row = {"unseen": False}
        if dome is not None:
            d = Dome(env)
            d.apply(*dome)
            row["unseen"] = d.unseen(*dome, looks)
        if pictures is not None:
            pictures.append((name, env.reset(seed=seeds[0])[0]))
        summary, _ = evaluate(env, checkpoint_policy(spec, run / "final"), seeds)  # fresh draws, as `fastrl eval`
        env.close()
        row |= {"subtasks": summary["subtasks_completed"], "success": summary["success_rate"]}
        out[name] = row | {"seconds": time.perf_counter() - t0}
    return out


def save_pictures(pictures: list, path: Path) -> None:
    """The newest frame of each dome's first observation, side by side."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(pictures), figsize=(2.2 * len(pictures), 3.0))
    for ax, (name, obs) in zip(axes, pictures, strict=True):
        ax.imshow(obs[:, :, -3:], interpolation="nearest")
        ax.set_title(name.replace(", ", ",\n"), fontsize=7)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"pictures: {path}")


def main() -> None:
    """Evaluate every run on every dome and print one line per dome."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+", type=Path)
    p.add_argument("--json", type=Path)
    p.add_argument("--pictures", type=Path)
    args = p.parse_args()
    print(f"{utc_stamp()}  {machine_line()}", flush=True)
    rows = {}
    for i, run in enumerate(args.runs):
        pictures = [] if args.pictures and i == 0 else None
        rows[str(run)] = r = on_domes(run, pictures)
        print(f"{run}: looks {read_run_spec(run).observation.image.looks}", flush=True)
        for name, row in r.items():
            flag = "unseen" if row["unseen"] else "      "
            print(f"  {flag} {name:32s} {row['subtasks']:6.1%} of subtasks, success {row['success']:4.0%}", flush=True)
        if pictures:
            save_pictures(pictures, args.pictures)
    print(f"{utc_stamp()}  {machine_line()}", flush=True)
    if args.json:
        rows = {"machine": machine_line(), "utc": utc_stamp(), "domes": DOMES, "runs": rows}
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
