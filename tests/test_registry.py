"""The core's registries (qprr.registry): lookups, lazy sources, plug-ins through entry points, clear errors."""

from __future__ import annotations

from importlib import metadata

import pytest

from qprr import registry
from qprr.errors import InputError, UnknownNameError
from qprr.registry import Registry


def test_lookup_register_and_unknown_names():
    r = Registry("widget", default="b")
    r.register("a", 1)
    r.register("b", 2)
    assert r["a"] == 1 and "b" in r and "c" not in r
    assert list(r) == ["b", "a"]  # the default first, then registration order
    with pytest.raises(UnknownNameError, match=r"unknown widget 'c'; valid: 'b', 'a'"):
        r["c"]
    r.register("a", r["a"])  # the same object again: accepted
    with pytest.raises(InputError, match="widget 'a' is already registered"):
        r.register("a", 3)
    with pytest.raises(InputError, match="non-empty string"):
        r.register("", 4)
    with pytest.raises(InputError, match="callable"):
        r.register_source([("x", 1)])


def test_sources_run_once_on_first_read():
    calls = []
    r = Registry("gadget")

    def source():
        calls.append(1)
        return [("x", 10), ("y", 20)]

    r.register_source(source)
    assert calls == []  # nothing computed at registration
    assert r["y"] == 20 and dict(r) == {"x": 10, "y": 20} and len(r) == 2
    assert calls == [1]


class _EntryPoint:
    def __init__(self, name, func):
        self.name, self.value, self._func = name, f"tests:{name}", func

    def load(self):
        return self._func


def test_plugins_load_lazily_once_and_failures_fail(monkeypatch):
    r = Registry("thing")
    seen = []

    def good():
        seen.append("good")
        r.register("from-plugin", 42)

    def broken():
        raise ModuleNotFoundError("No module named 'qprr.nonexistent'", name="qprr.nonexistent")

    eps = [_EntryPoint("good-test-plugin", good)]
    monkeypatch.setattr(metadata, "entry_points", lambda group: eps if group == registry.PLUGIN_GROUP else [])
    monkeypatch.setattr(registry, "_LOADED", {})
    monkeypatch.setattr(registry, "_PENDING", None)
    r.register("core", 1)
    assert r["core"] == 1 and seen == []  # a known name loads no plug-in
    assert r["from-plugin"] == 42 and seen == ["good"]  # an unknown one does, once
    assert list(r) == ["core", "from-plugin"] and seen == ["good"]
    eps.append(_EntryPoint("broken-test-plugin", broken))
    monkeypatch.setattr(registry, "_PENDING", None)  # as in a new session where the broken plug-in is installed
    for _ in range(2):  # a broken plug-in raises at every lookup that loads it: never a silent missing name
        with pytest.raises(ModuleNotFoundError, match="qprr.nonexistent"):
            r["nope"]


def test_without_any_plugin_the_error_says_so(monkeypatch):
    monkeypatch.setattr(metadata, "entry_points", lambda group: [])
    monkeypatch.setattr(registry, "_LOADED", {})
    monkeypatch.setattr(registry, "_PENDING", None)
    r = Registry("platform")
    with pytest.raises(UnknownNameError, match="no plug-in found.*pip install -e"):
        r["q-prr"]


def test_the_thesis_fills_every_registry_of_the_core():
    import qprr
    from qprr.platforms import PLATFORMS, ROTOR_DYNAMICS

    assert list(PLATFORMS)[0] == "q-prr" and qprr.load().name == qprr.load("q-prr").name
    assert "q-prr" in ROTOR_DYNAMICS
    assert {"q-prr:thesis", "q-prr:cad"} <= set(registry.PARAMETER_SETS)
    assert registry.PARAMETER_SETS["q-prr:cad"]() == qprr.thesis.cad_params()
    assert "q-prr:table-6.2" in registry.GAIN_TABLES and "static-idc" in registry.SCENARIOS
    assert {"table", "all"} - set(registry.COMPARISONS) == {"all"}
    assert list(registry.CHECKS) == ["thesis"] and list(registry.MAP_REFERENCES) == ["thesis"]
    assert list(registry.COMMANDS) == ["thesis"]


def test_a_check_refuses_entries_with_the_reason_and_views_follow_the_registry():
    def positive(name, value):
        if not value > 0:
            raise InputError(f"widget {name!r} must be > 0, got {value!r}")

    r = Registry("widget", default="a", check=positive)
    r.register("a", 1)
    with pytest.raises(InputError, match="widget 'b' must be > 0, got -2"):
        r.register("b", -2)
    assert "b" not in r
    doubled = r.derived(lambda v: 2 * v)
    odd = r.derived(lambda v: v, keep=lambda v: v % 2 == 1)
    r.register("c", 4)  # a view reads the registry when looked up: later entries are in it
    assert dict(doubled) == {"a": 2, "c": 8} and list(odd) == ["a"] and len(odd) == 1
    assert "c" in r and "c" not in odd and odd.get("c", "absent") == "absent"
    with pytest.raises(UnknownNameError, match="unknown widget 'c'; valid: 'a'"):
        odd["c"]
