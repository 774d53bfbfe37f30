"""Bad-input catalogue over the public API of qprr (the engine of tests/test_catalogue.py and benchmarks/bad_input_audit.py).

Every public callable of every qprr module (names in ``__all__``, else every name without a
leading underscore defined in the module), every public method of its classes, is found by
introspection: a function added later is covered without editing this file.  For each one the
engine

1. builds valid arguments from :data:`SPECS`, a table keyed by *parameter name* (``platform``,
   ``data``, ``xi``, ``q``, ``target``, ``dt``...; a few entries are qualified by module or
   callable where one name means two things), falling back on the parameter's default (a float
   default is a real number, a string default a name among choices, a tuple of floats a vector);
2. calls it once with these (the baseline: it must succeed, else the table is wrong);
3. calls it again with one argument replaced by a bad value of its kind (:func:`bad_values`):
   wrong shape, complex, object, string and boolean arrays, NaN, inf, empty, None, a unit
   quaternion of norm 0 or 2, a non-orthonormal rotation, unknown names, missing, empty,
   corrupted files, non-positive lengths and durations...

Each bad call is an :class:`Outcome`: ``good`` (a :class:`qprr.errors.QprrError` whose message
names the argument - or, for an unknown name, the name given), ``unclear`` (any other exception,
or a qprr error that does not say which argument), ``silent`` (returned a value), ``hang`` (still
running after :data:`WORK_LIMIT` s of processor time), ``allowed`` (a documented valid result: :data:`ALLOWED`).
The audit runs cases in child processes and adds ``crash`` (the interpreter died).

The engine works on any qprr tree (it reads only names): the audit also runs it on the tree of
the old ``main`` (parameter ``robot`` of ``qprr.model``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import enum
import fnmatch
import importlib
import inspect
import io
import math
import os
import pkgutil
import signal
import tempfile
import types
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

WORK_LIMIT = 3.0
"""Processor seconds a single call may use (a bad value that is not checked may start a long computation).  The
limit counts this process's own work (``ITIMER_VIRTUAL``), not the wall clock: other programs loading the machine do
not move a verdict."""


# ============================================================================ the callables
@dataclass(frozen=True)
class Target:
    """One public callable: ``qualname`` (module.name or module.Class.method), the object, its owner class."""

    qualname: str
    obj: object
    owner: type | None = None
    method: str | None = None

    @property
    def module(self) -> str:
        return self.qualname.rsplit(".", 2 if self.owner is not None else 1)[0]


SKIP_MODULES = ("qprr.__main__",)

NOT_FED: dict[str, str] = {
    "qprr.cli.*": "the command line: tests/test_cli_errors.py runs bad invocations in child processes",
    "qprr.*.cli.*": "the command line: tests/test_cli_errors.py runs bad invocations in child processes",
    "qprr.control.base.not_reset": "builds the NotResetError a controller raises about itself (tests/test_control.py)",
    "qprr.cli.common.Parser*": "argparse.ArgumentParser with one-line errors: its constructor is argparse's own",
    "*.main": "a command-line entry point (reads sys.argv, exits the interpreter)",
    "qprr.ik.tasks.base.Task*": "abstract base class (its subclasses are fed)",
    "qprr.ik.iteration_fast.*": "compiled kernels (numba) on arrays their caller, qprr.ik.hierarchy.HierarchySolver, built and "
    "checked: tests/test_ik_fast.py checks them against the tasks' linearize and Pinocchio's log6 / Jlog6",
    "qprr.actuation.lexicographic_fast.*": "compiled kernels (numba) on arrays their caller, qprr.actuation.lexicographic, built "
    "and checked: tests/test_lexicographic_fast.py checks them against the numpy path",
    "qprr.ik.newton_fast.*": "the QP IK's compiled Newton loop, on arrays and levels its caller, qprr.ik.solver.QPMethod (through "
    "HierarchySolver.newton_loop), built from checked input: tests/test_ik_fast.py checks it against the readable loop",
    "qprr.control.base.Controller*": "abstract base class (its subclasses are fed)",
    "qprr.thesis.symbolic.SymbolicModel*": "the sympy model takes seconds to derive (tests/test_symbolic.py)",
    "qprr.thesis.symbolic.symbolic_model": "the sympy model takes seconds to derive (tests/test_symbolic.py)",
    "qprr.sim.environment.Environment*": "abstract base class (its subclasses are fed)",
    "qprr.sim.disturbances.Disturbance*": "a Protocol (its implementations are fed)",
    "qprr.sim.disturbances.StateDisturbance*": "a Protocol (its implementations are fed)",
    "qprr.wheeled.kinematics.KinematicModel*": "abstract base class (its subclasses are fed)",
    "qprr.wheeled.wheels.Wheel.*": "abstract base class (its subclasses are fed)",
    "qprr.thesis.checks.run_checks": "runs every check of `qprr check` (seconds): tests/test_checks.py",
    "qprr.viz.viewer.*": "starts a web server (viser): tests/test_viz_viewer.py",
    "qprr.viz.browser.*": "drives a browser: tests/test_viz_viewer.py",
    "qprr.campaign.backends.Backend*": "abstract base class (its subclasses are fed)",
    "qprr.campaign.backends.DaskBackend*": "starts a Dask cluster of worker processes: tests/test_campaign.py",
    "qprr.trajectory.Trajectory*": "a Protocol (its implementations are fed)",
    "qprr.envs.baseline.baseline_return": "flies whole episodes of a classical controller (seconds per seed): "
    "tests/test_envs.py feeds it bad env ids, controllers, seeds and platforms",
}
"""Callables the catalogue does not call (pattern -> where they are tested instead)."""


def public_names(mod) -> list[str]:
    names = getattr(mod, "__all__", None)
    if names is not None:
        return list(names)
    return [k for k, v in vars(mod).items() if not k.startswith("_") and getattr(v, "__module__", None) == mod.__name__]


MISSING: list[str] = []
"""Modules :func:`walk` could not import (an optional dependency is not installed)."""


def _optional_missing(exc: ImportError) -> bool:
    """An import error that says an optional package is missing (not a bug of qprr: that must fail)."""
    from qprr.errors import MissingDependencyError

    return isinstance(exc, MissingDependencyError) or (
        isinstance(exc, ModuleNotFoundError) and exc.name is not None and exc.name.split(".")[0] != "qprr"
    )


def walk(package: str = "qprr") -> list[Target]:
    """Every public callable of every module of ``package`` (each object once, under its first name)."""
    pkg = importlib.import_module(package)
    seen: set[int] = set()
    out: list[Target] = []
    modules = [pkg]
    for m in pkgutil.walk_packages(pkg.__path__, package + ".", onerror=lambda name: None):
        if m.name in SKIP_MODULES or m.name.rsplit(".", 1)[1].startswith("_"):
            continue
        try:
            modules.append(importlib.import_module(m.name))
        except ImportError as exc:  # only an optional dependency (MissingDependencyError names it): nothing to feed
            if not _optional_missing(exc):
                raise
            MISSING.append(m.name)
    for mod in modules:
        for name in public_names(mod):
            obj = getattr(mod, name, None)
            if obj is None or isinstance(obj, types.ModuleType) or not callable(obj) or id(obj) in seen:
                continue
            home = getattr(obj, "__module__", "") or ""
            if not home.startswith(package):
                continue  # re-exported from numpy, pinocchio...
            seen.add(id(obj))
            if isinstance(obj, type):
                if issubclass(obj, BaseException) or issubclass(obj, enum.Enum):
                    continue
                qual = f"{home}.{obj.__qualname__}"
                out.append(Target(qual, obj))
                for mname, member in vars(obj).items():
                    if mname.startswith("_") or isinstance(member, (property, classmethod)) and mname != "load":
                        continue
                    fn = member.__func__ if isinstance(member, (staticmethod, classmethod)) else member
                    if not callable(fn) or isinstance(fn, type):
                        continue
                    out.append(Target(f"{qual}.{mname}", fn, owner=obj, method=mname))
            else:
                out.append(Target(f"{home}.{getattr(obj, '__qualname__', name)}", obj))
    return out


# ============================================================================ valid arguments
class Ctx:
    """What the builders share: one platform (the thesis's Q-PRR; the old tree's Robot), made once."""

    def __init__(self, tmp: Path) -> None:
        self.tmp = tmp
        self._cache: dict[str, object] = {}
        import qprr

        self.qprr = qprr
        self.new = importlib.util.find_spec("qprr.model") is not None

    def once(self, key: str, make: Callable[[], object]):
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    # -- platform / model
    @property
    def platform(self):
        if self.new:
            return self.once("platform", lambda: importlib.import_module("qprr").load("q-prr"))  # the thesis plug-in's Q-PRR
        return self.robot

    @property
    def robot(self):
        if self.new:
            return self.platform
        return self.once("robot", lambda: importlib.import_module("qprr.model").load())

    @property
    def model(self):
        return self.platform.model

    def data(self):
        return self.model.createData()

    @property
    def n_xi(self) -> int:
        return self.model.nv

    @property
    def n_arm(self) -> int:
        return self.model.nv - 6

    def xi(self) -> np.ndarray:
        xi = np.zeros(self.n_xi)
        xi[0:3] = (0.1, -0.2, 1.0)
        xi[5] = 0.3
        xi[6:] = self.q_arm()
        return xi

    def q_arm(self) -> np.ndarray:
        m = self.model
        lo, hi = m.lowerPositionLimit[7:], m.upperPositionLimit[7:]
        mid = np.where(np.isfinite(lo) & np.isfinite(hi) & (hi - lo < 1e3), 0.5 * (lo + hi), 0.0)
        return 0.25 * lo + 0.75 * mid if np.all(np.isfinite(lo)) and np.all(lo > -1e3) else mid

    def q(self) -> np.ndarray:
        return self.once_xi_to_q()

    def once_xi_to_q(self) -> np.ndarray:
        import pinocchio as pin

        xi = self.xi()
        R = pin.rpy.rpyToMatrix(xi[3], xi[4], xi[5])
        quat = pin.Quaternion(R).coeffs()
        return np.concatenate([xi[0:3], quat, xi[6:]])

    def target(self):
        import pinocchio as pin

        m = self.model
        d = m.createData()
        pin.framesForwardKinematics(m, d, self.q())
        fid = m.getFrameId("end_effector") if m.existFrame("end_effector") else m.nframes - 1
        return d.oMf[fid].translation.copy()

    def target_pose(self):
        import pinocchio as pin

        m = self.model
        d = m.createData()
        pin.framesForwardKinematics(m, d, self.q())
        fid = m.getFrameId("end_effector") if m.existFrame("end_effector") else m.nframes - 1
        return d.oMf[fid].copy()

    def state(self):
        ch = _mod("qprr.charts", "qprr.coordinates")
        st = ch.State(self.n_arm) if self.new else ch.State()
        xi = self.xi()
        st.update_xi(0.0, xi, np.zeros(self.n_xi))
        return st

    def reference(self):
        base = importlib.import_module("qprr.control.base")
        return (
            base.Reference(self.xi(), np.zeros(self.n_xi), np.zeros(self.n_xi), self.n_xi)
            if self.new
            else base.Reference(self.xi(), np.zeros(self.n_xi), np.zeros(self.n_xi))
        )

    def controller(self):
        c = importlib.import_module("qprr.control")
        return c.make_controller("idc", self.platform)

    def trajectory(self):
        tr = importlib.import_module("qprr.trajectory")
        return tr.Hold(self.xi())

    def sim_result(self):
        def make():
            sim = importlib.import_module("qprr.sim")
            return sim.simulate(self.platform, self.controller(), self.trajectory(), 0.02, dt=0.002)

        return self.once("sim_result", make)

    def result_file(self) -> Path:
        def make():
            return self.sim_result().save(self.tmp / "result.npz")

        return self.once("result_file", make)

    def file(self, name: str, content: bytes) -> Path:
        p = self.tmp / name
        p.write_bytes(content)
        return p

    def rotors_toml(self) -> Path:
        def make():
            plats = importlib.import_module("qprr.platforms")
            return (
                next(plats.robots_dir().glob("*.toml"))
                if hasattr(plats, "robots_dir") and list(plats.robots_dir().glob("*.toml"))
                else next((Path(importlib.import_module("qprr").__file__).parent / "data").glob("*.toml"))
            )

        return self.once("rotors_toml", make)

    def ideal_platform(self):
        """The platform with qprr.rotors.ideal_wrench_set thrusters (what IdealAllocator allocates on)."""

        def make():
            ideal = importlib.import_module("qprr.rotors").ideal_wrench_set(40.0, 5.0)
            return self.platform.replace(rotors=ideal, name="ideal")

        return self.once("ideal_platform", make)

    def campaign_spec(self):
        """A one-run campaign of a 0.02 s hover-reach."""
        return self.once(
            "campaign_spec",
            lambda: importlib.import_module("qprr.campaign.spec").CampaignSpec(name="catalogue", scenario="hover-reach", options={"duration": 0.02}),
        )

    def campaign_spec_file(self) -> Path:
        return self.once(
            "campaign_spec_file", lambda: self.file("campaign.toml", b'name = "catalogue"\nscenario = "hover-reach"\n[options]\nduration = 0.02\n')
        )

    def campaign_results_file(self) -> Path:
        def make():
            runner = importlib.import_module("qprr.campaign.runner")
            return runner.run_campaign(self.campaign_spec(), self.tmp / "campaign.csv", backend="inline", progress=False).path

        return self.once("campaign_results_file", make)

    def fresh_path(self, name: str) -> Path:
        """A new file path at each call (objects that lock their file)."""
        self._cache["fresh"] = self._cache.get("fresh", 0) + 1
        return self.tmp / f"{self._cache['fresh']}-{name}"

    def urdf_path(self) -> Path:
        root = Path(importlib.import_module("qprr").__file__).resolve().parent.parent
        return root / "urdf" / "qprr.urdf"


def _mod(*names: str):
    for n in names:
        try:
            return importlib.import_module(n)
        except ImportError:
            continue
    raise ImportError(names[0])


@dataclass(frozen=True)
class Spec:
    """How to build a valid argument (``make(ctx)``) and which bad values fit its kind (see :func:`bad_values`).

    ``sized``: the length follows the platform (xi, q, q_arm...): a longer vector is wrong only for a
    callable that knows the platform.  ``always``: pass it even when the parameter has a default
    (cheap sizes, short durations)."""

    kind: str
    make: Callable[[Ctx], object]
    always: bool = False
    sized: bool = False


def V(make, always=False, sized=True):
    return Spec("vec", make, always, sized)


def F(make):
    """A vector of fixed length (3 for a position, 6 for a wrench...)."""
    return Spec("vec", make, False, False)


def S(value, kind="real", always=False):
    return Spec(kind, lambda ctx: value, always)


SPECS: dict[str, Spec] = {
    # -- objects
    "platform": Spec("platform", lambda c: c.platform),
    "robot": Spec("platform", lambda c: c.robot),
    "data": Spec("data", lambda c: c.data()),
    "model": Spec("model", lambda c: c.model),
    "rotors": Spec("obj", lambda c: c.platform.rotors),
    "moments": F(lambda c: np.array([1.0, 2.0, 2.5])),
    "inertia": F(lambda c: np.array([1.0, 2.0, 2.5, 0.0, 0.0, 0.0])),
    "com": F(lambda c: np.array([0.0, 0.0, 0.1])),
    "body": S("body", "skip"),
    "state": Spec("obj", lambda c: c.state()),
    "gains": S(None, "skip"),
    "ref": Spec("obj", lambda c: c.reference()),
    "controller": Spec("obj", lambda c: c.controller()),
    "trajectory": Spec("obj", lambda c: c.trajectory()),
    "rng": Spec("obj", lambda c: np.random.default_rng(0)),
    "params": Spec("obj", lambda c: _mod("qprr.thesis.params", "qprr.params").thesis_params()),
    "p": Spec("obj", lambda c: _mod("qprr.thesis.params", "qprr.params").thesis_params()),
    # -- states (thesis chart and Pinocchio)
    "xi": V(lambda c: c.xi()),
    "xi0": V(lambda c: c.xi()),
    "xi_dot": V(lambda c: np.full(c.n_xi, 0.1)),
    "xi_dot0": V(lambda c: np.full(c.n_xi, 0.1)),
    "xi_ddot": V(lambda c: np.full(c.n_xi, 0.1)),
    "q": Spec("q", lambda c: c.q(), sized=True),
    "v": V(lambda c: np.full(c.n_xi, 0.1)),
    "a": V(lambda c: np.full(c.n_xi, 0.1)),
    "tau": V(lambda c: np.full(c.n_xi, 0.1)),
    "u": V(lambda c: np.full(c.n_xi, 0.1)),
    "tau_desired": V(lambda c: np.full(c.n_xi, 0.1)),
    "q_arm": V(lambda c: c.q_arm()),
    "q_arm_dot": V(lambda c: np.full(c.n_arm, 0.1)),
    "euler_zyx": F(lambda c: np.array([0.1, -0.2, 0.3])),
    "euler": F(lambda c: np.array([0.1, -0.2, 0.3])),
    "wrench_world": F(lambda c: np.array([0.1, 0.2, 0.3, 0.01, 0.02, 0.03])),
    "wrench_body": F(lambda c: np.array([0.1, 0.2, 20.0, 0.01, 0.02, 0.03])),
    "h_world": F(lambda c: np.array([0.1, 0.2, 0.3, 0.01, 0.02, 0.03])),
    "p_world": F(lambda c: np.array([0.1, 0.2, 1.0])),
    "com_ee": F(lambda c: np.array([0.0, 0.0, 0.01])),
    "quat_xyzw": F(lambda c: np.array([0.0, 0.0, 0.0, 1.0])),
    "R": Spec("rot", lambda c: _rot()),
    "R_world": Spec("rot", lambda c: _rot()),
    "R_b": Spec("rot", lambda c: _rot()),
    "target": F(lambda c: c.target()),
    "f": V(lambda c: np.full(c.model.nv - 6 + 4, 1.0)),
    "tau_d": V(lambda c: np.full(c.n_xi, 0.1)),
    "f_out": V(lambda c: np.zeros(c.n_xi - 6 + 4)),
    # -- scalars
    "t": S(0.0),
    "dt": S(0.002, "pos"),
    "duration": S(0.02, "pos", always=True),
    "mass": S(0.2, "nonneg"),
    "payload": S(0.2, "nonneg"),
    "q_prev": Spec("q", lambda c: c.q(), sized=True),
    "v_prev": V(lambda c: np.full(c.n_xi, 0.1)),
    "v_now": V(lambda c: np.full(c.n_xi, 0.2)),
    "tau_prev": V(lambda c: np.full(c.n_xi, 0.1)),
    "g": S(9.81, "pos"),
    "n_samples": S(64, "count", always=True),
    "n_grid": S(5, "count", always=True),
    "n_states": S(2, "count", always=True),
    # -- names and files
    "method": S("qp", "name"),
    "integrator": S("euler", "name"),
    "layout": S("plus", "name"),
    "law": S("septic", "name"),
    "approach": S("body", "name"),
    "frame": S(None, "frame"),
}


# parameter names qualified by callable (fnmatch pattern on the qualname) where one name means two things
def _thesis_settings(name: str, **fields):
    """A settings object of :mod:`qprr.thesis.scenarios` (looked up by name: the engine reads any qprr tree)."""
    return vars(importlib.import_module("qprr.thesis.scenarios"))[name](**fields)


QUALIFIED: list[tuple[str, str, Spec]] = [
    ("qprr.platforms.load", "name", S("q-prr", "name")),
    ("qprr.nomenclature.parse", "name", S("Q-PRR", "name")),
    ("qprr.nomenclature.build", "name", S("Q-PRR", "name")),
    ("qprr.scenarios.*", "name", S("hover-reach", "name")),
    ("qprr.scenarios.missions.MissionSettings", "name", S("", "skip")),  # free text: the run's title ("" keeps the scenario's), no registry name
    ("qprr.scenarios.run", "controller", S("idc", "name")),
    ("qprr.scenarios.Scenario.run", "controller", S("idc", "name")),
    ("qprr.control.make_controller", "name", S("idc", "name")),
    ("qprr.sim.result.SimResult.load", "path", Spec("path_in", lambda c: c.result_file())),
    ("qprr.sim.result.SimResult.save", "path", Spec("path_out", lambda c: c.tmp / "saved.npz")),
    ("qprr.rotors.read_rotor_file", "path", Spec("path_in", lambda c: c.rotors_toml())),
    ("qprr.model.from_urdf", "urdf", Spec("path_in", lambda c: c.urdf_path())),
    ("qprr.model.from_urdf", "rotors", Spec("obj", lambda c: c.platform.rotors)),
    ("qprr.model.from_model", "rotors", Spec("obj", lambda c: c.platform.rotors)),
    ("qprr.platforms.multirotor_model", "name", S("hector", "name")),
    ("qprr.charts.rot_?", "a", S(0.3)),
    ("qprr.model.*frame_id", "name", S("end_effector", "frame")),
    ("qprr.model.check_*", "name", S("platform", "skip")),
    ("qprr.model.Platform.check_arm_limits", "name", S("q_arm", "skip")),
    ("qprr.model.from_*", "name", S("P", "skip")),
    ("qprr.model.Platform", "name", S("P", "skip")),
    ("qprr.model.Platform", "base_frame", S(1, "frame")),
    ("qprr.model.Platform", "ee_frame", Spec("frame", lambda c: c.platform.ee_frame)),
    ("qprr.model.Platform", "arm", Spec("obj", lambda c: c.platform.arm)),
    ("qprr.urdf.reader.*", "xml_text", Spec("text", lambda c: c.urdf_path().read_text())),
    ("qprr.urdf.reader.*", "urdf", Spec("obj", lambda c: importlib.import_module("qprr.urdf.reader").parse_urdf(c.urdf_path().read_text()))),
    ("qprr.urdf.reader.*", "source", S("URDF", "skip")),
    ("qprr.rotors.*", "n", S(4, "count")),
    ("qprr.viz.*", "t", Spec("vec", lambda c: np.linspace(0.0, 1.0, 5))),
    ("qprr.viz.*", "p_world", Spec("mat", lambda c: np.tile(c.target(), (5, 1)))),
    ("qprr.viz.*", "xi", Spec("mat", lambda c: np.tile(c.xi(), (5, 1)))),
    ("qprr.viz.*", "path", Spec("path_out", lambda c: c.tmp / "fig.png")),
    ("qprr.viz.*", "res", Spec("obj", lambda c: c.sim_result())),
    ("qprr.viz.*", "result", Spec("obj", lambda c: c.sim_result())),
    ("qprr.viz.*", "allocator", Spec("obj", lambda c: importlib.import_module("qprr.actuation").Allocator(c.platform))),
    ("qprr.viz.*", "q_arm_posture", V(lambda c: c.q_arm())),
    ("qprr.viz.run.RunLog", "platform", S("Q-PRR", "skip")),
    ("qprr.viz.run.RunLog", "xi", Spec("mat", lambda c: np.tile(c.xi(), (5, 1)), sized=True)),
    ("qprr.analysis.*", "n_samples", S(64, "count", always=True)),
    ("qprr.analysis.opspace.opspace_map", "n_samples", S(8, "count", always=True)),
    ("qprr.nomenclature.mdh.*", "rows", Spec("obj", lambda c: importlib.import_module("qprr.thesis.printed").table_3_4((0.04, 0.055, 0.18, 0.1)))),
    ("qprr.nomenclature.mdh.*", "q", V(lambda c: c.q_arm())),
    ("qprr.nomenclature.mdh.MDHRow", "sigma", S(0, "int")),
    ("qprr.nomenclature.mdh.MDHRow.*", "q", S(0.1)),
    ("qprr.thesis.scenarios.*", "duration", S(0.05, "pos", always=True)),
    ("qprr.nomenclature.mdh.frame_name", "j", S(2, "int")),
    ("qprr.thesis.bsg.CogStabilizer", "inner", Spec("obj", lambda c: c.controller())),
    ("qprr.thesis.urdf.write_urdf", "path", Spec("path_out", lambda c: c.tmp / "q.urdf", always=True)),
    ("qprr.thesis.igm.solve_igm", "target", Spec("obj", lambda c: c.target_pose())),
    ("qprr.thesis.igm.*", "x_b*", S(0.01)),
    ("qprr.thesis.igm.*", "y_b*", S(0.0)),
    ("qprr.thesis.igm.*", "r0_min", S(-0.04)),
    ("qprr.thesis.igm.*", "r0_max", S(0.04)),
    ("qprr.thesis.*", "d", F(lambda c: np.array([0.04, 0.055, 0.18, 0.1]))),
    ("qprr.thesis.*", "angles", F(lambda c: np.array([0.1, 0.2, 0.3]))),
    ("qprr.thesis.*", "euler_rates", F(lambda c: np.array([0.1, 0.2, 0.3]))),
    ("qprr.thesis.*", "q_arm_ddot", V(lambda c: np.full(c.n_arm, 0.1))),
    ("qprr.thesis.*", "p_b*", F(lambda c: np.array([0.1, 0.2, 0.3]))),
    ("qprr.thesis.*", "p_cm*", F(lambda c: np.array([0.01, 0.0, 0.1]))),
    ("qprr.thesis.*", "omega_b", F(lambda c: np.array([0.1, 0.0, 0.1]))),
    ("qprr.thesis.*", "lambdas", F(lambda c: np.array([0.1, 0.2, 0.3, 0.4]))),
    (
        "qprr.thesis.*",
        "factors",
        Spec("obj", lambda c: importlib.import_module("qprr.thesis.printed").lu_factors_4_42(c.q_arm(), (0.04, 0.055, 0.18, 0.1))),
    ),
    ("qprr.thesis.*", "B??", Spec("mat", lambda c: np.eye(3))),
    ("qprr.thesis.interaction.*", "h", F(lambda c: np.array([0.1, 0.0, 0.2, 0.0, 0.01, 0.0]))),
    ("qprr.thesis.interaction.*", "contact_b", F(lambda c: np.array([0.3, 0.0, 0.1]))),
    ("qprr.thesis.payload.*", "I*", Spec("mat", lambda c: np.eye(3) * 1e-3)),
    ("qprr.thesis.payload.*", "m*", S(0.3, "pos")),
    ("qprr.thesis.payload.*", "m_c*", S(0.3, "nonneg")),
    ("qprr.thesis.printed.mdh_3_28*", "d", S(0.1)),
    ("qprr.thesis.printed.det_JJt_4_45", "lambdas", F(lambda c: np.linspace(0.1, 0.8, 8))),
    ("qprr.trajectory.*", "t", Spec("vec", lambda c: np.linspace(0.0, 1.0, 5))),
    ("qprr.trajectory.transition", "t?", S(0.2)),
    ("qprr.trajectory.line_phases", "a", S(0.5)),
    ("qprr.trajectory.line_phases", "t1", S(0.1)),
    ("qprr.trajectory.line_phases", "t2", S(0.5)),
    ("qprr.trajectory.transition", "t2", S(0.8)),
    ("qprr.trajectory.Phase", "coordinate", S("z", "skip")),
    ("qprr.trajectory.Phase", "t1", S(0.1)),
    ("qprr.trajectory.Phase", "t2", S(0.5)),
    ("qprr.trajectory.Phase", "value", S(1.0)),
    ("qprr.trajectory.MultiPhase*", "phases", Spec("obj", lambda c: (importlib.import_module("qprr.trajectory").Phase("z", 0.1, 0.5, 1.0),))),
    ("qprr.sim.integrators.make_stepper", "method", S("midpoint", "name")),
    ("qprr.sim.disturbances.*", "gamma", F(lambda c: np.ones(c.n_xi))),
    ("qprr.sim.disturbances.*", "t", Spec("vec", lambda c: np.linspace(0.0, 0.1, 11))),
    ("qprr.sim.disturbances.*", "n_xi", S(9, "count")),
    ("qprr.sim.disturbances.Pulse", "t1", S(0.01)),
    ("qprr.sim.disturbances.Pulse", "t2", S(0.05)),
    ("qprr.sim.disturbances.Disturbances", "parts", Spec("obj", lambda c: (importlib.import_module("qprr.sim").WhiteNoise(0.1),))),
    ("qprr.sim.disturbances.split", "disturbance", Spec("obj", lambda c: importlib.import_module("qprr.sim").WhiteNoise(0.1))),
    ("qprr.sim.payload.*", "schedule", Spec("obj", lambda c: importlib.import_module("qprr.sim").PayloadSchedule(()))),
    ("qprr.sim.loop.check_sample", "sample", Spec("obj", lambda c: c.trajectory().sample(np.zeros(2)))),
    ("qprr.sim.loop.check_sample", "n", S(2, "count")),
    ("qprr.sim.loop.check_sample", "nxi", S(9, "count")),
    ("qprr.sim.contact.*", "wrench", F(lambda c: np.zeros(6))),
    ("qprr.sim.contact.*", "point", F(lambda c: np.array([1.0, 0.0, 0.0]))),
    ("qprr.sim.contact.*", "normal", F(lambda c: np.array([-1.0, 0.0, 0.0]))),
    ("qprr.sim.contact.*", "origin", F(lambda c: np.array([1.0, 0.0, 0.0]))),
    ("qprr.control.*", "omega", S(20.0, "pos")),
    ("qprr.control.*", "max_tilt", S(0.5, "pos")),
    ("qprr.control.*", "uz_min", S(1.0, "nonneg")),
    ("qprr.control.*", "n", S(2, "int")),
    ("qprr.control.*", "values", F(lambda c: np.ones(2))),
    ("qprr.control.mfc.ipid", "gains", F(lambda c: (60.0, 8.0, 35.0))),
    ("qprr.control.*", "raw", F(lambda c: np.ones(2))),
    ("qprr.control.*", "n_arm", S(3, "count")),
    ("qprr.control.*", "n_xi", S(9, "count")),
    ("qprr.control.impedance.ImpedanceFilter*", "?", F(lambda c: np.ones(2))),
    ("qprr.control.impedance.ImpedanceFilter.*", "f", F(lambda c: np.ones(2))),
    ("qprr.control.impedance.*", "euler_e", F(lambda c: np.array([0.1, 0.0, 0.2]))),
    ("qprr.control.inverse_dynamics.IDCGains", "k?", V(lambda c: np.ones(c.n_xi))),
    ("qprr.control.inverse_dynamics.IDCGains.*", "names", S(None, "skip")),
    (
        "qprr.payload.combine_inertias",
        "?",
        Spec("obj", lambda c: importlib.import_module("qprr.payload").RigidInertia(0.5, np.zeros(3), np.eye(3) * 1e-3)),
    ),
    ("qprr.ik.tasks.pose.*Pose*", "target", Spec("obj", lambda c: c.target_pose())),
    ("qprr.ik.tasks.pose.BaseOrientationTask", "R_target", Spec("rot", lambda c: _rot())),
    ("qprr.ik.tasks.*", "name", S("t", "label")),
    ("qprr.ik.tasks.*", "q_arm_ref", V(lambda c: c.q_arm())),
    ("qprr.ik.tasks.*", "weights", S(None, "skip")),
    ("qprr.ik.*", "q_arm_posture", V(lambda c: c.q_arm())),
    ("qprr.ik.*", "M", Spec("obj", lambda c: c.target_pose())),
    ("qprr.ik.*", "p_d", F(lambda c: c.target())),
    ("qprr.ik.*", "R_d", Spec("rot", lambda c: _rot())),
    (
        "qprr.ik.hierarchy.HierarchySolver.solve",
        "levels",
        Spec("obj", lambda c: importlib.import_module("qprr.ik").default_levels(c.platform, c.target(), c.q_arm())),
    ),
    ("qprr.nomenclature.LinkSpec", "kind", S("R", "name")),
    ("qprr.nomenclature.BuildSpec", "*_name", S("x", "xmlname")),
    ("qprr.urdf.writer.num", "name", S("x", "skip")),
    ("qprr.urdf.writer.vec", "name", S("v", "skip")),
    ("qprr.urdf.writer.*", "name", S("a", "xmlname")),
    ("qprr.urdf.writer.*", "parent", S("a", "xmlname")),
    ("qprr.urdf.writer.*", "child", S("b", "xmlname")),
    ("qprr.urdf.writer.*", "kind", S("fixed", "name")),
    ("qprr.urdf.writer.xml_name", "x", S("a", "xmlname")),
    ("qprr.urdf.writer.xml_name", "name", S("name", "skip")),
    ("qprr.urdf.writer.*", "xyz", F(lambda c: np.zeros(3))),
    ("qprr.urdf.writer.*", "size", F(lambda c: np.ones(3))),
    ("qprr.urdf.writer.*", "axis", F(lambda c: np.array([0.0, 0.0, 1.0]))),
    ("qprr.urdf.writer.*", "inertia6", F(lambda c: np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]))),
    ("qprr.urdf.writer.*", "parts", Spec("obj", lambda c: ["<link/>"])),
    ("qprr.urdf.writer.*", "generator", S("test", "skip")),
    ("qprr.urdf.writer.num", "x", S(0.5)),
    ("qprr.urdf.writer.link", "inner", S("", "skip")),
    ("qprr.urdf.writer.vec", "v", V(lambda c: np.ones(3), sized=True)),
    ("qprr.rotors.*", "desc", Spec("obj", lambda c: {"rotor": [{"position": [0.2, 0, 0], "spin": 1}, {"position": [-0.2, 0, 0], "spin": -1}]})),
    ("qprr.rotors.Rotor", "position_body", F(lambda c: np.array([0.2, 0.0, 0.0]))),
    ("qprr.rotors.Rotor", "axis_body", F(lambda c: np.array([0.0, 0.0, 1.0]))),
    ("qprr.rotors.Rotor", "f_max", S(10.0, "pos")),
    ("qprr.kinematics.*", "Jc", Spec("mat", lambda c: np.ones((3, c.n_xi)))),
    ("qprr.kinematics.*", "Jc_body", Spec("mat", lambda c: np.ones((3, c.n_xi)))),
    ("qprr.charts.*_batch", "R", Spec("mat", lambda c: np.stack([_rot(), _rot()]))),
    ("qprr.charts.*", "euler", Spec("mat", lambda c: np.array([[0.1, 0.2, 0.3], [0.0, 0.1, 0.0]]))),
    ("qprr.charts.*_batch", "xi", Spec("mat", lambda c: np.stack([c.xi(), c.xi()]))),
    ("qprr.charts.*_batch", "u", Spec("mat", lambda c: np.ones((2, c.n_xi)))),
    ("qprr.charts.*_batch", "tau", Spec("mat", lambda c: np.ones((2, c.n_xi)))),
    ("qprr.charts.to_body_batch", "R", Spec("mat", lambda c: np.stack([_rot(), _rot()]))),
    ("qprr.charts.to_body_batch", "p_world", Spec("mat", lambda c: np.ones((2, 3)))),
    ("qprr.charts.to_body_batch", "origin_world", Spec("mat", lambda c: np.zeros((2, 3)))),
    ("qprr.validation.as_real", "x", S(0.5)),
    ("qprr.validation.as_int", "x", S(3, "int")),
    ("qprr.validation.as_name", "x", S("a", "name")),
    ("qprr.validation.as_interval", "x", F(lambda c: np.array([0.0, 1.0]))),
    ("qprr.validation.as_file", "x", Spec("path_in", lambda c: c.result_file())),
    ("qprr.validation.as_output_path", "x", Spec("path_out", lambda c: c.tmp / "out.npz")),
    ("qprr.charts.as_*", "x", F(lambda c: np.ones(3))),
    ("qprr.charts.as_*", "name", Spec("skip", lambda c: "x")),
    ("qprr.validation.as_*", "x", F(lambda c: np.ones(3))),
    ("qprr.validation.as_*", "name", Spec("skip", lambda c: "x")),
    ("qprr.validation.as_*", "what", Spec("skip", lambda c: "file")),
    ("qprr.validation.as_name", "valid", Spec("skip", lambda c: ("a", "b"))),
    ("qprr.validation.as_vector", "n", S(3, "skip")),
    ("qprr.validation.as_matrix", "shape", Spec("skip", lambda c: (3,))),
    ("qprr.charts.xi_names", "n_arm", S(3, "int")),
    ("qprr.charts.State.lin_to_*", "f_*", F(lambda c: np.ones(3))),
    ("qprr.actuation.IdealAllocator", "platform", Spec("platform", lambda c: c.ideal_platform())),
    ("qprr.actuation.IdealAllocator.allocate_into", "f_out", V(lambda c: np.zeros(18 + c.n_arm))),
    ("qprr.sim.actuators.*", "thrust_factor", F(lambda c: np.full(4, 1e-5))),
    ("qprr.sim.actuators.*", "time_constant", F(lambda c: np.full(4, 0.005))),
    ("qprr.sim.actuators.RotorDynamics", "w_min", F(lambda c: np.zeros(4))),
    ("qprr.sim.actuators.RotorDynamics", "w_max", F(lambda c: np.full(4, 1400.0))),
    ("qprr.sim.actuators.RotorDynamics.*", "w*", F(lambda c: np.full(4, 600.0))),
    ("qprr.sim.actuators.RotorDynamics.*", "f_command", F(lambda c: np.full(4, 8.0))),
    ("qprr.sim.actuators.RotorDynamics.*", "t", Spec("vec", lambda c: np.linspace(0.0, 0.02, 5))),
    ("qprr.sim.actuators.RotorDynamics.bind", "n_rotors", S(4, "count")),
    ("qprr.sim.wind.Dryden", "sigma", F(lambda c: np.array([1.0, 1.0, 0.5]))),
    ("qprr.sim.wind.Dryden", "length", F(lambda c: np.array([50.0, 50.0, 10.0]))),
    ("qprr.sim.wind.Dryden", "airspeed", S(2.0, "pos")),
    ("qprr.sim.wind.Dryden.*", "period", S(0.01, "pos")),
    ("qprr.sim.wind.Dryden.sample", "n", S(5, "count")),
    ("qprr.sim.wind.Dryden.*", "omega", Spec("vec", lambda c: np.linspace(0.1, 1.0, 4))),
    ("qprr.sim.wind.Dryden.*", "lag", Spec("vec", lambda c: np.linspace(0.0, 1.0, 4))),
    ("qprr.sim.wind.Dryden.*", "f", Spec("vec", lambda c: np.linspace(0.1, 1.0, 4))),
    ("qprr.sim.wind.Gust", "start", S(0.1)),
    ("qprr.sim.wind.Gust", "duration", S(0.5, "pos")),
    ("qprr.sim.wind.Gust", "amplitude", F(lambda c: np.array([0.0, 2.0, 0.0]))),
    ("qprr.sim.wind.Gust.velocity", "t", Spec("vec", lambda c: np.linspace(0.0, 1.0, 5))),
    ("qprr.sim.wind.ViscousFriction", "coefficients", V(lambda c: np.full(c.n_xi, 0.01))),
    ("qprr.campaign.*", "spec", Spec("obj", lambda c: c.campaign_spec())),
    ("qprr.campaign.*", "params", Spec("obj", lambda c: {"model.mass": 1.05, "duration": 0.02, "dt": 0.002})),
    ("qprr.campaign.*", "groups", Spec("obj", lambda c: ("rmse", "saturation"))),
    ("qprr.campaign.*", "names", Spec("obj", lambda c: c.platform.xi_names)),
    ("qprr.campaign.*", "result", Spec("obj", lambda c: c.sim_result())),
    ("qprr.campaign.*", "seed", S(3, "int")),
    ("qprr.campaign.runner.run_campaign", "output", Spec("path_out", lambda c: c.tmp / "campaign-run.csv")),
    (
        "qprr.campaign.runner.run_campaign",
        "options",
        Spec("skip", lambda c: importlib.import_module("qprr.campaign.runner").CampaignRunOptions(backend="inline", progress=False), always=True),
    ),
    ("qprr.thesis.scenarios.push_thrust", "settings", Spec("skip", lambda c: _thesis_settings("PushSettings", duration=0.02), always=True)),
    ("qprr.thesis.scenarios.push_prismatic", "settings", Spec("skip", lambda c: _thesis_settings("PushSettings", duration=0.02), always=True)),
    ("qprr.thesis.scenarios.impedance", "settings", Spec("skip", lambda c: _thesis_settings("ImpedanceSettings", duration=0.02), always=True)),
    ("qprr.campaign.spec.CampaignSpec", "name", S("catalogue", "label")),
    ("qprr.campaign.spec.CampaignSpec", "scenario", S("hover-reach", "name", always=True)),
    ("qprr.campaign.spec.CampaignSpec", "options", Spec("obj", lambda c: {"duration": 0.02}, always=True)),
    ("qprr.campaign.spec.CampaignSpec.load", "path", Spec("path_in", lambda c: c.campaign_spec_file())),
    ("qprr.campaign.spec.CampaignSpec.run", "index", S(0, "int")),
    ("qprr.campaign.spec.Distribution", "kind", S("uniform", "name")),
    ("qprr.campaign.spec.Distribution", "low", S(0.5, "real", always=True)),
    ("qprr.campaign.spec.Distribution", "high", S(1.5, "real", always=True)),
    ("qprr.campaign.store.read_results", "path", Spec("path_in", lambda c: c.campaign_results_file())),
    ("qprr.campaign.store.check_output", "path", Spec("path_out", lambda c: c.tmp / "out.csv")),
    ("qprr.campaign.store.ResultStore", "path", Spec("path_out", lambda c: c.fresh_path("store.csv"))),
    ("qprr.campaign.store.ResultStore", "columns", Spec("obj", lambda c: ("run", "status"))),
    ("qprr.campaign.store.ResultStore", "meta", Spec("obj", lambda c: {"fingerprint": "catalogue"})),
    ("qprr.campaign.store.ResultStore.append", "row", Spec("obj", lambda c: {"run": 0, "status": "ok"})),
    ("qprr.campaign.targets.scale_bandwidth", "gains", Spec("obj", lambda c: importlib.import_module("qprr.thesis.gains").idc())),
    ("qprr.campaign.targets.scale_bandwidth", "group", S("position", "name")),
    ("qprr.campaign.targets.scale_bandwidth", "s", S(2.0, "pos")),
    ("qprr.campaign.targets.scale_bandwidth", "n_xi", S(9, "count")),
    ("qprr.campaign.worker.load_platform", "name", S("q-prr", "name")),
    # qprr.envs (the rl extra): a task is named by its value or its Gymnasium id; 2 copies of the default platform
    ("qprr.envs.*", "task", S("hover", "name")),
    ("qprr.envs.*", "kind", S("hover", "name")),
    ("qprr.envs.*", "n", S(2, "count")),
    ("qprr.envs.*", "geometry", Spec("obj", lambda c: _envs("settings").Geometry())),
    ("qprr.envs.*", "settings", Spec("obj", lambda c: _envs("settings").EnvSettings())),
    ("qprr.envs.*.reset", "seed", S(3, "int")),
    ("qprr.envs.*.reset", "options", Spec("obj", lambda c: {})),
    ("qprr.envs.settings.settings_with", "options", Spec("obj", lambda c: {"duration": 1.0})),
    ("qprr.envs.actions.*", "controller", S("idc", "name")),
    ("qprr.envs.actions.*", "period", S(0.005, "pos")),
    ("qprr.envs.actions.ReferenceMap", "residual", F(lambda c: np.array([0.5, 0.5, 0.25]))),
    ("qprr.envs.randomize.Randomization", "entries", Spec("obj", lambda c: (("model.mass", (0.9, 1.1)), ("tau", 0.02)))),
    ("qprr.envs.randomize.Randomization.*", "key", S("model.mass", "name")),
    ("qprr.envs.tasks.posture", "u", V(lambda c: np.full(c.n_arm, 0.5))),
    ("qprr.envs.tasks.posture", "fraction", S(0.5)),
    ("qprr.envs.tasks.ee_positions", "xi", Spec("mat", lambda c: np.stack([c.xi(), c.xi()]))),
    ("qprr.envs.tasks.mission_sample", "mission", Spec("obj", lambda c: c.trajectory())),
    ("qprr.envs.tasks.mission_sample", "t", Spec("vec", lambda c: np.linspace(0.0, 1.0, 5))),
    ("qprr.envs.tasks.mission_sample", "n_xi", Spec("count", lambda c: c.n_xi)),
    ("qprr.envs.tasks.TaskSpec", "duration", S(5.0, "pos")),
    ("qprr.envs.tasks.TaskSpec", "weights", Spec("obj", lambda c: _envs("tasks").RewardWeights())),
    ("qprr.envs.tasks.TaskSpec", "success", Spec("obj", lambda c: _envs("tasks").Success.BASE_WINDOW)),
    ("qprr.envs.tasks.TaskSpec", "tolerance", S(0.1, "pos")),
    ("qprr.envs.tasks.TaskSpec", "window", S(1.0, "pos")),
    ("qprr.envs.scalar.AerialEnv.step", "action", V(lambda c: np.zeros(_action_size(c)))),
    ("qprr.envs.vector.AerialVectorEnv.step", "actions", Spec("mat", lambda c: np.zeros((2, _action_size(c))))),
    ("qprr.envs.core.BatchCore.step", "actions", Spec("mat", lambda c: np.zeros((2, _action_size(c))))),
    ("qprr.envs.core.BatchCore.step", "frozen", Spec("obj", lambda c: np.zeros(2, dtype=bool))),
    ("qprr.envs.core.BatchCore.*", "rngs", Spec("obj", lambda c: [np.random.default_rng(0), np.random.default_rng(1)])),
    ("qprr.envs.core.BatchCore.reset_rows", "rows", Spec("obj", lambda c: np.arange(2))),
    ("qprr.envs.core.check_actions", "actions", Spec("mat", lambda c: np.zeros((2, _action_size(c))))),
    ("qprr.envs.core.check_actions", "shape", Spec("skip", lambda c: (2, _action_size(c)))),
    ("qprr.envs.core.check_actions", "name", Spec("skip", lambda c: "actions")),
]

INSTANCES: dict[str, Callable[[Ctx], object]] = {
    "qprr.sim.result.SimResult": lambda c: c.sim_result(),
    "qprr.model.Platform": lambda c: c.platform,
    "qprr.charts.State": lambda c: importlib.import_module("qprr.charts").State(c.platform.n_arm),
    "qprr.thesis.params.QPRRParams": lambda c: importlib.import_module("qprr.thesis.params").thesis_params(),
    "qprr.nomenclature.mdh.MDHRow": lambda c: importlib.import_module("qprr.nomenclature.mdh").MDHRow(0, 0.1, 0.2, 0.3, 0.4),
    "qprr.thesis.params.Link": lambda c: importlib.import_module("qprr.thesis.params").thesis_params().links[0],
    "qprr.actuation.IdealAllocator": lambda c: importlib.import_module("qprr.actuation").IdealAllocator(c.ideal_platform()),
    "qprr.dynamics.friction.JointFriction": lambda c: _joint_friction(c.platform),
    "qprr.actuation.lexicographic.Lexicographic": lambda c: importlib.import_module("qprr.actuation.lexicographic").Lexicographic(3),
    "qprr.campaign.spec.CampaignSpec": lambda c: c.campaign_spec(),
    "qprr.campaign.spec.Distribution": lambda c: importlib.import_module("qprr.campaign.spec").Distribution("uniform", 0.5, 1.5),
    "qprr.envs.scalar.AerialEnv": lambda c: _reset_env(_envs("scalar").AerialEnv("hover")),
    "qprr.envs.vector.AerialVectorEnv": lambda c: _reset_env(_envs("vector").AerialVectorEnv(2, "hover")),
    "qprr.envs.core.BatchCore": lambda c: _batch_core(),
    "qprr.campaign.store.ResultStore": lambda c: importlib.import_module("qprr.campaign.store").ResultStore(
        c.fresh_path("store.csv"), ("run", "status"), {"fingerprint": "catalogue"}
    ),
}


def _envs(module: str):
    """A module of qprr.envs (imported when a builder runs: the rl extra is optional)."""
    return importlib.import_module(f"qprr.envs.{module}")


def _action_size(c: Ctx) -> int:
    """The size of an action of the thrusts mode on the catalogue's platform (one per rotor and arm joint)."""
    return c.platform.n_rotors + c.n_arm


