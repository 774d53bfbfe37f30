"""PX4's control allocation for rotors: the ``CA_*`` geometry, its effectiveness matrix, PX4's normalised
pseudo-inverse mix, ``.params`` files, and the conversions to and from qprr's rotors.

The geometry (PX4 parameters, module.yaml of src/modules/control_allocator): ``CA_AIRFRAME`` (0: multirotor),
``CA_ROTOR_COUNT``, and per rotor i (from 0) ``CA_ROTOR{i}_PX/PY/PZ`` (position [m] relative to the centre of gravity,
FRD), ``_AX/AY/AZ`` (thrust axis, FRD, normalised by PX4), ``_CT`` (thrust [N] at full command u = 1, PX4's
"Thrust = CT u^2" with its thrust model turning u into a thrust fraction) and ``_KM`` (moment ratio [m]: reaction torque
= KM x thrust; positive for a rotor spinning counter-clockwise seen from above).

The mapping from qprr (:mod:`qprr.rotors`, :mod:`qprr.flightstack.frames`).  qprr's rotor i applies, per newton, the
wrench [a; p x a + s kappa a] in FLU at the point it is taken about; PX4's rotor applies, per unit command,
[CT a'; CT (p' x a') - CT KM a'] in FRD (``ActuatorEffectivenessRotors::computeEffectivenessMatrix``,
src/modules/control_allocator/ActuatorEffectiveness/ActuatorEffectivenessRotors.cpp).  With p' = C (p - c) (c the
centre of gravity in B), a' = C a and C = diag(1, -1, -1) a proper rotation, (C u) x (C v) = C (u x v), so the two
columns agree exactly when

    CT = f_max        KM = -s kappa

(a qprr rotor with s = +1 has its reaction torque along +a, i.e. up for a lifting rotor: it turns clockwise seen from
above, and PX4 wants a negative KM for it).  :func:`geometry_from_platform` applies this at an arm pose;
:func:`rotors_from_geometry` inverts it.  The tests check that the effectiveness matrix equals qprr's rotor matrix
about the centre of gravity, scaled by f_max and mapped to FRD.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ActuationError, InputError
from ..model import Platform, check_platform
from ..rotors import Rotor
from ..validation import as_file, as_int, as_real, as_vector
from .frames import body_from_frd, frd_from_body

FLT_EPSILON = float(np.finfo(np.float32).eps)
"""C's FLT_EPSILON (2^-23): PX4's threshold for a zero thrust coefficient, axis norm and scale."""
MIX_ZERO = 1e-3
"""Entries of PX4's normalised mix smaller than this are set to 0 (``normalizeControlAllocationMatrix``)."""
NUM_ROTORS_MAX = 12
"""The most rotors PX4's ``ActuatorEffectivenessRotors`` reads (its NUM_ROTORS_MAX)."""
PINV_RCOND = 1e-6
"""Singular values below this x the largest are zero in the pseudo-inverse: PX4 computes it in float32 (eps 1.2e-7)."""
CONDITION_MAX = 1e4
"""Largest accepted condition number of the rows a multirotor needs (roll, pitch, yaw torque, Fz; all six for a fully
actuated set), torques divided by the rotor span: PX4 inverts in float32 (eps 1.2e-7), so a condition of 1e4 already
costs ~1e-3 relative error in the mix, the size of entry PX4 sets to zero (:data:`MIX_ZERO`)."""
STANDARD_GRAVITY = 9.80665
"""g0 [m/s^2]: PX4's CONSTANTS_ONE_G (src/lib/geo/geo.h), the gravity of its hover-thrust and allocation models (and of
jMAVSim's plant); the one home of this value in qprr's flight-stack code."""
AXES = ("Mx", "My", "Mz", "Fx", "Fy", "Fz")
"""Rows of PX4's effectiveness matrix (columns of the mix): torques then thrusts, FRD, normalised setpoints."""
AXIS_MEANING = {
    "Mx": "roll torque",
    "My": "pitch torque",
    "Mz": "yaw torque",
    "Fx": "forward thrust",
    "Fy": "sideways thrust",
    "Fz": "vertical thrust",
}
AIRFRAME_MULTIROTOR = 0
"""``CA_AIRFRAME`` of a multirotor (the only geometry :func:`geometry_from_platform` writes)."""
_PARAM_SOURCE = "PX4 writes the CA_* parameters of the multirotor control allocation (QGroundControl's Actuators tab, or `qprr export px4`)"


