"""(a) Pose of the end effector and centre of gravity for a given configuration xi.

    python examples/pose_and_cog.py

xi = [x, y, z, phi, theta, psi, r0, theta2, theta3]: the base position [m] in the world, its ZYX
Euler angles [rad] (Thesis (3.4)) and the arm joints [m, rad, rad].
"""

import numpy as np

import qprr
from qprr import kinematics as kin

platform = qprr.load("q-prr")  # the thesis's Q-PRR, "+" layout (qprr.load("q-prr", layout="x") for "X")
data = platform.data()  # Pinocchio's workspace: the only thing the functions below write
print(platform)
print("coordinates:", platform.xi_names)

xi = np.array([0.0, 0.0, 2.0, 0.1, -0.05, 0.3, 0.02, 0.4, -0.2])

p_e, R_e = kin.ee_pose_xi(platform, data, xi)  # world pose of the end effector, Thesis (3.61)
print("end effector p_world [m]:", np.round(p_e, 6))
print("end effector R_world:\n", np.round(R_e, 6))

q = qprr.charts.xi_to_q(xi)  # Pinocchio's configuration [p, quaternion xyzw, q_arm]
c_world = kin.com_world(platform, data, q)  # CoG of the whole system, world frame [m]
c_body = kin.com_body(platform, data, q)  # the same in the body frame B, Thesis (3.76)-(3.78)
offset = kin.cog_offset_body(platform, data, q)  # (x_cm, y_cm): distance from the thrust axis in B
print("CoG world [m]:", np.round(c_world, 6))
print("CoG in B [m]:", np.round(c_body, 6))
print(f"CoG offset from the thrust axis: x_cm = {1e3 * offset[0]:.3f} mm, y_cm = {1e3 * offset[1]:.3f} mm")
J = kin.jacobian_xi(platform, data, xi)  # [p_e_dot; omega_e] (world) = J xi_dot, Thesis (4.11)-(4.13)
print("Jacobian in thesis coordinates:", J.shape)
