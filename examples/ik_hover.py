"""(b) Inverse kinematics: reach a position with the base hovering and the CoG on the thrust axis.

    python examples/ik_hover.py

The task-priority IK (method "qp") solves, in strict order: 1 the end-effector position, 2 hover
(roll = pitch = 0), 3 the CoG on the thrust axis, 4 a posture; the joint limits hold at every
level.  A position target leaves the orientation free.
"""

import numpy as np

import qprr
from qprr import ik
from qprr import kinematics as kin

platform = qprr.load("q-prr")
data = platform.data()
target = np.array([1.0, 0.5, 2.3])  # end-effector position in the world [m]

# a posture with the arm bent forward (the posture level: the CoG level then moves r0)
solver = ik.IKSolver(platform, method="qp", options={"posture": (0.0, 0.6, 0.5)})
res = solver.solve(data, target)
print(f"{res.status}: success {res.success}, {res.iterations} iterations, {1e3 * res.wall_time:.2f} ms")
print("xi =", np.round(res.xi, 6))
print(
    f"position error {res.position_error:.2e} m; roll {res.roll:.1e} rad, pitch {res.pitch:.1e} rad "
    f"(hover-feasible: {res.hover_feasible}); CoG offset x_cm {res.x_cm:.2e} m, y_cm {res.y_cm:.2e} m"
)

# check with forward kinematics, independently of the solver
p_e, _ = kin.ee_pose_xi(platform, data, res.xi)
print(f"forward kinematics: |p_e - target| = {np.linalg.norm(p_e - target):.2e} m")

# the thesis's analytic IGM (Algorithms 3-5) needs a full pose; qprr.thesis.igm.solve_qprr adds it
# to the methods above for the Q-PRR:
#   from qprr.thesis import igm; igm.solve_qprr(platform, data, (p_world, R_world), method="igm")

# the slider value that balances the CoG for given revolute angles, in closed form (any platform
# with a prismatic joint): Thesis (3.79)-(3.81)
bal = ik.balance_prismatic(platform, data, [0.0, 0.4, -0.6])  # (r0 ignored, theta2, theta3)
print(
    f"balance: {bal.joint} = {1e3 * bal.value:.3f} mm ({bal.status}), offset left "
    f"{1e3 * np.linalg.norm(bal.offset):.2e} mm, limits [{bal.lower}, {bal.upper}] m"
)
bal = ik.balance_prismatic(platform, data, [0.0, 1.8, 0.5])
print(f"balance: {bal.joint} = {1e3 * bal.value:.3f} mm ({bal.status}: {bal.reason})")
