"""EagerAdam: torch's Adam bit for bit, and training never imports torch's compiler."""

import subprocess
import sys

import torch

from fastrl.agents.eager_adam import EagerAdam


def trained(optimizer_class, steps: int = 25) -> tuple[list[torch.Tensor], dict]:
    """A small net's weights and optimizer state after Adam steps, a state_dict round trip and an lr change."""
    torch.manual_seed(3)
    net = torch.nn.Sequential(torch.nn.Linear(6, 16), torch.nn.Tanh(), torch.nn.Linear(16, 4))
    opt = optimizer_class(net.parameters(), lr=3e-3, eps=1e-5)
    x = torch.randn(128, 6)
    for i in range(steps):
        opt.zero_grad()
        net(x).square().mean().backward()
        torch.nn.utils.clip_grad_norm_(net.parameters(), 0.5)
        opt.step()
        if i == steps // 2:
            opt.load_state_dict(opt.state_dict())
            opt.param_groups[0]["lr"] = 1e-3
    return [p.detach().clone() for p in net.parameters()], opt.state_dict()


def test_eager_adam_updates_as_torchs_adam():
    mine, mine_state = trained(EagerAdam)
    theirs, their_state = trained(torch.optim.Adam)
    assert all(torch.equal(a, b) for a, b in zip(mine, theirs, strict=True))
    assert mine_state["param_groups"] == their_state["param_groups"]
    for k, state in their_state["state"].items():
        assert all(torch.equal(mine_state["state"][k][name], value) for name, value in state.items())
    assert not all(torch.equal(a, b) for a, b in zip(mine, trained(EagerAdam, steps=5)[0]))  # the steps did move


def test_runs_and_airl_train_without_importing_torchs_compiler(tmp_path):
    code = (
        "import sys\n"
        "from fastrl.cli import app\n"
        "for command in ('run', 'irl'):\n"
        "    try:\n"
        f"        app([command, 'tracelines', '--timesteps', '1024', '--runs', '{tmp_path}', '--no-progress',\n"
        "             '--set', 'train.n_envs=4', '--set', 'evaluate.episodes=1',\n"
        "             '--set', 'irl.demonstrations.expert=2'])\n"
        "    except SystemExit as e:\n"
        "        assert not e.code, e.code\n"
        "print('torch._dynamo' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split()[-1] == "False"
    assert len(list(tmp_path.glob("tracelines/*Z-ppo-s0/final"))) == 1
    assert len(list(tmp_path.glob("tracelines/*-airl-ppo-s0/final"))) == 1