def _joint_friction(platform):
    """The friction of ``platform``'s model given arm damping 0.05 and Coulomb friction 0.02 (the Q-PRR's URDF has none)."""
    model = platform.model.copy()
    model.damping[6:] = 0.05
    model.friction[6:] = 0.02
    return importlib.import_module("qprr.dynamics.friction").JointFriction.from_model(model, 1e-3)


def _reset_env(env):
    """An environment after ``reset(seed=0)`` (what its step needs)."""
    env.reset(seed=0)
    return env


def _batch_core():
    """Two copies of Hover on the default platform, reset."""
    core = _envs("core").BatchCore("hover", 2, _envs("settings").EnvSettings())
    core.reset_rows(np.arange(2), [np.random.default_rng(0), np.random.default_rng(1)])
    return core


def _rot() -> np.ndarray:
    a, b, c = 0.1, -0.2, 0.3
    ca, sa, cb, sb, cc, sc = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    Rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    Rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def spec_for(target: Target, param: inspect.Parameter) -> Spec | None:
    hits = [
        (sum(x.count(w) for x in (pattern, name) for w in "*?"), -len(pattern) - len(name), k, spec)
        for k, (pattern, name, spec) in enumerate(QUALIFIED)
        if fnmatch.fnmatchcase(param.name, name) and fnmatch.fnmatchcase(target.qualname, pattern)
    ]
    if hits:
        return min(hits, key=lambda h: h[:3])[3]  # the most specific pattern
    if param.name in SPECS:
        return SPECS[param.name]
    d = param.default
    if d is inspect.Parameter.empty:
        ann = str(param.annotation)
        if ann in ("float", "'float'"):
            return S(0.3)
        return None
    # from the default
    if isinstance(d, bool) or d is None or callable(d) or isinstance(d, types.ModuleType):
        return Spec("skip", lambda c, d=d: d)
    if isinstance(d, (int, np.integer)):
        return Spec("int", lambda c, d=d: d)
    if isinstance(d, float):
        return Spec("real_default", lambda c, d=d: d)
    if isinstance(d, str):
        return Spec("name" if param.name not in FREE_TEXT else "skip", lambda c, d=d: d)
    if isinstance(d, tuple) and d and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in d):
        return Spec("vec", lambda c, d=d: np.array(d, dtype=float))
    return Spec("skip", lambda c, d=d: d)


