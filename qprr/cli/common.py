"""What every command-line front end shares (``qprr`` and the command groups of :mod:`qprr.viz`,
:mod:`qprr.analysis`, :mod:`qprr.campaign`, :mod:`qprr.wheeled` and of plug-ins): the one-line error,
output-path checks, the platform options, and the converters of numeric options.

Every numeric option is read by :func:`real`, :func:`integer` or :func:`reals` (argparse ``type``
functions built on :func:`qprr.validation.as_real` and :func:`qprr.validation.as_int`): a bad value ends in
one line naming the option, exit code 2, before anything runs.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

from ..errors import InputError
from ..platforms import DEFAULT_PLATFORM
from ..validation import as_bool, as_int, as_real


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit code 2) and no raw markup in the help."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def fail(prog: str, message: str) -> int:
    print(f"{prog}: error: {message}", file=sys.stderr)
    return 2


def _writable(folder: Path) -> str:
    """ "" if a file can be created in ``folder`` (tried with a temporary file, removed at once), else why not."""
    import tempfile

    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".qprr-write-test-"):
            pass
    except OSError as exc:
        return exc.strerror or str(exc)
    return ""


def output_path(path: str | None, suffixes: tuple[str, ...], what: str) -> Path | None:
    """Check an output path before a run: known suffix, existing and writable folder (nothing is created).

    Shared by every command group (``simulate``, ``analyze``, ``wheeled``, ``animate``...); raises
    ValueError with a one-line message naming the option ``--what`` and the path."""
    if path is None:
        return None
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise ValueError(f"--{what} {path!r}: the file must end in {' or '.join(suffixes)}")
    if not p.parent.is_dir():
        raise ValueError(f"--{what} {path!r}: folder {str(p.parent)!r} does not exist")
    if p.is_dir():
        raise ValueError(f"--{what} {path!r} is a folder, not a file")
    why = _writable(p.parent)
    if why:
        raise ValueError(f"--{what} {path!r}: cannot write in folder {str(p.parent)!r} ({why})")
    return p


def cache_dir(path: str | None) -> Path | None:
    """Check ``--cache-dir``: an existing writable folder, or a new one whose parent folder exists (then made)."""
    if path is None:
        return None
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise ValueError(f"--cache-dir {path!r} is a file, not a folder")
    if not p.exists():
        if not p.parent.is_dir():
            raise ValueError(f"--cache-dir {path!r}: folder {str(p.parent)!r} does not exist")
        try:
            p.mkdir()
        except OSError as exc:
            raise ValueError(f"--cache-dir {path!r}: cannot create it ({exc.strerror or exc})") from None
    why = _writable(p)
    if why:
        raise ValueError(f"--cache-dir {path!r}: cannot write in it ({why})")
    return p


PLATFORM_HELP = (
    f"{DEFAULT_PLATFORM} (default), borinot_flying_arm_2, hextilt_flying_arm_5, a plug-in's platform or a (2.1) name such as HEX-RRR; "
    "your own: --urdf FILE.urdf --rotors FILE.toml"
)


def add_platform_options(p: argparse.ArgumentParser, *, name_option: bool = True) -> None:
    """``--platform NAME`` (unless the command takes the name as a positional argument), ``--layout plus|x``
    and a user's own platform: ``--urdf FILE --rotors FILE.toml [--ee-frame NAME]``; read back by
    :func:`platform_from_args`."""
    if name_option:
        p.add_argument("--platform", default=None, help=PLATFORM_HELP)
    p.add_argument("--layout", default=None, choices=("plus", "x"), help="rotor layout of the Q-PRR or of a built platform")
    p.add_argument("--urdf", default=None, metavar="FILE.urdf", help="your own platform: its URDF (docs/platforms.md); with --rotors")
    p.add_argument("--rotors", default=None, metavar="FILE.toml", help="the rotor description of --urdf")
    p.add_argument("--ee-frame", default=None, metavar="NAME", help="end-effector frame of --urdf (default: the last frame of the arm)")
    p.add_argument(
        "--inertials", default=None, metavar="FILE.toml", help="inertial overrides of the platform's links (qprr log identify --write-inertials)"
    )


def platform_from_args(args: argparse.Namespace):
    """The platform named by the options of :func:`add_platform_options` (:func:`qprr.platforms.resolve`);
    raises :class:`~qprr.errors.QprrError` with the option names in its message."""
    from ..platforms import resolve

    layout = args.layout

    if args.urdf is None and (args.rotors is not None or args.ee_frame is not None):
        raise InputError("--rotors and --ee-frame describe your own platform: give its --urdf too")
    if args.urdf is not None and args.rotors is None:
        raise InputError(f"--urdf {args.urdf!r} needs --rotors FILE.toml (the URDF format has no rotors; docs/platforms.md)")
    if args.urdf is not None and (args.platform is not None or layout is not None):
        raise InputError("--urdf names your own platform: leave out --platform and --layout")
    return resolve(args.platform, layout=layout, urdf=args.urdf, rotors=args.rotors, ee_frame=args.ee_frame, inertials=args.inertials)


def _argument_error(exc: InputError) -> argparse.ArgumentTypeError:
    return argparse.ArgumentTypeError(str(exc))


def real(
    *, positive: bool = False, nonnegative: bool = False, lo: float | None = None, hi: float | None = None, unit: str = ""
) -> Callable[[str], float]:
    """An argparse ``type``: the option's text as a finite float checked by :func:`qprr.validation.as_real` (same bounds)."""

    def real_number(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"value must be a real number, got {text!r}") from None
        try:
            return as_real(value, "value", positive=positive, nonnegative=nonnegative, lo=lo, hi=hi, unit=unit)
        except InputError as exc:
            raise _argument_error(exc) from None

    return real_number


