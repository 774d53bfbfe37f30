"""NSGA-II from a well-kept library, driven by ask/tell so that the campaign backends evaluate.

Two engines behind one interface (:class:`Optimiser`): pymoo's ``NSGA2`` (default) and Optuna's
``NSGAIISampler``.  Each generation is asked as a whole (``population`` points in [low, high]),
evaluated in parallel elsewhere, and told back in the order asked, so that a seeded study gives
the same designs whatever the backend, the number of workers or the order evaluations finish.
Constraints are told as violations (<= 0 feasible); a failed evaluation is told as infeasible with
the worst objective values.  Both packages are optional: pymoo is the extra ``qprr[design]`` (chosen by
measurement, docs/design.md), Optuna is installed apart (``pip install optuna``).
"""

from __future__ import annotations

import warnings
from abc import ABC, abstractmethod

import numpy as np

from ...errors import InputError, MissingDependencyError

INSTALL = {"pymoo": "pip install 'qprr[design]' (or pip install pymoo)", "optuna": "pip install optuna"}
"""Install command of each engine: pymoo is the ``design`` extra (docs/design.md says why), Optuna the alternative."""


class Optimiser(ABC):
    """Ask a generation of points (``(population, n_var)`` in the box), tell their objectives (to minimise) and violations."""

    def __init__(self, low, high, n_obj: int, n_constr: int, population: int, seed: int) -> None:
        self.low, self.high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
        if self.low.shape != self.high.shape or not np.all(self.low < self.high):
            raise InputError(f"optimiser bounds: low {self.low.tolist()} must be below high {self.high.tolist()} elementwise")
        self.n_obj, self.n_constr, self.population, self.seed = n_obj, n_constr, population, seed

    @abstractmethod
    def ask(self) -> np.ndarray: ...

    @abstractmethod
    def tell(self, F: np.ndarray, G: np.ndarray) -> None: ...


class PymooNSGA2(Optimiser):
    """pymoo's NSGA2 (``pymoo.algorithms.moo.nsga2``) through its ask/tell interface."""

    def __init__(self, low, high, n_obj, n_constr, population, seed) -> None:
        super().__init__(low, high, n_obj, n_constr, population, seed)
        try:
            from pymoo.algorithms.moo.nsga2 import NSGA2
            from pymoo.core.evaluator import Evaluator
            from pymoo.core.problem import Problem
            from pymoo.problems.static import StaticProblem
        except ImportError as exc:
            raise MissingDependencyError("pymoo", 'the NSGA-II design search (search.optimiser = "pymoo")', INSTALL["pymoo"]) from exc
        self._static, self._evaluator = StaticProblem, Evaluator
        self._problem = Problem(n_var=len(self.low), n_obj=n_obj, n_ieq_constr=max(n_constr, 1), xl=self.low, xu=self.high)
        self._alg = NSGA2(pop_size=population)
        self._alg.setup(self._problem, termination=("n_gen", 10**9), seed=seed, verbose=False)
        self._pop = None

    def ask(self) -> np.ndarray:
        self._pop = self._alg.ask()
        return np.array(self._pop.get("X"), dtype=float)

    def tell(self, F, G) -> None:
        G = np.asarray(G, dtype=float).reshape(len(F), -1) if self.n_constr else np.zeros((len(F), 1))
        self._evaluator().eval(self._static(self._problem, F=np.asarray(F, dtype=float), G=G), self._pop)
        self._alg.tell(infills=self._pop)


class OptunaNSGA2(Optimiser):
    """Optuna's ``NSGAIISampler`` through ``study.ask`` / ``study.tell``."""

    def __init__(self, low, high, n_obj, n_constr, population, seed) -> None:
        super().__init__(low, high, n_obj, n_constr, population, seed)
        try:
            import optuna
        except ImportError as exc:
            raise MissingDependencyError("optuna", 'the NSGA-II design search (search.optimiser = "optuna")', INSTALL["optuna"]) from exc
        optuna.logging.set_verbosity(optuna.logging.WARNING)
        cons = _violations if n_constr else None
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # constraints_func is flagged experimental
            sampler = optuna.samplers.NSGAIISampler(population_size=population, seed=seed, constraints_func=cons)
        self._study = optuna.create_study(directions=["minimize"] * n_obj, sampler=sampler)
        self._trials = []

    def ask(self) -> np.ndarray:
        self._trials = [self._study.ask() for _ in range(self.population)]
        return np.array([[t.suggest_float(f"x{i}", lo, hi) for i, (lo, hi) in enumerate(zip(self.low, self.high))] for t in self._trials])

    def tell(self, F, G) -> None:
        for t, f, g in zip(self._trials, np.asarray(F, dtype=float), np.asarray(G, dtype=float).reshape(len(F), -1)):
            t.set_user_attr("violation", [float(x) for x in g])
            self._study.tell(t, [float(x) for x in f])


def _violations(trial) -> list[float]:
    return trial.user_attrs["violation"]


ENGINES = {"pymoo": PymooNSGA2, "optuna": OptunaNSGA2}


def make_optimiser(name: str, low, high, n_obj: int, n_constr: int, population: int, seed: int) -> Optimiser:
    """An NSGA-II :class:`Optimiser` of engine ``name`` ("pymoo" or "optuna")."""
    if name not in ENGINES:
        raise InputError(f"optimiser {name!r} is not one of {', '.join(ENGINES)}")
    return ENGINES[name](low, high, n_obj, n_constr, population, seed)