FREE_TEXT = {
    "name",
    "label",
    "title",
    "description",
    "color",
    "help",
    "message",
    "source",
    "scenario",
    "detail",
    "reason",
    "provenance",
    "prefix",
    "suffix",
    "unit",
    "text",
    "what",
}


# ============================================================================ bad values
def bad_values(kind: str, valid, ctx: Ctx, length_known: bool = True) -> list[tuple[str, object]]:
    """(label, value) pairs of the bad inputs of a kind, derived from a valid value (``length_known``: a vector one
    entry longer is wrong; False for a platform-sized vector given to a callable that cannot know the platform)."""
    out: list[tuple[str, object]] = []
    if kind in ("vec", "q", "rot", "mat"):
        a = np.asarray(valid, dtype=float)
        if a.ndim == 1 and length_known:
            out.append(("wrong length", np.append(a, 0.0)))
        out += [
            ("2-D" if a.ndim == 1 else "wrong shape", a[None, :] if a.ndim == 1 else a[..., :-1]),
            ("complex", a + 1j),
            ("object array", a.astype(object)),
            ("string array", np.full(a.shape, "x")),
            ("bool array", np.ones(a.shape, dtype=bool)),
            ("NaN entry", _with(a, math.nan)),
            ("inf entry", _with(a, math.inf)),
            ("empty", np.zeros((0,))),
            ("None", None),
        ]
        if kind == "q":
            z = a.copy()
            z[3:7] = 0.0
            u = a.copy()
            u[3:7] *= 2.0
            out += [("zero quaternion", z), ("unnormalised quaternion", u)]
        if kind == "rot":
            out += [("not orthonormal", 2.0 * a)]
    elif kind in ("real", "pos", "nonneg", "real_default"):
        out += [("NaN", math.nan), ("string", "fast"), ("complex", 1.0 + 1.0j), ("None", None)]
        if kind != "real_default":
            out += [("inf", math.inf)]
        if kind == "pos":
            out += [("zero", 0.0), ("negative", -1.0)]
        if kind == "nonneg":
            out += [("negative", -1.0)]
    elif kind == "count":
        out += [("zero", 0), ("negative", -3), ("fraction", 2.5), ("string", "3"), ("None", None)]
    elif kind == "int":
        out += [("fraction", 2.5), ("string", "3")]
    elif kind == "name":
        out += [("unknown name", "no-such-name"), ("None", None), ("number", 3)]
    elif kind == "label":
        out += [("empty name", ""), ("None", None), ("number", 3)]
    elif kind == "xmlname":
        out += [("quote in name", 'a"b'), ("empty name", ""), ("None", None), ("number", 3)]
    elif kind == "text":
        out += [("not XML", "garbage <<"), ("None", None), ("number", 3)]
    elif kind == "frame":
        out += [("unknown frame", "no-such-frame"), ("frame id out of range", 10**6)]
    elif kind == "path_in":
        out += [
            ("missing file", ctx.tmp / "missing" / "none.npz"),
            ("directory", ctx.tmp),
            ("empty file", ctx.file("empty" + Path(str(valid)).suffix, b"")),
            ("corrupted file", ctx.file("corrupt" + Path(str(valid)).suffix, b"\x00\x01garbage\xff" * 8)),
            ("None", None),
        ]
    elif kind == "path_out":
        blocker = ctx.file("blocker", b"")
        out += [("parent is a file", blocker / ("out" + Path(str(valid)).suffix)), ("None", None)]
    elif kind in ("platform", "model", "obj"):
        out += [("None", None), ("string", "x"), ("number", 1.5)]
    elif kind == "data":
        other = ctx.once("other_data", lambda: _other_data())
        out += [("None", None), ("string", "x"), ("data of another model", other)]
    return out