def integer(*, lo: int | None = None, hi: int | None = None) -> Callable[[str], int]:
    """An argparse ``type``: the option's text as an int checked by :func:`qprr.validation.as_int` (same bounds)."""

    def whole_number(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"value must be an integer, got {text!r}") from None
        try:
            return as_int(value, "value", lo=lo, hi=hi)
        except InputError as exc:
            raise _argument_error(exc) from None

    return whole_number


def reals(*, nonnegative: bool = False, unit: str = "") -> Callable[[str], list[float]]:
    """An argparse ``type``: comma-separated real numbers (e.g. ``0,0.5``), each checked as by :func:`real`."""
    one = real(nonnegative=nonnegative, unit=unit)

    def real_numbers(text: str) -> list[float]:
        items = [x for x in text.split(",") if x.strip()]
        if not items:
            raise argparse.ArgumentTypeError(f"value must be real numbers separated by commas, got {text!r}")
        return [one(x) for x in items]

    return real_numbers


def option_value(text: str, default, name: str):
    """A ``NAME=VALUE`` option's text converted to the type of its ``default`` (a bool, int, float, tuple of
    floats or string), numbers by :func:`qprr.validation.as_real` / :func:`qprr.validation.as_int`; raises
    :class:`~qprr.errors.InputError` naming ``name`` and the text."""
    if isinstance(default, bool):
        return as_bool(text, name)
    kind = int if isinstance(default, int) else float if isinstance(default, (float, tuple)) else None
    if kind is None:
        return text
    items = text.split(",") if isinstance(default, tuple) else [text]
    try:
        values = [kind(x) for x in items]
    except ValueError:
        what = "an integer" if kind is int else "real numbers separated by commas" if isinstance(default, tuple) else "a real number"
        raise InputError(f"{name} must be {what}, got {text!r}") from None
    values = [as_int(v, name) if kind is int else as_real(v, name) for v in values]
    return tuple(values) if isinstance(default, tuple) else values[0]


__all__ = [
    "PLATFORM_HELP",
    "Parser",
    "add_platform_options",
    "cache_dir",
    "fail",
    "integer",
    "option_value",
    "output_path",
    "platform_from_args",
    "real",
    "reals",
]


def add_store_options(parser: argparse.ArgumentParser) -> None:
    """The options of a command that evaluates many runs into a results file (``campaign run``, ``design run``):
    ``-o/--output``, ``--backend`` (local, dask, inline), ``--workers``, ``--scheduler``, ``--fresh``."""
    parser.add_argument("-o", "--output", default=None, help="results file, .csv (default: NAME.csv) or .parquet (needs pyarrow)")
    parser.add_argument(
        "--backend",
        default="local",
        choices=("local", "dask", "inline"),
        help="local process pool (default), dask (LocalCluster or --scheduler), inline (this process)",
    )
    parser.add_argument("--workers", type=integer(lo=1), default=None, help="worker processes (default: one per core)")
    parser.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT", help="a running Dask scheduler (implies --backend dask)")
    parser.add_argument("--fresh", action="store_true", help="discard existing results in the output instead of resuming")
