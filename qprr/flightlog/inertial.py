"""The inertial parameters from a flight, through Pinocchio's joint-torque regressor.

Pinocchio's ``computeJointTorqueRegressor(model, data, q, v, a)`` gives Y (nv x 10 n_bodies) with tau = Y pi, pi the
bodies' dynamic parameters [m, m c, I (about the joint frame's origin: xx, xy, yy, xz, yz, zz)]
(``Inertia.toDynamicParameters``).  The free flyer's rows are the base wrench [f; tau] in B at B's origin: the rotor
wrench ct sum_i g_i [a_i; p_i x a_i - km_i a_i] (PX4's ActuatorEffectivenessRotors.cpp, in FLU).  The arm's rows
equal the joint torques, which a PX4 log does not hold: only the base rows are used.

The base's motion: with gravity set to zero in the model, the base at the origin with zero linear velocity and the
linear acceleration equal to the IMU's specific force, the regressor equals the true one (the Newton-Euler
equations depend on the classical accelerations only, and the specific force is the classical acceleration of B's
origin minus gravity, in B); the attitude is not needed.

Only what the flight determines is reported: the stacked, row-weighted and column-scaled regressor is decomposed
(SVD); a derived quantity (a centre of gravity, an inertia about it, a ratio) is identifiable when its gradient lies
in the row space of the regressor (structurally) and its std is small against its scale (excitation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..model import Platform
from ..validation import as_real
from .samples import RELATIVE_STD_MAX, Estimate, Samples, not_identifiable
from .stats import autocorrelation_time

RANK_RTOL = 1e-7
"""Singular values of the scaled regressor below this fraction of the largest are structural zeros."""

ROW_SPACE_TOL = 1e-6
"""A gradient whose part outside the regressor's row space exceeds this fraction of its norm is not identifiable."""


def rigid_model() -> pin.Model:
    """A free-flyer model of one rigid body (its parameters to identify), gravity zero (module docstring)."""
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "base")
    model.appendBodyToJoint(j, pin.Inertia(1.0, np.zeros(3), np.eye(3) * 1e-2), pin.SE3.Identity())
    model.gravity = pin.Motion.Zero()
    return model


@dataclass(frozen=True)
class RegressorFit:
    """The solution of Y pi = ct W (module docstring): x the unknowns (scaled back), cov their covariance, V_r the
    row space (in scaled coordinates), scale the column scales, names of the unknowns, and the fixed values."""

    x: np.ndarray
    cov: np.ndarray
    row_space: np.ndarray
    scale: np.ndarray
    names: tuple[str, ...]
    tau: float
    condition: float
    A: np.ndarray = field(repr=False, default=None)
    b: np.ndarray = field(repr=False, default=None)