def _other_data():
    import pinocchio as pin

    m = pin.buildSampleModelManipulator()
    return m.createData()


def _with(a: np.ndarray, x: float) -> np.ndarray:
    b = np.array(a, dtype=float, copy=True)
    if b.size:
        b.flat[min(1, b.size - 1)] = x
    return b


# ============================================================================ outcomes
HOT = "hot-loop form on plain floats, unvalidated by design (runs every simulated millisecond); the validated forms are "
ALLOWED: dict[tuple[str, str, str], str] = {
    ("qprr.analysis.cog.BalanceOptions", "slider", "None"): "None: no slider, the map of |offset| (documented)",
    ("qprr.analysis.cog.BalanceOptions", "slider", "unknown name"): "a slider is a joint of a platform: balance() "
    "checks it against the platform's prismatic joints (naming them)",
    ("qprr.analysis.singularity.SingularityOptions", "frame", "*"): "a frame is a name or id of a platform: singularity() "
    "resolves it against the platform it maps (an unknown one is refused there, naming the frames)",
    ("qprr.analysis.workspace.WorkspaceOptions", "frame", "*"): "a frame is a name or id of a platform: workspace() "
    "resolves it against the platform it maps (an unknown one is refused there, naming the frames)",
    ("qprr.analysis.opspace.OpSpaceOptions", "frame", "*"): "a frame is a name or id of a platform: opspace_map() "
    "resolves it against the platform it maps (an unknown one is refused there, naming the frames)",
    ("qprr.validation.as_file", "x", "*file"): "as_file checks that the file exists; its content is for the reader to check",
    ("qprr.validation.as_array", "x", "*"): "as_array converts any shape; NaN and inf pass unless finite=True is asked",
    ("qprr.charts.wrap_angle", "a", "NaN entry"): "elementwise on any array: NaN stays NaN (logs of diverged runs), like numpy's ufuncs",
    ("qprr.charts.wrap_angle", "a", "inf entry"): "elementwise on any array: inf maps to NaN, like numpy's remainder",
    ("qprr.charts.wrap_angle", "a", "2-D"): "elementwise on an array of any shape",
    ("qprr.charts.wrap_angle", "a", "empty"): "elementwise on an array of any shape (empty in, empty out)",
    ("qprr.charts.State.*", "*", "*"): HOT + "the array functions of qprr.charts (tests check them against each other)",
    ("qprr.actuation.*Allocator.*_into", "*", "*"): HOT + "Allocator.allocate (allocate_into, its screened form and its reference)",
    ("qprr.kinematics.com_jacobian_body_from", "*", "*"): "the second half of com_jacobian_body for a caller whose data already holds "
    "the CoM and its Jacobian (hot path); without the platform it cannot check data or the width of Jc",
    ("qprr.rotors.Rotor", "f_max", "inf"): "f_max = inf: a rotor without an upper thrust bound (the default)",
    ("qprr.model.from_*", "params", "*"): "params is an opaque record of what built the platform: the library never reads it",
    ("qprr.model.Platform", "params", "*"): "params is an opaque record of what built the platform: the library never reads it",
    ("qprr.ik.tasks.*.linearize", "*", "*"): HOT + "IKSolver.solve (linearize runs in every iteration on a configuration the "
    "solver validated; its output is checked: qprr.ik.tasks.base.check_linearized)",
    ("qprr.ik.tasks.*.error", "*", "*"): HOT + "IKSolver.solve (the first step of a solve asks for the errors alone at a "
    "configuration the solver validated)",
    ("qprr.ik.tasks.base.update_kinematics", "*", "*"): HOT + "IKSolver.solve (once per iteration, before the tasks)",
    ("qprr.ik.hierarchy.HierarchySolver.solve", "*", "*"): HOT + "IKSolver.solve (one hierarchical step per iteration)",
    ("qprr.ik.solver.pose_errors", "R_d", "None"): "R_d None: a position target (orientation error 0 by definition)",
    ("qprr.ik.solver.pose_error_values", "*", "*"): HOT + "IKSolver.solve and the methods (once per iteration, on the target "
    "parse_target checked once per solve); pose_errors is its checked form",
    ("qprr.ik.solver.hover_q", "*", "*"): HOT + "the IK methods' last step (the IGM's answer as q: its speed is the IGM's point); "
    "the configurations it gets come from the methods, on inputs IKSolver.solve checked",
    ("qprr.ik.solver.default_guess", "R_world", "None"): "R_world None: a position target (the orientation is free)",
    ("qprr.control.*.step", "*", "*"): HOT + "the simulator's per-tick call: reset checks the state and reference once per run",
    ("qprr.thesis.bsg.CogStabilizer.joint_references", "*", "*"): HOT + "CogStabilizer.step's per-tick part",
    ("qprr.control.*.update_references", "*", "*"): HOT + "the controller's per-tick hook (reset checks once per run)",
    ("qprr.control.*.feedforward", "*", "*"): HOT + "the controller's per-tick hook (reset checks once per run)",
    ("qprr.control.*.measure", "*", "*"): HOT + "the controller's per-tick hook; the sensor outputs are checked",
    ("qprr.control.filters.*.update", "*", "*"): HOT + "the filter's constructor (its settings) and reset",
    ("qprr.control.filters.*.write", "*", "*"): HOT + "the filter's constructor (its settings) and reset",
    ("qprr.control.mfc.ipid", "*", "*"): HOT + "ModelFreeController (the iPID law (6.21) of each coordinate at every tick)",
    ("qprr.control.filters.tilt_6_17", "*", "*"): HOT + "TiltReference (tilt_6_17 runs every control tick on its checked state)",
    ("qprr.control.filters.CommandFilter.reset", "*", "*"): HOT + "CommandFilter's constructor (reset is its per-run start on the "
    "values update gives it)",
    ("qprr.control.impedance.ImpedanceFilter.step", "*", "*"): HOT + "ImpedanceFilter's constructor and reset (step runs every tick)",
    ("qprr.dynamics.friction.JointFriction.solve", "*", "*"): HOT + "JointFriction.choose, max_rate and stable_step (solve runs "
    "at every integration stage on the simulator's checked state)",
    ("qprr.dynamics.friction.JointFriction.start", "*", "*"): HOT + "JointFriction.generalized_force (start runs at every "
    "integration step on the simulator's checked state)",
    ("qprr.sim.disturbances.*.generalized_force", "*", "*"): HOT + "simulate (a state disturbance runs at every integration stage)",
    ("qprr.sim.wind.*.generalized_force", "*", "*"): HOT + "simulate (a state disturbance runs at every integration stage; the "
    "constructors check the coefficients and the wind)",
    ("qprr.control.decoupled.DecoupledController.arm_accelerations", "*", "*"): HOT + "DecoupledController.step's per-tick arm "
    "law (reset checks the state and reference once per run)",
    ("qprr.control.mpc.MPCController.set_preview", "trajectory", "None"): "None: no preview (the current reference is "
    "extrapolated over the horizon, as documented)",
    ("qprr.model.from_urdf", "g", "zero"): "g = 0: free flight (momentum and energy conservation tests fly without gravity)",
    ("qprr.campaign.metrics.metrics_of", "wall_time", "NaN"): "NaN (the default): not measured, the result's own wall time is used",
    ("qprr.campaign.spec.CampaignSpec", "base_dir", "unknown name"): "base_dir is any folder name: a relative callable file is "
    "read from it when the runs start (a remote worker need not have it: the file travels as text)",
    ("qprr.sim.actuators.RotorDynamics", "initial", "number"): "one initial speed [rad/s] for every rotor (one value or one per "
    "rotor, as every per-rotor field)",
    ("qprr.sim.actuators.RotorDynamics.step_response", "t", "wrong length"): "any number of sample times",
    ("qprr.sim.actuators.RotorDynamics.step_response", "t", "empty"): "no sample times: an empty response",
    ("qprr.sim.wind.*", "*", "wrong length"): "any number of sample times, lags or frequencies",
    ("qprr.sim.wind.*", "*", "empty"): "no sample times, lags or frequencies: an empty result",
    ("qprr.campaign.metrics.metrics_of", "result", "None"): "None: a run that raised before simulating (its row gets the "
    "status and reason given, NaN metrics)",
    ("qprr.sim.integrators.*", "*", "*"): HOT + "simulate (one integration step; make_stepper checks the method and dt)",
    ("qprr.sim.contact.*", "*", "*"): HOT + "simulate (an Environment's hooks run at every stage; their constructors check the settings)",
    ("qprr.sim.disturbances.Pulse", "gamma", "wrong length"): "gamma's length is checked against the platform when the simulator "
    "samples the pulse (Pulse.values with n_xi)",
    ("qprr.sim.disturbances.split", "disturbance", "None"): "None: no disturbance",
    ("qprr.sim.disturbances.*", "t", "wrong length"): "any number of sample times (the grid of the run)",
    ("qprr.sim.disturbances.*", "t", "empty"): "no sample times: no values (an empty array of shape (0, n_xi))",
    ("qprr.sim.disturbances.check_values_args", "rng", "None"): "rng None: a disturbance without randomness (Pulse)",
    ("qprr.trajectory.Spiral", "arm", "wrong length"): "any number of arm joints",
    ("qprr.trajectory.Spiral", "arm", "empty"): "a platform without an arm",
    ("qprr.trajectory.*", "t", "wrong length"): "any number of sample times",
    ("qprr.trajectory.*", "t", "empty"): "no sample times: an empty sample",
    ("qprr.trajectory.transition", "t", "2-D"): "transition is elementwise over times of any shape",
    ("qprr.analysis.chain.ArmChain.*", "q_arm", "2-D"): "a batch of configurations, one per row",
    ("qprr.analysis.*", "payload_masses", "wrong length"): "any number of payload masses",
    ("qprr.viz.animation.frame_indices", "t", "wrong length"): "any number of samples",
    ("qprr.viz.run.RunLog", "xi", "wrong shape"): "xi of (n, 8): a platform with two arm joints",
    ("qprr.wheeled.wheels.*Wheel.*", "s", "*"): "dual numeric/symbolic (backend m): s may be a sympy expression",
    ("qprr.wheeled.robots.*.[AB]", "q", "*"): "dual numeric/symbolic (backend m): q may hold sympy symbols; simulate and the controllers check q",
    ("qprr.wheeled.robots.*.singularity", "q", "*"): "dual numeric/symbolic: q may hold sympy symbols",
    ("qprr.wheeled.sim.sinc", "*", "*"): HOT + "se2_flow (every integration step)",
    ("qprr.wheeled.robots.Omnidirectional", "robot", "*"): "robot None: the default three-wheel layout",
    ("qprr.urdf.writer.xml_name", "x", "*"): "a converter: its error names the argument it is told (its name parameter)",
    ("qprr.control.impedance.ImpedanceGains.arm", "n_arm", "zero"): "n_arm = 0: a platform without an arm (empty filters)",
    ("qprr.charts.*_batch", "*", "NaN entry"): "batch forms over logged runs: a diverged run logs NaN rows, which stay NaN",
    ("qprr.charts.*_batch", "*", "inf entry"): "batch forms over logged runs: rows of a diverged run pass through",
    ("qprr.flightlog.stats.lag_response", "u", "2-D"): "samples in rows, one column per motor",
    ("qprr.envs.randomize.lag_factors", "tau", "empty"): "one time constant per copy, elementwise: no copies, no factors",
    ("qprr.envs.tasks.mission_sample", "t", "wrong length"): "any number of sample times",
    ("qprr.envs.tasks.mission_sample", "t", "empty"): "no sample times: an empty sample",
    ("qprr.envs.settings.settings_with", "settings", "None"): "None: the default EnvSettings() (documented)",
}
"""(qualname pattern, parameter, bad label pattern) -> why returning a value is the right answer there."""


