#!/usr/bin/env bash
# The wheel as users get it: build it from the tracked files, install it into a fresh venv outside the checkout,
# and from outside the checkout train the quick start's task by its bundled name and make every registered env.
# Runs alone (`bash .ci/wheel_check.sh`, `just wheel-check`) or from .ci/run: 4 to 7 min on 2 busy cores
# (pip 2 to 4, the run 1, removing the 2 GB venv up to 2).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
unset PYTHONPATH  # the installed wheel only, never a source tree
export MUJOCO_GL="${MUJOCO_GL:-egl}"
start=$SECONDS
stage() { echo "[$((SECONDS - start)) s] $*"; }
# pip, quietly: this machine's pip.conf names local indexes that may be absent (one warning per package)
pip() { "$py" -m pip -q "$@" 2> >(grep -v "is ignored: it is neither a file nor a directory" >&2); }

# The tracked files as they are in the work tree (uncommitted edits included; new files once `git add`ed),
# so the build leaves nothing behind in the checkout.
tree=$(git -C "$root" stash create || true)
mkdir "$tmp/src"
git -C "$root" archive "${tree:-HEAD}" | tar -x -C "$tmp/src"

"${PYTHON:-python3}" -m venv "$tmp/venv"
py="$tmp/venv/bin/python"
pip install torch==2.13.0  # first, so the CPU build is the one that satisfies the pin
pip wheel --no-deps -w "$tmp/dist" "$tmp/src"
wheel=$(ls "$tmp"/dist/*.whl)
stage "built $(basename "$wheel")"

# Every spec of the tree is in the wheel, byte for byte.
"$py" - "$wheel" "$tmp/src/fastrl/specs" <<'EOF'
import sys, zipfile
from pathlib import Path

wheel, specs = zipfile.ZipFile(sys.argv[1]), sorted(Path(sys.argv[2]).glob("*.yaml"))
held = {n for n in wheel.namelist() if n.startswith("fastrl/specs/")}
missing = [p.name for p in specs if f"fastrl/specs/{p.name}" not in held]
changed = [p.name for p in specs if p.name not in missing and wheel.read(f"fastrl/specs/{p.name}") != p.read_bytes()]
assert specs and not missing and not changed, f"wheel lacks {missing}, differs in {changed}"
print(f"the wheel holds all {len(specs)} bundled specs")
EOF

pip install "$wheel"
stage "installed the wheel and its dependencies"
mkdir "$tmp/work" && cd "$tmp/work"  # outside the checkout: no specs/ folder here
version=$("$tmp/venv/bin/fastrl" --version) && echo "$version"
[[ $version == "fastrl-surgery "* && $version != *"without installed metadata"* ]]  # the wheel's own metadata
"$py" - <<'EOF'
import gymnasium as gym

import fastrl

assert "site-packages" in fastrl.__file__, fastrl.__file__
for task in fastrl.TASK_IDS:
    env = gym.make(f"fastrl/{task}-v0")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.close()
    print(f"gym.make('fastrl/{task}-v0'): reset and one step")
EOF
stage "made every registered env"
"$tmp/venv/bin/fastrl" run tracelines --no-progress
run=$(ls -d runs/tracelines/*/ | head -1)
test -s "$run/recording.rrd"
"$py" -c "import json, sys; v = json.load(open(sys.argv[1]))['versions']; assert v['fastrl-surgery'], v" "$run/meta.json"
stage "fastrl run tracelines: trained, evaluated, recorded"
cd / && rm -rf "$tmp" && trap - EXIT  # ~2 GB of venv: it takes a while on a busy disk
echo "wheel check passed in $((SECONDS - start)) s"
