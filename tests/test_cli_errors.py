"""Every bad invocation of the command line ends in one line on stderr and exit code 2, before any run.

The invocations of issue 10 (item 5) and their neighbours, through ``qprr.cli.main([...])``.
"""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from qprr.cli import build_parser, main
from qprr.validation import as_real

BAD = [
    (["simulate", "static-idc", "--integrator", "rk5"], "rk5"),
    (["simulate", "static-idc", "--law", "foo"], "foo"),
    (["simulate", "static-idc", "--duration", "-1"], "--duration"),
    (["simulate", "static-idc", "--duration", "nan"], "--duration"),
    (["simulate", "static-idc", "--duration", "inf"], "--duration"),
    (["simulate", "static-idc", "--save", "/proc/x.npz"], "/proc"),
    (["simulate", "static-idc", "--plot", "/nonexistent/dir/x.png"], "/nonexistent/dir"),
    (["simulate", "static-idc", "--save", "/nonexistent/dir/x.npz"], "/nonexistent/dir"),
    (["simulate", "static-idc", "--animate", "/nonexistent/dir/x.gif"], "/nonexistent/dir"),
    (["simulate", "static-idc", "--plot", "x.txt"], ".png"),
    (["simulate", "static-idc", "--animate", "out.avi"], ".gif"),
    (["simulate", "nosuch"], "nosuch"),
    (["simulate", "static-idc", "--controller", "foo"], "foo"),
    (["simulate", "static-idc", "--dt", "0"], "--dt"),
    (["simulate", "static-idc", "--dt", "abc"], "abc"),
    (["simulate", "static-idc", "--dt", "0.003", "--duration", "0.001"], "0.001"),
    (["simulate", "static-idc", "--seed", "1.5"], "1.5"),
    (["simulate", "static-idc", "--set", "foo=1"], "foo"),
    (["simulate", "hover-reach", "--thesis-as-printed"], "static-dsid"),
    (["simulate", "static-idc", "--thesis-as-printed"], "Routh-Hurwitz"),
    (["simulate", "static-idc", "--set", "duration=abc"], "abc"),
    (["simulate", "static-idc", "--set", "noequals"], "NAME=VALUE"),
    (["simulate", "static-idc", "--set", "law=foo"], "foo"),
    (["simulate", "static-idc", "--platform", "nosuch"], "nosuch"),
    (["simulate", "static-idc", "--platform", "borinot_flying_arm_2"], "borinot_flying_arm_2"),
    (["simulate", "static-idc", "--layout", "y"], "'y'"),
    (["simulate", "hover-reach", "--platform", "HEX-RQ"], "HEX-RQ"),
    (["simulate", "hover-reach", "--set", "z=nan"], "finite"),
    (["analyze", "cog", "--collision", "on"], "--collision on does not apply to the cog map"),
    (["analyze", "singularity", "--collision", "off"], "--collision off does not apply to the singularity map"),
    (["simulate", "static-dsid", "--set", "as_printed=maybe"], "as_printed must be true or false"),
    (["simulate", "hover-reach", "--set", "reach_fraction=5"], r"reach_fraction must be in \[0, 1\], got 5"),
    (["simulate", "payload-drop", "--set", "mass=-1"], "mass"),
    (["simulate", "payload-drop", "--set", "release_time=-5"], "time"),
    (["simulate", "payload-drop", "--set", "mission=foo"], "foo"),
    (["simulate", "push-thrust", "--set", "object_mass=0"], "mass"),
    (["simulate", "impedance", "--set", "t_off=-1"], "t_off|t_on"),
    (["compare", "--duration", "0"], "--duration"),
    (["urdf", "-o", "/nonexistent/x.urdf"], "/nonexistent"),
    (["check", "--cache-dir", "/nonexistent/a/b"], "/nonexistent/a"),
    (["check", "--cache-dir", "/proc/version"], "not a folder|file"),
    (["animate", "nosuch.npz"], "nosuch.npz"),
    ([], "command"),
    (["frobnicate"], "frobnicate"),
]
NUMBERS = [  # issue 22 item 7: every numeric option through the one converter set (qprr.cli.common: as_real/as_int)
    (["simulate", "static-idc", "--duration", "1e12"], "duration"),  # logs that cannot fit in memory (the simulator's bound or MemoryError)
    (["simulate", "static-idc", "--duration", "1e400"], "--duration.*finite"),
    (["simulate", "static-idc", "--seed", "-1"], "--seed"),
    (["simulate", "static-idc", "--seed", "abc"], "--seed.*abc"),
    (["simulate", "hover-reach", "--set", "seed=1.5"], "seed.*1.5"),
    (["simulate", "hover-reach", "--set", "z=1e400"], "z.*finite"),
    (["simulate", "hover-reach", "--set", "z=abc"], "z.*abc"),
    (["compare", "--duration", "abc"], "--duration.*abc"),
    (["compare", "--duration", "inf"], "--duration.*finite"),
    (["analyze", "cog", "--payload", "abc"], "--payload.*abc"),
    (["analyze", "cog", "--payload", "0,-1"], "--payload.*-1"),
    (["analyze", "hover", "--payload", "nan"], "--payload.*finite"),
    (["analyze", "workspace", "--samples", "0"], "--samples"),
    (["analyze", "workspace", "--samples", "1.5"], "--samples.*1.5"),
    (["analyze", "hover", "--reserve", "-1"], "--reserve"),
    (["analyze", "cog", "--tol", "nan"], "--tol"),
    (["view", "--port", "70000"], "--port"),
    (["view", "--port", "http"], "--port.*http"),
    (["animate", "--fps", "0"], "--fps"),
    (["animate", "--speed", "-2"], "--speed"),
    (["animate", "--size", "0", "480"], "--size"),
    (["animate", "--duration", "abc"], "--duration.*abc"),
    (["campaign", "run", "spec.toml", "--workers", "0"], "--workers"),
    (["campaign", "run", "spec.toml", "--limit", "-1"], "--limit"),
    (["campaign", "show", "spec.toml", "--first", "x"], "--first.*x"),
]
BAD += NUMBERS