def allowed(qualname: str, param: str, label: str) -> str | None:
    for (pat, p, lab), why in ALLOWED.items():
        if fnmatch.fnmatchcase(qualname, pat) and fnmatch.fnmatchcase(param, p) and fnmatch.fnmatchcase(label, lab):
            return why
    return None


@dataclass
class Outcome:
    target: str
    param: str
    label: str
    verdict: str  # good | unclear | silent | hang | allowed | crash
    detail: str = ""


@dataclass
class Report:
    outcomes: list[Outcome] = field(default_factory=list)
    not_fed: dict[str, str] = field(default_factory=dict)  # callable -> why it was not called
    baseline_failed: dict[str, str] = field(default_factory=dict)

    def counts(self) -> dict[str, int]:
        c: dict[str, int] = {}
        for o in self.outcomes:
            c[o.verdict] = c.get(o.verdict, 0) + 1
        return c


class _Timeout(BaseException):
    pass


def _alarm(signum, frame):
    raise _Timeout()


@contextlib.contextmanager
def _work_limit(seconds: float):
    if seconds <= 0 or not hasattr(signal, "setitimer"):
        yield
        return
    old = signal.signal(signal.SIGVTALRM, _alarm)
    signal.setitimer(signal.ITIMER_VIRTUAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_VIRTUAL, 0)
        signal.signal(signal.SIGVTALRM, old)


