"""The plug-in's platform: an X quadrotor with a two-joint arm below it, built from qprr's nomenclature (2.1).

A platform is a loader ``(**options) -> qprr.Platform`` registered under a name in ``qprr.platforms.PLATFORMS``: then
``qprr.load("example-quad")``, ``--platform example-quad`` and ``platform = "example-quad"`` in a campaign find it.
"""

from __future__ import annotations

import qprr
from qprr.errors import UnknownNameError


def load(**options) -> qprr.Platform:
    """The example quadrotor; ``options``: ``body_mass`` [kg] (default 1.2) and ``layout`` ("x", as the name says)."""
    unknown = sorted(set(options) - {"body_mass", "layout"})
    if unknown:
        raise UnknownNameError("option of platform 'example-quad'", unknown[0], ("body_mass", "layout"))
    return qprr.build(
        "QX-RR",
        layout=options.get("layout", "x"),
        body_mass=options.get("body_mass", 1.2),
        arm_direction="down",
        thrust_to_weight=2.2,
        platform_name="example-quad",
    )
