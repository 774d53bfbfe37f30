"""(e) A quick analysis: what the slider buys in hover, over the range of theta2.

    python examples/hover_analysis.py [OUT_DIR]

For each theta2 (theta3 = 0), the slider value that puts the CoG on the thrust axis (closed form,
Thesis (3.79)-(3.81)) and the rotor thrusts that hold the Q-PRR still, with the slider at 0 and at
that value: with the CoG off the axis the rotors share the weight unequally (Thesis Sec. 2.5).
"""

import sys
from pathlib import Path

import numpy as np

import qprr
from qprr.actuation import Allocator
from qprr.ik import balance_prismatic
from qprr.viz import new_figure

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)

platform = qprr.load("q-prr")
data = platform.data()
alloc = Allocator(platform)
theta2 = np.linspace(platform.arm_lower[1], platform.arm_upper[1], 121)
r0_star, spread_fixed, spread_bal = [], [], []
for t2 in theta2:
    bal = balance_prismatic(platform, data, [0.0, t2, 0.0])
    r0_star.append(bal.unclamped)
    for r0, spread in ((0.0, spread_fixed), (bal.value, spread_bal)):
        q = platform.neutral_q()
        q[7:] = (r0, t2, 0.0)
        f = alloc.hover_thrusts(data, q)  # rotor thrusts holding this configuration still [N]
        spread.append(f.max() - f.min())
r0_star, spread_fixed, spread_bal = map(np.array, (r0_star, spread_fixed, spread_bal))
inside = (r0_star >= platform.arm_lower[0]) & (r0_star <= platform.arm_upper[0])
print(
    f"the slider balances the CoG for theta2 in [{theta2[inside].min():.3f}, {theta2[inside].max():.3f}] rad "
    f"(slider range [{platform.arm_lower[0]}, {platform.arm_upper[0]}] m)"
)
print(f"largest hover thrust spread: {spread_fixed.max():.3f} N with the slider at 0, {spread_bal.max():.3f} N balancing")

fig = new_figure((10, 3.8))
ax1, ax2 = fig.subplots(1, 2)
ax1.plot(theta2, 1e3 * r0_star, label="balancing value")
ax1.axhspan(1e3 * platform.arm_lower[0], 1e3 * platform.arm_upper[0], color="C2", alpha=0.15, label="slider range")
ax1.set(xlabel=r"$\theta_2$ [rad] ($\theta_3$ = 0)", ylabel="$r_0$ [mm]", title="slider value that balances the CoG")
ax2.plot(theta2, spread_fixed, label="slider at 0")
ax2.plot(theta2, spread_bal, label="slider balancing (within its range)")
ax2.set(xlabel=r"$\theta_2$ [rad] ($\theta_3$ = 0)", ylabel="max - min rotor thrust [N]", title="unequal rotor thrusts in hover")
for ax in (ax1, ax2):
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
fig.savefig(out / "hover_analysis.png", dpi=110)
print("figure", out / "hover_analysis.png")