def _printable(value) -> str | None:
    if isinstance(value, (str, int, float)) and not isinstance(value, bool):
        return repr(value) if not isinstance(value, float) else None
    return None


def judge(exc: BaseException, param: str, value, errors) -> tuple[str, str]:
    """``good`` if ``exc`` is a qprr error naming ``param`` (or the unknown name given); else ``unclear``."""
    msg = str(exc)
    if errors is None or not isinstance(exc, errors.QprrError):
        return "unclear", f"{type(exc).__name__}: {msg[:300]}"
    names_it = param in msg
    if not names_it and isinstance(exc, errors.UnknownNameError):
        names_it = repr(value) in msg  # "unknown platform 'x'; valid: ..." names the value and its role
    if not names_it and isinstance(value, Path):
        names_it = str(value) in msg  # a file named in full
    if not names_it:
        return "unclear", f"{type(exc).__name__} (does not name {param!r}): {msg[:300]}"
    return "good", f"{type(exc).__name__}: {msg[:200]}"


@dataclass
class Plan:
    """A callable with the arguments to call it (``args`` positional, ``kwargs`` by name) and the specs of its parameters."""

    target: Target
    params: list[tuple[inspect.Parameter, Spec]]
    passed: list[str]


def plan(target: Target) -> Plan | str:
    """The parameters to pass, or why the callable cannot be fed."""
    try:
        sig = inspect.signature(target.obj)
    except (TypeError, ValueError):
        return "no signature"
    params = []
    passed = []
    first = True
    for p in sig.parameters.values():
        if target.owner is not None and first and p.name in ("self", "cls"):
            first = False
            continue
        first = False
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        spec = spec_for(target, p)
        if spec is None:
            return f"no builder for parameter {p.name!r}"
        params.append((p, spec))
        if p.default is p.empty or spec.always:
            passed.append(p.name)
    return Plan(target, params, passed)


