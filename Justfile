# fastrl developer recipes (https://just.systems; `pip install rust-just` provides `just`)

spec := "specs/tracelines.yaml"

# install the package with test and dev tools
install:
    pip install -e '.[dev]'

# train, evaluate and record one run of a spec (default: TraceLines)
run spec=spec *args:
    fastrl run {{spec}} {{args}}

# the test suite (what CI runs)
test *args:
    MUJOCO_GL=egl python -m pytest {{args}}

# build the wheel, install it in a fresh venv and use it from outside the checkout (CI runs it too)
wheel-check:
    bash .ci/wheel_check.sh

# benchmarks: env throughput against raw mj_step
bench:
    MUJOCO_GL=egl python bench/env_throughput.py

# where the wall time of a run goes (env stepping, learner, rendering, logging)
bench-run spec=spec:
    MUJOCO_GL=egl python bench/run_profile.py --spec {{spec}}

# lint, format check and the import layers
lint:
    ruff check fastrl tests bench
    ruff format --check fastrl tests bench
    lint-imports --no-logo

# validate every bundled spec
check:
    fastrl check specs/*.yaml