def f32(x: float) -> float:
    """``x`` (finite) rounded to the nearest float32 (PX4's parameters are float32), as a Python float."""
    return float(np.float32(as_real(x, "x")))


def _unit_f32(axis) -> tuple[float, float, float]:
    """A float32 unit vector along ``axis`` that normalising in float64 and rounding to float32 gives back unchanged
    (so an exported axis survives the import's normalisation bit for bit)."""
    a = np.asarray(axis, dtype=float)
    a32 = np.float32(a / np.linalg.norm(a)).astype(float)
    for _ in range(8):
        nxt = np.float32(a32 / np.linalg.norm(a32)).astype(float)
        if np.array_equal(nxt, a32):
            break
        a32 = nxt
    return (float(a32[0]), float(a32[1]), float(a32[2]))


@dataclass(frozen=True)
class Px4Rotor:
    """One rotor of PX4's geometry: ``position_frd`` [m] relative to the centre of gravity and ``axis_frd`` (thrust
    direction, any length: PX4 normalises it) in FRD, ``ct`` [N] thrust at full command, ``km`` [m] moment ratio
    (PX4 sign: positive = counter-clockwise seen from above)."""

    position_frd: tuple[float, float, float]
    axis_frd: tuple[float, float, float]
    ct: float
    km: float

    def __post_init__(self) -> None:
        p = as_vector(self.position_frd, 3, "position_frd")
        a = as_vector(self.axis_frd, 3, "axis_frd")
        object.__setattr__(self, "position_frd", (float(p[0]), float(p[1]), float(p[2])))
        object.__setattr__(self, "axis_frd", (float(a[0]), float(a[1]), float(a[2])))
        object.__setattr__(self, "ct", as_real(self.ct, "ct", unit="N"))
        object.__setattr__(self, "km", as_real(self.km, "km", unit="m"))


