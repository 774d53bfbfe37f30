"""ArduPilot: a Lua frame script for a qprr platform (``MotorsMatrix``, ``Motors_6DoF``) and the ``Motors_dynamic``
factor table as a function of the arm's joints.

ArduPilot's multirotor mixer (libraries/AP_Motors/AP_MotorsMatrix.cpp) gives motor i the output
throttle x t_i + roll x r_i + pitch x p_i + yaw x y_i, its commands in FRD (positive roll: right side down, positive
pitch: nose up, positive yaw: nose right, clockwise seen from above).  Its own frames place motor i at an angle
theta from the nose with r_i = cos(theta + 90 deg), p_i = cos(theta) and y_i = +1 for a counter-clockwise propeller
(``AP_MOTORS_MATRIX_YAW_FACTOR_CCW``), then ``normalise_rpy_factors`` scales each of roll, pitch, yaw to a largest
magnitude of 0.5 and the throttle factors to a largest value of 1 (negatives to 0).

qprr writes the factors of any rotor set as the columns of the pseudo-inverse of the effectiveness rows [Mx, My, Mz,
Fz] about the centre of gravity at the arm pose (:meth:`qprr.flightstack.px4.Px4Geometry.effectiveness`, FRD), the
throttle factor being the upward thrust's (-Fz) column, then normalised as ``normalise_rpy_factors``.  For a
symmetric frame these are ArduPilot's own factors (a quad X gives +-0.5 everywhere, tested); for a centre of gravity
off the middle they give the mix that puts no torque into a throttle change.

Scripts (libraries/AP_Scripting/docs/docs.lua and examples/):

* parallel rotors, ``FRAME_CLASS`` 15: ``MotorsMatrix:add_motor_raw(motor, roll, pitch, yaw, testing_order)``,
  ``MotorsMatrix:set_throttle_factor(motor, t)``, ``MotorsMatrix:init(n)``, ``motors:set_frame_string(name)``;
* tilted, fully actuated rotors, ``FRAME_CLASS`` 16: ``Motors_6DoF:add_motor(motor, roll, pitch, yaw, throttle,
  forward, right, reversible, testing_order)``, ``Motors_6DoF:init(n)`` (libraries/AP_Motors/AP_MotorsMatrix_6DoF_Scripting.cpp);
* the arm moving the centre of gravity, ``FRAME_CLASS`` 17: ``Motors_dynamic:add_motor(motor, testing_order)``, a
  ``motor_factor_table()`` filled with ``:roll(i, v)``, ``:pitch``, ``:yaw``, ``:throttle``, loaded by
  ``Motors_dynamic:load_factors(table)`` before ``Motors_dynamic:init(n)`` and again whenever the geometry changes
  (libraries/AP_Motors/AP_MotorsMatrix_Scripting_Dynamic.cpp copies the factors as given: qprr normalises them).
  The script interpolates a table over a grid of one or two arm joints, read from ``SCR_USER1`` / ``SCR_USER2``
  [rad or m] (set them from the arm's controller, or edit ``read_arm_joints``).

Motor numbers follow the rotor order (motor i+1 is rotor i+1 of the platform); the testing order goes clockwise
from the nose, as ArduPilot's motor test does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ActuationError, InputError
from ..model import Platform, check_platform
from ..validation import as_int
from .mixer import arm_grid, map_joint_indices
from .px4 import PINV_RCOND, Px4Geometry, com_body_at, coms_body_at, geometry_from_rotors

PARALLEL_TOL = 1e-6
"""Rotors whose axes differ from the collective thrust axis by less than this (1 - cos) count as parallel."""
FRAME_CLASS = {"matrix": 15, "6dof": 16, "dynamic": 17}
"""ArduPilot's ``FRAME_CLASS`` of each kind of script (Scripting Matrix, 6DoF Scripting, Dynamic Scripting Matrix)."""
UPDATE_MS = 100
"""Period [ms] at which the dynamic script reloads the factors."""


