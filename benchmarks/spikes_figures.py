"""Figures of docs/notes-spikes.md: each spike of issue 10 item 3 before and after its fix.

    python benchmarks/spikes_figures.py [out_dir]      # default docs/figures
    python benchmarks/spikes_figures.py --quick        # the phase-switch figure only, to a temporary folder

The "before" cases stay reproducible with the current code: the quintic transition law
(``law="quintic"``), the printed spiral (``Spiral(blend=0)``), the printed velocity gain of
(A.3) for the desired-state controller (K_D = 18) and the push with the force cancelled through
the thrust.  About 15 s of simulation in all.  The spikes are the subject here: unlike
:func:`qprr.viz.plot_result`, these axes are not clipped to robust limits.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from pathlib import Path

import numpy as np

import qprr
from qprr import kinematics as kin
from qprr.control import DesiredStateInverseDynamics, LayeredIDC
from qprr.sim import PushedMass, simulate
from qprr.thesis import gains, params_of
from qprr.thesis import scenarios as scn
from qprr.thesis.missions import static_mission
from qprr.trajectory import MultiPhase, Phase, Spiral
from qprr.viz.plots import DEG, REFERENCE_STYLE, legend, new_figure, save_figure

NAMES = ("x", "y", "z", "phi", "theta", "psi", "r0", "theta2", "theta3")


def _finish(ax_flat, loc="best"):
    for a in ax_flat:
        a.grid(alpha=0.3)
        legend(a, loc=loc)


def static_switch(robot, out: Path) -> Path:
    """static-idc around the x -> y switch at t = 10 s, quintic vs septic law."""
    fig = new_figure((11, 8))
    ax = fig.subplots(3, 2, sharex=True, sharey="row")
    peak = {}
    for col, law in enumerate(("quintic", "septic")):
        res = simulate(robot, scn.flight_controller("idc", robot), static_mission(law=law), 10.1)
        s = res.t >= 9.98
        t = res.t[s]
        peak[law] = float(np.max(np.abs(np.diff(res.u[s, 3:5], axis=0))))  # the largest tick-to-tick jump of u_tau
        for j in range(4):
            ax[0, col].plot(t, res.f[s, j], lw=1.0, label=f"$f_{j + 1}$")
        ax[1, col].plot(t, res.u[s, 3], lw=1.0, label=r"$u_{\tau,\phi}$ [N m]")
        ax[1, col].plot(t, res.u[s, 4], lw=1.0, label=r"$u_{\tau,\theta}$ [N m]")
        ax[1, col].plot(t, res.u[s, 6], lw=1.0, ls="--", label=r"$u_{\mu,r_0}$ [N]")
        ax[2, col].plot(t, DEG * res.xi_dot_d[s, 3], lw=1.0, label=r"$\dot\phi_d$")
        ax[2, col].plot(t, DEG * res.xi_dot_d[s, 4], lw=1.0, label=r"$\dot\theta_d$")
        ax[0, col].set_title(f"static-idc, {law} law: x -> y phase switch at t = 10 s", fontsize=10)
        ax[0, col].set_ylim(-0.5, 18.0)
        ax[2, col].set_xlabel("t [s]")
    ax[0, 0].set_ylabel("rotor thrust [N]")
    ax[1, 0].set_ylabel("controller output u [N m, N]")
    ax[2, 0].set_ylabel("tilt-rate reference [deg/s]")
    _finish(ax.flat, "lower left")
    print(
        f"static switch: largest tick-to-tick jump of the attitude torques, quintic {peak['quintic']:.3g} N m, septic "
        f"{peak['septic']:.3g} N m; ratio quintic / septic {peak['quintic'] / peak['septic']:.2f}"
    )
    return save_figure(fig, out / "spikes-static-switch.png", dpi=80)


def spiral_start(robot, out: Path) -> Path:
    """spiral (6.25) as printed (blend 0) and faded in over 2 s: torques and thrusts at t_f = 5 s."""
    fig = new_figure((11, 8))
    ax = fig.subplots(3, 2, sharex="col")
    for col, blend in enumerate((0.0, 2.0)):
        res = simulate(robot, scn.flight_controller("idc", robot), Spiral(blend=blend), 7.5)
        s = res.t >= 4.95
        t = res.t[s]
        ax[0, col].plot(t, res.xi_dot_d[s, 0], lw=1.0, label=r"$\dot x_d$ [m/s]")
        ax[0, col].plot(t, res.xi_dot_d[s, 1], lw=1.0, label=r"$\dot y_d$ [m/s]")
        ax[1, col].plot(t, res.u[s, 3], lw=1.0, label=r"$u_{\tau,\phi}$")
        ax[1, col].plot(t, res.u[s, 4], lw=1.0, label=r"$u_{\tau,\theta}$")
        for b in (0.0, 20.0):
            ax[2, col].axhline(b, color="0.3", ls=":", lw=1.0)
        for j in range(4):
            ax[2, col].plot(t, res.f[s, j], lw=1.0, label=f"$f_{j + 1}$")
        ax[0, col].set_title("printed (6.25): steps at $t_f$" if blend == 0 else f"faded in over {blend:g} s (septic)")
        ax[2, col].set_xlabel("t [s]")
        ax[1, col].set_ylabel("attitude torque [N m]")
        ax[2, col].set_ylabel("rotor thrust [N]")
        ax[0, col].set_ylabel("reference velocity [m/s]")
    _finish(ax.flat, "upper right")
    return save_figure(fig, out / "spikes-spiral-start.png", dpi=80)


def dsid_chatter(robot, out: Path) -> Path:
    """static-dsid roll and pitch (measured and reference) with the printed K_D = 18 and with K_D = 2 sqrt(K_P)."""
    default = gains.desired_state()
    printed = dataclasses.replace(default, kd=(18.0,) * 3 + default.kd[3:])
    fig = new_figure((11, 6))
    ax = fig.subplots(2, 1, sharex=True, sharey=True)
    for row, (g, label) in enumerate(((printed, "printed $K_D$ = 18"), (default, r"$K_D = 2\sqrt{K_P}$ = 10.95"))):
        res = simulate(robot, DesiredStateInverseDynamics(robot, g), static_mission(), 30.0)
        for i, name, c in ((3, r"\phi", "C0"), (4, r"\theta", "C1")):
            ax[row].plot(res.t, DEG * res.xi[:, i], c, lw=1.0, label=f"${name}$")
            ax[row].plot(res.t, DEG * res.xi_d[:, i], label=f"${name}_d$ (6.17)" if i == 3 else None, **REFERENCE_STYLE)
        ax[row].set_title(f"static-dsid, {label}: roll and pitch (dashed: references)")
        ax[row].set_ylabel("angle [deg]")
    ax[1].set_xlabel("t [s]")
    _finish(ax, "upper left")
    return save_figure(fig, out / "spikes-dsid.png", dpi=80)


class _NoTranslationalCompensation(LayeredIDC):
    def feedforward(self, t, state):
        ff = super().feedforward(t, state)  # a list (thesis coordinates) or None
        if ff is not None:
            ff = [0.0, 0.0, 0.0, *ff[3:]]
        return ff


def push_prismatic(robot, out: Path) -> Path:
    """push-prismatic contact force: 200 and 500 N/m contacts, and 500 N/m without cancelling the force through the thrust."""
    lo, hi = params_of(robot).r0_limits
    data = robot.data()
    xi_end = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, hi, *scn.ARM_PUSH[1:]])
    h = kin.ee_pose_xi(robot, data, xi_end)[0][2] - kin.com_world(robot, data, qprr.charts.xi_to_q(xi_end))[2]
    weight = robot.total_mass * robot.g
    fig = new_figure((11, 4.5))
    ax = fig.add_subplot()
    for k in (200.0, 500.0):
        c = scn.contact_history(scn.push_prismatic(settings=scn.PushSettings.prismatic(stiffness=k)))
        ax.plot(c.t, c.force, lw=1.0, label=f"k = {k:g} N/m (loop gain k h / m g = {k * h / weight:.2f})")
    xi0 = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, lo, *scn.ARM_PUSH[1:]])
    p0, _ = kin.ee_pose_xi(robot, data, xi0)
    obj = PushedMass(robot, mass=0.2, origin=p0, stiffness=500.0, damping=20.0, friction=0.3)
    ctrl = _NoTranslationalCompensation(robot, gains.payload_idc(), ee_sensor=obj.measured, sensor_filter=scn.SENSOR_FILTER)
    simulate(robot, ctrl, MultiPhase((Phase("r0", 2.0, 7.0, hi),), tuple(xi0), names=NAMES), 10.0, external_wrench=obj)
    c = obj.history()
    ax.plot(c.t, c.force, lw=1.0, ls="--", label="k = 500 N/m, force not cancelled through the thrust")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("contact force [N]")
    ax.set_title(f"push-prismatic: once the object sticks, contacts stiffer than k* = m g / h = {weight / h:.0f} N/m (h = {100 * h:.1f} cm) bounce")
    _finish([ax], "lower left")
    return save_figure(fig, out / "spikes-push-prismatic.png", dpi=80)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out_dir", nargs="?", type=Path, default=Path(__file__).resolve().parents[1] / "docs" / "figures")
    ap.add_argument("--quick", action="store_true", help="the phase-switch figure only, to a temporary folder (a smoke run)")
    args = ap.parse_args(argv)
    robot = qprr.load()
    if args.quick:
        with tempfile.TemporaryDirectory() as tmp:
            print(f"static_switch: {static_switch(robot, Path(tmp))}", flush=True)
        return 0
    if not args.out_dir.is_dir():
        print(f"spikes_figures: error: folder {args.out_dir} does not exist", file=sys.stderr)
        return 2
    for fn in (static_switch, spiral_start, dsid_chatter, push_prismatic):
        print(f"{fn.__name__}: {fn(robot, args.out_dir)}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
