"""(c) A custom mission: the "X" layout, your trajectory, a controller, the allocator, a run, figures.

    python examples/custom_mission.py [OUT_DIR]      (figures in OUT_DIR, default ./out)

Climb to 2 m, fly 1 m along x, then swing the arm (theta2 to 0.5 rad, theta3 to -0.8 rad) while hovering: the CoG leaves
the thrust axis (x_cm, Thesis (3.78)).  Fly it again with the slider r0 moving to the balancing
value, and plot x_cm(t) of both runs and every panel of the second.
"""

import sys
from pathlib import Path

import numpy as np

import qprr
from qprr.actuation import Allocator
from qprr.control import IDCGains, make_controller
from qprr.ik import balance_prismatic
from qprr.sim import simulate
from qprr.trajectory import MultiPhase, Phase
from qprr.viz import new_figure, plot_result

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)

platform = qprr.load("q-prr", layout="x")  # the Q-PRR with its rotors in "X"

# 1. the reference: smooth transitions (minimum-snap septic law) of named coordinates, from rest
trajectory = MultiPhase(
    (
        Phase("z", 0.0, 3.0, 2.0),  # coordinate, start [s], end [s], value [m or rad]
        Phase("x", 3.0, 6.0, 1.0),
        Phase("theta2", 6.0, 9.0, 0.5),
        Phase("theta3", 6.0, 9.0, -0.8),
    ),
    xi0=platform.neutral_xi(),
    names=platform.xi_names,
)

# 2. the controller: inverse dynamics (Thesis Sec. 6.3.1); default gains for any platform,
#    or your own per-coordinate gains (order x, y, z, phi, theta, psi, then the arm)
controller = make_controller("idc", platform, gains=IDCGains.default(platform.n_arm))

# 3. the allocator: rotor thrusts within their bounds (here 0.5..15 N instead of the platform's 0..20 N)
allocator = Allocator(platform, thrust_bounds=(0.5, 15.0))

# 4. the run: 12 s at 1 kHz, explicit midpoint on the Lie group
res = simulate(platform, controller, trajectory, 12.0, dt=1e-3, allocator=allocator)
print(f"{res.status}: {res.n} steps in {res.wall_time:.2f} s; rotor bound active on {100 * res.saturation_fraction():.1f} % of the steps")
print("RMSE (6.26):", {k: f"{v:.1e}" for k, v in res.rmse().items()})
print(f"final CoG offset x_cm = {1e3 * res.x_cm[-1, 0]:.2f} mm (the arm leans forward, the slider stays at 0)")

# 5. the same with the slider moving to the value that puts the CoG back on the thrust axis
#    (closed form, Thesis (3.79)-(3.81), for any platform with a prismatic joint)
bal = balance_prismatic(platform, platform.data(), [0.0, 0.5, -0.8])  # (r0: ignored, theta2, theta3)
print(f"balancing slider for theta2 = 0.5, theta3 = -0.8 rad: r0 = {1e3 * bal.value:.2f} mm ({bal.status})")
balanced = MultiPhase(trajectory.phases + (Phase("r0", 6.0, 9.0, bal.value),), xi0=trajectory.xi0, names=platform.xi_names)
res_b = simulate(platform, make_controller("idc", platform), balanced, 12.0, allocator=allocator)
k = int(np.argmax(np.abs(res_b.x_cm[:, 0])))
print(f"with the slider: final x_cm = {1e3 * res_b.x_cm[-1, 0]:.4f} mm, largest {1e3 * res_b.x_cm[k, 0]:.3f} mm at t = {res_b.t[k]:.2f} s")

# 6. figures: x_cm(t) of both runs on your own axes, then every panel of the second run
#    (plot_result saves and returns the path; path=None returns a matplotlib Figure; ax= draws into your Axes)
fig = new_figure((7, 3.5))
ax = fig.add_subplot()
ax.plot(res.t, 1e3 * res.x_cm[:, 0], label="slider held at 0")
ax.plot(res_b.t, 1e3 * res_b.x_cm[:, 0], label="slider balancing the CoG")
ax.set(xlabel="t [s]", ylabel="$x_{cm}$, CoG offset in B [mm]", title="CoG offset during the arm swing (X layout)")
ax.grid(alpha=0.3)
ax.legend()
fig.savefig(out / "custom_x_cm.png", dpi=110)
print("figure", out / "custom_x_cm.png")
print("figure", plot_result(res_b, out / "custom_run.png", thrust_bounds=(0.5, 15.0)))
res_b.save(out / "custom_run.npz")  # reload with qprr.sim.SimResult.load