@dataclass(frozen=True)
class MotorFactors:
    """ArduPilot's factors of n motors (each (n,)), normalised as ``normalise_rpy_factors``: roll, pitch, yaw in
    [-0.5, 0.5], throttle in [0, 1]; forward and right (6DoF only, else None) in [-1, 1]; testing_order (n,) from 1."""

    roll: np.ndarray
    pitch: np.ndarray
    yaw: np.ndarray
    throttle: np.ndarray
    testing_order: tuple[int, ...]
    forward: np.ndarray | None = None
    right: np.ndarray | None = None


def _scaled(x: np.ndarray, top: float) -> np.ndarray:
    m = float(np.max(np.abs(x)))
    return x * (top / m) if m > 0.0 else x.copy()


def _testing_order(geometry: Px4Geometry) -> tuple[int, ...]:
    """Testing order (from 1) of each motor: clockwise seen from above, starting at the nose (FRD bearing)."""
    bearing = [math.atan2(r.position_frd[1], r.position_frd[0]) % (2.0 * math.pi) for r in geometry.rotors]
    order = sorted(range(len(bearing)), key=lambda i: (round(bearing[i], 9), i))
    out = [0] * len(order)
    for rank, i in enumerate(order):
        out[i] = rank + 1
    return tuple(out)


def parallel(geometry: Px4Geometry) -> bool:
    """True when every rotor axis is the collective thrust axis (a ``MotorsMatrix`` frame) and that axis is up."""
    a = np.array([np.asarray(r.axis_frd) / np.linalg.norm(r.axis_frd) for r in geometry.rotors])
    return bool(np.all(a @ np.array([0.0, 0.0, -1.0]) > 1.0 - PARALLEL_TOL))


def motor_factors(geometry: Px4Geometry) -> MotorFactors:
    """ArduPilot's factors of ``geometry`` (see the module docstring): a ``MotorsMatrix`` set (rotors parallel to
    -z FRD) from the rows Mx, My, Mz, Fz; a tilted set from all six rows (``Motors_6DoF``), refused when it is not
    fully actuated (ArduPilot's 6DoF mixer needs every direction)."""
    if not isinstance(geometry, Px4Geometry):
        raise InputError(f"geometry must be a Px4Geometry, got {type(geometry).__name__}")
    E = geometry.effectiveness()
    order = _testing_order(geometry)
    if parallel(geometry):
        M = np.linalg.pinv(E[[0, 1, 2, 5]], rcond=PINV_RCOND)
        thr = _scaled(-M[:, 3], 1.0)
        return MotorFactors(_scaled(M[:, 0], 0.5), _scaled(M[:, 1], 0.5), _scaled(M[:, 2], 0.5), np.maximum(thr, 0.0), order)
    s = np.linalg.svd(E, compute_uv=False)
    if s.size < 6 or not s[5] > PINV_RCOND * s[0]:
        raise ActuationError(
            "the rotors are tilted but do not span all six wrench directions: neither ArduPilot's MotorsMatrix "
            "(parallel rotors) nor its Motors_6DoF (fully actuated) mixer fits this set"
        )
    M = np.linalg.pinv(E, rcond=PINV_RCOND)
    return MotorFactors(
        _scaled(M[:, 0], 0.5),
        _scaled(M[:, 1], 0.5),
        _scaled(M[:, 2], 0.5),
        _scaled(-M[:, 5], 1.0),
        order,
        _scaled(M[:, 3], 1.0),
        _scaled(M[:, 4], 1.0),
    )


def _num(x: float) -> str:
    return f"{float(x):.7g}" if abs(x) >= 1e-9 else "0"


def _header(platform: Platform, what: str, frame_class: int, pose: str) -> list[str]:
    return [
        f"-- {what} for {platform.name}, written by qprr (qprr export ardupilot)",
        f"-- arm pose: {pose}; rotor positions relative to the centre of gravity there, FRD",
        f"-- set FRAME_CLASS = {frame_class}, SCR_ENABLE = 1, put this file in APM/scripts/ and reboot",
        "-- motor i+1 is rotor i+1 of the platform; factors normalised as AP_MotorsMatrix::normalise_rpy_factors",
        "",
    ]


