"""Residual RL on the Q-PRR: PPO learns offsets of the IDC's reference that cancel an airframe mass it does not know.

    PYTHONPATH=. python examples/rl/train_reach.py             # the default budget (about 10 min on 2 cores)
    PYTHONPATH=. python examples/rl/train_reach.py --quick     # smoke test: one rollout, 2 seeds, no MPC (about 1 min)
    PYTHONPATH=. python examples/rl/train_reach.py --timesteps 98304 --out /tmp/rl

The setting (``ENV_OPTIONS``): ``qprr/Reach-v0`` on the Q-PRR in the ``reference`` action mode, the thesis's
inverse-dynamics controller (IDC, 200 Hz inner loop) tracking the task's plan plus the policy's offset of the base
height (one action per 0.02 s); every episode the base body's mass and inertia are scaled by a factor drawn
uniformly in [0.9, 1.2] (``randomize={"model.mass": (0.9, 1.2)}``) that no controller's model knows.  The IDC has no
integral action on position: a heavier (lighter) airframe leaves the base, hence the end effector, below (above) its
reference by about Delta m g / (m k_p), 0.08 m at the factor 0.9 and 0.13 m at 1.18 (measured at the end of the
evaluation episodes; the horizontal error stays below 2 mm), more than Reach's 5 cm when the factor is off 1 by more
than about 6 %: the IDC misses half the evaluation episodes.  The policy sees the base's error to the plan, its
attitude and velocities, the plan's velocity and the rotor thrusts (which give the mass away), and learns the height
offset that removes the sag.

The policy offsets the base height only (``--actions vertical``) because the sag is vertical: offsetting the whole
base position (``--actions position``, three actions) learnt more slowly, to a success rate of 0.79 on 24 seeds after
25k steps where the height alone reached 0.96 (docs/rl.md, "Training example").  PPO explores with generalised
state-dependent noise (gSDE), smooth in time, starting small, so that the policy starts flying close to the IDC it
corrects rather than shaking its reference every 20 ms.

What it does: trains PPO (stable-baselines3, hyper-parameters in ``PPO_SETTINGS``) on N robots stepped by one call of
:class:`qprr.envs.AerialVectorEnv` through :class:`AerialVecEnvForSB3`; every ``--eval-every`` steps flies the
deterministic policy on fixed evaluation seeds (mean return, success rate); flies the classical baselines
(:func:`qprr.envs.baseline_return`: IDC, MFC, MPC) on the same seeds and randomisation in a second process; draws the
learning curve against them (``rl_reach.png``), writes the curve as JSON (``rl_reach_curve.json``) and prints a
summary table.

Outputs: by default ``docs/figures/rl_reach.png`` and ``examples/rl/rl_reach_curve.json`` of this repository;
``--out DIR`` writes both into DIR (``--quick`` without ``--out`` writes into ``./rl-quick``).
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import gymnasium
import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecEnv, VecNormalize

import qprr.envs  # noqa: F401 - registers qprr/Reach-v0
from qprr.envs import AerialVectorEnv, BaselineStatus, baseline_return
from qprr.envs.settings import TaskKind
from qprr.envs.tasks import TASKS
from qprr.viz import new_figure

ROOT = Path(__file__).resolve().parents[2]
ENV_ID = "qprr/Reach-v0"
ENV_OPTIONS = {
    "platform": "q-prr",
    "action_mode": "reference",
    "controller": "idc",
    "controller_period": 0.005,  # [s] the IDC runs at 200 Hz, the policy's offsets change every control_period (0.02 s)
    "dt": 2.5e-3,  # [s] plant integration step (default 1 ms): 2.5x cheaper, the baselines' returns agree to 0.1
    "residual": (0.3, 0.3, 0.1),  # full scale of an action: 0.3 m of base position, 0.3 rad of yaw, 10 % of the arm's range
    "randomize": {"model.mass": (0.9, 1.2)},  # base mass and inertia x U(0.9, 1.2), unknown to the controllers
    "threads": 1,
}
"""The environment of the policy and of every baseline (options of :class:`qprr.envs.EnvSettings`)."""
CONTROL_PERIOD = 0.02
"""[s] one environment step (EnvSettings.control_period's default)."""
SUCCESS_THRESHOLD = 0.8
"""The example succeeds when the final policy's success rate on the evaluation seeds reaches this."""
EVAL_SEED_START = 1000
"""Evaluation seeds are EVAL_SEED_START, EVAL_SEED_START + 1, ... (the training environments are seeded from --seed)."""
BASELINES = ("idc", "mfc", "mpc")
POLICY_ACTIONS = {"vertical": (2,), "position": (0, 1, 2), "all": None}
"""What the policy offsets (the other entries of the reference mode's action stay 0): the base height (world z; the
sag is vertical), the base position (world x, y, z), or every entry (base position, yaw, arm joints)."""
POLICY_OBSERVATIONS = {
    "base": ("base_error_world", "rotation_world_body", "v_body", "omega_body", "v_ref_world", "thrust"),
    "all": None,
}
"""What the policy sees: the base's state, its error to the plan and the rotor thrusts (not the end effector's error,
nor the arm's state), or the whole observation (docs/rl.md, "Observations")."""


@dataclass(frozen=True)
class Budget:
    """How much to run: environment steps, robots, evaluation period and seeds, MPC seeds."""

    timesteps: int = 65_536  # 32 PPO rollouts of 16 x 128 steps
    num_envs: int = 16
    eval_every: int = 8_192  # [steps] 4 rollouts
    eval_seeds: int = 32
    mpc_seeds: int = 8  # the slow baseline: its 8 episodes took 357 s in the committed run, the IDC's 32 took 50 s


QUICK = Budget(timesteps=1_024, num_envs=8, eval_every=1_024, eval_seeds=2, mpc_seeds=0)
"""--quick: one PPO rollout of 8 x 128 steps, evaluated before and after on 2 seeds, no MPC (a smoke test, not a result)."""

PPO_SETTINGS = {
    "n_steps": 128,  # steps per robot and rollout: 16 x 128 = 2048 samples per update
    "batch_size": 512,
    "n_epochs": 5,
    "learning_rate": 1e-4,
    "gamma": 0.99,  # horizon ~100 steps = 2 s; an episode is 300 steps (6 s)
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "ent_coef": 0.0,
    "vf_coef": 0.5,
    "max_grad_norm": 0.5,
    "use_sde": True,  # generalised state-dependent exploration: noise smooth in time
    "sde_sample_freq": -1,  # one noise matrix per rollout
    "policy_kwargs": {"net_arch": [64, 64], "activation_fn": torch.nn.Tanh, "log_std_init": -3.0},
}
"""PPO's hyper-parameters: SB3's defaults but shorter rollouts, fewer epochs, a smaller learning rate and gSDE
exploration starting small (noise std e^-3 per feature: a few percent of the residual's full scale, so the policy
starts flying close to the IDC it corrects).  Observations and rewards are normalised by a running mean and variance
(VecNormalize)."""


# ------------------------------------------------------------------------------------------------ the adapter
class AerialVecEnvForSB3(VecEnv):
    """A :class:`qprr.envs.AerialVectorEnv` seen through stable-baselines3's VecEnv API: every robot is stepped by one
    call of the batched environment (not one scalar environment per robot).

    SB3 resets an environment in the step it ends: the observation returned for it is its new episode's first, the
    last one goes to ``infos[i]["terminal_observation"]`` (``infos[i]["TimeLimit.truncated"]`` True when the episode
    reached its time limit rather than crashing, so that PPO bootstraps its value).  The batched environment resets
    at the next step instead; this adapter resets the ended robots at once through ``reset(options={"reset_mask":
    done})``.  ``infos[i]`` also holds the batched environment's info entries (``ee_error`` [m], ``success``, ``end``...)
    as Python scalars.

    ``action_rows``: the entries of the environment's action the policy commands (the others stay 0), e.g. (0, 1, 2)
    for the base position offsets of the reference mode; ``observation_rows``: the entries of the observation it sees;
    None: all of them.

    The robots share one batched environment: ``get_attr`` returns its attribute for every index, ``set_attr`` sets it
    for all, ``env_method`` calls the method once and returns its result for every index.
    """

    def __init__(self, env: AerialVectorEnv, action_rows: tuple[int, ...] | None = None, observation_rows: tuple[int, ...] | None = None) -> None:
        self.env = env
        self.render_mode = None
        size = env.single_action_space.shape[0]
        self.action_rows = tuple(range(size)) if action_rows is None else tuple(action_rows)
        action_space = gymnasium.spaces.Box(-1.0, 1.0, (len(self.action_rows),), dtype=np.float32)
        full = env.single_observation_space
        self.observation_rows = tuple(range(full.shape[0])) if observation_rows is None else tuple(observation_rows)
        rows = list(self.observation_rows)
        observation_space = gymnasium.spaces.Box(full.low[rows], full.high[rows], dtype=np.float32)
        super().__init__(env.num_envs, observation_space, action_space)
        self._actions: np.ndarray | None = None

    def reset(self) -> np.ndarray:
        """New episodes for every robot; the seeds given by :meth:`seed` (robot i: seed + i) or each robot's generator."""
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        obs, _ = self.env.reset(seed=seeds)
        obs = obs[:, list(self.observation_rows)]
        self.reset_infos = [{} for _ in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = full_actions(self.env, actions, self.action_rows)

    def step_wait(self):
        obs, reward, terminated, truncated, info = self.env.step(self._actions)
        done = terminated | truncated
        infos = [{key: np.asarray(value)[i].item() for key, value in info.items()} for i in range(self.num_envs)]
        rows = list(self.observation_rows)
        for i in np.flatnonzero(done).tolist():
            infos[i]["terminal_observation"] = obs[i, rows].copy()
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        if done.any():
            obs, _ = self.env.reset(options={"reset_mask": done})
        return obs[:, rows], reward.astype(np.float32), done, infos

    def close(self) -> None:
        self.env.close()

    def _indices(self, indices) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        return [int(indices)] if np.isscalar(indices) else [int(i) for i in indices]

    def get_attr(self, attr_name: str, indices=None) -> list:
        """SB3's access by name (VecEnv's API): the batched environment's attribute, once per index."""
        value = getattr(self.env, attr_name)
        return [value for _ in self._indices(indices)]

    def set_attr(self, attr_name: str, value, indices=None) -> None:
        setattr(self.env, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list:
        result = getattr(self.env, method_name)(*method_args, **method_kwargs)
        return [result for _ in self._indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._indices(indices)]


def observation_rows(env: AerialVectorEnv, entries: tuple[str, ...] | None) -> tuple[int, ...] | None:
    """The indices of the observation entries named ``entries`` (qprr.envs.observation's names; None: all)."""
    if entries is None:
        return None
    slices = env.core.layout.slices()
    return tuple(i for name in entries for i in range(slices[name].start, slices[name].stop))


def full_actions(env: AerialVectorEnv, actions: np.ndarray, rows: tuple[int, ...]) -> np.ndarray:
    """The environment's actions (num_envs, m) with the policy's ``actions`` (num_envs, len(rows)) in ``rows``, 0 elsewhere."""
    out = np.zeros((env.num_envs, env.single_action_space.shape[0]), dtype=np.float32)
    out[:, list(rows)] = np.asarray(actions, dtype=np.float32).reshape(env.num_envs, len(rows))
    return out


def make_env(num_envs: int, **changes) -> AerialVectorEnv:
    """``num_envs`` robots of the setting (``ENV_OPTIONS``, with the options ``changes`` replaced) in one batched environment."""
    return gymnasium.make_vec(ENV_ID, num_envs=num_envs, vectorization_mode="vector_entry_point", **{**ENV_OPTIONS, **changes})


# ------------------------------------------------------------------------------------------------ evaluation
@dataclass(frozen=True)
class Evaluation:
    """One episode per evaluation seed: returns and successes (the task's criterion, docs/rl.md)."""

    returns: np.ndarray
    successes: np.ndarray

    @property
    def mean_return(self) -> float:
        return float(np.mean(self.returns))

    @property
    def std_return(self) -> float:
        return float(np.std(self.returns))

    @property
    def success_rate(self) -> float:
        return float(np.mean(self.successes))


def evaluate(model: PPO, normalizer: VecNormalize, env: AerialVectorEnv, seeds: list[int], adapter: AerialVecEnvForSB3) -> Evaluation:
    """The deterministic policy (its mean action) on the first episode of each seed, as :func:`qprr.envs.baseline_return`
    flies a controller (same seeds: the same episodes); returns in the environment's own reward units."""
    obs, _ = env.reset(seed=list(seeds))
    n = env.num_envs
    returns, successes, done = np.zeros(n), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    while not done.all():
        action, _ = model.predict(normalizer.normalize_obs(obs[:, list(adapter.observation_rows)]), deterministic=True)
        obs, reward, terminated, truncated, info = env.step(full_actions(env, action, adapter.action_rows))
        returns += np.where(done, 0.0, reward)
        ended = (terminated | truncated) & ~done
        successes[ended] = info["success"][ended]
        done |= ended
    return Evaluation(returns, successes)


@dataclass
class Curve:
    """The learning curve: one row per evaluation."""

    steps: list[int] = field(default_factory=list)
    mean_return: list[float] = field(default_factory=list)
    std_return: list[float] = field(default_factory=list)
    success_rate: list[float] = field(default_factory=list)
    wall_time: list[float] = field(default_factory=list)  # [s] since the training started
    last: Evaluation | None = None


class EvaluateEvery(BaseCallback):
    """Evaluates the policy before training, every ``every`` environment steps and at the end."""

    def __init__(self, every: int, env: AerialVectorEnv, seeds: list[int], curve: Curve) -> None:
        super().__init__()
        self.every, self.eval_env, self.seeds, self.curve = every, env, seeds, curve
        self.next_at, self.start = 0, time.perf_counter()

    def _evaluate(self) -> None:
        normalizer = self.model.get_vec_normalize_env()
        result = evaluate(self.model, normalizer, self.eval_env, self.seeds, normalizer.venv)
        c = self.curve
        c.steps.append(int(self.num_timesteps))
        c.mean_return.append(result.mean_return)
        c.std_return.append(result.std_return)
        c.success_rate.append(result.success_rate)
        c.wall_time.append(time.perf_counter() - self.start)
        c.last = result
        print(
            f"  {self.num_timesteps:7d} steps  return {result.mean_return:7.1f} +- {result.std_return:5.1f}  "
            f"success {result.success_rate:4.2f}  ({c.wall_time[-1]:5.0f} s)",
            flush=True,
        )
        self.next_at = self.num_timesteps + self.every

    def _on_training_start(self) -> None:
        self.start = time.perf_counter()
        self._evaluate()

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.next_at:
            self._evaluate()
        return True

    def _on_training_end(self) -> None:
        if self.curve.steps[-1] != self.num_timesteps:
            self._evaluate()


# ------------------------------------------------------------------------------------------------ the run
def train(budget: Budget, seed: int, eval_seeds: list[int], actions: str, observations: str) -> tuple[PPO, Curve]:
    """PPO on ``budget.num_envs`` robots for ``budget.timesteps`` steps, evaluated on ``eval_seeds``; the policy
    commands the action entries ``POLICY_ACTIONS[actions]`` from the observation entries ``POLICY_OBSERVATIONS[observations]``."""
    env = make_env(budget.num_envs)
    adapter = AerialVecEnvForSB3(env, POLICY_ACTIONS[actions], observation_rows(env, POLICY_OBSERVATIONS[observations]))
    venv = VecNormalize(adapter, gamma=PPO_SETTINGS["gamma"])
    model = PPO("MlpPolicy", venv, seed=seed, device="cpu", verbose=0, **PPO_SETTINGS)
    curve = Curve()
    model.learn(budget.timesteps, callback=EvaluateEvery(budget.eval_every, make_env(len(eval_seeds)), eval_seeds, curve))
    return model, curve


def fly_baselines(eval_seeds: list[int], mpc_seeds: int) -> dict:
    """The classical controllers on the evaluation seeds (the MPC on the first ``mpc_seeds`` of them): name ->
    (BaselineResult, wall time [s]); a controller whose optional package is missing is left out with its reason."""
    torch.set_num_threads(1)
    out = {}
    options = {k: v for k, v in ENV_OPTIONS.items() if k not in ("platform", "action_mode", "controller")}
    for name in BASELINES:
        seeds = eval_seeds[:mpc_seeds] if name == "mpc" else eval_seeds
        if seeds:
            start = time.perf_counter()
            out[name] = (baseline_return(ENV_ID, name, seeds, ENV_OPTIONS["platform"], **options), time.perf_counter() - start)
    return out


def mass_scales(seeds: list[int]) -> list[float]:
    """The airframe mass factor each evaluation seed draws (for the report)."""
    env = make_env(len(seeds))
    env.reset(seed=list(seeds))
    return [d.mass_scale for d in env.core.draws]


def table(curve: Curve, found: dict, eval_seeds: list[int], mpc_seeds: int) -> list[dict]:
    """Rows (name, seeds, return mean and std, success rate) on all the evaluation seeds and on the MPC's subset."""
    rows = []
    final = curve.last
    entries = [("PPO residual on IDC", np.asarray(final.returns), np.asarray(final.successes))]
    entries += [(name.upper(), np.asarray(r.returns), np.asarray(r.successes)) for name, r in found.items()]
    for name, returns, successes in entries:
        for subset, k in (("all", len(eval_seeds)), ("mpc", mpc_seeds)):
            if k == 0 or len(returns) < k or (subset == "mpc" and k == len(eval_seeds)):
                continue
            rows.append(
                {
                    "name": name,
                    "seeds": f"{eval_seeds[0]}..{eval_seeds[k - 1]}",
                    "n": k,
                    "return_mean": float(np.mean(returns[:k])),
                    "return_std": float(np.std(returns[:k])),
                    "success_rate": float(np.mean(successes[:k])),
                }
            )
    return rows


def plot(curve: Curve, found: dict, rows: list[dict], path: Path, budget: Budget) -> None:
    """The learning curve (mean return with a +-1 standard error band over the evaluation seeds) and the success rate against the
    classical controllers (horizontal lines)."""
    steps = np.asarray(curve.steps) / 1e3
    n_seeds = len(curve.last.returns)
    mean, sem = np.asarray(curve.mean_return), np.asarray(curve.std_return) / math.sqrt(n_seeds)
    fig = new_figure((11, 4.8))
    ax_return, ax_success = fig.subplots(1, 2)
    ax_return.fill_between(steps, mean - sem, mean + sem, color="C0", alpha=0.2, label=f"PPO: +-1 standard error of the mean over {n_seeds} seeds")
    ax_return.plot(steps, mean, "o-", color="C0", ms=3, label="PPO residual on IDC (deterministic policy)")
    ax_success.plot(steps, curve.success_rate, "o-", color="C0", ms=3)
    styles = {"IDC": ("C3", "--"), "MFC": ("C2", "-."), "MPC": ("C1", ":")}
    for row in rows:
        if row["name"] not in styles:
            continue
        color, line = styles[row["name"]]
        label = f"{row['name']} (seeds {row['seeds']})"
        if row["n"] == n_seeds or row["name"] == "MPC":
            ax_return.axhline(row["return_mean"], color=color, ls=line, lw=1.5, label=label)
            ax_success.axhline(row["success_rate"], color=color, ls=line, lw=1.5)
            ax_success.annotate(
                row["name"],
                (1.0, row["success_rate"]),
                xycoords=("axes fraction", "data"),
                xytext=(-4, 3),
                textcoords="offset points",
                ha="right",
                va="bottom",
                color=color,
                fontsize=8,
            )
    ax_success.axhline(SUCCESS_THRESHOLD, color="0.4", lw=0.8, label=f"success threshold {SUCCESS_THRESHOLD:g}")
    steps_label = f"environment steps [thousands] (one step: one robot, {CONTROL_PERIOD * 1e3:.0f} ms)"
    ax_return.set(xlabel=steps_label, ylabel="mean return over the seeds [-]", title="return (reward per 20 ms step summed over 6 s)")
    ax_success.set(
        xlabel=steps_label,
        ylabel="success rate [fraction of seeds]",
        title=f"success: end effector within {TASKS[TaskKind.REACH].tolerance * 100:.0f} cm over the last 1 s",
        ylim=(-0.03, 1.1),
    )
    for ax in (ax_return, ax_success):
        ax.grid(alpha=0.3)
    handles = [h for ax in (ax_return, ax_success) for h in ax.get_legend_handles_labels()[0]]
    fig.legend(handles=handles, loc="outside lower center", ncols=3, fontsize=8)
    fig.suptitle(
        f"qprr/Reach-v0, Q-PRR, reference mode: PPO ({budget.num_envs} robots) on an airframe mass x U(0.9, 1.2) unknown to the controllers",
        fontsize=10,
    )
    fig.savefig(path, dpi=120)


def arguments(argv: list[str] | None) -> argparse.Namespace:
    """The command line (module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help=f"smoke test: {QUICK.timesteps} steps, {QUICK.eval_seeds} seeds, no MPC")
    parser.add_argument("--timesteps", type=int, help=f"environment steps of training (default {Budget.timesteps})")
    parser.add_argument("--envs", type=int, help=f"robots stepped together (default {Budget.num_envs})")
    parser.add_argument("--eval-every", type=int, help=f"environment steps between evaluations (default {Budget.eval_every})")
    parser.add_argument("--eval-seeds", type=int, help=f"number of evaluation seeds (default {Budget.eval_seeds})")
    parser.add_argument("--mpc-seeds", type=int, help=f"evaluation seeds the MPC flies (default {Budget.mpc_seeds}; 0: no MPC)")
    parser.add_argument("--observations", choices=tuple(POLICY_OBSERVATIONS), default="base", help="what the policy sees (default: base)")
    parser.add_argument("--actions", choices=tuple(POLICY_ACTIONS), default="vertical", help="what the policy offsets (default: vertical)")
    parser.add_argument("--seed", type=int, default=0, help="seed of PPO and of the training environments (default 0)")
    parser.add_argument("--out", type=Path, help="folder of the figure and the curve (default: docs/figures and examples/rl)")
    return parser.parse_args(argv)


def budget_of(args: argparse.Namespace) -> Budget:
    """The budget of the command line: the default's (or --quick's) with the options given replacing its fields."""
    base = QUICK if args.quick else Budget()
    eval_seeds = args.eval_seeds or base.eval_seeds
    return Budget(
        timesteps=args.timesteps or base.timesteps,
        num_envs=args.envs or base.num_envs,
        eval_every=args.eval_every or base.eval_every,
        eval_seeds=eval_seeds,
        mpc_seeds=min(base.mpc_seeds if args.mpc_seeds is None else args.mpc_seeds, eval_seeds),
    )


def run(budget: Budget, args: argparse.Namespace, eval_seeds: list[int]) -> tuple[Curve, dict, dict]:
    """Train (this process) while the baselines fly (a second process); returns the curve, the baselines that ran
    (name -> BaselineResult) and the wall times [s]."""
    with ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn")) as pool:
        flown = pool.submit(fly_baselines, eval_seeds, budget.mpc_seeds)  # on the second core while PPO trains
        t0 = time.perf_counter()
        _, curve = train(budget, args.seed, eval_seeds, args.actions, args.observations)
        train_time = time.perf_counter() - t0
        print(f"training: {train_time:.0f} s ({budget.timesteps / train_time:.0f} steps/s with the evaluations)")
        baseline_runs = flown.result()
    print("baselines (same seeds, same randomisation; flown in a second process during the training):")
    found = {}
    for name, (result, seconds) in baseline_runs.items():
        print(f"  {result}  ({seconds:.0f} s)")
        if result.status is BaselineStatus.DONE:
            found[name] = result
    if budget.mpc_seeds == 0:
        print("  mpc: not flown (--mpc-seeds 0)")
    baseline_time = sum(seconds for _, seconds in baseline_runs.values())
    return curve, found, {"training": train_time, "baselines_cpu_in_second_process": baseline_time}


def record_of(budget: Budget, seed: int, eval_seeds: list[int], curve: Curve, found: dict, rows: list[dict]) -> dict:
    """What the JSON file holds: the setting, the budget, the curve, the per-seed results and the table."""
    return {
        "env_id": ENV_ID,
        "options": {k: (list(v) if isinstance(v, tuple) else v) for k, v in ENV_OPTIONS.items()},
        "ppo": {k: v for k, v in PPO_SETTINGS.items() if k != "policy_kwargs"},
        "budget": budget.__dict__,
        "seed": seed,
        "eval_seeds": eval_seeds,
        "mass_scale_per_eval_seed": mass_scales(eval_seeds),
        "curve": {
            "steps": curve.steps,
            "mean_return": curve.mean_return,
            "std_return": curve.std_return,
            "success_rate": curve.success_rate,
            "wall_time": curve.wall_time,
        },
        "policy_per_seed": {"returns": curve.last.returns.tolist(), "successes": curve.last.successes.tolist()},
        "baselines_per_seed": {n: {"seeds": list(r.seeds), "returns": list(r.returns), "successes": list(r.successes)} for n, r in found.items()},
        "table": rows,
        "threshold": SUCCESS_THRESHOLD,
        "reached": curve.success_rate[-1] >= SUCCESS_THRESHOLD,
    }


def main(argv: list[str] | None = None) -> int:
    args = arguments(argv)
    torch.set_num_threads(1)
    start = time.perf_counter()
    budget = budget_of(args)
    out = args.out if args.out is not None else (Path("rl-quick") if args.quick else None)
    figure_path = (out / "rl_reach.png") if out else ROOT / "docs" / "figures" / "rl_reach.png"
    curve_path = (out / "rl_reach_curve.json") if out else ROOT / "examples" / "rl" / "rl_reach_curve.json"
    figure_path.parent.mkdir(parents=True, exist_ok=True)
    eval_seeds = list(range(EVAL_SEED_START, EVAL_SEED_START + budget.eval_seeds))

    options = ENV_OPTIONS
    print(f"{ENV_ID} on {options['platform']}, {options['action_mode']} mode ({options['controller']}), randomize {options['randomize']}")
    print(f"PPO: {budget.timesteps} steps on {budget.num_envs} robots, evaluated every {budget.eval_every} steps", end="")
    print(f" on seeds {eval_seeds[0]}..{eval_seeds[-1]}")
    curve, found, wall_times = run(budget, args, eval_seeds)
    rows = table(curve, found, eval_seeds, budget.mpc_seeds)
    plot(curve, found, rows, figure_path, budget)
    record = record_of(budget, args.seed, eval_seeds, curve, found, rows)
    wall = time.perf_counter() - start
    record["wall_time_s"] = {**wall_times, "total": wall}
    curve_path.write_text(json.dumps(record, indent=1) + "\n")

    print(f"\n{'':22s} {'seeds':>11s}  {'return':>16s}  {'success':>7s}")
    for row in rows:
        print(f"{row['name']:22s} {row['seeds']:>11s}  {row['return_mean']:7.1f} +- {row['return_std']:5.1f}  {row['success_rate']:7.2f}")
    print(
        f"\nsuccess threshold (final policy's success rate >= {SUCCESS_THRESHOLD:g} on the {len(eval_seeds)} evaluation seeds): "
        f"{'reached' if record['reached'] else 'NOT reached'} ({curve.success_rate[-1]:.2f})"
    )
    print(f"figure {figure_path}, curve {curve_path}; wall time {wall:.0f} s ({math.ceil(wall / 60)} min)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
