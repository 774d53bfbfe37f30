"""Issue 16: every public callable of qprr fed wrong shapes, dtypes, NaN, inf, empty, None, unknown names, bad files.

The engine is :mod:`tests.catalogue` (it finds the callables by introspection: a function added
later is fed without an edit here).  Every bad call must end in a qprr error naming the argument
(or the unknown name / file given), or in a result documented in ``catalogue.ALLOWED``.
"""

from __future__ import annotations

import fnmatch

import pytest

from tests import catalogue


@pytest.fixture(scope="module")
def report() -> catalogue.Report:
    return catalogue.run()


def _show(outcomes, limit: int = 40) -> str:
    return "\n".join(f"{o.verdict:8s} {o.target}({o.param} = {o.label}): {o.detail}" for o in outcomes[:limit])


def test_every_bad_input_ends_in_a_named_qprr_error_or_a_documented_result(report):
    bad = [o for o in report.outcomes if o.verdict not in ("good", "allowed")]
    counts = report.counts()
    assert not bad, f"{len(bad)} bad inputs not refused with a qprr error naming them ({counts}):\n" + _show(bad)


def test_the_catalogue_covers_the_api(report):
    """The table builds valid arguments for most callables; the rest are listed with the reason (run with -s to read)."""
    fed = {o.target for o in report.outcomes}
    print(f"\n{len(report.outcomes)} bad calls on {len(fed)} callables: {report.counts()}")
    print(f"not fed ({len(report.not_fed)}): {sorted(set(report.not_fed.values()))}")
    print(f"no valid call from the table ({len(report.baseline_failed)}): {sorted(report.baseline_failed)}")
    print(f"modules not imported (optional dependency missing): {catalogue.MISSING}")
    assert len(fed) >= 400 and len(report.outcomes) >= 5000
    for core in (
        "qprr.charts.",
        "qprr.kinematics.",
        "qprr.dynamics.",
        "qprr.actuation.",
        "qprr.ik.",
        "qprr.payload.",
        "qprr.model.",
        "qprr.rotors.",
        "qprr.trajectory.",
        "qprr.sim.loop.",
        "qprr.sim.result.",
    ):
        unbuilt = [k for k in report.baseline_failed if k.startswith(core)]
        assert not unbuilt, f"the catalogue cannot call these core functions with valid arguments: {unbuilt}"


def test_allowed_entries_are_explained_and_in_use(report):
    used = {(o.target, o.param, o.label) for o in report.outcomes if o.verdict == "allowed"}
    for (pattern, param, label), why in catalogue.ALLOWED.items():
        assert why.strip(), f"allow-list entry {(pattern, param, label)} has no reason"
        if any(pattern.startswith(module + ".") for module in catalogue.MISSING):
            continue  # its module needs an optional dependency that is not installed: no case can use it here
        assert any(fnmatch.fnmatchcase(t, pattern) and fnmatch.fnmatchcase(p, param) and fnmatch.fnmatchcase(lb, label) for t, p, lb in used), (
            f"stale allow-list entry {(pattern, param, label)}: no case uses it"
        )


def test_the_judge_needs_the_argument_name():
    from qprr.errors import InputError, UnknownNameError

    assert catalogue.judge(InputError("xi must have shape (9,), got (8,)"), "xi", None, __import__("qprr.errors").errors)[0] == "good"
    assert catalogue.judge(InputError("must have shape (9,)"), "xi", None, __import__("qprr.errors").errors)[0] == "unclear"
    assert catalogue.judge(ValueError("xi bad"), "xi", None, __import__("qprr.errors").errors)[0] == "unclear"
    err = UnknownNameError("integrator", "rk5", ("euler", "rk4"))
    assert catalogue.judge(err, "method", "rk5", __import__("qprr.errors").errors)[0] == "good"


# ----------------------------------------------------------------------------------- files (issue 22)
def test_every_bad_urdf_and_rotor_file_ends_in_a_qprr_error_naming_the_element():
    """Generated bad variants of the example URDF and rotor file (tests/catalogue_files.py): each joint's origin, axis
    and limits, each link's name, mass and inertial, the tree, each rotor value and the rotor set."""
    from collections import Counter

    from tests import catalogue_files

    outcomes = catalogue_files.run_files()
    bad = [o for o in outcomes if o.verdict != "good"]
    assert len(outcomes) >= 90, len(outcomes)
    assert not bad, f"{len(bad)} of {len(outcomes)} bad files not refused naming the element ({Counter(o.verdict for o in outcomes)}):\n" + "\n".join(
        f"{o.verdict:8s} {o.label}: {o.detail}" for o in bad
    )


def test_the_near_mistakes_that_are_legitimate_load(tmp_path):
    import warnings

    import qprr
    from tests import catalogue_files

    for k, v in enumerate(catalogue_files.valid_variants()):
        path = tmp_path / f"ok{k}.rotors.toml"
        path.write_text(v.rotors)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            p = qprr.from_urdf(v.urdf, path, ee_frame=catalogue_files.EE)
        assert p.total_mass == pytest.approx(1.5, rel=1e-12), v.label
        assert p.actuation_summary().can_hover


# ----------------------------------------------------------------------------------- new surfaces (issue 34)
def test_every_issue_34_case_is_refused_or_warned_naming_the_input():
    """Missions, scenario options, rotor files, motor stages, controllers, studies (tests/catalogue.py, :func:`cases`):
    each ends in a qprr error (or a warning where the input is legal but suspicious) naming the input, its value and the fix."""
    outcomes = catalogue.run_cases()
    bad = [o for o in outcomes if o.verdict != "good"]
    assert len(outcomes) >= 7
    assert not bad, "\n".join(f"{o.verdict:8s} {o.target}: {o.detail}" for o in bad)