@pytest.mark.parametrize("argv, names", BAD, ids=[" ".join(a) or "(none)" for a, _ in BAD])
def test_bad_invocation_is_one_line_and_exit_code_2(argv, names, capsys):
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own errors (through the one-line error of qprr.cli._Parser)
        code = exc.code
    out, err = capsys.readouterr()
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, (code, err)
    assert len(lines) == 1, err
    assert "Traceback" not in err and re.search(names, lines[0]), lines[0]
    assert out == ""  # nothing ran: no summary, no figure


def test_the_issue_lists_at_least_twenty():
    assert len(BAD) >= 20


def test_help_has_no_raw_markup(capsys):
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    texts = [parser.format_help()] + [p.format_help() for p in sub.choices.values()]
    for text in texts:
        for mark in ("``", ":func:", ":class:", ":mod:", ":data:", ":meth:", "=====", ".. "):
            assert mark not in text, (mark, text[:200])


def test_cache_dir_is_documented_in_help():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    text = sub.choices["check"].format_help()
    assert "--cache-dir" in text and "QPRR_CACHE_DIR" in text and "~/.cache/qprr" in text


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert re.fullmatch(r"qprr \d+\.\d+\.\d+\n", capsys.readouterr().out)


def test_no_numeric_option_bypasses_the_converters():
    """No ``add_argument(..., type=float|int)`` anywhere: argparse's own conversion lets nan, inf and negative counts
    through and names no bound; every numeric option goes through qprr.cli.common.real/integer/reals."""
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] / "qprr"
    bare = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "add_argument":
                for kw in node.keywords:
                    if kw.arg == "type" and isinstance(kw.value, ast.Name) and kw.value.id in ("float", "int"):
                        bare.append(f"{path.relative_to(root.parent)}:{node.lineno}")
    assert bare == [], bare


def test_the_converters_are_the_charts_checks():
    """The CLI's messages are those of qprr.validation.as_real / as_int (one set of rules for Python and the command line)."""
    import argparse

    from qprr.cli.common import integer, real, reals
    from qprr.errors import InputError
    from qprr.validation import as_int

    cases = [
        (real(**kw), text, lambda t, kw=kw: as_real(float(t), "value", **kw))
        for text, kw in (("-1", dict(positive=True)), ("nan", {}), ("inf", dict(nonnegative=True)), ("5", dict(lo=0.0, hi=1.0)))
    ]
    cases.append((integer(lo=1), "0", lambda t: as_int(int(t), "value", lo=1)))
    for convert, text, check in cases:
        with pytest.raises(argparse.ArgumentTypeError) as cli_err:
            convert(text)
        with pytest.raises(InputError) as py_err:
            check(text)
        assert str(cli_err.value) == str(py_err.value)
    assert real(positive=True)("1e-3") == 1e-3 and integer(lo=0, hi=9)("7") == 7 and reals(nonnegative=True)("0, 0.5,") == [0.0, 0.5]


def test_a_group_command_builds_its_own_parser_alone():
    """``qprr analyze ...`` builds the analysis group's parser only (GROUP_COMMANDS): the same sub-parser as in the full
    command line (same options and help), and the full command line has every group."""
    from qprr.cli import GROUP_COMMANDS

    def commands(parser):
        return next(a for a in parser._actions if a.dest == "command").choices

    full = commands(build_parser())
    assert set(GROUP_COMMANDS) <= set(full)
    for name in GROUP_COMMANDS:
        alone = commands(build_parser(name))
        assert set(alone) == {n for n, m in GROUP_COMMANDS.items() if m == GROUP_COMMANDS[name]}  # its module's commands
        assert alone[name].format_help() == full[name].format_help()


def test_a_group_command_runs_without_the_other_groups():
    """A fresh interpreter running ``qprr analyze --help`` imports neither the viewer, the campaigns, the design studies,
    the wheeled robots nor the scenario table."""
    code = (
        "import sys, contextlib, io\n"
        "from qprr.cli import main\n"
        "with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
        "    main(['analyze', '--help'])\n"
        "print(sorted(m for m in ('qprr.viz', 'qprr.campaign', 'qprr.design', 'qprr.wheeled', 'qprr.scenarios') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert out.stdout.strip() == "[]", out.stdout
