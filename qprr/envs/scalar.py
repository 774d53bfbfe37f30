"""The single Gymnasium environment (``gymnasium.make``'s entry point of every qprr environment): the batched core
with one copy, so the scalar and the vector environments are one implementation."""

from __future__ import annotations

from collections.abc import Mapping

import gymnasium
import numpy as np
from gymnasium.spaces import Box

from ..errors import InputError, NotResetError, UnknownNameError
from ..validation import as_int
from .core import BatchCore, check_actions
from .settings import EnvSettings, settings_with


class AerialEnv(gymnasium.Env):
    """One environment of a qprr task: :class:`qprr.envs.vector.AerialVectorEnv` with ``num_envs = 1`` and no
    autoreset (docs/rl.md).

    Parameters
    ----------
    task : ``"hover"``, ``"reach"``, ``"carry"``, ``"track"`` (or the Gymnasium id; ``make`` passes it).
    settings : an :class:`~qprr.envs.settings.EnvSettings`; ``**options`` its fields by name, overriding it.

    ``observation_space``: a float32 Box of the layout of :mod:`qprr.envs.observation` (units and frames there; the
    names of its entries: :attr:`observation_names`); ``action_space``: a float32 Box [-1, 1]^m
    (:mod:`qprr.envs.actions`).  ``reset(seed=s)`` seeds :attr:`np_random`, from which the episode draws everything
    random (the randomisation, the goals, the initial state, the sensor noise).  ``step`` returns the info of the vector
    environment as Python scalars; stepping an ended episode raises :class:`~qprr.errors.NotResetError`.
    """

    metadata = {"render_modes": []}

    def __init__(self, task="hover", settings: EnvSettings | None = None, **options) -> None:
        self.settings = settings_with(settings, options)
        self.core = BatchCore(task, 1, self.settings)
        layout = self.core.layout
        self.observation_space = Box(layout.low, layout.high, dtype=np.float32)
        self.action_space = Box(-1.0, 1.0, (self.core.action_size,), dtype=np.float32)
        self.render_mode = None
        self.observation_names = layout.names()
        self._running = False

    def reset(self, *, seed: int | None = None, options: Mapping | None = None) -> tuple[np.ndarray, dict]:
        seed = None if seed is None else as_int(seed, "seed", lo=0)  # Gymnasium's own check raises a non-qprr error
        if options is not None and not isinstance(options, Mapping):
            raise InputError(f"options must be None or a mapping (AerialEnv.reset takes no options), got {type(options).__name__} {options!r}")
        if options:
            raise UnknownNameError("reset option (options)", sorted(map(str, options))[0], ("none: AerialEnv.reset takes no options",))
        super().reset(seed=seed)
        self.core.reset_rows(np.zeros(1, dtype=int), [self.np_random])
        self._running = True
        return self.core.obs[0].copy(), {}

    def step(self, action) -> tuple[np.ndarray, float, bool, bool, dict]:
        if not self._running:
            raise NotResetError("AerialEnv.step: the episode has ended (or never started): call reset() first")
        action = check_actions(action, self.action_space.shape, "action")
        obs, reward, terminated, truncated, info = self.core.step(action[None], np.zeros(1, dtype=bool), [self.np_random])
        self._running = not (terminated[0] or truncated[0])
        return obs[0], float(reward[0]), bool(terminated[0]), bool(truncated[0]), {k: np.asarray(v)[0].item() for k, v in info.items()}

    def __repr__(self) -> str:
        return f"AerialEnv({self.core.kind.value}, {self.core.platform.name!r}, {self.settings.action_mode.value})"


__all__ = ["AerialEnv"]
