"""Classical baselines of the learning environments: a qprr controller flies the task on the same seeds.

:func:`baseline_return` runs the ``reference`` action mode with a zero residual: the controller tracks the task's plan
(:mod:`qprr.envs.tasks`) on each seed's episode, exactly the episode a policy meets with that seed.  It returns the
returns (sum of the rewards of the first episode of each seed), their mean and standard deviation, and the success
rate (the task's criterion, docs/rl.md).  ``"idc"`` and ``"mfc"`` are the thesis's inverse-dynamics and model-free
controllers (gains derived from the platform for the control period); ``"mpc"`` the receding-horizon MPC (one solve
per control period), skipped with its install command when crocoddyl is missing.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from enum import Enum

import numpy as np

from ..control import CONTROLLERS, OPTIONAL
from ..errors import InputError
from ..platforms import DEFAULT_PLATFORM
from ..validation import as_int, as_name
from .settings import ENV_IDS, REFERENCE_CONTROLLERS, task_kind
from .vector import AerialVectorEnv


class BaselineStatus(Enum):
    """Whether a baseline ran (``DONE``) or was skipped for a missing optional dependency (``SKIPPED``, its install
    command in :attr:`BaselineResult.reason`)."""

    DONE = "done"
    SKIPPED = "skipped"


@dataclass(frozen=True)
class BaselineResult:
    """The baseline of ``controller`` on ``env_id`` and ``platform`` over ``seeds``: per seed its episode's return and
    success; :attr:`mean_return`, :attr:`std_return`, :attr:`success_rate` (NaN when skipped)."""

    env_id: str
    controller: str
    platform: str
    seeds: tuple[int, ...]
    returns: tuple[float, ...] = ()
    successes: tuple[bool, ...] = ()
    status: BaselineStatus = BaselineStatus.DONE
    reason: str = ""

    @property
    def mean_return(self) -> float:
        return float(np.mean(self.returns)) if self.returns else math.nan

    @property
    def std_return(self) -> float:
        return float(np.std(self.returns)) if self.returns else math.nan

    @property
    def success_rate(self) -> float:
        return float(np.mean(self.successes)) if self.successes else math.nan

    def __str__(self) -> str:
        if self.status is BaselineStatus.SKIPPED:
            return f"{self.env_id} {self.controller} on {self.platform}: skipped ({self.reason})"
        return (
            f"{self.env_id} {self.controller} on {self.platform}: return {self.mean_return:.2f} +- {self.std_return:.2f}, "
            f"success {100.0 * self.success_rate:.0f} % over {len(self.seeds)} seeds"
        )


def baseline_return(env_id, controller: str = "idc", seeds=(0, 1, 2, 3), platform=None, **options) -> BaselineResult:
    """The classical baseline of ``env_id`` (a Gymnasium id such as ``"qprr/Reach-v0"`` or a task name) flown by
    ``controller`` (``"idc"``, ``"mfc"``, ``"mpc"``; also ``"dsid"``, ``"decoupled"``) on ``seeds`` (one episode each,
    all in one batch), on ``platform`` (a name or a Platform; default q-prr).  ``options``: other environment options
    (``randomize=``, ``duration=``, ``urdf=``...; not ``action_mode``, which is ``"reference"`` with a zero residual)."""
    kind = task_kind(env_id, "env_id")
    as_name(controller, "controller", REFERENCE_CONTROLLERS, "baseline controller")
    if "action_mode" in options or "controller" in options:
        raise InputError("baseline_return flies action_mode='reference' with its controller argument: do not pass action_mode in options")
    if isinstance(seeds, (str, bytes)) or not isinstance(seeds, Iterable):
        raise InputError(f"seeds must be a sequence of seeds (ints >= 0, one episode each, e.g. seeds=range(8)), got {seeds!r}")
    seeds = tuple(as_int(s, f"seeds[{i}]", lo=0) for i, s in enumerate(seeds))
    if not seeds:
        raise InputError("seeds must hold at least one seed (e.g. seeds=range(8)), got an empty sequence")
    name = platform if isinstance(platform, str) else (DEFAULT_PLATFORM if platform is None and "urdf" not in options else "")
    if controller not in CONTROLLERS:
        package, _, install = OPTIONAL[controller]
        return BaselineResult(ENV_IDS[kind], controller, name, seeds, status=BaselineStatus.SKIPPED, reason=f"{package} is not installed: {install}")
    env = AerialVectorEnv(len(seeds), kind, platform=platform, action_mode="reference", controller=controller, **options)
    env.reset(seed=list(seeds))
    returns, successes = _first_episodes(env)
    return BaselineResult(ENV_IDS[kind], controller, env.core.platform.name, seeds, tuple(returns.tolist()), tuple(successes.tolist()))


def _first_episodes(env: AerialVectorEnv) -> tuple[np.ndarray, np.ndarray]:
    """(return, success) of each environment's first episode under zero actions."""
    n = env.num_envs
    zero = np.zeros((n, env.single_action_space.shape[0]), dtype=np.float32)
    returns, successes, done = np.zeros(n), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    while not done.all():
        _, reward, terminated, truncated, info = env.step(zero)
        returns += np.where(done, 0.0, reward)
        ended = (terminated | truncated) & ~done
        successes[ended] = info["success"][ended]
        done |= ended
    return returns, successes


__all__ = ["BaselineResult", "BaselineStatus", "baseline_return"]
