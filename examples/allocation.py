"""(d) Allocation: rotor thrusts (and arm efforts) for a given wrench, "+" and "X" layouts.

    python examples/allocation.py

The body wrench [f_B; tau_B] at B in B axes [N, N m] is produced by the rotors, tau = Omega f
(Thesis (3.31)-(3.36)); the Allocator inverts it within the thrust bounds, with PX4-like
priorities when a bound is active (force and roll/pitch first, then yaw).
"""

import numpy as np

import qprr
from qprr.actuation import Allocator

for layout in ("plus", "x"):
    platform = qprr.load("q-prr", layout=layout)  # the rotor layout is part of the platform
    alloc = Allocator(platform)  # bounds from the rotors (0..20 N each); thrust_bounds=(lo, hi) to change them
    print(f"--- {platform.name}: Omega (6 x {platform.n_rotors}) rows f_x f_y f_z tau_x tau_y tau_z")
    print(np.round(platform.rotor_matrix, 4))

    hover = alloc.hover_thrusts()  # at the neutral configuration (arm straight): m g / 4 each
    print("hover thrusts [N]:", np.round(hover, 4))

    wrench = np.array([0.0, 0.0, 40.0, 0.3, -0.2, 0.05])  # [f_B (N); tau_B (N m)]
    f, saturated = alloc.rotor_thrusts(wrench)
    print("thrusts for", wrench.tolist(), "->", np.round(f, 4), "saturated" if saturated else "exact")
    print("  check: Omega f =", np.round(platform.rotor_matrix @ f, 10))

    # a generalised force of the whole platform (nv = 9: body wrench then arm efforts)
    tau = np.r_[0.0, 0.0, 30.0, 6.0, 0.0, 0.2, 1.0, 0.3, 0.1]  # 6 N m of roll torque: beyond the bounds
    r = alloc.allocate(tau)
    print(f"allocate: {r.status} - {r.reason}")
    print("  f =", np.round(r.f, 4), "; achieved wrench", np.round(r.tau_achieved[:6], 4))
