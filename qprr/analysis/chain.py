"""Batched kinematics and statics of a platform's arm in the base frame B, for many configurations at once.

The arm is read from the Pinocchio model: for every joint after the free flyer, its parent,
its placement in the parent joint frame (``model.jointPlacements``), its kind (1-DOF revolute
or prismatic, any axis: ``RX/RY/RZ``, ``PX/PY/PZ``, unaligned) and its axis (the motion
subspace S of the joint), the body inertia it carries (mass and centre of mass).  Forward
kinematics is then the product Pinocchio computes,

    ^B M_j = ^B M_parent(j) * jointPlacement_j * exp(S_j q_j),

evaluated for a whole batch with the base at the identity (everything is in B).  Rotations are
kept as 3x3 tables of *entries*, each a Python float (an entry that does not depend on the
joints: 0 and 1 of an axis-aligned joint) or an array over the batch; products skip the exact
zeros and ones, so an axis-aligned arm costs a fraction of a dense batched matrix product.
Entries within 1e-15 of 0 or +-1 in the model's constant placements are rounded to them
(the change of a result is below 1e-15 m per metre of arm).

On top of it: frame positions and rotations, the geometric Jacobian of a frame in B (the arm
columns of Pinocchio's ``LOCAL_WORLD_ALIGNED`` Jacobian with the base at the identity), the
centre of mass in B (Thesis (3.75)-(3.77)) and the statics of a level hover: the arm efforts
that hold the arm (Pinocchio's generalised gravity, arm rows) and the base wrench the rotors
must produce (its base rows), each split into the unloaded part and the part per kilogram of
a point payload so that a payload-mass sweep costs nothing more.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InputError, ShapeError
from ..model import Platform
from ..validation import as_array, as_vector

_SNAP = 1e-15


def _snap(x: float) -> float:
    for v in (0.0, 1.0, -1.0):
        if abs(x - v) < _SNAP:
            return v
    return float(x)


# ------------------------------------------------------------ entry algebra (float or array)
def _mul(a, b):
    if isinstance(a, float):
        if a == 0.0:
            return 0.0
        if a == 1.0:
            return b
        if a == -1.0:
            return -b
    if isinstance(b, float):
        if b == 0.0:
            return 0.0
        if b == 1.0:
            return a
        if b == -1.0:
            return -a
    return a * b


def _add(terms):
    const = 0.0
    arr = None
    for t in terms:
        if isinstance(t, float):
            const += t
        else:
            arr = t if arr is None else arr + t
    if arr is None:
        return const
    return arr + const if const != 0.0 else arr


def _matmul(A, B):
    """3x3 entry tables: A @ B."""
    return [[_add(_mul(A[i][j], B[j][k]) for j in range(3)) for k in range(3)] for i in range(3)]


def _matvec(A, v):
    return [_add(_mul(A[i][j], v[j]) for j in range(3)) for i in range(3)]


def _vadd(a, b):
    return [_add((a[i], b[i])) for i in range(3)]


def _const_table(M: np.ndarray):
    return [[_snap(M[i, j]) for j in range(3)] for i in range(3)]


def _const_vec(v: np.ndarray):
    return [_snap(x) for x in v]


def _materialise(entries, n: int) -> np.ndarray:
    """An entry, entry list or entry table as a dense array with the batch as the first axis."""
    if isinstance(entries, list):
        if entries and isinstance(entries[0], list):
            out = np.empty((n, len(entries), len(entries[0])))
            for i, row in enumerate(entries):
                for j, e in enumerate(row):
                    out[:, i, j] = e
            return out
        out = np.empty((n, len(entries)))
        for i, e in enumerate(entries):
            out[:, i] = e
        return out
    out = np.empty(n)
    out[:] = entries
    return out


# ------------------------------------------------------------------------------ the chain
@dataclass(frozen=True)
class _Joint:
    jid: int
    parent: int  # model joint id; 1 = the base
    kind: str  # "revolute" or "prismatic"
    axis: np.ndarray  # (3,) unit axis in the joint frame
    R0: list  # placement rotation (entry table)
    p0: list  # placement translation
    R0K: list  # R0 hat(axis)
    R0K2: list  # R0 hat(axis)^2
    R0a: list  # R0 axis
    mass: float
    lever: np.ndarray  # CoM in the joint frame


@dataclass
class ChainPose:
    """Placements in B of every model joint for a batch of ``n`` arm configurations.

    ``R[j]``, ``p[j]``: rotation (3x3 entry table) and origin (3 entries) of model joint j
    (index 1 is the base, the identity); entries are floats or arrays of length ``n``.
    """

    n: int
    R: dict
    p: dict


class ArmChain:
    """Batched kinematics of ``platform``'s arm with the base frame B fixed (see the module docstring).

    Build once per platform (it reads the model), then call :meth:`pose` on (n, n_arm) arrays of
    arm configurations.  Read-only after construction; it never modifies the platform.
    """

    def __init__(self, platform: Platform) -> None:
        if not isinstance(platform, Platform):
            raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
        model = platform.model
        self.platform = platform
        self.n_arm = platform.n_arm
        self.g = platform.g
        base_inertia = model.inertias[1]
        self.base_mass = float(base_inertia.mass)
        self.base_lever = np.array(base_inertia.lever)
        joints = []
        for jt in platform.arm:
            j = jt.joint_id
            jm = model.joints[j]
            jd = jm.createData()
            jm.calc(jd, np.zeros(1))
            S = np.array(jd.S).reshape(6)
            axis = S[3:6] if jt.kind == "revolute" else S[0:3]
            nrm = float(np.linalg.norm(axis))
            if abs(nrm - 1.0) > 1e-9:
                raise InputError(f"joint {jt.name!r}: motion subspace {S.tolist()} is not a unit {jt.kind} axis")
            axis = axis / nrm
            M0 = model.jointPlacements[j]
            R0 = np.array(M0.rotation)
            K = pin.skew(axis)
            Y = model.inertias[j]
            joints.append(
                _Joint(
                    j,
                    int(model.parents[j]),
                    jt.kind,
                    axis,
                    _const_table(R0),
                    _const_vec(np.array(M0.translation)),
                    _const_table(R0 @ K),
                    _const_table(R0 @ K @ K),
                    _const_vec(R0 @ axis),
                    float(Y.mass),
                    np.array(Y.lever),
                )
            )
        self._joints = joints
        self.total_mass = self.base_mass + sum(j.mass for j in joints)
        # subtree membership: ancestors of each joint (arm joints only, model ids)
        self._ancestors = {}
        for jt in joints:
            anc, a = [], jt.parent
            while a > 1:
                anc.append(a)
                a = int(model.parents[a])
            self._ancestors[jt.jid] = anc
        # children lists for the reverse accumulation of subtree first moments
        self._children = {1: []}
        for jt in joints:
            self._children.setdefault(jt.jid, [])
            self._children.setdefault(jt.parent, []).append(jt.jid)

    # ------------------------------------------------------------------ forward kinematics
    def check_q_arm(self, q_arm) -> np.ndarray:
        """``q_arm`` as a finite (n, n_arm) float array (a single configuration (n_arm,) becomes (1, n_arm))."""
        q = as_array(q_arm, "q_arm")
        if q.ndim == 1:
            q = q[None, :]
        if q.ndim != 2 or q.shape[1] != self.n_arm:
            raise ShapeError(f"q_arm must have shape (n, {self.n_arm}), got {q.shape}")
        if not np.all(np.isfinite(q)):
            raise InputError("q_arm must be finite")
        return q

    def pose(self, q_arm) -> ChainPose:
        """Placements in B of every joint for the batch ``q_arm`` (n, n_arm)."""
        q = self.check_q_arm(q_arm)
        n = q.shape[0]
        eye = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        R = {1: eye}
        p = {1: [0.0, 0.0, 0.0]}
        for k, jt in enumerate(self._joints):
            qk = q[:, k]
            Rp, pp = R[jt.parent], p[jt.parent]
            if jt.kind == "revolute":
                s, c1 = np.sin(qk), 1.0 - np.cos(qk)
                local = [[_add((jt.R0[i][m], _mul(jt.R0K[i][m], s), _mul(jt.R0K2[i][m], c1))) for m in range(3)] for i in range(3)]
                trans = jt.p0
            else:
                local = jt.R0
                trans = [_add((jt.p0[i], _mul(jt.R0a[i], qk))) for i in range(3)]
            R[jt.jid] = _matmul(Rp, local)
            p[jt.jid] = _vadd(pp, _matvec(Rp, trans))
        return ChainPose(n, R, p)

    def frame_placement(self, pose: ChainPose, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """(R (n, 3, 3), p (n, 3)) of model frame ``frame`` in B."""
        R, p = self._frame_entries(pose, frame)
        return _materialise(R, pose.n), _materialise(p, pose.n)

    def frame_position(self, pose: ChainPose, frame: int, offset=None) -> np.ndarray:
        """(n, 3) position in B of the point ``offset`` (3,) [m] of frame ``frame`` (default its origin)."""
        return _materialise(self._point_entries(pose, frame, offset), pose.n)

    def _frame_entries(self, pose: ChainPose, frame: int):
        f = self.platform.model.frames[frame]
        j = int(f.parentJoint)
        if j == 0:
            raise InputError(f"frame {f.name!r} is attached to the world, not to the platform")
        Rj, pj = pose.R[j], pose.p[j]
        return _matmul(Rj, _const_table(np.array(f.placement.rotation))), _vadd(pj, _matvec(Rj, _const_vec(np.array(f.placement.translation))))

    def _point_entries(self, pose: ChainPose, frame: int, offset=None):
        f = self.platform.model.frames[frame]
        j = int(f.parentJoint)
        if j == 0:
            raise InputError(f"frame {f.name!r} is attached to the world, not to the platform")
        local = np.array(f.placement.translation)
        if offset is not None:
            local = local + np.array(f.placement.rotation) @ as_vector(offset, 3, "offset")
        return _vadd(pose.p[j], _matvec(pose.R[j], _const_vec(local)))

    # ------------------------------------------------------------------ Jacobian
    def jacobian(self, pose: ChainPose, frame: int, offset=None) -> np.ndarray:
        """(n, 6, n_arm): [v; omega] in B of the point ``offset`` of ``frame`` per unit arm rate.

        Revolute joint k with axis w_k and origin o_k in B: [w_k x (p - o_k); w_k]; prismatic:
        [w_k; 0]; zero for joints that do not carry the frame.  Equals the arm columns of
        Pinocchio's LOCAL_WORLD_ALIGNED frame Jacobian with the base at the identity.
        """
        fj = int(self.platform.model.frames[frame].parentJoint)
        pt = self._point_entries(pose, frame, offset)
        carriers = set(self._ancestors.get(fj, [])) | ({fj} if fj > 1 else set())
        J = np.zeros((pose.n, 6, self.n_arm))
        for k, jt in enumerate(self._joints):
            if jt.jid not in carriers:
                continue
            w = _matvec(pose.R[jt.jid], _const_vec(jt.axis))
            if jt.kind == "prismatic":
                for i in range(3):
                    J[:, i, k] = w[i]
            else:
                o = pose.p[jt.jid]
                r = [_add((pt[i], _mul(-1.0, o[i]))) for i in range(3)]
                cr = _cross(w, r)
                for i in range(3):
                    J[:, i, k] = cr[i]
                    J[:, 3 + i, k] = w[i]
        return J

    # ------------------------------------------------------------------ mass distribution
    def _body_moments(self, pose: ChainPose):
        """Per arm joint j: m_j and m_j c_j (3 entries) of the body it carries, in B."""
        out = {}
        for jt in self._joints:
            c = _vadd(pose.p[jt.jid], _matvec(pose.R[jt.jid], _const_vec(jt.lever)))
            out[jt.jid] = (jt.mass, [_mul(float(jt.mass), x) for x in c])
        return out

    def com(self, pose: ChainPose) -> np.ndarray:
        """(n, 3) centre of mass of the whole platform in B [m] (no payload), Thesis (3.76)-(3.77)."""
        first = [self.base_mass * self.base_lever[i] for i in range(3)]
        for _, (_, mc) in self._body_moments(pose).items():
            first = [_add((first[i], mc[i])) for i in range(3)]
        return _materialise(first, pose.n) / self.total_mass

    def statics(self, pose: ChainPose, payload_frame: int, payload_offset=None, gravity_body=None) -> Statics:
        """Hover statics of the batch: everything affine in the payload mass m (see :class:`Statics`).

        ``gravity_body``: gravity in B [m/s^2] (default level hover: (0, 0, -g)).
        """
        gB = np.array([0.0, 0.0, -self.g]) if gravity_body is None else as_vector(gravity_body, 3, "gravity_body")
        n = pose.n
        moments = self._body_moments(pose)
        # subtree mass and first moment per arm joint (reverse topological order: ids increase down the tree)
        sub_m, sub_mc = {}, {}
        for jt in reversed(self._joints):
            m, mc = moments[jt.jid]
            for ch in self._children.get(jt.jid, []):
                m += sub_m[ch]
                mc = [_add((mc[i], sub_mc[ch][i])) for i in range(3)]
            sub_m[jt.jid], sub_mc[jt.jid] = m, mc
        first = [self.base_mass * self.base_lever[i] for i in range(3)]
        for ch in self._children.get(1, []):
            first = [_add((first[i], sub_mc[ch][i])) for i in range(3)]
        com = _materialise(first, n) / self.total_mass
        gl = [float(x) for x in gB]
        tau0 = np.zeros((n, self.n_arm))
        tau1 = np.zeros((n, self.n_arm))
        pl = self._point_entries(pose, payload_frame, payload_offset)
        pj = int(self.platform.model.frames[payload_frame].parentJoint)
        carriers = set(self._ancestors.get(pj, [])) | ({pj} if pj > 1 else set())
        for k, jt in enumerate(self._joints):
            w = _matvec(pose.R[jt.jid], _const_vec(jt.axis))
            if jt.kind == "prismatic":
                # d U / d q = -sum m_i g . w
                tau0[:, k] = _materialise(_mul(-sub_m[jt.jid], _dot(w, gl)), n)
                if jt.jid in carriers:
                    tau1[:, k] = _materialise(_mul(-1.0, _dot(w, gl)), n)
            else:
                o = pose.p[jt.jid]
                # -w . ((S - M o) x g)
                rel = [_add((sub_mc[jt.jid][i], _mul(-sub_m[jt.jid], o[i]))) for i in range(3)]
                tau0[:, k] = _materialise(_mul(-1.0, _dot(w, _cross(rel, gl))), n)
                if jt.jid in carriers:
                    r = [_add((pl[i], _mul(-1.0, o[i]))) for i in range(3)]
                    tau1[:, k] = _materialise(_mul(-1.0, _dot(w, _cross(r, gl))), n)
        p_load = _materialise(pl, n)
        M = self.total_mass
        f = -M * gB
        w0 = np.empty((n, 6))
        w0[:, 0:3] = f
        w0[:, 3:6] = np.cross(M * com, -gB)
        w1 = np.empty((n, 6))
        w1[:, 0:3] = -gB
        w1[:, 3:6] = np.cross(p_load, -gB)
        return Statics(M, com, tau0, tau1, w0, w1, p_load)


def _cross(a, b):
    return [
        _add((_mul(a[1], b[2]), _mul(-1.0, _mul(a[2], b[1])))),
        _add((_mul(a[2], b[0]), _mul(-1.0, _mul(a[0], b[2])))),
        _add((_mul(a[0], b[1]), _mul(-1.0, _mul(a[1], b[0])))),
    ]


def _dot(a, b):
    return _add(_mul(a[i], b[i]) for i in range(3))


@dataclass(frozen=True)
class Statics:
    """Level-hover statics of a batch of arm configurations, affine in a point payload m [kg].

    ``mass`` [kg] and ``com`` (n, 3) [m, B]: the unloaded platform; ``p_load`` (n, 3): where the
    payload sits in B.  Arm efforts that hold the arm still, Pinocchio's generalised gravity
    (arm rows): ``tau_arm0 + m * tau_arm1`` (n, n_arm) [N or N m].  Base wrench at B in B axes
    the rotors must produce, [f; tau] = the base rows of the generalised gravity:
    ``wrench0 + m * wrench1`` (n, 6) [N, N m].  The loaded CoM is (mass com + m p_load) / (mass + m).
    """

    mass: float
    com: np.ndarray
    tau_arm0: np.ndarray
    tau_arm1: np.ndarray
    wrench0: np.ndarray
    wrench1: np.ndarray
    p_load: np.ndarray

    def com_loaded(self, m: float) -> np.ndarray:
        """(n, 3) CoM in B with payload m [kg]."""
        return (self.mass * self.com + m * self.p_load) / (self.mass + m)

    def tau_arm(self, m: float) -> np.ndarray:
        return self.tau_arm0 + m * self.tau_arm1

    def wrench(self, m: float) -> np.ndarray:
        return self.wrench0 + m * self.wrench1
