"""(f) The same custom run on other aerial manipulators: a built HEX-RRR and example-robot-data's borinot.

    python examples/other_platforms.py [OUT_DIR]

Nothing in the mission, the controller or the simulator is specific to the Q-PRR: each platform
brings its model, arm joints (names, limits) and rotor set.  qprr.build() reads the thesis
nomenclature (2.1) ("HEX-RRR": a hexarotor with a 3-revolute arm); qprr.load() knows the Q-PRR
and two robots of example-robot-data.
"""

import sys
from pathlib import Path

import qprr
from qprr.control import make_controller
from qprr.sim import simulate
from qprr.trajectory import MultiPhase, Phase
from qprr.viz import new_figure, plot_result

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)


def fly(platform):
    """Climb to 2 m, 1 m along x, then the second arm joint to 60 % of its upper limit."""
    joint = platform.arm_names[1]
    target = 0.6 * float(platform.arm_upper[1])
    trajectory = MultiPhase(
        (Phase("z", 0.0, 3.0, 2.0), Phase("x", 3.0, 6.0, 1.0), Phase(joint, 6.0, 9.0, target)), xi0=platform.neutral_xi(), names=platform.xi_names
    )
    return simulate(platform, make_controller("idc", platform), trajectory, 12.0)


fig = new_figure((7, 4))  # a matplotlib Figure without pyplot (pyplot works too in your own scripts)
ax = fig.add_subplot()
for platform in (qprr.load("q-prr", layout="x"), qprr.build("HEX-RRR"), qprr.load("borinot_flying_arm_2")):
    res = fly(platform)
    e = res.rmse()
    print(
        f"{platform.name}: {platform.n_rotors} rotors, arm {platform.arm_names}: {res.status}, "
        f"RMSE x {e['x']:.1e} m, z {e['z']:.1e} m; wall time {res.wall_time:.2f} s"
    )
    ax.plot(res.t, 1e3 * res.x_cm[:, 0], label=platform.name)
    plot_result(res, out / f"run_{platform.name.split(' ')[0].lower()}.png")
ax.set_xlabel("t [s]")
ax.set_ylabel("$x_{cm}$, CoG offset in B [mm]")
ax.set_title("the same mission on three platforms")
ax.grid(alpha=0.3)
ax.legend()
fig.savefig(out / "x_cm_three_platforms.png", dpi=110)
print("figure", out / "x_cm_three_platforms.png")
