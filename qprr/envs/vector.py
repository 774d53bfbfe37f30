"""The batched Gymnasium environment: N robots stepped through one BatchSimulator (``gymnasium.make_vec``'s
``vector_entry_point`` of every qprr environment)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from gymnasium.spaces import Box
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ..errors import InputError, NotResetError, UnknownNameError
from ..validation import as_int
from .core import BatchCore, check_actions
from .settings import EnvSettings, settings_with


class AerialVectorEnv(VectorEnv):
    """``num_envs`` copies of a qprr task (:class:`~qprr.envs.settings.TaskKind`) in one
    :class:`~qprr.envs.core.BatchCore` (docs/rl.md).

    Parameters
    ----------
    num_envs : number of environments (>= 1).
    task : ``"hover"``, ``"reach"``, ``"carry"``, ``"track"`` (or the Gymnasium id; ``make_vec`` passes it).
    settings : an :class:`~qprr.envs.settings.EnvSettings`; ``**options`` its fields by name (``platform=``,
        ``action_mode=``, ``randomize=``...), overriding it.

    Spaces: ``single_observation_space`` a float32 Box of the layout of :mod:`qprr.envs.observation` (units and frames
    there); ``single_action_space`` a float32 Box [-1, 1]^m (:mod:`qprr.envs.actions`); ``observation_space`` and
    ``action_space`` their batches (num_envs rows).

    Seeding: ``reset(seed=s)`` seeds environment i with s + i (as Gymnasium's SyncVectorEnv does), ``reset(seed=[s_0,
    ...])`` with s_i; environment i then flies exactly the episodes of ``AerialEnv`` reset with the same seed.
    Autoreset: next step (``metadata["autoreset_mode"]``): the step after an environment terminates or truncates resets
    it and returns its first observation, reward 0 and both flags False, ignoring its action.  ``info``: arrays (one
    entry per environment) ``t`` [s], ``base_error`` [m], ``ee_error`` [m], ``attached``, ``success`` (True only at the
    truncating step of a successful episode) and ``end`` (why an episode ended there, :class:`~qprr.envs.core.EndReason`).
    """

    metadata = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, num_envs: int = 1, task="hover", settings: EnvSettings | None = None, **options) -> None:
        self.num_envs = as_int(num_envs, "num_envs", lo=1)
        self.settings = settings_with(settings, options)
        self.core = BatchCore(task, self.num_envs, self.settings)
        layout = self.core.layout
        self.single_observation_space = Box(layout.low, layout.high, dtype=np.float32)
        self.single_action_space = Box(-1.0, 1.0, (self.core.action_size,), dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.render_mode = None
        self.observation_names = layout.names()
        self._rngs: list[np.random.Generator] | None = None
        self._autoreset = np.zeros(self.num_envs, dtype=bool)

    def reset(self, *, seed: int | Sequence[int | None] | None = None, options: Mapping | None = None) -> tuple[np.ndarray, dict]:
        """New episodes for every environment (or those of ``options["reset_mask"]``, a boolean array); ``seed``: an
        int (environment i gets seed + i), one seed per environment, or None (each continues its own generator)."""
        mask = _reset_mask(options, self.num_envs)
        seeds = _row_seeds(seed, self.num_envs)
        if isinstance(seed, (int, np.integer)):
            super().reset(seed=seeds[0])
        rngs = self._rngs if self._rngs is not None else [seeding.np_random(None)[0] for _ in range(self.num_envs)]
        for i, s in enumerate(seeds):
            if s is not None and mask[i]:
                rngs[i] = seeding.np_random(s)[0]
        self._rngs = rngs
        rows = np.flatnonzero(mask)
        self.core.reset_rows(rows, [rngs[i] for i in rows.tolist()])
        self._autoreset[rows] = False
        return self.core.obs.copy(), {}

    def step(self, actions) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        """One control period of every environment (autoreset of those that ended at the previous step)."""
        if self._rngs is None:
            raise NotResetError("AerialVectorEnv.step before reset: call reset(seed=...) first")
        actions = check_actions(actions, self.action_space.shape, "actions")  # before the autoreset changes anything
        rows = np.flatnonzero(self._autoreset)
        if rows.size:
            self.core.reset_rows(rows, [self._rngs[i] for i in rows.tolist()])
        obs, reward, terminated, truncated, info = self.core.step(actions, self._autoreset, self._rngs)
        self._autoreset = terminated | truncated
        return obs, reward, terminated, truncated, info

    def __repr__(self) -> str:
        return f"AerialVectorEnv({self.core.kind.value}, {self.core.platform.name!r}, {self.settings.action_mode.value}, num_envs={self.num_envs})"


def _row_seeds(seed, n: int) -> list[int | None]:
    """One seed (or None) per environment from ``reset``'s ``seed``."""
    if seed is None:
        return [None] * n
    if isinstance(seed, (int, np.integer)):
        first = as_int(seed, "seed", lo=0)
        return [first + i for i in range(n)]
    if not isinstance(seed, Sequence) or isinstance(seed, str) or len(seed) != n:
        raise InputError(f"seed must be None, an int or a sequence of {n} ints or None (one per environment), got {seed!r}")
    return [None if s is None else as_int(s, f"seed[{i}]", lo=0) for i, s in enumerate(seed)]


def _reset_mask(options: Mapping | None, n: int) -> np.ndarray:
    """The environments ``reset`` renews: ``options["reset_mask"]`` (n booleans) or all."""
    if options is not None and not isinstance(options, Mapping):
        raise InputError(f"options must be None or a mapping such as {{'reset_mask': mask}}, got {type(options).__name__} {options!r}")
    options = dict(options or {})
    unknown = set(options) - {"reset_mask"}
    if unknown:
        raise UnknownNameError("reset option (options)", sorted(map(str, unknown))[0], ("reset_mask",))
    if "reset_mask" not in options:
        return np.ones(n, dtype=bool)
    mask = np.asarray(options["reset_mask"])
    if mask.shape != (n,) or mask.dtype != bool:
        raise InputError(f"options['reset_mask'] must be a boolean array of shape ({n},) (True: reset that environment), got {mask!r}")
    return mask


__all__ = ["AerialVectorEnv"]
