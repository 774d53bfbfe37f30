"""The registries a user extends (docs/extending.md): what each refuses at registration, the tables that are views of
them, the core's entries, and the platform the core names.

Registering into the core's registries here would leave the entries for the other tests of the session: the accepted
registrations run in the page's blocks (tests/test_docs.py) and in the installed example plug-in (tests/test_plugin.py);
this file checks what is refused (nothing is added) and uses fresh registries where an entry must be accepted.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import qprr
from qprr.campaign import DEFAULT_METRICS, METRICS, CampaignMetric
from qprr.control import CONTROLLERS, GAIN_ARGUMENTS, ControllerEntry, DerivedGains, InverseDynamicsController, NoGains
from qprr.control import gains as gain_rules
from qprr.design import DESIGN_METRICS
from qprr.design.metrics import RANGES, DesignMetric
from qprr.errors import InputError, UnknownNameError
from qprr.ik import IK_METHODS, OPTIONS, IKMethod
from qprr.platforms import DEFAULT_PLATFORM, PLATFORMS
from qprr.registry import Registry
from qprr.sim import INTEGRATORS, ORDERS, STEPPERS, Integrator

ROOT = Path(__file__).resolve().parents[1]


def test_a_controller_must_say_how_its_gains_are_derived():
    with pytest.raises(InputError, match=r"declares no gain derivation .*DerivedGains\(arguments, derive\).*NoGains\(reason\)"):
        ControllerEntry(InverseDynamicsController)
    with pytest.raises(InputError, match="declares no gain derivation"):
        ControllerEntry(InverseDynamicsController, {"gains": None})
    with pytest.raises(InputError, match="the reason"):
        NoGains("  ")
    with pytest.raises(InputError, match="non-empty tuple"):
        DerivedGains("gains", gain_rules.derive_idc)
    with pytest.raises(InputError, match=r"register a qprr.control.ControllerEntry"):
        CONTROLLERS.register("test-bare-class", InverseDynamicsController)
    assert "test-bare-class" not in CONTROLLERS


def test_every_core_controller_declares_its_gains():
    for name, entry in CONTROLLERS.items():
        assert isinstance(entry.gains, (DerivedGains, NoGains)), name
    assert "idc" == CONTROLLERS.default == next(iter(CONTROLLERS))
    assert set(GAIN_ARGUMENTS) == {n for n, e in CONTROLLERS.items() if isinstance(e.gains, DerivedGains)}
    assert GAIN_ARGUMENTS["impedance"] == ("gains", "impedance") and "mpc" not in GAIN_ARGUMENTS


def test_a_derivation_must_return_its_declared_arguments(monkeypatch, platform_authority):
    controllers = Registry("controller", check=CONTROLLERS.check)
    controllers.register("odd", ControllerEntry(InverseDynamicsController, DerivedGains(("gains",), lambda a, t: {"gain": 1.0})))
    controllers.register("none", ControllerEntry(InverseDynamicsController, NoGains("cost weights")))
    monkeypatch.setattr(gain_rules, "CONTROLLERS", controllers)
    with pytest.raises(InputError, match=r"returned \['gain'\], not its declared arguments \['gains'\]"):
        gain_rules.derive("odd", platform_authority, gain_rules.Targets())
    with pytest.raises(InputError, match="no gains derived from a platform: cost weights"):
        gain_rules.derive("none", platform_authority, gain_rules.Targets())


@pytest.fixture(scope="module")
def platform_authority():
    return gain_rules.Authority.from_platform(qprr.build("Q-RR"))


@pytest.mark.parametrize(
    "registry, value, message",
    [
        (IK_METHODS, object(), "register a qprr.ik.solver.IKMethod"),
        (INTEGRATORS, lambda model, dt: None, "register a qprr.sim.integrators.Integrator"),
        (METRICS, lambda result, names: 0.0, "register a qprr.campaign.metrics.CampaignMetric"),
        (DESIGN_METRICS, lambda maps: 0.0, "register a qprr.design.DesignMetric"),
    ],
)
def test_each_registry_refuses_a_value_of_another_kind(registry, value, message):
    with pytest.raises(InputError, match=message):
        registry.register("test-wrong-kind", value)
    assert "test-wrong-kind" not in registry


def test_the_entries_check_themselves():
    with pytest.raises(InputError, match="deriving from qprr.ik.solver.Tolerances"):
        IKMethod(dict, lambda platform, options: None)
    with pytest.raises(InputError, match="order must be an integer >= 1"):
        Integrator(lambda model, dt: None, 0)
    with pytest.raises(InputError, match="'max' or 'min'"):
        DesignMetric(lambda maps: 0.0, "m", "more", "reach")
    with pytest.raises(InputError, match="a column the campaign keeps itself"):
        METRICS.register("rmse_extra", CampaignMetric(lambda result, names: 0.0))
    with pytest.raises(InputError, match="already registered"):
        METRICS.register("rmse", CampaignMetric(lambda result, names: 0.0))


def test_the_tables_beside_a_registry_are_views_of_it():
    assert list(ORDERS) == list(STEPPERS) == list(INTEGRATORS) and ORDERS == {"midpoint": 2, "rk4": 4, "euler": 1}
    assert INTEGRATORS.default == qprr.sim.SimConfig().integrator == "midpoint"
    assert list(OPTIONS) == list(IK_METHODS) and IK_METHODS.default == "qp" and "igm" in IK_METHODS  # the thesis's, registered
    assert list(RANGES) == list(DESIGN_METRICS) and RANGES["balance_fraction"] == (0.0, 1.0)
    assert DEFAULT_METRICS == ("rmse", "x_cm_max", "saturation", "recovery_time") and set(DEFAULT_METRICS) <= set(METRICS)
    with pytest.raises(UnknownNameError, match="unknown integrator 'rk5'"):
        qprr.sim.SimConfig(integrator="rk5")


def _literals(path: Path) -> list[tuple[int, str]]:
    """(line, value) of the string constants of a module that are not documentation (a bare string statement: the
    docstrings of modules, classes, functions and of module attributes)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docs = {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant)}
    return [(n.lineno, n.value) for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs]


def test_no_core_module_names_the_thesis_platform_but_as_the_default():
    """Issue 33: the platform the core names is the registry's documented default, defined once (qprr/platforms.py)."""
    named = [
        f"{path.relative_to(ROOT)}:{line}"
        for path in sorted((ROOT / "qprr").rglob("*.py"))
        if "thesis" not in path.relative_to(ROOT / "qprr").parts
        for line, value in _literals(path)
        if "q-prr" in value  # the registry name (the (2.1) designation "Q-PRR" is a nomenclature name, not a platform)
    ]
    assert named == ["qprr/platforms.py:43"], named
    assert PLATFORMS.default == DEFAULT_PLATFORM and next(iter(PLATFORMS)) == DEFAULT_PLATFORM