@dataclass(frozen=True)
class Px4Geometry:
    """PX4's rotor geometry (``CA_AIRFRAME``, ``CA_ROTOR*``): what its control allocator inverts."""

    rotors: tuple[Px4Rotor, ...]
    airframe: int = AIRFRAME_MULTIROTOR

    def __post_init__(self) -> None:
        if not isinstance(self.rotors, (tuple, list)) or not all(isinstance(r, Px4Rotor) for r in self.rotors):
            raise InputError(f"rotors must be a sequence of Px4Rotor, got {self.rotors!r:.80}")
        if not 1 <= len(self.rotors) <= NUM_ROTORS_MAX:
            raise InputError(f"PX4 takes 1 to {NUM_ROTORS_MAX} rotors (CA_ROTOR_COUNT), got {len(self.rotors)}")
        object.__setattr__(self, "rotors", tuple(self.rotors))
        object.__setattr__(self, "airframe", as_int(self.airframe, "airframe (CA_AIRFRAME)", lo=0))

    @property
    def n(self) -> int:
        return len(self.rotors)

    def effectiveness(self) -> np.ndarray:
        """(6, n) rows [Mx, My, Mz, Fx, Fy, Fz] (FRD) per unit command, as PX4's
        ``ActuatorEffectivenessRotors::computeEffectivenessMatrix`` (ActuatorEffectivenessRotors.cpp): axis a
        normalised, thrust CT a, moment CT (p x a) - CT KM a; a rotor with |CT| < FLT_EPSILON or a zero axis gives a
        zero column."""
        E = np.zeros((6, self.n))
        for i, r in enumerate(self.rotors):
            a = np.array(r.axis_frd)
            norm = float(np.linalg.norm(a))
            if not norm > FLT_EPSILON or abs(r.ct) < FLT_EPSILON:
                continue
            a /= norm
            E[0:3, i] = r.ct * np.cross(r.position_frd, a) - r.ct * r.km * a
            E[3:6, i] = r.ct * a
        return E

    def normalization_scale(self) -> np.ndarray:
        """(6,) the scales PX4 divides the mix's columns by (``updateControlAllocationMatrixScale``), see :meth:`mix`."""
        return _mix_scale(_pseudo_inverse(self.effectiveness()))

    def mix(self) -> np.ndarray:
        """(n, 6) PX4's normalised pseudo-inverse of :meth:`effectiveness`, as its multirotor allocator builds it
        (src/modules/control_allocator/ControlAllocation/ControlAllocationPseudoInverse.cpp: ``updatePseudoInverse``,
        ``updateControlAllocationMatrixScale`` with normalize_rpy true, ``normalizeControlAllocationMatrix``).

        Moore-Penrose pseudo-inverse M of E (singular values below :data:`PINV_RCOND` x the largest dropped); roll and
        pitch share the scale max(s_roll, s_pitch), s = sqrt(|column|^2 / (k / 2)) with k the entries above 1e-3 (1
        if none); yaw's scale is the column's largest (signed) entry; thrust z, then y, then x: the mean |entry| over
        the entries above FLT_EPSILON, an empty column taking z's scale (z's: 1).  A column is divided by its scale
        when that exceeds FLT_EPSILON; then every entry below 1e-3 in magnitude is set to 0.  (PX4's main branch of
        2025 scales all three thrust columns by the mean norm of the rows' thrust parts instead: the same numbers when
        the rotors are parallel, as on every multirotor that is not tilted.)"""
        M = _pseudo_inverse(self.effectiveness())
        s = _mix_scale(M)
        if s[0] > FLT_EPSILON:
            M[:, 0:2] /= s[0:2]
        if s[2] > FLT_EPSILON:
            M[:, 2] /= s[2]
        if s[3] > FLT_EPSILON:
            M[:, 3:6] /= s[3:6]
        M[np.abs(M) < MIX_ZERO] = 0.0
        return M

    def allocate(self, control_sp) -> np.ndarray:
        """Unclipped actuator setpoints (n,) or (N, n) for normalised ``control_sp`` (6,) or (N, 6) = [torque xyz;
        thrust xyz] as ``vehicle_torque_setpoint`` / ``vehicle_thrust_setpoint`` (FRD): mix @ control_sp.

        This is PX4's allocation when no actuator saturates (ControlAllocationPseudoInverse.cpp ``allocate`` with zero
        trim; ControlAllocationSequentialDesaturation.cpp then changes nothing)."""
        c = np.asarray(control_sp, dtype=float)
        if c.shape[-1:] != (6,) or c.ndim not in (1, 2) or not np.all(np.isfinite(c)):
            raise InputError(f"control_sp must be finite with shape (6,) or (N, 6) ([torque xyz; thrust xyz]), got shape {c.shape}")
        return c @ self.mix().T

    @classmethod
    def from_parameters(cls, params: Mapping[str, float]) -> Px4Geometry:
        """The geometry in PX4 parameters ``params`` (name -> value, e.g. :func:`read_params` or a ULog's); a missing
        ``CA_*`` key raises :class:`~qprr.errors.InputError` naming it."""
        if not isinstance(params, Mapping):
            raise InputError(f"params must be a mapping of PX4 parameter names to values, got {type(params).__name__}")

        def get(key: str) -> float:
            if key not in params:
                raise InputError(f"parameter {key} is missing: {_PARAM_SOURCE}")
            return as_real(params[key], key)

        count = get("CA_ROTOR_COUNT")
        airframe = get("CA_AIRFRAME")
        if count != int(count) or not 1 <= count <= NUM_ROTORS_MAX:
            raise InputError(f"CA_ROTOR_COUNT = {count!r}: PX4 takes 1 to {NUM_ROTORS_MAX} rotors")
        rotors = []
        for i in range(int(count)):
            v = {k: get(f"CA_ROTOR{i}_{k}") for k in ("PX", "PY", "PZ", "AX", "AY", "AZ", "CT", "KM")}
            rotors.append(Px4Rotor((v["PX"], v["PY"], v["PZ"]), (v["AX"], v["AY"], v["AZ"]), v["CT"], v["KM"]))
        return cls(tuple(rotors), int(airframe))

    def parameters(self) -> dict[str, float | int]:
        """name -> value of the geometry's PX4 parameters (``CA_AIRFRAME``, ``CA_ROTOR_COUNT`` as int, the rest as
        float rounded to float32, so writing and reading them gives back the same bits)."""
        out: dict[str, float | int] = {"CA_AIRFRAME": self.airframe, "CA_ROTOR_COUNT": self.n}
        for i, r in enumerate(self.rotors):
            for k, x in zip(("PX", "PY", "PZ"), r.position_frd):
                out[f"CA_ROTOR{i}_{k}"] = f32(x)
            for k, x in zip(("AX", "AY", "AZ"), r.axis_frd):
                out[f"CA_ROTOR{i}_{k}"] = f32(x)
            out[f"CA_ROTOR{i}_CT"] = f32(r.ct)
            out[f"CA_ROTOR{i}_KM"] = f32(r.km)
        return out

    def summary(self) -> str:
        """One line per rotor: position, axis (FRD), CT and KM."""
        lines = [f"PX4 geometry: CA_AIRFRAME {self.airframe}, {self.n} rotors (FRD, positions relative to the centre of gravity)"]
        for i, r in enumerate(self.rotors):
            p = ", ".join(f"{x:+.4f}" for x in r.position_frd)
            a = ", ".join(f"{x:+.4f}" for x in r.axis_frd)
            turn = "ccw" if r.km > 0 else "cw" if r.km < 0 else "-"
            lines.append(f"  rotor {i}: p [{p}] m  axis [{a}]  CT {r.ct:.4g} N  KM {r.km:+.4g} m ({turn})")
        return "\n".join(lines)


