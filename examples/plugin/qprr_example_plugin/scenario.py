"""The plug-in's scenario: from hover at height z, fly a square of side ``side`` with the arm reached out, and return.

A scenario is a :class:`qprr.scenarios.Scenario`: a name, a runner ``(platform, controller, progress, **options) ->
SimResult``, the controllers it flies (the first the default) and its options with their defaults (what ``--set`` and a
campaign's parameters may change).  ``platforms=None``: any platform.
"""

from __future__ import annotations

from qprr.control import make_controller
from qprr.platforms import load
from qprr.scenarios import Option, Scenario
from qprr.scenarios.missions import reach_posture
from qprr.sim import SimConfig, simulate
from qprr.trajectory import MultiPhase, Phase

CORNERS = ((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0))
"""The square's corners in units of ``side`` (x, y), flown in this order after the arm has reached out."""


def square_tour(platform, controller, progress, **o):
    """Hover at ``z``; reach the arm out in the first 15 % of the run; then one leg of the square per fifth of the rest."""
    platform = load("example-quad") if platform is None else platform
    D, side = o["duration"], o["side"]
    q_arm = reach_posture(platform, o["reach_fraction"])
    phases = [Phase(6 + k, 0.0, 0.15 * D, float(v)) for k, v in enumerate(q_arm)]
    leg, here = 0.8 * D / len(CORNERS), (0.0, 0.0)
    for k, corner in enumerate(CORNERS):
        t1, t2 = 0.15 * D + k * leg, 0.15 * D + (k + 1) * leg
        phases += [Phase(axis, t1, t2, side * b) for axis, a, b in zip("xy", here, corner) if a != b]  # the coordinate that moves
        here = corner
    xi0 = (0.0, 0.0, o["z"], 0.0, 0.0, 0.0, *platform.neutral_q()[7:].tolist())
    reference = MultiPhase(tuple(phases), xi0, name="square-tour", law=o["law"], names=platform.xi_names)
    config = SimConfig(dt=o["dt"], integrator=o["integrator"], seed=o["seed"], progress=progress, scenario="square-tour")
    return simulate(platform, make_controller(controller, platform), reference, D, config=config, xi0=xi0)


SCENARIO = Scenario(
    "square-tour",
    "any platform: hover, reach the arm out, fly a square of side 'side' and return (the example plug-in)",
    square_tour,
    ("pd-gravity", "idc"),
    {
        "duration": Option(12.0, "run length [s]"),
        "dt": Option(1e-3, "integration step [s]"),
        "integrator": Option("midpoint", "a name of qprr.sim.INTEGRATORS"),
        "seed": Option(0, "seed"),
        "law": Option("septic", "transition law of qprr.trajectory"),
        "z": Option(1.5, "hover height [m]"),
        "side": Option(0.5, "side of the square [m]"),
        "reach_fraction": Option(0.3, "arm posture: fraction of the way from neutral to the upper joint limits"),
    },
)
"""What :func:`qprr_example_plugin.register` puts in ``qprr.registry.SCENARIOS``."""
