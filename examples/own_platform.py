"""Your own aerial manipulator: a URDF written by hand, a rotor file, and the whole tour.

    python examples/own_platform.py [OUTDIR]

examples/my_platform/ holds an X quadrotor (1.5 kg) carrying a 3-DOF arm under its body (a yaw
joint, then two pitch joints: a Q-RRR): quad_rrr.urdf (links with the masses and inertias of
simple solids) and quad_rrr.rotors.toml (its four rotors).  The script loads them, solves the
task-priority IK of an end-effector pose (pose > hover > CoG on the thrust axis > posture),
allocates the rotor thrusts that hold the IK configuration, and flies there with the
inverse-dynamics controller; the figure of the flight goes to OUTDIR (default: out/).
docs/platforms.md walks through the same steps.
"""

import sys
from pathlib import Path

import numpy as np
import pinocchio as pin

import qprr
from qprr import charts, ik, kinematics
from qprr.actuation import Allocator
from qprr.control import make_controller
from qprr.sim import simulate
from qprr.trajectory import hover_and_reach
from qprr.viz import plot_result

here = Path(__file__).resolve().parent / "my_platform"
out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)

platform = qprr.from_urdf(here / "quad_rrr.urdf", here / "quad_rrr.rotors.toml", ee_frame="gripper")
print(platform)
print("arm joints:", platform.arm_names, "limits [rad]:", platform.arm_lower.tolist(), platform.arm_upper.tolist())
print("rotor matrix Omega ([f_B; tau_B] = Omega f):")
print(np.array2string(platform.rotor_matrix, precision=4, suppress_small=True))

# 1. IK: the gripper at 1.5 m, pointing 1.2 rad below the horizontal, heading 0.4 rad
data = platform.data()
target = pin.SE3(pin.rpy.rpyToMatrix(0.0, 1.2, 0.4), np.array([1.0, 0.5, 1.5]))
res = ik.IKSolver(platform, "qp").solve(data, target)
# independent check: Pinocchio's forward kinematics at the returned configuration
check = pin.Data(platform.model)
pin.framesForwardKinematics(platform.model, check, res.q)
M = check.oMf[platform.ee_frame]
print(f"IK {res.status}: xi = {np.round(res.xi, 4).tolist()}")
print(
    f"IK position error {np.linalg.norm(M.translation - target.translation):.2e} m, orientation error "
    f"{np.linalg.norm(pin.log3(target.rotation.T @ M.rotation)):.2e} rad, roll/pitch ({res.roll:+.1e}, {res.pitch:+.1e}) rad, "
    f"CoG offset ({res.x_cm * 1e3:+.2e}, {res.y_cm * 1e3:+.2e}) mm"
)

# 2. allocation: the rotor thrusts that hold the IK configuration still
f = Allocator(platform).hover_thrusts(data, res.q)
mg = platform.total_mass * platform.g
print(f"hover thrusts {np.round(f, 4).tolist()} N, sum {f.sum():.15g} N = m g {mg:.15g} N (relative difference {abs(f.sum() - mg) / mg:.1e})")

# 3. fly there: climb to the IK base position with the IK heading, then move the arm to the IK posture
mission = hover_and_reach(platform, res.xi[0:3], res.xi[6:], psi=res.xi[5])
flight = simulate(platform, make_controller("idc", platform), mission, 8.0, scenario="reach the IK target")
end = kinematics.ee_placement(platform, data, charts.xi_to_q(flight.xi[-1]))
e = flight.rmse()
print(
    f"flight {flight.status}: position RMSE {max(e['x'], e['y'], e['z']):.1e} m, "
    f"end effector {np.linalg.norm(end.translation - target.translation) * 1e3:.3f} mm from the target at t = 8 s, "
    f"rotor saturation {100 * flight.saturation_fraction():.1f} %"
)
print("figure", plot_result(flight, out / "own_platform.png"))