def stacked_regressor(model: pin.Model, samples: Samples, wrench_columns: np.ndarray, thrust: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Y (6 n, 10 n_bodies) the base rows of every sample, W (6 n,) the rotor wrench per unit ct)."""
    data = model.createData()
    n = samples.t_s.shape[0]
    na = model.nv - 6
    q = pin.neutral(model)
    v = np.zeros(model.nv)
    a = np.zeros(model.nv)
    Y = np.empty((6 * n, 10 * (model.njoints - 1)))
    for k in range(n):
        v[3:6] = samples.gyro_body[k]
        a[0:3] = samples.specific_force_body[k]
        a[3:6] = samples.omega_dot_body[k]
        if na:
            q[7:] = samples.joints[0][k]
            v[6:] = samples.joints[1][k]
            a[6:] = samples.joints[2][k]
        Y[6 * k : 6 * k + 6] = pin.computeJointTorqueRegressor(model, data, q, v, a)[0:6]
    W = (thrust @ wrench_columns.T).reshape(-1)
    return Y, W


def solve_regressor(Y: np.ndarray, W: np.ndarray, known: dict, names: tuple[str, ...]) -> RegressorFit:
    """Least squares of Y pi - ct W = 0 with the ``known`` unknowns (name -> value; "ct" or "mass_total" with the
    index list of the mass columns) moved to the right-hand side; rows weighted per kind (force, moment) by their
    first-pass residual rms; minimum-norm solution in the regressor's row space (SVD)."""
    A = np.hstack([Y, -W[:, None]])
    cols = list(names) + ["ct"]
    b = np.zeros(A.shape[0])
    if "ct" in known:
        b += W * known["ct"]
        A, cols = A[:, :-1], cols[:-1]
    if "mass_total" in known:  # the first mass column (the base's) = m_total - the others
        m_total, mass_cols = known["mass_total"]
        base = mass_cols[0]
        for j in mass_cols[1:]:
            A[:, j] -= A[:, base]
        b -= A[:, base] * m_total
        A = np.delete(A, base, axis=1)
        cols.pop(base)
    w = np.ones(A.shape[0])
    for _ in range(2):
        x, V, s, sc, r = _svd_solve(A * w[:, None], b * w)
        res = (b - A @ x).reshape(-1, 6)
        rms = np.sqrt(np.mean(res**2, axis=0))
        rms_f, rms_m = max(float(np.mean(rms[0:3])), 1e-12), max(float(np.mean(rms[3:6])), 1e-12)
        w = np.tile(np.r_[np.full(3, 1.0 / rms_f), np.full(3, 1.0 / rms_m)], res.shape[0])
    Aw, bw = A * w[:, None], b * w
    x, V, s, sc, r = _svd_solve(Aw, bw)
    resid = bw - Aw @ x
    dof = max(Aw.shape[0] - V.shape[1], 1)
    s2 = float(resid @ resid) / dof
    tau = autocorrelation_time(resid.reshape(-1, 6))
    cov_z = (V / s**2) @ V.T * s2 * tau
    cov = cov_z / np.outer(sc, sc)
    return RegressorFit(x, cov, V, sc, tuple(cols), tau, float(s[0] / s[-1]) if s.size else math.inf, Aw, bw)


def _svd_solve(A: np.ndarray, b: np.ndarray):
    """(x, V_r, s_r, column scales, rank) of the minimum-norm least-squares solution of A x = b, columns scaled to unit
    norm, singular values below RANK_RTOL of the largest dropped."""
    sc = np.linalg.norm(A, axis=0)
    sc = np.where(sc > 0.0, sc, 1.0)
    Qa, Ra = np.linalg.qr(A / sc)  # A / sc = Qa Ra, then the SVD of the small Ra (the same singular values, faster)
    U, s, Vt = np.linalg.svd(Ra)
    r = int(np.sum(s > RANK_RTOL * s[0]))
    U, s, V = U[:, :r], s[:r], Vt[:r].T
    z = V @ ((U.T @ (Qa.T @ b)) / s)
    return z / sc, V, s, sc, r


def derived(fit: RegressorFit, fn, unit: str, scale: float, what: str) -> Estimate:
    """The estimate of ``fn(x)`` (a scalar of the unknowns): structurally identifiable when its gradient lies in the row
    space, then identified when its std <= RELATIVE_STD_MAX x ``scale``."""
    x = fit.x
    value = float(fn(x))
    if not math.isfinite(value):
        return not_identifiable(unit, f"{what} is undefined at the fitted values")
    grad = np.empty(x.size)
    for j in range(x.size):
        h = 1e-6 * max(abs(x[j]), 1e-3)
        xp, xm = x.copy(), x.copy()
        xp[j] += h
        xm[j] -= h
        grad[j] = (fn(xp) - fn(xm)) / (2 * h)
    gz = grad / fit.scale  # the gradient in scaled coordinates
    outside = gz - fit.row_space @ (fit.row_space.T @ gz)
    if np.linalg.norm(outside) > ROW_SPACE_TOL * max(np.linalg.norm(gz), 1e-300):
        return not_identifiable(
            unit,
            f"{what} enters the base wrench only within the combinations listed (the regressor's row space): the joint "
            "torques that would separate it are not in a PX4 log, and this flight's motion does not",
        )
    std = float(math.sqrt(max(grad @ fit.cov @ grad, 0.0)))
    if not std <= RELATIVE_STD_MAX * scale:
        return not_identifiable(
            unit, f"too little excitation: {what} = {value:.3g} ± {std:.2g} {unit}, std above {RELATIVE_STD_MAX:.0%} of {scale:.3g} {unit}"
        )
    return Estimate(value, std, unit)


def _param(fit: RegressorFit, name: str, fixed: dict):
    """A getter x -> the unknown called ``name`` (or its fixed value)."""
    if name in fit.names:
        j = fit.names.index(name)
        return lambda x: x[j]
    return lambda x: fixed[name](x)