def frame_script(platform: Platform, q_arm=None) -> str:
    """A Lua frame script for ``platform`` with the arm at ``q_arm`` (default: neutral): ``MotorsMatrix`` for
    parallel rotors, ``Motors_6DoF`` for a tilted, fully actuated set."""
    platform = check_platform(platform)
    c = com_body_at(platform, q_arm)
    geometry = geometry_from_rotors(platform.rotors, c, source=f"platform {platform.name!r}")
    f = motor_factors(geometry)
    pose = "neutral" if q_arm is None else str(np.round(np.asarray(q_arm, dtype=float), 6).tolist())
    n = geometry.n
    if f.forward is None:
        lines = _header(platform, "ArduPilot Scripting Matrix frame", FRAME_CLASS["matrix"], pose)
        for i in range(n):
            lines.append(f"MotorsMatrix:add_motor_raw({i}, {_num(f.roll[i])}, {_num(f.pitch[i])}, {_num(f.yaw[i])}, {f.testing_order[i]})")
        for i in range(n):
            lines.append(f"MotorsMatrix:set_throttle_factor({i}, {_num(f.throttle[i])})")
        lines += [f'assert(MotorsMatrix:init({n}), "qprr: MotorsMatrix init failed")', f'motors:set_frame_string("qprr {platform.name}")', ""]
        return "\n".join(lines)
    lines = _header(platform, "ArduPilot 6DoF Scripting frame", FRAME_CLASS["6dof"], pose)
    lines.append("-- Motors_6DoF:add_motor(motor, roll, pitch, yaw, throttle, forward, right, reversible, testing_order)")
    for i in range(n):
        args = ", ".join(_num(v[i]) for v in (f.roll, f.pitch, f.yaw, f.throttle, f.forward, f.right))
        lines.append(f"Motors_6DoF:add_motor({i}, {args}, false, {f.testing_order[i]})")
    lines += [f'assert(Motors_6DoF:init({n}), "qprr: Motors_6DoF init failed")', f'motors:set_frame_string("qprr {platform.name}")', ""]
    return "\n".join(lines)


@dataclass(frozen=True)
class FactorTable:
    """``Motors_dynamic`` factors over a grid of one or two arm joints: ``joints`` (their indices), ``axes`` (grid
    values, rad or m), ``roll``/``pitch``/``yaw``/``throttle`` (grid shape + (n,)), ``q0`` (the other joints' values),
    ``testing_order``."""

    joint_names: tuple[str, ...]
    joints: tuple[int, ...]
    axes: tuple[np.ndarray, ...]
    roll: np.ndarray
    pitch: np.ndarray
    yaw: np.ndarray
    throttle: np.ndarray
    q0: np.ndarray
    testing_order: tuple[int, ...]


def factor_table(platform: Platform, q0=None, *, joints=None, resolution: int = 9) -> FactorTable:
    """ArduPilot's factors (:func:`motor_factors`) at every point of a grid of ``resolution`` values over one or two
    arm ``joints`` (default the first two) across their limits, the other joints at ``q0`` (default neutral); parallel
    rotors only (``Motors_dynamic`` is a ``MotorsMatrix``)."""
    platform = check_platform(platform)
    mj = map_joint_indices(platform, joints)
    resolution = as_int(resolution, "resolution", lo=2, hi=101)
    q0, axes, Q = arm_grid(platform, q0, mj, resolution)
    coms = coms_body_at(platform, Q)
    roll, pitch, yaw, throttle = [], [], [], []
    order = ()
    for c in coms:
        g = geometry_from_rotors(platform.rotors, c, source=f"platform {platform.name!r}")
        if not parallel(g):
            raise ActuationError(f"platform {platform.name!r}: Motors_dynamic is a MotorsMatrix mixer, for parallel rotors; this set is tilted")
        f = motor_factors(g)
        order = f.testing_order
        roll.append(f.roll)
        pitch.append(f.pitch)
        yaw.append(f.yaw)
        throttle.append(f.throttle)
    shape = tuple(a.size for a in axes) + (len(platform.rotors),)
    r, p, y, t = (np.array(v).reshape(shape) for v in (roll, pitch, yaw, throttle))
    return FactorTable(platform.arm_names, mj, axes, r, p, y, t, np.array(q0), order)


def _lua_list(values) -> str:
    return "{" + ", ".join(_num(v) for v in values) + "}"