def _pseudo_inverse(E: np.ndarray) -> np.ndarray:
    """Moore-Penrose pseudo-inverse (n, 6) of E (6, n) (PX4: ``matrix::geninv``)."""
    return np.linalg.pinv(E, rcond=PINV_RCOND)


def _mix_scale(M: np.ndarray) -> np.ndarray:
    """The six column scales of PX4's ``updateControlAllocationMatrixScale`` (normalize_rpy true) for the raw
    pseudo-inverse M (n, 6) (ControlAllocationPseudoInverse.cpp)."""
    s = np.ones(6)
    rp = []
    for k in (0, 1):
        count = int(np.sum(np.abs(M[:, k]) > MIX_ZERO))
        rp.append(math.sqrt(float(M[:, k] @ M[:, k]) / (count / 2.0)) if count > 0 else 1.0)
    s[0] = s[1] = max(rp)
    s[2] = float(M[:, 2].max())
    for k in (5, 4, 3):  # thrust z first: an empty x or y column takes z's scale
        col = np.abs(M[:, k])
        count = int(np.sum(col > FLT_EPSILON))
        s[k] = float(col.sum()) / count if count > 0 else s[5]
    return s


# ------------------------------------------------------------------ qprr <-> PX4
def geometry_from_rotors(rotors: Sequence[Rotor], com_body=(0.0, 0.0, 0.0), *, check: bool = True, source: str = "the rotor set") -> Px4Geometry:
    """PX4's geometry of qprr ``rotors`` for a vehicle whose centre of gravity is at ``com_body`` [m] (B): positions
    p - c and axes mapped to FRD (:func:`qprr.flightstack.frames.frd_from_body`), CT = f_max, KM = -spin kappa (see
    the module docstring); axes written as float32 unit vectors that survive an import.  ``check``: refuse a set PX4
    would invert badly (:func:`check_geometry`).  An infinite f_max is refused (PX4's CT is the thrust at full
    command)."""
    if not isinstance(rotors, (tuple, list)) or not rotors or not all(isinstance(r, Rotor) for r in rotors):
        raise InputError(f"rotors must be a non-empty sequence of qprr.rotors.Rotor, got {rotors!r:.80}")
    c = as_vector(com_body, 3, "com_body")
    out = []
    for i, r in enumerate(rotors):
        if not math.isfinite(r.f_max):
            raise InputError(
                f"{source}: rotor {i + 1} ({r.name or 'unnamed'}) has f_max = inf, but PX4's CA_ROTOR{i}_CT is the thrust "
                "at full command [N]: give f_max in the rotor file (the rotor's measured or rated maximum thrust)"
            )
        p = frd_from_body(np.asarray(r.position_body) - c) + 0.0  # + 0.0: no negative zeros in the file
        a = frd_from_body(r.axis_body) + 0.0
        out.append(Px4Rotor(tuple(float(x) for x in p), _unit_f32(a), r.f_max, -r.spin * r.kappa + 0.0))
    geometry = Px4Geometry(tuple(out), AIRFRAME_MULTIROTOR)
    if check:
        check_geometry(geometry, source)
    return geometry