def _bound(pl: Plan, ctx: Ctx, instance, override: tuple[str, object] | None):
    args, kwargs = [], {}
    for p, spec in pl.params:
        if p.name not in pl.passed and (override is None or override[0] != p.name):
            continue
        value = override[1] if override is not None and override[0] == p.name else spec.make(ctx)
        if p.kind == p.POSITIONAL_ONLY:
            args.append(value)
        else:
            kwargs[p.name] = value
    fn = pl.target.obj
    if pl.target.owner is not None:
        fn = getattr(instance, pl.target.method)
    return fn, args, kwargs


def instance_of(cls: type, ctx: Ctx):
    """An instance to call the methods of ``cls`` on (INSTANCES table, else its constructor with built arguments)."""
    qual = f"{cls.__module__}.{cls.__qualname__}"
    if qual in INSTANCES:
        return INSTANCES[qual](ctx)
    pl = plan(Target(qual, cls))
    if isinstance(pl, str):
        raise LookupError(pl)
    fn, args, kwargs = _bound(pl, ctx, None, None)
    return fn(*args, **kwargs)


RECORDS = {
    "ArmJoint": "a joint record that from_model reads off the Pinocchio model",
    "Evidence": "what a check of qprr.thesis.checks returns (the numbers it measured)",
}


def is_record(cls: type, returned: set[str]) -> bool:
    """A result record: a dataclass that some public callable returns and that does not validate itself (no
    ``__post_init__``): the API builds it, its constructor is not an entry point."""
    if cls.__name__ in RECORDS:
        return True
    return dataclasses.is_dataclass(cls) and cls.__name__ in returned and "__post_init__" not in vars(cls)


def returned_types(targets: list[Target]) -> set[str]:
    out = set()
    for t in targets:
        ann = getattr(t.obj, "__annotations__", {}).get("return") if not isinstance(t.obj, type) else None
        if isinstance(ann, str):
            for tok in ann.replace("|", " ").replace("[", " ").replace("]", " ").replace(",", " ").split():
                out.add(tok.strip("'\""))
        elif isinstance(ann, type):
            out.add(ann.__name__)
    return out


@dataclass
class _Hooks:
    """For the audit's child processes: skip the first ``start_at`` cases; ``on_start(index)`` before each case (a crash
    inside it is then known), ``on_outcome(index, outcome)`` after it."""

    start_at: int = 0
    on_start: Callable[[int], None] | None = None
    on_outcome: Callable[[int, Outcome], None] | None = None
    index: int = 0

    def begin(self) -> bool:
        """Whether the next case is to run (and announce it)."""
        self.index += 1
        if self.index <= self.start_at:
            return False
        if self.on_start is not None:
            self.on_start(self.index)
        return True


def run(
    targets: list[Target] | None = None,
    *,
    include: Callable[[Target], bool] | None = None,
    timeout: float = WORK_LIMIT,
    progress: Callable[[str], None] | None = None,
    hooks: _Hooks | None = None,
) -> Report:
    """Feed every target its bad values; see the module docstring.  ``hooks``: see :class:`_Hooks` (audit only)."""
    targets = walk() if targets is None else targets
    returned = returned_types(targets)
    errors = importlib.import_module("qprr.errors")
    report = Report()
    hooks = hooks or _Hooks()
    cwd = os.getcwd()
    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        os.chdir(tmp)  # a default relative output path lands in the temporary folder
        try:
            report = _run_all(targets, include, timeout, progress, hooks, returned, errors, Ctx(Path(tmp)), report)
        finally:
            os.chdir(cwd)
    return report


def _run_all(targets, include, timeout, progress, hooks, returned, errors, ctx, report) -> Report:
    """The loop of :func:`run` over the targets (in the temporary working folder)."""
    for target in targets:
        if include is not None and not include(target):
            continue
        why = next((w for pat, w in NOT_FED.items() if fnmatch.fnmatchcase(target.qualname, pat)), None)
        if why is not None:
            report.not_fed[target.qualname] = why
            continue
        if isinstance(target.obj, type) and is_record(target.obj, returned):
            report.not_fed[target.qualname] = "result record (returned by the API, not an entry point)"
            continue
        if (
            target.owner is not None
            and is_record(target.owner, returned)
            and f"{target.owner.__module__}.{target.owner.__qualname__}" not in INSTANCES
        ):
            report.not_fed[target.qualname] = "method of a result record without an instance builder (INSTANCES)"
            continue
        pl = plan(target)
        if isinstance(pl, str):
            report.not_fed[target.qualname] = pl
            continue
        if progress:
            progress(target.qualname)
        _feed(pl, ctx, report, errors, timeout, hooks)
    return report


SIZE_PARAMS = {"platform", "robot", "model", "data", "state", "ref", "n", "n_xi", "n_arm"}


def knows_size(pl: Plan) -> bool:
    """Whether the callable can know the platform's sizes (a platform-like argument, or a method of an object built on one)."""
    return pl.target.owner is not None or any(p.name in SIZE_PARAMS and p.name in pl.passed for p, _ in pl.params)


def _call(pl: Plan, ctx: Ctx, override, timeout: float):
    instance = instance_of(pl.target.owner, ctx) if pl.target.owner is not None else None
    fn, args, kwargs = _bound(pl, ctx, instance, override)
    with _work_limit(timeout), warnings.catch_warnings():
        if override is not None:  # numpy's warnings on the bad value itself (NaN, complex: a ComplexWarning is one)
            warnings.simplefilter("ignore", RuntimeWarning)
        return fn(*args, **kwargs)


def _feed(pl: Plan, ctx: Ctx, report: Report, errors, timeout: float, hooks: _Hooks) -> None:
    qual = pl.target.qualname
    record = hooks.begin()  # a skipped baseline still runs (it decides whether the bad values are fed), unrecorded
    try:
        _call(pl, ctx, None, timeout)
    except _Timeout:
        if record:
            report.baseline_failed[qual] = f"valid call still running after {timeout} s of processor time"
        return
    except (Exception, SystemExit) as exc:
        if record:
            report.baseline_failed[qual] = f"{type(exc).__name__}: {str(exc)[:200]}"
        return
    for p, spec in pl.params:
        try:
            valid = spec.make(ctx)
        except Exception:
            continue
        knows = knows_size(pl)
        for label, value in bad_values(spec.kind, valid, ctx, not (spec.sized and not knows)):
            if value is None and p.default is None:
                continue  # None is the documented default there
            if not hooks.begin():
                continue
            try:
                _call(pl, ctx, (p.name, value), timeout)
            except _Timeout:
                verdict, detail = "hang", f"still running after {timeout} s of processor time"
            except (Exception, SystemExit) as exc:
                verdict, detail = judge(exc, p.name, value, errors)
            else:
                verdict, detail = "silent", "returned without an error"
            if verdict in ("silent", "unclear", "hang"):
                why = allowed(qual, p.name, label)
                if why is not None:
                    verdict, detail = "allowed", why
            report.outcomes.append(Outcome(qual, p.name, label, verdict, detail))
            if hooks.on_outcome is not None:
                hooks.on_outcome(hooks.index, report.outcomes[-1])


# ============================================================================ issue 34: cases on the new surfaces
@dataclass(frozen=True)
class Case:
    """One bad input on a surface the introspection above cannot feed (a scenario option, a mission, a rotor file, a
    controller, a study): ``call()`` must raise a :class:`qprr.errors.QprrError` - or, with ``warns``, emit a warning -
    whose message contains every string of ``names`` (the argument, the value, the fix)."""

    label: str
    call: Callable[[], object]
    names: tuple[str, ...]
    warns: bool = False


_EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "my_platform"


def example_platform():
    """examples/my_platform's quad_rrr (the platform docs/platforms.md builds), loaded once."""
    import qprr

    if "quad" not in _CASE_CACHE:
        _CASE_CACHE["quad"] = qprr.from_urdf(_EXAMPLE / "quad_rrr.urdf", _EXAMPLE / "quad_rrr.rotors.toml", ee_frame="gripper")
    return _CASE_CACHE["quad"]


_CASE_CACHE: dict[str, object] = {}


def _scenario(name: str, **options):
    from qprr.scenarios import run as run_scenario

    return lambda: run_scenario(name, platform=example_platform(), duration=0.05, **options)


def _z_phase(end: float = 0.02) -> dict:
    return {"coordinate": "z", "start": 0.0, "end": end, "target": 1.0}


def mission_cases() -> list[Case]:
    """Issue 34, items 2 and 3: missions, scenario options."""
    late = {"coordinate": "x", "start": 0.5, "end": 0.8, "target": 1.0}
    return [
        Case(
            "mission phase after the run's end",
            _scenario("mission", mission={"phase": [_z_phase(), late]}),
            ("phase 2", "start = 0.5", "duration = 0.05", "never flown"),
            warns=True,
        ),
        Case(
            "mission payload event after the run's end",
            _scenario("mission", mission={"phase": [_z_phase()], "payload": [{"time": 0.5, "mass": 0.1}]}),
            ("payload event 1", "time = 0.5", "duration", "never flown or applied"),
            warns=True,
        ),
        Case(
            "mission payload of 150 kg (grams?)",
            _scenario("mission", mission={"phase": [_z_phase()], "payload": [{"time": 0.01, "mass": 150.0}]}),
            ("payload event 1", "mass = 150", "grams"),
        ),
        Case(
            "mission phase ending after the run's end (flown in part)",
            _scenario("mission", mission={"phase": [_z_phase(0.08)]}),
            ("phase 1", "end = 0.08", "duration", "flown in part"),
            warns=True,
        ),
        *mission_file_cases(),
        Case("fly-to target of two numbers", _scenario("fly-to", target=(1.0, 0.5)), ("target", "(1.0, 0.5)", "(x, y, z)")),
        Case("hover-noise fraction NaN", _scenario("hover-noise", fraction=math.nan), ("fraction", "nan")),
        Case("hover-noise fraction text", _scenario("hover-noise", fraction="2%"), ("fraction", "'2%'")),
        Case("thesis flag as_printed = 'maybe'", lambda: _thesis_run(as_printed="maybe"), ("as_printed", "'maybe'", "true or false")),
    ]