def dynamic_script(platform: Platform, q0=None, *, joints=None, resolution: int = 9) -> str:
    """A ``Motors_dynamic`` Lua script (``FRAME_CLASS`` 17) that reloads the factors of :func:`factor_table` as the
    arm moves: the joint values come from ``SCR_USER1`` (and ``SCR_USER2``), clamped to the grid, the factors
    interpolated (linear, or bilinear over two joints) every :data:`UPDATE_MS` ms."""
    platform = check_platform(platform)
    t = factor_table(platform, q0, joints=joints, resolution=resolution)
    n = len(platform.rotors)
    names = [t.joint_names[j] for j in t.joints]
    lines = _header(platform, "ArduPilot Dynamic Scripting Matrix frame", FRAME_CLASS["dynamic"], f"table over {', '.join(names)}")
    lines += [
        f"-- the arm joints of the table: {', '.join(f'SCR_USER{k + 1} = {nm}' for k, nm in enumerate(names))} [rad or m]",
        f"-- the other joints held at {np.round(t.q0, 6).tolist()}",
        f"local N = {n}",
        f"local ORDER = {{{', '.join(str(x) for x in t.testing_order)}}}",
        f"local Q1 = {_lua_list(t.axes[0])}",
        f"local Q2 = {_lua_list(t.axes[1]) if len(t.axes) > 1 else '{0}'}",
    ]
    for key, table in (("ROLL", t.roll), ("PITCH", t.pitch), ("YAW", t.yaw), ("THROTTLE", t.throttle)):
        rows = table.reshape(-1, n)
        lines.append(f"local {key} = {{")
        lines += [f"  {_lua_list(r)}," for r in rows]
        lines.append("}")
    lines += _LUA_BODY.splitlines()
    return "\n".join(lines) + "\n"


_LUA_BODY = """
local function bracket(q, grid)
  -- index i (from 1) and weight w of q between grid[i] and grid[i + 1], q clamped to the grid
  local m = #grid
  if m == 1 then return 1, 0.0 end
  if q <= grid[1] then return 1, 0.0 end
  if q >= grid[m] then return m - 1, 1.0 end
  for i = 1, m - 1 do
    if q <= grid[i + 1] then return i, (q - grid[i]) / (grid[i + 1] - grid[i]) end
  end
  return m - 1, 1.0
end

local function factor(tab, q1, q2, motor)
  local i, wi = bracket(q1, Q1)
  local j, wj = bracket(q2, Q2)
  local m2 = #Q2
  local j1 = math.min(j + 1, m2)
  local i1 = math.min(i + 1, #Q1)
  local function at(a, b) return tab[(a - 1) * m2 + b][motor] end
  return (1 - wi) * ((1 - wj) * at(i, j) + wj * at(i, j1)) + wi * ((1 - wj) * at(i1, j) + wj * at(i1, j1))
end

local function read_arm_joints()
  -- replace with your arm's joint readings if they are not sent to SCR_USER1 / SCR_USER2
  return param:get("SCR_USER1") or 0.0, param:get("SCR_USER2") or 0.0
end

local function load(q1, q2)
  local ft = motor_factor_table()
  for k = 1, N do
    ft:roll(k - 1, factor(ROLL, q1, q2, k))
    ft:pitch(k - 1, factor(PITCH, q1, q2, k))
    ft:yaw(k - 1, factor(YAW, q1, q2, k))
    ft:throttle(k - 1, factor(THROTTLE, q1, q2, k))
  end
  Motors_dynamic:load_factors(ft)
end

for k = 1, N do
  Motors_dynamic:add_motor(k - 1, ORDER[k])
end
load(read_arm_joints())
assert(Motors_dynamic:init(N), "qprr: Motors_dynamic init failed")
motors:set_frame_string("qprr dynamic")

local function update()
  load(read_arm_joints())
  return update, UPDATE_MS
end

return update, UPDATE_MS
""".replace("UPDATE_MS", str(UPDATE_MS))


def write_script(text: str, path: str | Path) -> Path:
    """Write a Lua script ``text`` to ``path`` (.lua)."""
    path = Path(path)
    if path.suffix.lower() != ".lua":
        raise InputError(f"path {str(path)!r}: an ArduPilot script ends in .lua")
    path.write_text(text, encoding="utf-8")
    return path