def com_body_at(platform: Platform, q_arm=None) -> np.ndarray:
    """The centre of gravity of the whole robot [m] in B at the arm configuration ``q_arm`` (default: the neutral
    one), by Pinocchio's ``centerOfMass`` with the base at the origin, level."""
    platform = check_platform(platform)
    q = platform.neutral_q()
    if q_arm is not None:
        q[7:] = platform.check_arm_limits(q_arm, "q_arm")
    return np.array(pin.centerOfMass(platform.model, platform.model.createData(), q))


def coms_body_at(platform: Platform, Q) -> np.ndarray:
    """Centres of gravity (N, 3) [m] in B of the whole robot at the arm configurations ``Q`` (N, n_arm) (not checked
    against the limits: the callers build Q inside them)."""
    platform = check_platform(platform)
    Q = np.asarray(Q, dtype=float).reshape(-1, platform.n_arm)
    model = platform.model
    data = model.createData()
    q = platform.neutral_q()
    out = np.empty((len(Q), 3))
    for k, qa in enumerate(Q):
        q[7:] = qa
        out[k] = pin.centerOfMass(model, data, q)
    return out


def geometry_from_platform(platform: Platform, q_arm=None, *, check: bool = True) -> Px4Geometry:
    """PX4's geometry of ``platform`` with the arm at ``q_arm`` (default: the neutral configuration): rotor positions
    relative to the whole robot's centre of gravity at that pose (:func:`com_body_at`), in FRD; see
    :func:`geometry_from_rotors`."""
    platform = check_platform(platform)
    c = com_body_at(platform, q_arm)
    pose = "neutral" if q_arm is None else f"q_arm = {np.round(np.asarray(q_arm, dtype=float), 6).tolist()}"
    return geometry_from_rotors(platform.rotors, c, check=check, source=f"platform {platform.name!r} at {pose}")


