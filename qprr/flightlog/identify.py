"""Identification from a flight: the thrust per rotor at full command, the hover command, the mass (or the thrust
given the mass), the motor time constant, and through Pinocchio's regressor the centre of gravity, the inertia and,
for an aerial manipulator, the arm's inertial parameters; each with an uncertainty, cross-validated over time blocks.

The vertical model (PX4's thrust model, THR_MDL_FAC f; ActuatorEffectivenessRotors.cpp for the axes):

    m a_z = ct sum_i a_z,i g(lag_T(u_i)),   g(u) = f u^2 + (1 - f) u

with a_z the accelerometer's specific force along z_B (FLU; -a_z in FRD), a_z,i the z components of the log's
CA_ROTOR*_AX/AY/AZ in FLU, u_i the motor commands (interpolated linearly between their logged samples) and lag_T the
first-order motor lag.  The fit is on the airborne intervals only, both sides low-passed by the same zero-phase
filter below half the command logging rate (what the log cannot resolve is cut from both), least squares with a
covariance inflated for the residuals' autocorrelation (:mod:`qprr.flightlog.stats`).  The hover command is g(u) =
g0 / (theta sum_i a_z,i), theta = ct / m.  The motor time constant is profiled (the fit's residual against T); it is
reported only where the profile's one-sigma interval excludes 0 and lies above half the command logging period.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..flightstack.frames import body_from_frd
from ..flightstack.px4 import STANDARD_GRAVITY
from ..model import Platform
from ..validation import as_int, as_output_path, as_real
from ..viz.plots import new_figure
from .inertial import InertialResult, derived, identify_inertial
from .record import FlightRecord, read_joint_csv, record_from_log
from .samples import Estimate, Samples, not_identifiable, prepare_samples
from .stats import least_squares
from .ulog import FlightLog

LAG_GRID_S = np.concatenate([[0.0], np.geomspace(2e-3, 0.4, 40)])
"""The motor time constants profiled [s]."""


@dataclass(frozen=True)
class IdentifyOptions:
    """mass [kg] or ct [N] (at most one: a flight gives their ratio); folds: the k of the k-fold cross-validation over
    time blocks; gravity [m/s^2]; cutoff_hz: the low-pass (default a quarter of the command logging rate, at most
    5 Hz); margin_s: trimmed from both ends of every airborne interval (ground effect, the take-off transient)."""

    mass: float | None = None
    ct: float | None = None
    folds: int = 5
    gravity: float = STANDARD_GRAVITY
    cutoff_hz: float | None = None
    margin_s: float = 1.0

    def __post_init__(self) -> None:
        if self.mass is not None and self.ct is not None:
            raise InputError("give the mass or ct, not both: with both known nothing is left to identify in the vertical model")
        if self.mass is not None:
            object.__setattr__(self, "mass", as_real(self.mass, "mass", positive=True, unit="kg"))
        if self.ct is not None:
            object.__setattr__(self, "ct", as_real(self.ct, "ct", positive=True, unit="N"))
        object.__setattr__(self, "folds", as_int(self.folds, "folds", lo=2, hi=50))
        object.__setattr__(self, "gravity", as_real(self.gravity, "gravity", positive=True, unit="m/s^2"))
        if self.cutoff_hz is not None:
            object.__setattr__(self, "cutoff_hz", as_real(self.cutoff_hz, "cutoff_hz", positive=True, unit="Hz"))
        object.__setattr__(self, "margin_s", as_real(self.margin_s, "margin_s", nonnegative=True, unit="s"))


@dataclass(frozen=True)
class Fold:
    """One fold: the held-out time block [t_start_s, t_end_s], the values fitted on the other blocks, the rms residual
    of the vertical model on the fitted blocks and on the held-out one [m/s^2]."""

    index: int
    t_start_s: float
    t_end_s: float
    values: dict
    rms_fit: float
    rms_held_out: float


@dataclass(frozen=True)
class Identification:
    """Every estimate (key -> :class:`Estimate`), the folds, and the series of the fit (for :meth:`plot`)."""

    estimates: dict
    folds: tuple[Fold, ...]
    source: str = ""
    series: dict = field(default_factory=dict, repr=False)
    combinations: tuple = ()

    def __getitem__(self, key: str) -> Estimate:
        if key not in self.estimates:
            raise InputError(f"no estimate {key!r}; the estimates: {', '.join(self.estimates)}")
        return self.estimates[key]

    def summary(self) -> str:
        """One line per value (value ± std unit, or "not identifiable: reason"), then one per fold."""
        lines = [f"identification of {self.source or 'the flight'}"]
        lines += ["  " + e.line(k) for k, e in self.estimates.items()]
        if self.combinations:
            lines.append("  the combinations of the inertial parameters this flight determines (the regressor's row space):")
            lines += ["    " + c.estimate.line(c.label) for c in self.combinations]
        for f in self.folds:
            vals = ", ".join(f"{k} {v:.5g}" for k, v in f.values.items())
            lines.append(
                f"  fold {f.index + 1}: held out {f.t_start_s:.1f}-{f.t_end_s:.1f} s: {vals}; "
                f"rms fit {f.rms_fit:.3g}, held out {f.rms_held_out:.3g} m/s^2"
            )
        return "\n".join(lines)

    def to_json(self, path) -> Path:
        """Write every value at the top level as ``{"value": ..., "std": ..., "unit": ..., "status": ...}`` (null where not
        identifiable, with its "reason"): ``ct`` [N], ``hover_command``, ``mass`` [kg]...; and, under keys starting with
        an underscore (not values), the log ``_source``, the inertial ``_combinations`` and the cross-validation
        ``_folds``."""
        path = as_output_path(path, "json", suffixes=(".json",))
        out = {}
        for k, e in self.estimates.items():
            out[k] = {"value": e.value if e.identified else None, "std": e.std if e.identified else None, "unit": e.unit, "status": e.status.value}
            if not e.identified:
                out[k]["reason"] = e.reason
        folds = [{"held_out_s": [f.t_start_s, f.t_end_s], **f.values, "rms_fit": f.rms_fit, "rms_held_out": f.rms_held_out} for f in self.folds]
        combos = [
            {
                "label": c.label,
                "coefficients": c.coefficients,
                "value": c.estimate.value if c.estimate.identified else None,
                "std": c.estimate.std if c.estimate.identified else None,
                "status": c.estimate.status.value,
                "reason": c.estimate.reason,
            }
            for c in self.combinations
        ]
        path.write_text(json.dumps({**out, "_source": self.source, "_combinations": combos, "_folds": folds}, indent=2))
        return path

    def plot(self, path) -> Path:
        """Measured against predicted specific force along z_B (the vertical model) and angular acceleration in B (the
        regressor's prediction on each block by the parameters fitted on the others: cross-validated; not drawn, with
        the reason, when the flight does not determine the base's rotational inertia), the held-out blocks shaded."""
        path = as_output_path(path, "plot", suffixes=(".png", ".pdf", ".svg"))
        s = self.series
        rows = 2 if "omega_dot_body" in s else 1
        fig = new_figure((10, 3.2 * rows))
        axes = fig.subplots(rows, 1, sharex=True, squeeze=False)
        ax = axes[0, 0]
        ax.plot(s["t_s"], s["measured_z"], ".", ms=2, label="measured a_z (B)")
        ax.plot(s["t_s"], s["predicted_z"], ".", ms=2, label="predicted")
        ax.set_ylabel("specific force z [m/s^2]")
        if rows == 2:
            ax = axes[1, 0]
            notes = s.get("omega_dot_notes", {})
            for k, name in enumerate("xyz"):
                ax.plot(s["t_s"], s["omega_dot_body"][:, k], ".", ms=2, color=f"C{k}", label=f"measured {name} (B)")
                if name not in notes:
                    ax.plot(s["t_s"], s["omega_dot_predicted"][:, k], "-", lw=1.0, color=f"C{k}", label=f"predicted {name}, held out")
            if notes:
                text = "\n".join(f"{a}: not predicted, {why[:150]}" for a, why in notes.items())
                ax.text(0.01, 0.03, text, transform=ax.transAxes, fontsize=6)
            ax.set_ylabel("angular acceleration [rad/s^2]")
        for f in self.folds:
            for a in axes[:, 0]:
                a.axvspan(f.t_start_s, f.t_end_s, color=f"C{f.index % 10}", alpha=0.08)
        axes[-1, 0].set_xlabel("time since log start [s] (shaded: held-out folds)")
        for a in axes[:, 0]:
            a.legend(fontsize=7, ncol=3)
        fig.savefig(path)
        return path


# ------------------------------------------------------------------------------------------------ the vertical model
@dataclass(frozen=True)
class VerticalFit:
    """theta = ct / m [N/kg] of the vertical model, its LeastSquares, the regressor x (n,) and the motor time
    constant used [s]."""

    theta: float
    theta_std: float
    fit: object
    x: np.ndarray
    time_constant: float


def vertical_regressor(samples: Samples, axis_z: np.ndarray, time_constant: float) -> np.ndarray:
    """x = sum_i a_z,i g(lag_T(u_i)) (n,): the vertical model's regressor (module docstring)."""
    return samples.commands(time_constant) @ axis_z


def fit_vertical(y: np.ndarray, x: np.ndarray, time_constant: float) -> VerticalFit:
    ls = least_squares(x[:, None], y)
    return VerticalFit(float(ls.beta[0]), float(ls.std[0]), ls, x, time_constant)


def profile_time_constant(samples: Samples, axis_z: np.ndarray, command_rate_hz: float) -> tuple[Estimate, float]:
    """(the motor time constant's estimate, the T the other fits use) from the profile of the vertical fit's residual
    sum of squares over LAG_GRID_S: the one-sigma interval {T : (SSR(T) - SSR_min) / (s^2 tau) <= 1}."""
    y = samples.specific_force_body[:, 2]
    fits = [fit_vertical(y, vertical_regressor(samples, axis_z, T), T) for T in LAG_GRID_S]
    ssr = np.array([float(f.fit.residual @ f.fit.residual) for f in fits])
    k = int(np.argmin(ssr))
    best = fits[k].fit
    inside = (ssr - ssr[k]) / (best.s2 * best.tau) <= 1.0
    lo_k, hi_k = k, k
    while lo_k > 0 and inside[lo_k - 1]:
        lo_k -= 1
    while hi_k < len(ssr) - 1 and inside[hi_k + 1]:
        hi_k += 1
    resolution = 0.5 / command_rate_hz
    T = float(LAG_GRID_S[k])
    if lo_k == 0 or T < resolution:
        why = (
            f"motor commands logged at {command_rate_hz:.3g} Hz: a time constant below ~{1e3 * resolution:.0f} ms cannot be seen"
            f" (the fit's best {1e3 * T:.0f} ms, one-sigma range {1e3 * LAG_GRID_S[lo_k]:.0f}-{1e3 * LAG_GRID_S[hi_k]:.0f} ms)"
        )
        return not_identifiable("s", why), 0.0
    if hi_k == len(ssr) - 1:
        return not_identifiable("s", "too little excitation: the residual does not rise for long time constants"), T
    return Estimate(T, 0.5 * float(LAG_GRID_S[hi_k] - LAG_GRID_S[lo_k]), "s"), T


def _hover(theta: float, theta_std: float, axis_sum: float, fac: float, g0: float) -> Estimate:
    """The hover command: g(u) = g0 / (theta sum_i a_z,i), g(u) = f u^2 + (1 - f) u (PX4's THR_MDL_FAC), its std by the
    delta method."""
    r = g0 / (theta * axis_sum)
    u = r if fac == 0.0 else (-(1.0 - fac) + math.sqrt((1.0 - fac) ** 2 + 4.0 * fac * r)) / (2.0 * fac)
    du_dr = 1.0 / (2.0 * fac * u + 1.0 - fac)
    return Estimate(u, abs(du_dr * r * theta_std / theta), "")


def vertical_estimates(theta: float, theta_std: float, record: FlightRecord, axis_sum: float, options: IdentifyOptions) -> dict:
    """ct [N], mass [kg], thrust_to_mass [N/kg] and hover_command of the vertical fit (module docstring)."""
    out = {"thrust_to_mass": Estimate(theta, theta_std, "N/kg")}
    if options.mass is not None:
        out["ct"] = Estimate(theta * options.mass, theta_std * options.mass, "N")
        out["mass"] = Estimate(options.mass, 0.0, "kg", reason="given")
    elif options.ct is not None:
        out["ct"] = Estimate(options.ct, 0.0, "N", reason="given")
        out["mass"] = Estimate(options.ct / theta, options.ct * theta_std / theta**2, "kg")
    else:
        why = "a flight gives only the ratio ct / mass (thrust_to_mass): give the mass (--mass) or the thrust (--ct)"
        out["ct"], out["mass"] = not_identifiable("N", why), not_identifiable("kg", why)
    out["hover_command"] = _hover(theta, theta_std, axis_sum, record.thr_mdl_fac, options.gravity)
    return out


def fold_blocks(n: int, k: int) -> list[np.ndarray]:
    """``k`` contiguous blocks of the sample indices 0..n-1 (time order)."""
    edges = np.linspace(0, n, k + 1).astype(int)
    return [np.arange(edges[j], edges[j + 1]) for j in range(k)]


def cross_validate(
    samples: Samples, y: np.ndarray, x: np.ndarray, record: FlightRecord, axis_sum: float, options: IdentifyOptions
) -> tuple[Fold, ...]:
    """The k folds: the vertical model fitted on k - 1 time blocks, its residual on the held-out block."""
    folds = []
    n = y.shape[0]
    if n < 10 * options.folds:
        raise InputError(f"folds = {options.folds}: the flight gives {n} samples, too few for that many blocks; give fewer folds")
    for j, held in enumerate(fold_blocks(n, options.folds)):
        train = np.setdiff1d(np.arange(n), held)
        vf = fit_vertical(y[train], x[train], 0.0)
        est = vertical_estimates(vf.theta, vf.theta_std, record, axis_sum, options)
        values = {k: e.value for k, e in est.items() if e.identified and k in ("ct", "mass", "hover_command", "thrust_to_mass")}
        r_held = y[held] - vf.theta * x[held]
        folds.append(
            Fold(
                j,
                float(samples.t_s[held[0]]),
                float(samples.t_s[held[-1]]),
                values,
                float(np.sqrt(np.mean(vf.fit.residual**2))),
                float(np.sqrt(np.mean(r_held**2))),
            )
        )
    return tuple(folds)


def rotor_axes_body(record: FlightRecord, platform: Platform | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(positions (n, 3) [m], unit axes (n, 3), km (n,) [m]) of the rotors in B: the platform's when one is given (an
    aerial manipulator: positions from B's origin), else the log's CA_* geometry (FRD -> FLU; positions from the
    centre of gravity PX4 was told, shifted to the IMU, the origin of the rigid model)."""
    if platform is not None:
        p = np.array([r.position_body for r in platform.rotors])
        a = np.array([r.axis_body for r in platform.rotors])
        km = np.array([-r.spin * r.kappa for r in platform.rotors])
        return p, a, km
    g = record.geometry
    p = body_from_frd(np.array([r.position_frd for r in g.rotors])) - np.array(record.imu_position_body)
    a = body_from_frd(np.array([r.axis_frd for r in g.rotors]))
    a /= np.linalg.norm(a, axis=1)[:, None]
    return p, a, np.array([r.km for r in g.rotors])


def identify(record: FlightRecord, options: IdentifyOptions | None = None, platform: Platform | None = None) -> Identification:
    """Identify the vehicle that flew ``record`` (module docstring): the vertical model (ct, mass or ct given the
    other, hover command, motor time constant), its k-fold cross-validation, and the inertial parameters through
    Pinocchio's regressor (:mod:`qprr.flightlog.inertial`; ``platform``: the aerial manipulator whose URDF and rotor
    file give the bodies and the rotor positions from B, with ``record.joints`` its joint angles).  With an arm, ct
    (or the mass) is taken from the regressor, jointly with the inertial parameters: the vertical model of a rigid
    body would read the arm's reaction on the base as thrust."""
    options = IdentifyOptions() if options is None else options
    if not isinstance(options, IdentifyOptions):
        raise InputError(f"options must be an IdentifyOptions, got {type(options).__name__}")
    if platform is not None and record.joints is None and platform.n_arm:
        raise InputError(f"platform {platform.name!r} has arm joints {', '.join(platform.arm_names)}: give their angles (joints CSV)")
    if platform is not None and platform.n_rotors != record.commands.shape[1]:
        raise InputError(f"platform {platform.name!r} has {platform.n_rotors} rotors, the log {record.commands.shape[1]} motor commands")
    samples = prepare_samples(record, options)
    rotors = rotor_axes_body(record, platform)
    axis_z = rotors[1][:, 2]
    axis_sum = float(np.sum(axis_z))
    lag, T = profile_time_constant(samples, axis_z, record.command_rate_hz)
    thrust = samples.commands(T)
    y, x = samples.specific_force_body[:, 2], thrust @ axis_z
    vf = fit_vertical(y, x, T)
    folds = cross_validate(samples, y, x, record, axis_sum, options)
    estimates = vertical_estimates(vf.theta, vf.theta_std, record, axis_sum, options)
    known = {"mass": options.mass} if options.mass is not None else {"ct": options.ct} if options.ct is not None else {}
    mass_scale = estimates["mass"].value if estimates["mass"].identified else 1.0
    blocks = fold_blocks(y.shape[0], options.folds)
    inertial = identify_inertial(samples, rotors, thrust, platform, known, mass_scale, blocks)
    if platform is not None and platform.n_arm:
        theta = regressor_thrust_to_mass(inertial, options)
        if theta.identified:
            estimates = vertical_estimates(theta.value, theta.std, record, axis_sum, options)
    estimates["motor_time_constant"] = lag
    estimates.update(inertial.estimates)
    series = {
        "t_s": samples.t_s,
        "measured_z": y,
        "predicted_z": vf.theta * x,
        "omega_dot_body": samples.omega_dot_body,
        "omega_dot_predicted": inertial.held_out[:, 3:6],
        "omega_dot_notes": rotational_notes(inertial.combinations),
    }
    return Identification(estimates, folds, record.source, series, inertial.combinations)


def rotational_notes(combinations: tuple) -> dict:
    """{axis: why its angular acceleration is not predicted} for the axes x, y, z of B whose diagonal inertia
    (the combination holding base.Ixx, base.Iyy or base.Izz) the flight does not determine."""
    notes = {}
    for axis in "xyz":
        for c in combinations:
            if f"base.I{axis}{axis}" in c.coefficients and not c.estimate.identified:
                notes[axis] = f"{c.label}: {c.estimate.reason}"
    return notes


def regressor_thrust_to_mass(inertial: InertialResult, options: IdentifyOptions) -> Estimate:
    """theta = ct / m [N/kg] from the joint fit of the regressor: ct / M with the mass M given (or 1 kg: the ratio), or
    ct / (the sum of the bodies' masses) with ct given; not identifiable outside the regressor's row space."""
    fit = inertial.fit
    if options.ct is not None:
        cols = [fit.names.index(f"{b}.m") for b in inertial.bodies]
        return derived(fit, lambda x: options.ct / sum(x[j] for j in cols), "N/kg", 1.0, "thrust_to_mass")
    mass = options.mass if options.mass is not None else 1.0
    j = fit.names.index("ct")
    return derived(fit, lambda x: x[j] / mass, "N/kg", abs(fit.x[j] / mass), "thrust_to_mass")


def identify_log(path, options: IdentifyOptions | None = None, platform: Platform | None = None, joints_csv=None) -> Identification:
    """:func:`identify` of the ULog file at ``path`` (:meth:`qprr.flightlog.ulog.FlightLog.read`), with the joint
    angles of ``joints_csv`` (:func:`qprr.flightlog.record.read_joint_csv`) for an aerial manipulator ``platform``."""
    log = FlightLog.read(path)
    joints = read_joint_csv(joints_csv, platform) if joints_csv is not None else None
    return identify(record_from_log(log, joints), options, platform)