_WIND = {"model": "mean", "mean_world": [3.0, 0.0, 0.0]}
_DRAG = {"linear": 0.3}


def _mission(**tables):
    """A mission on examples/my_platform: one short climb and ``tables`` (a scenario run of 0.05 s)."""
    return _scenario("mission", mission={"phase": [_z_phase()], **tables})


def mission_file_cases() -> list[Case]:
    """Issue 35, item 2: the tables of a mission file beyond its phases (qprr.scenarios.mission_file), and settings objects."""
    from qprr.scenarios import run as run_scenario
    from qprr.scenarios.missions import MissionSettings

    dryden = {"model": "dryden", "mean_world": [3.0, 0.0, 0.0]}
    named_idc = {"phase": [_z_phase()], "controller": {"name": "idc"}}
    gains_platform = {"phase": [_z_phase()], "controller": {"gains": "platform"}}
    return [
        Case("mission table misspelt", _mission(winds=_WIND), ("mission table", "'winds'", "'wind'", "'gust'")),
        Case("mission [wind] key misspelt", _mission(wind={**_WIND, "speed": 3.0}, drag=_DRAG), ("[wind]", "'speed'", "'mean_world'")),
        Case("mission [wind] model unknown", _mission(wind={"model": "gusty"}, drag=_DRAG), ("[wind] model", "'gusty'", "'dryden'")),
        Case("mission wind without drag", _mission(wind=_WIND), ("[wind]", "[drag]", "linear")),
        Case("mission wind with zero drag", _mission(wind=_WIND, drag={"linear": 0.0}), ("[drag] linear or quadratic", "nothing")),
        Case("mission seed of a wind without turbulence", _mission(wind={**_WIND, "seed": 3}, drag=_DRAG), ("seed", 'model = "dryden"')),
        Case("mission wind in km/h", _mission(wind={"model": "mean", "mean_world": [54.0, 0.0, 0.0]}, drag=_DRAG), ("mean_world", "54", "km/h")),
        Case("mission Dryden without intensities", _mission(wind=dryden, drag=_DRAG), ("dryden", "sigma", "w20")),
        Case("mission Dryden negative sigma", _mission(wind={**dryden, "sigma": -1.0, "length": 30.0}, drag=_DRAG), ("sigma", "-1.0")),
        Case("mission [drag] negative", _mission(drag={"linear": -0.3}), ("[drag] linear", "-0.3")),
        Case("mission gust without duration", _mission(gust=[{"start": 0.0, "amplitude_world": [1.0, 0, 0]}], drag=_DRAG), ("gust 1", "duration")),
        Case(
            "mission gust after the run's end",
            _mission(gust=[{"start": 0.5, "duration": 0.2, "amplitude_world": [1.0, 0.0, 0.0]}], drag=_DRAG),
            ("gust 1", "start = 0.5", "duration = 0.05", "never flown or applied"),
            warns=True,
        ),
        Case("mission payload of negative mass", _mission(payload=[{"time": 0.01, "mass": -0.1}]), ("payload event 1 mass", "-0.1", "kg")),
        Case("mission [motor] key misspelt", _mission(motor={"tau": 0.01}), ("[motor]", "'tau'", "'time_constant'")),
        Case("mission [motor] without thrust factor", _mission(motor={"time_constant": 0.01}), ("thrust_factor", "quad_rrr", "[motor]")),
        Case(
            "mission [motor] time constant in ms",
            _mission(motor={"time_constant": 20.0, "thrust_factor": 8.5e-6}),
            ("time_constant", "20", "milliseconds"),
        ),
        Case("mission controller unknown", _mission(controller={"name": "pid"}), ("[controller] name", "'pid'", "'idc'")),
        Case(
            "mission controller named twice",
            lambda: run_scenario("mission", "dsid", platform=example_platform(), duration=0.05, mission=named_idc),
            ("'idc'", "'dsid'", "one place"),
        ),
        Case(
            "mission gains given twice in [controller]",
            _mission(controller={"gains": "platform", "targets": {"ratio": 3.0}}),
            ("gains = 'platform'", "['targets']", "give one"),
        ),
        Case(
            "mission gains in the file and as an option",
            lambda: run_scenario("mission", platform=example_platform(), duration=0.05, gains="class", mission=gains_platform),
            ("gains = 'class'", "one place"),
        ),
        Case(
            "mission as data with a relative gains file",
            _mission(controller={"gains": "gains.toml"}),
            ("gains = 'gains.toml'", "relative", "[controller.targets]"),
        ),
        Case("mission [controller] gain field misspelt", _mission(controller={"idc": {"gains": {"kq": 1.0}}}), ("kq",)),
        Case(
            "settings object to a scenario that takes none",
            lambda: run_scenario("hover-reach", platform=example_platform(), duration=0.05, settings=MissionSettings()),
            ("hover-reach", "takes no settings", "mission"),
        ),
        Case("settings of the wrong type", _scenario("mission", settings={"name": "x"}), ("settings", "MissionSettings", "dict")),
    ]


def _thesis_run(**options):
    from qprr.scenarios import run as run_scenario

    return run_scenario("static-dsid", duration=0.01, **options)


def _rotor_file(text: str) -> Path:
    folder = Path(tempfile.mkdtemp(prefix="qprr-case-"))
    path = folder / "case.rotors.toml"
    path.write_text(text)
    return path


def _load_with_rotors(text: str):
    import qprr

    return lambda: qprr.from_urdf(_EXAMPLE / "quad_rrr.urdf", _rotor_file(text), ee_frame="gripper")


def rotor_cases() -> list[Case]:
    """Issue 34, item 2: rotor sets that loaded and flew wrong (the file variants of tests/catalogue_files.py: the rest)."""
    from tests.catalogue_files import coaxial

    x8 = coaxial((_EXAMPLE / "quad_rrr.rotors.toml").read_text())
    head, *tables = x8.split("[[rotor]]")
    flipped = tables[:-1] + [tables[-1].replace('"cw"', '"x"').replace('"ccw"', '"cw"').replace('"x"', '"ccw"')]
    return [
        Case(
            "a coaxial rotor spinning the wrong way",
            _load_with_rotors(head + "[[rotor]]" + "[[rotor]]".join(flipped)),
            ("spins do not balance the yaw", "rotor 8", "cw, spin +1", "case.rotors.toml"),
            warns=True,
        ),
    ]


def _motor_lag_with(motor_table: str):
    import qprr
    from qprr.scenarios import run as run_scenario

    text = (_EXAMPLE / "quad_rrr.rotors.toml").read_text() + "\n" + motor_table

    def call():
        platform = qprr.from_urdf(_EXAMPLE / "quad_rrr.urdf", _rotor_file(text), ee_frame="gripper")
        return run_scenario("motor-lag", platform=platform, duration=0.05)

    return call


def motor_cases() -> list[Case]:
    """Issue 34, item 2: the motor stage motor-lag flies (its tau, the rotor file's [motor] table)."""
    return [
        Case(
            "motor-lag tau = 5 (milliseconds as seconds)", _scenario("motor-lag", tau=5.0), ("tau", "5.0", "milliseconds", "rotor_time_constant_max")
        ),
        Case(
            "a [motor] time_constant of 5 (milliseconds as seconds)",
            _motor_lag_with("[motor]\nthrust_factor = 1e-5\ntime_constant = 5.0\n"),
            ("time_constant", "case.rotors.toml", "5.0", "milliseconds"),
        ),
        Case("a [motor] table with an unknown key", _motor_lag_with("[motor]\ntau = 0.005\n"), ("motor key", "'tau'", "case.rotors.toml")),
        Case(
            "a [motor] table with a text value",
            _motor_lag_with('[motor]\nthrust_factor = "1e-5"\ntime_constant = 0.005\n'),
            ("thrust_factor", "case.rotors.toml", "strings"),
        ),
    ]


def _controller_returning(bad: Callable):
    """simulate() with an IDC whose step's output goes through ``bad`` (a user's controller with a bug)."""
    import qprr
    from qprr.control import make_controller
    from qprr.sim import simulate
    from qprr.trajectory import Hold

    def call():
        platform = qprr.load()
        ctrl = make_controller("idc", platform)
        own = ctrl.step
        ctrl.step = lambda t, state, ref: bad(own(t, state, ref))
        return simulate(platform, ctrl, Hold(tuple(platform.neutral_xi())), 0.01)

    return call


def controller_cases() -> list[Case]:
    """Issue 34, item 3: a controller's output of the wrong shape, named as the controller's."""
    return [
        Case(
            "a controller returning 8 values", _controller_returning(lambda u: u[:8]), ("controller 'idc'", "step returned shape (8,)", "shape (9,)")
        ),
        Case("a controller returning None", _controller_returning(lambda u: None), ("controller 'idc'", "step returned NoneType None", "shape (9,)")),
    ]


def _study(constraints: dict):
    from qprr.design.spec import DesignSpec

    study = {"name": "case", "architectures": ["Q-RR"], "objectives": ["hover_volume", "arm_mass"], "constraints": constraints}
    return lambda: DesignSpec.from_mapping(study)


def design_cases() -> list[Case]:
    """Issue 34, item 2: a design constraint no design can meet."""
    return [
        Case("a design constraint arm_mass max = -1", _study({"arm_mass": {"max": -1}}), ("constraints.arm_mass.max", "-1", "excludes every design")),
        Case(
            "a design constraint balance_fraction min = 50 (a percentage)",
            _study({"balance_fraction": {"min": 50}}),
            ("constraints.balance_fraction.min", "50", "never above 1"),
        ),
    ]


def cases() -> list[Case]:
    """Every :class:`Case` (issue 34)."""
    return mission_cases() + rotor_cases() + motor_cases() + controller_cases() + design_cases()


def run_cases(selected: list[Case] | None = None) -> list[Outcome]:
    """Each case's outcome: ``good`` (a qprr error, or a warning for ``warns``, naming every string), ``unclear`` (it
    does not name them, or another exception), ``silent`` (nothing said)."""
    errors = importlib.import_module("qprr.errors")
    out = []
    for case in cases() if selected is None else selected:
        with warnings.catch_warnings(record=True) as caught, contextlib.redirect_stderr(io.StringIO()):
            warnings.simplefilter("always")
            try:
                case.call()
            except errors.QprrError as exc:
                said, kind = str(exc), type(exc).__name__
            except Exception as exc:
                out.append(Outcome(case.label, "", "", "unclear", f"{type(exc).__name__}: {exc}"[:300]))
                continue
            else:
                said = "\n".join(str(w.message) for w in caught) if case.warns else ""
                kind = "warning"
        missing = [n for n in case.names if n not in said]
        verdict = "silent" if not said else ("unclear" if missing else "good")
        out.append(Outcome(case.label, "", "", verdict, f"{kind}: {said[:300]}" + (f" (does not name {missing})" if missing and said else "")))
    return out