def rotors_from_geometry(geometry: Px4Geometry) -> tuple[Rotor, ...]:
    """qprr rotors of a PX4 geometry (positions relative to the centre of gravity, in B): position and axis from FRD,
    f_min 0, f_max = CT, kappa = |KM|, spin = -sign(KM) (+1 when KM = 0); named ``CA_ROTOR{i}``.  A rotor PX4 ignores
    (CT <= 0 or a zero axis) is refused with the reason."""
    if not isinstance(geometry, Px4Geometry):
        raise InputError(f"geometry must be a Px4Geometry, got {type(geometry).__name__}")
    out = []
    for i, r in enumerate(geometry.rotors):
        if not r.ct >= FLT_EPSILON:
            raise InputError(f"CA_ROTOR{i}_CT = {r.ct!r}: PX4 ignores a rotor without thrust; give its thrust at full command [N] (> 0)")
        if not np.linalg.norm(r.axis_frd) > FLT_EPSILON:
            raise InputError(
                f"CA_ROTOR{i}_AX/AY/AZ = {list(r.axis_frd)}: a zero axis, PX4 ignores the rotor; give its thrust direction (FRD, e.g. 0, 0, -1)"
            )
        spin = -1 if r.km > 0.0 else 1
        p = body_from_frd(r.position_frd) + 0.0
        a = body_from_frd(r.axis_frd) + 0.0
        out.append(Rotor(tuple(float(x) for x in p), tuple(float(x) for x in a), spin, abs(r.km), 0.0, r.ct, f"CA_ROTOR{i}"))
    return tuple(out)


# ------------------------------------------------------------------ refusal
def _needed_rows(E_scaled: np.ndarray) -> tuple[int, ...]:
    """All six rows for a fully actuated set (rank 6), else roll, pitch, yaw torque and Fz."""
    s = np.linalg.svd(E_scaled, compute_uv=False)
    full = s.size == 6 and s[0] > 0 and s[5] > PINV_RCOND * s[0]
    return (0, 1, 2, 3, 4, 5) if full else (0, 1, 2, 5)


def check_geometry(geometry: Px4Geometry, source: str = "the geometry") -> None:
    """Nothing if PX4 can invert ``geometry`` well, else an :class:`~qprr.errors.ActuationError` with the reason.

    The rows a multirotor needs (roll, pitch, yaw torque and vertical thrust Fz; all six when the set is fully
    actuated) with torques divided by the rotor span: refused when the rotors push down (Fz >= 0 in FRD: an axis sign
    slip), when one of those rows is out of reach (a lost axis), or when their condition number exceeds
    :data:`CONDITION_MAX`."""
    E = geometry.effectiveness()
    span = max([math.hypot(*r.position_frd) for r in geometry.rotors] + [abs(r.km) for r in geometry.rotors] + [1e-9])
    Es = E.copy()
    Es[0:3] /= span
    if not Es[5].sum() < 0.0:
        raise ActuationError(
            f"{source}: the rotors' thrust points down in FRD (sum of the Fz row {E[5].sum():.4g} N >= 0): PX4's axes are "
            "FRD, a lifting rotor has axis (0, 0, -1); check the axis signs and CT > 0"
        )
    rows = _needed_rows(Es)
    A = Es[list(rows)]
    P = A @ np.linalg.pinv(A, rcond=PINV_RCOND)
    lost = [AXES[k] for j, k in enumerate(rows) if abs(P[j, j] - 1.0) > 1e-6]
    if lost:
        names = ", ".join(f"{k} ({AXIS_MEANING[k]})" for k in lost)
        raise ActuationError(
            f"{source}: PX4 could not command {names}: the rotors cannot produce it on its own (rank "
            f"{np.linalg.matrix_rank(A, tol=PINV_RCOND * np.abs(A).max())} of {len(rows)}); check the spins (KM signs), "
            "the moment ratios (|KM| > 0) and that the rotors do not lie on one line"
        )
    U, s, _ = np.linalg.svd(A)
    cond = float(s[0] / s[-1])
    if cond > CONDITION_MAX:
        weak = U[:, -1]
        k = int(np.argmax(np.abs(weak)))
        raise ActuationError(
            f"{source}: PX4 would invert this set badly: the condition number of its {'/'.join(AXES[r] for r in rows)} "
            f"rows is {cond:.3g} > {CONDITION_MAX:g} (the weakest direction is mostly {AXES[rows[k]]}, "
            f"{AXIS_MEANING[AXES[rows[k]]]}); spread the rotors or give the spins more moment (|KM|)"
        )


