"""The key map: GLFW key codes to discrete portal actions and session commands.

Letters are avoided on purpose: the MuJoCo viewer binds most of them to rendering toggles (W wireframe, S
shadows, T transparency, ...).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..env.actions import DISCRETE_MEANINGS


@dataclass(frozen=True)
class Key:
    """One binding: GLFW code, the key's name (as xdotool spells it), and what it does."""

    code: int
    name: str
    label: str
    action: int | None = None  # discrete action index, or None for a command
    command: str | None = None  # "suggest" or "quit"


KEYS = (
    Key(265, "Up", "pitch +", 1),
    Key(264, "Down", "pitch -", 2),
    Key(262, "Right", "yaw +", 3),
    Key(263, "Left", "yaw -", 4),
    Key(266, "Prior", "insert", 5),
    Key(267, "Next", "retract", 6),
    Key(260, "Insert", "roll +", 7),
    Key(261, "Delete", "roll -", 8),
    Key(268, "Home", "light cable +", 9),
    Key(269, "End", "light cable -", 10),
    Key(258, "Tab", "switch what the keys move: scope, then each instrument", command="switch"),
    Key(257, "Return", "suggest a path (with --assist)", command="suggest"),
    Key(256, "Escape", "finish and save", command="quit"),
)
BY_CODE = {k.code: k for k in KEYS}
KEY_NAMES = {"Prior": "PageUp", "Next": "PageDown", "Return": "Enter", "Escape": "Esc"}

assert all(DISCRETE_MEANINGS[k.action] for k in KEYS if k.action is not None)


def driven_action(action: int, driven: int, sizes: list[int]) -> int:
    """The discrete action a scope key means for what the keys move (0: the scope; i: instrument i, of sizes[i - 1]
    coordinates).

    An instrument takes pitch, yaw, insertion and roll from the scope's keys and its jaw from the light cable's.
    """
    if driven == 0 or action == 0:
        return action
    coordinate, minus = divmod(action - 1, 2)
    if coordinate >= sizes[driven - 1]:
        return 0  # the light-cable keys of a probe: no jaw to move
    return 11 + 2 * (sum(sizes[: driven - 1]) + coordinate) + minus


def key_table() -> tuple[str, str]:
    """The key map as the viewer's two text columns (keys, what they do)."""
    keys = [KEY_NAMES.get(k.name, k.name) for k in KEYS]
    labels = [k.label for k in KEYS] + [
        "drag: turn the view; double-click the scope,",
        "then Ctrl + right-drag: pull it",
        "",
        "avatar cue | value cue",
        "magenta: tip, cyan: view centre",
    ]
    return "\n".join(keys + ["mouse", "", "", "bars", "paths"]), "\n".join(labels)


def key_markdown() -> str:
    """The key map as a markdown table (the README's)."""
    rows = [f"| {KEY_NAMES.get(k.name, k.name)} | {k.label} |" for k in KEYS]
    rows += [
        "| mouse drag / scroll | turn / zoom the 3D view |",
        "| double-click the scope, then Ctrl + right-drag | pull the scope (the servos follow it) |",
    ]
    return "\n".join(["| key | does |", "|---|---|", *rows])
