"""``qprr check``: the table of verdicts, its exit code and its verdict rule."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from qprr.thesis import checks

# The verdict each row must reach (docs/thesis-errata.md); a change in the model or in a
# closed form that flips a verdict fails here.
MISPRINT = "misprint (corrected form holds)"
EXPECTED = {
    ("(3.4)", "R_b"): "correct",
    ("(3.8)", "ZYX"): MISPRINT,
    ("(3.25)", "T(phi_b)"): "correct under omega in the body frame",
    ("(3.27)", "MDH chain"): "correct",
    ("(3.28)", "MDH transform"): MISPRINT,
    ("(3.36)", "allocation"): MISPRINT,
    ("(3.37)", "allocation"): MISPRINT,
    ("(3.37)", "det"): "correct",  # for the matrix as printed; its row 3 is the misprint
    ("(A.1)", "inverse"): MISPRINT,
    ("(3.42)", "potential"): "correct under NED",
    ("(3.43)", "torque"): "correct under NED",
    ("(3.44)", "CoM"): "correct",
    ("Tab. 3.4", "MDH parameter table"): MISPRINT,
    ("(3.48)", "^bT_0"): "correct",
    ("(3.50)", "^4T_eb"): MISPRINT,
    ("(3.51)", "^4T_eb"): "correct",
    ("(3.52)", "^0T_1"): "correct",
    ("(3.56)", "^bT_eb"): "correct",
    ("(3.58)", "^bT_eb"): "correct",
    ("(3.61)", "p_e"): MISPRINT,
    ("(3.62)", "R_e"): "correct",
    ("(3.64)", "angles"): "correct under ZYZ",
    ("(3.65)", "chi_e"): "correct under ZYZ",
    ("(3.68)", "lines 1-3"): "correct",
    ("(3.68)", "lines 4-6"): MISPRINT,
    ("(3.78)", "x_cm"): "correct",
    ("(3.78)", "z_cm"): MISPRINT,
    ("(3.76)", "p_cl"): "correct",
    ("(3.78)", "payload"): MISPRINT,
    ("(3.80)", "x_cm"): "correct",
    ("(4.24)", "v_4"): MISPRINT,
    ("(4.26)", "J_eb"): "correct",
    ("(4.27)", "J_eb*"): "correct",
    ("(4.28)", "det"): "correct",
    ("(4.12)", "J_e"): MISPRINT,
    ("(4.13)", "J_e"): "correct",
    ("(4.44)", "det"): "correct",
    ("(4.42)", "sparsity"): "correct",
    ("(4.42)", "L factors a42"): "correct",
    ("(4.42)", "L factor a53"): MISPRINT,
    ("(4.42)", "except b55"): "correct",
    ("(4.42)", "U factor b55"): MISPRINT,
    ("(4.43)", "identity"): "correct",  # the product is spoilt by b55 of (4.42) alone
    ("(4.43) text", "det(J_U)"): MISPRINT,
    ("(4.45)", "lambda"): MISPRINT,
    ("(4.46)", "sol"): "correct under 4-digit",
    ("(4.47)", "sol"): "correct under 4-digit",
    ("(4.48)", "sol"): "correct under 4-digit",
    ("5.2.2", "B11"): "correct",
    ("5.2.2", "B22"): MISPRINT,
    ("5.2.2", "B23"): MISPRINT,
    ("5.2.2", "B33"): MISPRINT,
    ("(5.15)", "kinetic"): MISPRINT,
    ("(5.20)", "z_(j-1)"): MISPRINT,
    ("(5.29)", "potential"): "correct",
    ("(5.41)", "R_Q"): MISPRINT,
    ("(5.43)", "R_Q"): MISPRINT,
    ("(5.46)", "N"): MISPRINT,
    ("(5.54)", "B"): "correct",
    ("5.5", "b_ij"): MISPRINT,
    ("5.5.1", "c_ij"): MISPRINT,
    ("5.5.2", "G"): "correct under gravity +g x_B",
    ("5.5.3", "u(1)"): MISPRINT,
    ("5.5.3", "u(2)"): MISPRINT,
    ("5.5.3", "u(3)"): MISPRINT,
    ("(6.29)", "p_c ="): "correct",
    ("(6.29)'", "p_c_dot"): "correct under omega_b the body rate",
    ("(6.30ab)", "x_cm, y_cm"): "correct",
    ("(6.30c)", "z_cm"): MISPRINT,
    ("(6.31)", "R_theta p_cm"): "correct under phi = psi = 0",
    ("(6.32)", "nabla"): "correct under phi = psi = 0",
    ("(6.34)", "theta_e"): "correct under phi = 0",
    ("(6.35)", "BSG"): "correct under phi = 0",
}
SYMBOLIC = [("(5.36)", "B:"), ("(5.36)", "C:"), ("(5.36)", "G:")]


@pytest.fixture(scope="module")
def results():
    return checks.run_checks()


def _find(results, equation, needle):
    rows = [r for r in results if r.equation == equation and needle in r.quantity]
    assert len(rows) == 1, f"expected one row {equation} '{needle}', got {[r.quantity for r in rows]}"
    return rows[0]


@pytest.mark.parametrize("key", sorted(EXPECTED))
def test_each_equation_reaches_its_verdict(results, key):
    row = _find(results, *key)
    assert row.status == "pass", row.reason
    assert row.verdict.startswith(EXPECTED[key]), (row.verdict, row.reason)


@pytest.mark.parametrize("key", SYMBOLIC)
def test_symbolic_rows_hold_when_sympy_is_installed(results, key):
    pytest.importorskip("sympy", reason="sympy is not installed: pip install 'qprr[symbolic]'")
    row = _find(results, *key)
    assert (row.status, row.verdict) == ("pass", "correct"), row.reason


def test_misprints_show_a_counterexample_and_a_holding_correction(results):
    for r in results:
        if r.verdict == MISPRINT:
            assert r.printed_error > 10 * r.tolerance, r  # the printed form fails clearly, not marginally
            assert r.corrected_error <= r.tolerance
            assert r.reason


def test_every_check_holds_or_is_skipped(results):
    assert all(r.ok for r in results), [(r.equation, r.quantity, r.verdict, r.reason) for r in results if not r.ok]
    assert len(results) == len(checks.CHECKS)


def test_main_prints_the_table_and_exits_zero(capsys):
    assert checks.print_check_table(verbose=True) == 0
    out = capsys.readouterr().out
    for equation, _ in EXPECTED:
        assert equation in out
    assert "0 failed" in out


def test_console_script_exits_zero():
    script = shutil.which("qprr")
    cmd = [script, "check"] if script else [sys.executable, "-m", "qprr.cli", "check"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "misprint (corrected form holds)" in proc.stdout


# ------------------------------------------------------------------- the verdict rule itself
def _fake(printed, corrected=None, convention=None, tol=1e-9):
    return checks.Check("(9.9)", "fake", lambda ctx: checks.Evidence(printed, corrected, "fake"), tol, convention)


@pytest.mark.parametrize(
    "printed, corrected, convention, verdict, status",
    [
        (1e-12, None, None, "correct", "pass"),
        (1e-12, None, "NED", "correct under NED", "pass"),
        (1.0, 1e-12, None, MISPRINT, "pass"),
        (1.0, None, None, "FAIL", "fail"),
        (1.0, 1.0, None, "FAIL", "fail"),
        (1e-12, 1.0, None, "FAIL (corrected form does not hold)", "fail"),
        (float("nan"), None, None, "FAIL", "fail"),
    ],
)
def test_verdict_rule(printed, corrected, convention, verdict, status):
    r = checks.evaluate_check(_fake(printed, corrected, convention), ctx=None)
    assert (r.verdict, r.status) == (verdict, status)


def test_a_crashing_check_fails_with_its_cause():
    def boom(ctx):
        raise RuntimeError("model exploded")

    r = checks.evaluate_check(checks.Check("(9.9)", "boom", boom, 1e-9), ctx=None)
    assert r.status == "fail" and "model exploded" in r.reason


def test_main_exits_one_when_a_check_fails(monkeypatch, capsys):
    monkeypatch.setattr(checks, "CHECKS", checks.CHECKS[:2] + (_fake(1.0),))
    assert checks.print_check_table() == 1
    assert "FAIL" in capsys.readouterr().out


def test_symbolic_row_is_skipped_without_the_module(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "qprr.thesis.symbolic", None)  # import now raises ImportError
    sym = [c for c in checks.CHECKS if "sympy" in c.quantity]
    assert len(sym) == 3
    monkeypatch.setattr(checks, "CHECKS", tuple(sym))
    assert checks.print_check_table() == 0
    out = capsys.readouterr().out
    assert "skipped" in out and "3 skipped, 0 failed" in out
