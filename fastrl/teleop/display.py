"""The MuJoCo viewer as the trainee's screen: 3D scene, endoscope image, key map, status, cue, suggestions."""

from __future__ import annotations

import mujoco
import mujoco.viewer
import numpy as np

from ..assist import cue_colour, draw_path, project_points
from ..env.fast_env import GREEN
from ..env.render import outside_camera
from .keymap import key_table

PATH_RGBA = np.array([1.0, 0.1, 0.9, 0.9], np.float32)  # suggested tip path (3D)
AIM_RGBA = np.array([0.0, 0.85, 0.95, 0.9], np.float32)  # suggested view centre on the scene (3D)
TIP_RGB, AIM_RGB = (255, 30, 230), (0, 215, 240)
LIFT = np.array([0.0, 0.0, 0.0005])  # keep paths on the plate visible
SMALL, BIG = mujoco.mjtFontScale.mjFONTSCALE_100, mujoco.mjtFontScale.mjFONTSCALE_150
GRID = mujoco.mjtGridPos
RND = mujoco.mjtRndFlag


class Display:
    """A passive viewer window (its own GUI thread) that the session updates once per tick."""

    def __init__(self, env, on_key, image_px: int = 384):
        self.env, self.image_px = env, image_px
        check_display()
        self.handle = mujoco.viewer.launch_passive(
            env.model, env.data, key_callback=on_key, show_left_ui=False, show_right_ui=False
        )
        cam = outside_camera(env.task)
        with self.handle.lock():
            c = self.handle.cam
            c.lookat[:], c.distance, c.azimuth, c.elevation = cam.lookat, cam.distance, cam.azimuth, cam.elevation
            self.handle.opt.geomgroup[2] = 0  # hide the dome's shell: the inside shows
            for flag in (RND.mjRND_SHADOW, RND.mjRND_REFLECTION, RND.mjRND_SKYBOX):  # software GL: keep frames cheap
                self.handle.user_scn.flags[flag] = 0  # the viewer copies user_scn's flags into its scene
        self.keys = key_table()
        m = env.model
        self.scope_bodies = {i for i in range(m.nbody) if m.body(i).name.startswith("scope")}
        self.footer = ""

    def pulling(self) -> bool:
        """Whether the mouse is pulling a part of the scope (double-click it, then Ctrl + right-drag)."""
        p = self.handle.perturb
        return bool(p.active) and p.select in self.scope_bodies

    def lock(self):
        """The viewer's lock: hold it while changing the model or data."""
        return self.handle.lock()

    def running(self) -> bool:
        """Whether the window is still open."""
        return self.handle.is_running()

    def show(self, session) -> bool:
        """Draw the current state; False once the window has been closed."""
        if not self.handle.is_running():
            return False
        info, total = session.info, session.info["subtasks_total"]
        cue = "GREEN (hold)" if info["cue"]["green"] else "orange"
        status = [
            ("subject", session.writer.meta["subject"]),
            ("subtask", f"{min(info['subtask'] + 1, total)} of {total} ({info['subtask']} done)"),
            ("time", f"{info['time']:.1f} s of {session.spec.episode.time_limit:g} s"),
            ("avatar cue", f"{cue}  dwell {100 * info['cue']['dwell']:.0f}%"),
            (f"{session.assist.cue.kind} cue", f"{100 * session.cue_level:.0f}%"),
        ]
        if session.suggestion is not None:
            sg = session.suggestion
            status.append(
                ("suggestion", f"{'reaches' if sg.reached else 'does not reach'} the next avatar ({sg.ms:.0f} ms)")
            )
        texts = [
            (SMALL, GRID.mjGRID_TOPLEFT, *self.keys),
            (BIG, GRID.mjGRID_TOPRIGHT, "\n".join(k for k, _ in status), "\n".join(v for _, v in status)),
        ]
        if self.footer:
            texts.append((SMALL, GRID.mjGRID_BOTTOMRIGHT, self.footer, ""))
        self.handle.set_texts(texts)
        self.handle.set_images(self._images(session))
        self._draw_path(session.suggestion)
        self.handle.sync()
        return True

    def _images(self, session) -> list:
        """The endoscope image (with the suggested path projected) and two colour bars: avatar cue, value cue."""
        env, px = self.env, self.image_px
        img = env.render()
        sg = session.suggestion
        if sg is not None and len(sg.tip) > 1:
            d, cam = env.data, env.task.camera
            for points, colour, width in ((sg.tip[1:], TIP_RGB, 1), (sg.aim, AIM_RGB, 2)):
                ok = np.isfinite(points).all(axis=1)
                uv, front = project_points(
                    points[ok],
                    d.cam_xpos[cam],
                    d.cam_xmat[cam],
                    float(env.model.cam_fovy[cam]),
                    img.shape[1],
                    img.shape[0],
                )
                img = draw_path(img, uv, front, colour, width)
        scale = max(1, px // img.shape[0])
        big = np.ascontiguousarray(np.repeat(np.repeat(img, scale, 0), scale, 1))
        h = big.shape[0]
        avatar = (
            (np.array(GREEN[:3]) * 255).astype(np.uint8)
            if session.info["cue"]["green"]
            else np.array([255, 140, 0], np.uint8)
        )
        bar = np.zeros((h, 24, 3), np.uint8)
        bar[:] = avatar
        value = np.zeros((h, 24, 3), np.uint8)
        value[:] = cue_colour(session.cue_level)
        value[: int(round(h * (1 - session.cue_level)))] //= 4  # filled to the level, from the bottom
        return [
            (mujoco.MjrRect(0, 0, big.shape[1], h), big),
            (mujoco.MjrRect(big.shape[1] + 4, 0, 24, h), np.ascontiguousarray(bar)),
            (mujoco.MjrRect(big.shape[1] + 32, 0, 24, h), np.ascontiguousarray(value)),
        ]

    def _draw_path(self, sg) -> None:
        """The suggested tip path as capsules in the 3D scene."""
        scn = self.handle.user_scn
        with self.handle.lock():
            scn.ngeom = 0
            if sg is None:
                return
            for path, rgba, radius in ((sg.tip, PATH_RGBA, 0.0008), (sg.aim, AIM_RGBA, 0.0006)):
                for a, b in zip(path[:-1], path[1:]):
                    if (
                        scn.ngeom >= scn.maxgeom
                        or not np.isfinite(a).all()
                        or not np.isfinite(b).all()
                        or np.linalg.norm(b - a) < 1e-6
                    ):
                        continue
                    g = scn.geoms[scn.ngeom]
                    mujoco.mjv_initGeom(
                        g, mujoco.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3), np.eye(3).ravel(), rgba
                    )
                    mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_CAPSULE, radius, a + LIFT, b + LIFT)
                    scn.ngeom += 1

    def message(self, text: str) -> None:
        """Replace the status with one message (e.g. while the attempt is scored)."""
        self.handle.set_texts([(SMALL, GRID.mjGRID_TOPLEFT, *self.keys), (BIG, GRID.mjGRID_TOPRIGHT, text, "")])
        self.handle.sync()

    def linger(self, text: str, seconds: float) -> None:
        """Show `text` (the feedback) until the window closes or `seconds` pass (forever if negative)."""
        import time

        self.footer = text
        end = time.monotonic() + (seconds if seconds >= 0 else float("inf"))
        while self.handle.is_running() and time.monotonic() < end:
            self.handle.set_texts([(SMALL, GRID.mjGRID_TOPLEFT, *self.keys), (SMALL, GRID.mjGRID_TOPRIGHT, text, "")])
            self.handle.sync()
            time.sleep(0.1)

    def close(self) -> None:
        """Close the window."""
        close_viewer(self.handle)


def check_display() -> None:
    """Raise RuntimeError if GLFW cannot start (no display): the viewer would exit the whole process instead."""
    import warnings

    import glfw

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # glfw warns with the reason; the error below says it
        if not glfw.init():
            raise RuntimeError("GLFW cannot open a display (is DISPLAY set?)")


def close_viewer(handle) -> None:
    """Close a passive viewer and wait for its GUI thread to let go of GLFW (exiting earlier can segfault)."""
    import time

    handle.close()
    end = time.monotonic() + 5.0
    while handle.is_running() and time.monotonic() < end:
        time.sleep(0.05)
    time.sleep(0.3)
