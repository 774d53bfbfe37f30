"""An example qprr plug-in: one file per kind it adds, and :func:`register`, which puts them in qprr's registries.

==================  =========================  =====================================================================
file                registered as              what
==================  =========================  =====================================================================
``platform.py``     platform ``example-quad``  an X quadrotor with a 2-joint arm hanging below, from qprr's
                                               nomenclature (2.1)
``controller.py``   controller ``pd-gravity``  PD + gravity compensation, its gains derived from the platform's
                                               authority (critically damped, the core's bandwidths)
``scenario.py``     scenario ``square-tour``   any platform: hover, fly a square with the arm reached out, return
``metric.py``       campaign metric            the largest roll or pitch of a run [rad]
                    ``max_tilt``
==================  =========================  =====================================================================

``pyproject.toml`` declares :func:`register` in the entry-point group ``qprr.plugins``; qprr calls it once, the first
time one of its registries misses a name or is listed.  Then::

    qprr simulate square-tour --controller pd-gravity --platform example-quad
    qprr simulate hover-reach --controller pd-gravity          # a core scenario flies the plug-in's controller
    qprr campaign run tour.toml -o tour.csv                    # metrics = ["rmse", "max_tilt"]
"""

from __future__ import annotations

PLATFORM = "example-quad"
"""The name the plug-in's platform is registered under."""


def register() -> None:
    """Put the plug-in's platform, controller, scenario and campaign metric in qprr's registries (called once by qprr)."""
    from qprr.campaign.metrics import METRICS
    from qprr.control import CONTROLLERS
    from qprr.platforms import PLATFORMS
    from qprr.registry import SCENARIOS

    from . import controller, metric, platform, scenario

    PLATFORMS.register(PLATFORM, platform.load)
    CONTROLLERS.register("pd-gravity", controller.ENTRY)
    SCENARIOS.register("square-tour", scenario.SCENARIO)
    METRICS.register("max_tilt", metric.MAX_TILT)


__all__ = ["PLATFORM", "register"]
