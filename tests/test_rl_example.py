"""examples/rl/train_reach.py (docs/rl.md, "Training example"): its stable-baselines3 adapter of the batched
environment returns, step by step, what :class:`qprr.envs.AerialVectorEnv` returns, with SB3's reset-in-the-same-step
semantics; its ``--quick`` mode runs end to end (train, evaluate, baselines, figure, curve, table).

Skipped with the install command when gymnasium or stable-baselines3 is missing; an import error of qprr itself fails.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium", reason='gymnasium is not installed: pip install "qprr[rl]"')
pytest.importorskip("stable_baselines3", reason="stable-baselines3 is not installed: pip install stable-baselines3")

import qprr.envs  # after the skips: a broken qprr fails here instead of skipping

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "examples" / "rl" / "train_reach.py"
SEEDS = [3, 4]
SHORT = {"box": 0.05, "duration": 0.3}
"""A setting where the episodes end soon, in two ways: robot 0, its base reference offset by +0.3 m in x, leaves the
0.05 m box after 11 steps (terminated); robot 1, with no offset, stays within it and reaches the 0.3 s time limit after
15 steps (truncated)."""


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("train_reach", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses resolve their annotations through it
    spec.loader.exec_module(module)
    return module


def offsets(n_actions: int) -> np.ndarray:
    """Actions of the two robots: robot 0 offsets its base reference by the full residual in x, robot 1 flies the IDC."""
    action = np.zeros((2, n_actions), dtype=np.float32)
    action[0, 0] = 1.0
    return action


def test_adapter_steps_as_the_vector_env_and_resets_in_the_same_step(example):
    from stable_baselines3.common.vec_env import VecEnv

    reference = example.make_env(2, **SHORT)
    venv = example.AerialVecEnvForSB3(example.make_env(2, **SHORT))
    assert isinstance(venv, VecEnv) and venv.num_envs == 2 and isinstance(venv.env, qprr.envs.AerialVectorEnv)
    assert venv.observation_space == reference.single_observation_space and venv.action_space == reference.single_action_space
    action = offsets(reference.single_action_space.shape[0])
    expected, _ = reference.reset(seed=SEEDS)
    venv.seed(SEEDS[0])  # robot i seeded SEEDS[0] + i, as reset(seed=SEEDS)
    np.testing.assert_array_equal(venv.reset(), expected)
    ended_at = {}
    for k in range(20):
        expected, reward, terminated, truncated, info = reference.step(action)
        obs, venv_reward, done, infos = venv.step(action)
        for i in range(2):
            if i in ended_at:
                continue  # in its second episode, one step ahead of the reference's
            assert venv_reward[i] == np.float32(reward[i]) and done[i] == (terminated[i] or truncated[i])
            assert infos[i]["ee_error"] == info["ee_error"][i] and infos[i]["end"] == info["end"][i]
            if not done[i]:
                np.testing.assert_array_equal(obs[i], expected[i])
                assert "terminal_observation" not in infos[i]
                continue
            ended_at[i] = k
            np.testing.assert_array_equal(infos[i]["terminal_observation"], expected[i])
            assert infos[i]["TimeLimit.truncated"] is bool(truncated[i])
            assert venv.env.core.tick[i] == 0  # reset in this step: obs[i] is the new episode's first observation
            first, reset_reward, *_ = reference.step(action)  # the vector env resets it one step later, ignoring the action
            np.testing.assert_array_equal(obs[i], first[i])
            assert reset_reward[i] == 0.0
            reference = example.make_env(2, **SHORT)  # re-synchronise the other robot's reference: replay up to k
            reference.reset(seed=SEEDS)
            for _ in range(k + 1):
                expected = reference.step(action)[0]
        if len(ended_at) == 2:
            break
    assert ended_at == {0: 10, 1: 14}, ended_at  # robot 0 left the box, robot 1 reached its time limit
    obs, _, done, _ = venv.step(action)
    assert not done.any() and venv.env.core.tick.tolist() == [5, 1]  # the new episodes run on, no second reset


def test_adapter_restricts_actions_and_observations(example):
    """The policy's action entries go to ``action_rows`` (0 elsewhere); it sees the entries ``observation_rows``."""
    env = example.make_env(2)
    rows = example.observation_rows(env, example.POLICY_OBSERVATIONS["base"])
    slices = env.core.layout.slices()
    assert rows[:3] == (0, 1, 2) and len(rows) == sum(slices[name].stop - slices[name].start for name in example.POLICY_OBSERVATIONS["base"])
    venv = example.AerialVecEnvForSB3(env, example.POLICY_ACTIONS["position"], rows)
    assert venv.action_space.shape == (3,) and venv.observation_space.shape == (len(rows),)
    full = example.full_actions(env, np.array([[0.1, 0.2, 0.3], [-0.1, -0.2, -0.3]]), venv.action_rows)
    assert full.shape == (2, env.single_action_space.shape[0]) and not full[:, 3:].any()
    np.testing.assert_array_equal(full[:, :3], np.array([[0.1, 0.2, 0.3], [-0.1, -0.2, -0.3]], dtype=np.float32))
    reference = example.make_env(2)
    expected, _ = reference.reset(seed=SEEDS)
    venv.seed(SEEDS[0])
    np.testing.assert_array_equal(venv.reset(), expected[:, list(rows)])
    obs, _, _, infos = venv.step(np.full((2, 3), 0.5, dtype=np.float32))
    np.testing.assert_array_equal(obs, reference.step(full_of(reference, 0.5))[0][:, list(rows)])
    assert venv.get_attr("num_envs") == [2, 2] and venv.env_is_wrapped(object) == [False, False]


def full_of(env, value: float) -> np.ndarray:
    """The environment's actions with ``value`` on the base position offsets, 0 elsewhere."""
    action = np.zeros((env.num_envs, env.single_action_space.shape[0]), dtype=np.float32)
    action[:, :3] = value
    return action


def test_quick_mode_runs(example, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    command = [sys.executable, str(SCRIPT), "--quick", "--out", str(tmp_path)]
    proc = subprocess.run(command, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr and "Warning" not in proc.stderr, proc.stderr
    for name in ("PPO residual on IDC", "IDC", "MFC", "success threshold"):
        assert name in proc.stdout, proc.stdout
    figure = tmp_path / "rl_reach.png"
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and figure.stat().st_size > 10_000
    record = json.loads((tmp_path / "rl_reach_curve.json").read_text())
    quick = example.QUICK
    assert record["budget"]["timesteps"] == quick.timesteps and record["budget"]["eval_seeds"] == quick.eval_seeds
    assert record["curve"]["steps"][0] == 0 and record["curve"]["steps"][-1] >= quick.timesteps
    assert len(record["policy_per_seed"]["returns"]) == quick.eval_seeds
    assert set(record["baselines_per_seed"]) == {"idc", "mfc"}  # no MPC in the quick mode
    assert record["threshold"] == example.SUCCESS_THRESHOLD and isinstance(record["reached"], bool)