# ------------------------------------------------------------------ .params files (QGroundControl)
PARAM_TYPE_INT32 = 6
PARAM_TYPE_REAL32 = 9
_INT_TYPES = {1, 2, 3, 4, 5, 6, 7, 8}
_REAL_TYPES = {9, 10}
_NAME = re.compile(r"^[A-Za-z0-9_]{1,16}$")


def format_float32(x: float) -> str:
    """The shortest decimal text of float32(x) that reads back (as a double, then rounded to float32) to the same
    float32 bits (``x`` finite)."""
    v = np.float32(as_real(x, "x"))
    text = np.format_float_positional(v, unique=True, trim="-")
    if np.float32(float(text)) != v:
        text = repr(float(v))
    return text


def write_params(geometry: Px4Geometry, path: str | Path, header: Sequence[str] = ()) -> Path:
    """Write ``geometry``'s parameters as a QGroundControl parameter file (``vehicle-id component-id NAME VALUE
    TYPE``, tab-separated, MAV_PARAM_TYPE 6 int32 / 9 real32) after ``#`` comment lines: "qprr" and ``header`` (the
    platform, the pose).  Values read back float32-exact (:func:`read_params`)."""
    if not isinstance(geometry, Px4Geometry):
        raise InputError(f"geometry must be a Px4Geometry, got {type(geometry).__name__}")
    path = Path(path)
    lines = ["# Onboard parameters for Vehicle 1", "#", "# written by qprr (qprr export px4)"]
    lines += [f"# {h}" for h in header]
    lines += ["#", "# Vehicle-Id Component-Id Name Value Type"]
    for name, value in geometry.parameters().items():
        if isinstance(value, int):
            lines.append(f"1\t1\t{name}\t{value}\t{PARAM_TYPE_INT32}")
        else:
            lines.append(f"1\t1\t{name}\t{format_float32(value)}\t{PARAM_TYPE_REAL32}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def read_params(path: str | Path) -> dict[str, float | int]:
    """name -> value of a QGroundControl parameter file (integer types as int, real32 rounded to float32, real64 as
    is); a malformed line raises :class:`~qprr.errors.InputError` naming the file and the line number."""
    path = as_file(path, "path", what="PX4 parameter file (.params)")
    out: dict[str, float | int] = {}
    seen: dict[str, int] = {}
    for number, raw in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        where = f"{path}, line {number}"
        parts = line.split()
        if len(parts) != 5:
            raise InputError(f"{where}: expected 5 fields 'vehicle-id component-id NAME VALUE TYPE', got {len(parts)}: {line[:80]!r}")
        _, _, name, text, kind = parts
        if not (parts[0].isdigit() and parts[1].isdigit() and kind.isdigit()):
            raise InputError(f"{where}: vehicle id, component id and type must be integers, got {line[:80]!r}")
        if not _NAME.match(name):
            raise InputError(f"{where}: {name!r} is not a PX4 parameter name (letters, digits, '_', at most 16)")
        if name in seen:
            raise InputError(f"{where}: {name} is given twice (first on line {seen[name]}); keep one")
        out[name] = _param_value(text, int(kind), where, name)
        seen[name] = number
    return out


def _param_value(text: str, kind: int, where: str, name: str) -> float | int:
    if kind in _INT_TYPES:
        try:
            return int(text)
        except ValueError:
            raise InputError(f"{where}: {name} has type {kind} (an integer) but value {text!r}") from None
    if kind in _REAL_TYPES:
        try:
            value = float(text)
        except ValueError:
            raise InputError(f"{where}: {name} has type {kind} (a real) but value {text!r}") from None
        if not math.isfinite(value):
            raise InputError(f"{where}: {name} = {text!r} is not finite")
        return f32(value) if kind == PARAM_TYPE_REAL32 else value
    raise InputError(f"{where}: {name} has type {kind}: MAV_PARAM_TYPE is 1-8 (integers), 9 (real32) or 10 (real64)")
