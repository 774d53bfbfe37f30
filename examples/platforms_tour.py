"""One API, five aerial manipulators: IK, allocation and a hover-and-reach flight on each.

    python examples/platforms_tour.py [OUTDIR]

The Q-PRR of the thesis in its "+" and "X" layouts, example-robot-data's borinot_flying_arm_2 (a
coplanar hexarotor with a 2-DOF arm) and hextilt_flying_arm_5 (a tilted, fully actuated hexarotor
with a 5-DOF arm), and a HEX-RRR built from the thesis nomenclature (2.1).  For each: the
task-priority IK of a reachable target (pose > hover, or the base pose on the fully actuated one >
CoG on the thrust axis > posture), the rotor thrusts that hold the IK configuration, and a
10 s hover-and-reach flight with inverse-dynamics control, its figure saved to OUTDIR (default: out/).
"""

import sys
from pathlib import Path

import numpy as np

import qprr
from qprr import charts, ik, kinematics
from qprr.actuation import Allocator
from qprr.dynamics import generalized_gravity
from qprr.scenarios import run
from qprr.viz import plot_result

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)
platforms = {
    "Q-PRR +": qprr.load("q-prr"),
    "Q-PRR X": qprr.load("q-prr", layout="x"),
    "borinot_flying_arm_2": qprr.load("borinot_flying_arm_2"),
    "hextilt_flying_arm_5": qprr.load("hextilt_flying_arm_5"),
    "HEX-RRR": qprr.build("HEX-RRR"),
}
for label, platform in platforms.items():
    data = platform.data()
    # a reachable target: the end-effector pose of a level configuration with the arm half-way to its limits
    xi = platform.neutral_xi()
    xi[0:3] = (1.0, -0.5, 2.0)
    xi[5] = 0.3
    xi[6:] = 0.5 * np.where(np.isfinite(platform.arm_upper), platform.arm_upper, 1.0)
    target = kinematics.ee_placement(platform, data, charts.xi_to_q(xi))
    res = ik.IKSolver(platform, "qp").solve(data, target)
    thrusts = Allocator(platform).allocate(generalized_gravity(platform, data, res.q))
    flight = run("hover-reach", "idc", platform=platform)
    figure = plot_result(flight, out / f"tour-{label.replace(' ', '').replace('+', 'plus').lower()}.png")
    e = flight.rmse()
    print(f"{label:22} {platform!r}")
    print(
        f"{'':22} IK {res.status}: position error {res.position_error:.1e} m, CoG offset "
        f"({res.x_cm * 1e3:+.2f}, {res.y_cm * 1e3:+.2f}) mm, roll/pitch ({res.roll:+.1e}, {res.pitch:+.1e}) rad"
    )
    print(f"{'':22} hover thrusts {np.round(thrusts.f[: platform.n_rotors], 3).tolist()} N ({thrusts.status})")
    print(
        f"{'':22} hover-and-reach: {flight.status}, position RMSE {max(e['x'], e['y'], e['z']):.1e} m, "
        f"saturation {100 * flight.saturation_fraction():.1f} %, figure {figure}"
    )