def body_quantities(fit: RegressorFit, body: str, fixed: dict, length: float) -> dict:
    """Mass, centre of gravity (in the body's frame) and the principal-axis inertia about it of ``body`` (the unknowns
    ``body.m``, ``body.mc_*``, ``body.I_*``), identifiable or not (:func:`derived`)."""
    get = {k: _param(fit, f"{body}.{k}", fixed) for k in ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")}

    def com(k: str):
        return lambda x: get["mc" + k](x) / get["m"](x)

    def inertia_about_com(a: str):
        i = "xyz".index(a)

        def fn(x):
            c = np.array([com(k)(x) for k in "xyz"])
            return get[f"I{a}{a}"](x) - get["m"](x) * (c @ c - c[i] ** 2)

        return fn

    out = {}
    mass_scale = abs(get["m"](fit.x)) if math.isfinite(get["m"](fit.x)) else 1.0
    out["mass"] = derived(fit, get["m"], "kg", mass_scale, f"{body} mass")
    for k in "xyz":
        out[f"cog_{k}"] = derived(fit, com(k), "m", 0.1 * length, f"{body} centre of gravity {k}")
    for a in "xyz":
        f = inertia_about_com(a)
        out[f"inertia_{a}{a}"] = derived(fit, f, "kg m^2", abs(f(fit.x)), f"{body} inertia {a}{a}")

    def product_about_com(a: str, b: str):
        i, k = "xyz".index(a), "xyz".index(b)

        def fn(x):  # I_c = I_o - m (|c|^2 E - c c^T): off the diagonal I_c,ab = I_o,ab + m c_a c_b
            c = np.array([com(n)(x) for n in "xyz"])
            return get[f"I{a}{b}"](x) + get["m"](x) * c[i] * c[k]

        return fn

    diag_scale = float(np.mean([abs(inertia_about_com(a)(fit.x)) for a in "xyz"]))
    for a, b in ("xy", "xz", "yz"):
        out[f"inertia_{a}{b}"] = derived(fit, product_about_com(a, b), "kg m^2", diag_scale, f"{body} inertia {a}{b}")
    ixx = inertia_about_com("x")
    for a in "yz":
        f = inertia_about_com(a)
        out[f"inertia_ratio_{a}{a}_xx"] = derived(
            fit, lambda x, f=f: f(x) / ixx(x), "", abs(f(fit.x) / ixx(fit.x)), f"{body} inertia ratio {a}{a}/xx"
        )
    return out


PARAMETER_NAMES = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
"""Pinocchio's dynamic parameters of a body (Inertia.toDynamicParameters), in order."""


def _checked_model(model) -> pin.Model:
    """``model`` if it is a Pinocchio model with a free-flyer base, else an InputError naming it."""
    if not isinstance(model, pin.Model) or model.njoints < 2 or model.joints[1].shortname() != "JointModelFreeFlyer":
        raise InputError(f"model must be a pinocchio.Model with a free-flyer base (Platform.model), got {type(model).__name__}")
    return model


def body_names(model: pin.Model) -> list[str]:
    """The name of each moving body of a free-flyer Pinocchio ``model``: "base" for the free flyer, the URDF link each
    arm joint moves."""
    model = _checked_model(model)
    out = ["base"]
    for j in range(2, model.njoints):
        links = [f.name for f in model.frames if f.parentJoint == j and f.type == pin.FrameType.BODY]
        out.append(links[0] if links else model.names[j])
    return out


@dataclass(frozen=True)
class InertialResult:
    """What :func:`identify_inertial` finds: ``estimates`` (key -> Estimate), the ``fit``, the ``combinations`` the
    flight determines (:func:`identifiable_combinations`), the model fitted, the body names, and ``held_out`` (n, 6)
    the base's acceleration predicted on each held-out block (:func:`held_out_predictions`)."""

    estimates: dict
    fit: RegressorFit
    combinations: tuple
    model: pin.Model
    bodies: tuple
    held_out: np.ndarray


def identify_inertial(
    samples: Samples, rotors: tuple, ct_thrust: np.ndarray, platform: Platform | None, known: dict, mass_scale: float, blocks: list
) -> InertialResult:
    """The inertial estimates of the flight (module docstring): for a rigid multirotor its centre of gravity (from the
    point PX4's CA_* positions are measured from), its inertia about it and the inertia ratios; for an aerial
    manipulator the same of the base and each arm link (mass, centre of gravity in the link frame, inertia); the
    identifiable combinations; the cross-validated prediction of the base's acceleration over ``blocks``.

    ``rotors``: (positions, axes, km) in B; ``ct_thrust``: g(lag_T(u)) on the samples (n, n_rotors); ``known``:
    {"ct": value} or {"mass": total mass} (neither: mass 1 kg, only the scale-free values are meaningful);
    ``mass_scale`` [kg]: the vehicle's mass (given or from the vertical fit), the scale of the combinations."""
    p, a, km = rotors
    wrench = np.vstack([a.T, (np.cross(p, a) - km[:, None] * a).T])  # (6, n_rotors), per unit ct
    if platform is None:
        model = rigid_model()
    else:
        model = pin.Model(platform.model)
        model.gravity = pin.Motion.Zero()
    bodies = body_names(model)
    names = tuple(f"{b}.{k}" for b in bodies for k in PARAMETER_NAMES)
    Y, W = stacked_regressor(model, samples, wrench, ct_thrust)
    solve_known = {}
    if "ct" in known:
        solve_known["ct"] = known["ct"]
    mass_total = known.get("mass", 1.0 if "ct" not in known else None)
    if mass_total is not None:
        solve_known["mass_total"] = (mass_total, [10 * i for i in range(len(bodies))])
    fit = solve_regressor(Y, W, solve_known, names)
    length = float(np.max(np.linalg.norm(p, axis=1)))
    out = _body_estimates(fit, bodies, mass_total, length, platform is None)
    if "ct" not in known and mass_total == 1.0:
        for k in list(out):
            if "inertia_" in k and "ratio" not in k or k.endswith("mass"):
                out[k] = not_identifiable(out[k].unit, "give the mass (--mass) or the thrust (--ct): without either the flight gives only ratios")
    combos = identifiable_combinations(fit, mass_scale, length)
    held = held_out_predictions(acceleration_maps(model, samples), (Y, W), solve_known, names, bodies, blocks)
    return InertialResult(out, fit, combos, model, tuple(bodies), held)


def _body_estimates(fit: RegressorFit, bodies: list[str], mass_total: float | None, length: float, rigid: bool) -> dict:
    """:func:`body_quantities` of every body, keyed "<body>.<quantity>" (a rigid multirotor: "<quantity>", no mass)."""
    fixed = {}
    if mass_total is not None:
        others = [fit.names.index(f"{b}.m") for b in bodies[1:]]
        fixed["base.m"] = lambda x, o=others, m=mass_total: m - sum(x[j] for j in o)
    out = {}
    for b in bodies:
        for k, e in body_quantities(fit, b, fixed, length).items():
            if b == "base" and k == "mass" and rigid:
                continue
            out[k if b == "base" and rigid else f"{b}.{k}"] = e
    return out


# ------------------------------------------------------------------------ the identifiable combinations (base parameters)
COMBINATION_TOL = 1e-6
"""A (unit-norm, scaled) regressor column whose part outside the span of the columns before it is below this is a
structural combination of them (Gautier, "Numerical calculation of the base inertial parameters of robots", J. of
Robotic Systems 8(4), 1991: the same test by QR, columns in a fixed order)."""

COMBINATION_SCALE = 0.1
"""The fraction of its physical scale (ct; the mass M; M L; M L^2) an unknown must be resolved to."""


@dataclass(frozen=True)
class Combination:
    """One identifiable combination of the unknowns (a base parameter): sum_k coefficients[k] x_k with x the unknowns
    of the fit ("ct" [N], "<body>.m" [kg], "<body>.mcx" = m c_x [kg m] with c in the body's joint frame, "<body>.Ixx"
    ... [kg m^2] about the joint frame's origin, Pinocchio's ``Inertia.toDynamicParameters``), its ``estimate``,
    and the ``label`` that writes it out."""

    label: str
    coefficients: dict
    estimate: Estimate

    def value_of(self, values: dict) -> float:
        """The combination evaluated at ``values`` (name -> value, e.g. the truth of a simulated flight)."""
        return float(sum(c * values[k] for k, c in self.coefficients.items()))


def _kind_scale(name: str, mass: float, length: float, ct: float) -> float:
    """The resolution an unknown must be known to (COMBINATION_SCALE of its physical scale): of ct itself, of the
    vehicle's mass M, of M L for a first moment, of M L^2 for a second moment (L: the largest rotor distance)."""
    kind = name.split(".")[-1]
    physical = ct if name == "ct" else mass if kind == "m" else mass * length if kind.startswith("mc") else mass * length**2
    return COMBINATION_SCALE * physical


def _label(coefficients: dict) -> str:
    terms = []
    for k, c in coefficients.items():
        sign = "-" if c < 0 else "+"
        mag = "" if abs(abs(c) - 1.0) < 1e-9 else f"{abs(c):.4g} "
        terms.append(f"{sign} {mag}{k}")
    text = " ".join(terms)
    return text[2:] if text.startswith("+ ") else text


def identifiable_combinations(fit: RegressorFit, mass: float, length: float) -> tuple[Combination, ...]:
    """A basis of what the flight determines (the row space of the weighted regressor of :func:`solve_regressor`),
    each vector written as one unknown plus the unknowns that enter the base wrench only together with it: the
    columns are taken in order (ct, then the bodies from the base out), a column in the span of those before it
    (COMBINATION_TOL) is regrouped into them, A_d = sum_i K_id A_i, so A x = A_I beta with beta_i = x_i + sum_d K_id
    x_d (Gautier 1991).  beta is fitted by least squares on A_I (full column rank), its covariance inflated for the
    residuals' autocorrelation (:mod:`qprr.flightlog.stats`); a combination is identified when its std is at most
    RELATIVE_STD_MAX of the scale of its largest term (|coefficient_k| x :func:`_kind_scale`): a scale fixed by the
    vehicle, never by the estimate (a noisy large value does not make itself identified)."""
    A, b = fit.A, fit.b
    sc = np.linalg.norm(A, axis=0)
    sc = np.where(sc > 0.0, sc, 1.0)
    As = A / sc
    order = ([fit.names.index("ct")] if "ct" in fit.names else []) + [j for j, n in enumerate(fit.names) if n != "ct"]
    Q = np.zeros((A.shape[0], 0))
    indep = []
    for j in order:
        r = As[:, j] - Q @ (Q.T @ As[:, j])
        r -= Q @ (Q.T @ r)  # re-orthogonalised (classical Gram-Schmidt twice)
        if np.linalg.norm(r) > COMBINATION_TOL:
            indep.append(j)
            Q = np.column_stack([Q, r / np.linalg.norm(r)])
    dep = [j for j in order if j not in indep]
    K = np.linalg.lstsq(As[:, indep], As[:, dep], rcond=None)[0] if dep else np.zeros((len(indep), 0))
    K = K * sc[dep][None, :] / sc[indep][:, None]  # unscaled: A_d = sum_i K_id A_i
    AI = A[:, indep]
    beta = np.linalg.lstsq(AI, b, rcond=None)[0]
    resid = b - AI @ beta
    s2 = float(resid @ resid) / max(A.shape[0] - len(indep), 1)
    tau = autocorrelation_time(resid.reshape(-1, 6))
    cov = np.linalg.inv(AI.T @ AI) * s2 * tau
    ct = abs(float(beta[0])) if "ct" in fit.names and indep[0] == fit.names.index("ct") else 1.0
    out = []
    for i, j in enumerate(indep):
        coef = {fit.names[j]: 1.0}
        coef.update({fit.names[d]: float(K[i, m]) for m, d in enumerate(dep) if abs(K[i, m]) > 1e-9})
        std = float(math.sqrt(max(cov[i, i], 0.0)))
        scale = max(abs(c) * _kind_scale(k, mass, length, ct) for k, c in coef.items())
        label = _label(coef)
        if std <= RELATIVE_STD_MAX * scale:
            est = Estimate(float(beta[i]), std, "")
        else:
            est = not_identifiable(
                "", f"too little excitation: {label} = {beta[i]:.3g} ± {std:.2g}, std above {RELATIVE_STD_MAX:.0%} of its scale {scale:.3g}"
            )
        out.append(Combination(label, coef, est))
    return tuple(out)


def parameter_values(model: pin.Model, ct: float, known: dict | None = None) -> dict:
    """The unknowns of :func:`identify_inertial` (name -> value) of a Pinocchio ``model`` (its bodies' dynamic
    parameters) and a thrust ``ct`` [N]: the truth a simulated flight's combinations are checked against."""
    model = _checked_model(model)
    out = {"ct": as_real(ct, "ct", positive=True, unit="N")}
    for b, j in zip(body_names(model), range(1, model.njoints)):
        for k, v in zip(PARAMETER_NAMES, model.inertias[j].toDynamicParameters()):
            out[f"{b}.{k}"] = float(v)
    return out


def full_parameters(fit: RegressorFit, x: np.ndarray, bodies: list[str], fixed: dict) -> tuple[np.ndarray, float]:
    """(pi (10 n_bodies,), ct) of the unknowns ``x`` of ``fit`` with the ``fixed`` ones ("ct": its value;
    "mass_total": the base's mass = the total - the others)."""
    values = dict(zip(fit.names, x))
    if "mass_total" in fixed:
        values[f"{bodies[0]}.m"] = fixed["mass_total"] - sum(values[f"{b}.m"] for b in bodies[1:])
    if "ct" in fixed:
        values["ct"] = fixed["ct"]
    return np.array([values[f"{b}.{k}"] for b in bodies for k in PARAMETER_NAMES]), float(values["ct"])


def acceleration_maps(model: pin.Model, samples: Samples) -> tuple[np.ndarray, np.ndarray]:
    """(H (n, 6, P), M (n, 6, 6, P)): the base rows of the regressor at the samples' (q, v) with the base's
    acceleration zero (H) and at v = 0 with a unit base acceleration along each axis (M[:, :, i]), so that the base
    wrench of parameters pi is Y pi = H pi + (M pi) a_b (the Newton-Euler equations are affine in a_b)."""
    data = model.createData()
    n, P = samples.t_s.shape[0], 10 * (model.njoints - 1)
    H, M = np.empty((n, 6, P)), np.empty((n, 6, 6, P))
    q, zero = pin.neutral(model), np.zeros(model.nv)
    for k in range(n):
        v, a = zero.copy(), zero.copy()
        v[3:6] = samples.gyro_body[k]
        if model.nv > 6:
            q[7:], v[6:], a[6:] = samples.joints[0][k], samples.joints[1][k], samples.joints[2][k]
        H[k] = pin.computeJointTorqueRegressor(model, data, q, v, a)[0:6]
        for i in range(6):
            e = zero.copy()
            e[i] = 1.0
            M[k, :, i] = pin.computeJointTorqueRegressor(model, data, q, zero, e)[0:6]
    return H, M


def predicted_base_acceleration(maps: tuple, pi: np.ndarray, wrench: np.ndarray) -> np.ndarray:
    """The base's acceleration [specific force; angular acceleration] (n, 6) in B that the parameters ``pi`` predict
    under the rotor wrench ``wrench`` (n, 6) [N, N m]: a_b = (M pi)^-1 (wrench - H pi) (:func:`acceleration_maps`)."""
    H, M = maps
    return np.linalg.solve(M @ pi, (wrench - H @ pi)[..., None])[..., 0]


def held_out_predictions(maps: tuple, system: tuple, known: dict, names: tuple, bodies: list[str], blocks: list) -> np.ndarray:
    """The base's acceleration (n, 6) predicted on each time block of ``blocks`` by the parameters fitted on the other
    blocks (:func:`solve_regressor` on their rows of ``system`` = (Y, W)): a cross-validated prediction."""
    Y, W = system
    n = Y.shape[0] // 6
    out = np.full((n, 6), np.nan)
    wrench = W.reshape(n, 6)
    for held in blocks:
        train = np.setdiff1d(np.arange(n), held)
        rows = (6 * train[:, None] + np.arange(6)).reshape(-1)
        fit = solve_regressor(Y[rows], W[rows], known, names)
        pi, ct = full_parameters(fit, fit.x, bodies, {"ct": known["ct"]} if "ct" in known else {"mass_total": known["mass_total"][0]})
        out[held] = predicted_base_acceleration((maps[0][held], maps[1][held]), pi, ct * wrench[held])
    return out
