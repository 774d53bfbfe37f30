"""What only the thesis has: the Q-PRR's parameters, its printed equations, algorithms and scenarios.

K. Bouzgou, *Contribution a l'architecture, la modelisation et la commande d'un bras
manipulateur aerien*, Universite Paris-Saclay, 2021.  Equation numbers refer to it.

* :func:`load_qprr` - the Q-PRR as a :class:`qprr.model.Platform` (the flagship instance of the
  generic core), from :mod:`qprr.thesis.params` (Tables 3.1-3.3 and the values the thesis does
  not print, each with its provenance) and the URDF of :mod:`qprr.thesis.urdf`;
* :mod:`qprr.thesis.printed` - closed forms as printed and corrected; :mod:`qprr.thesis.checks`
  (``qprr check``) tests every one against the model; :mod:`qprr.thesis.symbolic` is the
  independent sympy Lagrangian;
* the thesis's own algorithms: the analytic IGM (Alg. 3-5, :mod:`qprr.thesis.igm`), the CoG
  stabiliser BSG (:mod:`qprr.thesis.bsg`), the chapter-6 missions, gain tables and scenarios;
* beyond the thesis, on the Q-PRR: :mod:`qprr.thesis.control_scenarios` (point-to-point, Annex A,
  aggressive reach, realistic), :mod:`qprr.thesis.realistic` (its motor, drag, friction and wind
  values), :mod:`qprr.thesis.comparisons` (``qprr compare``).

The library (everything outside this package) never imports from here.  The thesis is a plug-in:
:func:`register` (the ``qprr.plugins`` entry point ``thesis`` of the distribution's metadata) puts
its platform, rotor dynamics, parameter sets, gain tables, scenarios, IK method (``igm``), comparisons, checks and
design-map references into the core's registries (:mod:`qprr.registry`), which call it the first
time they miss a name; it imports none of the modules it registers (each entry imports its module
when used).  Its front end, ``qprr urdf`` (:mod:`qprr.thesis.cli`), is the entry point ``thesis`` of
the group ``qprr.commands`` (:data:`qprr.registry.COMMANDS`).
"""

from __future__ import annotations

from .params import LAYOUTS, QPRRParams, cad_params, thesis_params
from .robot import ARM_JOINTS, EE_FRAME, load_qprr, params_of, rotor_set


def _rotor_dynamics(**overrides):
    from .realistic import qprr_rotor_dynamics

    return qprr_rotor_dynamics(**overrides)


def _scenarios():
    from .control_scenarios import SCENARIOS as CONTROL
    from .scenarios import SCENARIOS as THESIS

    return [(s.name, s) for s in (*THESIS, *CONTROL)]  # Sec. 6.3-6.4; point-to-point, Annex A, aggressive reach, realistic


def _gain_tables():
    from . import gains

    tables = {
        "table-6.2": gains.table_6_2,
        "idc": gains.idc,
        "desired-state": gains.desired_state,
        "annex-a3": gains.annex_a3,
        "table-6.5": gains.table_6_5,
        "payload": gains.payload_idc,
        "table-6.7": gains.table_6_7,
        "impedance": gains.impedance_idc,
        "impedance-table-6.7": gains.impedance_table_6_7,
        "impedance-filters": gains.impedance_filters,
        "mfc": gains.mfc,
    }
    return [(f"q-prr:{name}", fn) for name, fn in tables.items()]


def _ik_methods():
    from .igm import IGM

    return [("igm", IGM)]  # Algorithms 3-5 on the Q-PRR


def _comparisons():
    from .comparisons import COMPARISONS, run_comparisons

    return [(name, run_comparisons) for name in COMPARISONS]


def _check(verbose: bool = False) -> int:
    from .checks import print_check_table

    return print_check_table(verbose=verbose)


def _map_reference(map_name, platform, result):
    from .maps import analysis_reference

    return analysis_reference(map_name, platform, result)


def register() -> None:
    """Register the thesis into the core's registries (the ``qprr.plugins`` entry point; called once, by the registries)."""
    from ..ik.solver import IK_METHODS
    from ..platforms import PLATFORMS, ROTOR_DYNAMICS
    from ..registry import CHECKS, COMPARISONS, GAIN_TABLES, MAP_REFERENCES, PARAMETER_SETS, SCENARIOS
    from .params import VARIANTS

    PLATFORMS.register("q-prr", load_qprr)
    ROTOR_DYNAMICS.register("q-prr", _rotor_dynamics)
    for variant, make in VARIANTS.items():
        PARAMETER_SETS.register(f"q-prr:{variant}", make)
    GAIN_TABLES.register_source(_gain_tables)
    SCENARIOS.register_source(_scenarios)
    IK_METHODS.register_source(_ik_methods)
    COMPARISONS.register_source(_comparisons)
    CHECKS.register("thesis", _check)
    MAP_REFERENCES.register("thesis", _map_reference)


__all__ = ["ARM_JOINTS", "EE_FRAME", "LAYOUTS", "QPRRParams", "cad_params", "load_qprr", "params_of", "register", "rotor_set", "thesis_params"]
