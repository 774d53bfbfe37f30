"""Input validation for every entry point: converters that turn what a user passes into checked
values or raise a :class:`qprr.errors.QprrError` naming the argument, the value and the likely fix
(``as_real``, ``as_int``, ``as_vector``, ``as_matrix``, ``as_array``, ``as_interval``, ``as_name``,
``as_file``, ``as_output_path``, ``as_settings``, ``check_fields``), and the decorators that apply them from a function's annotations
(``checked_args``, ``checked_module``).
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import math
import os
from pathlib import Path

import numpy as np

from .errors import InputError, NonFiniteError, ShapeError, UnknownNameError

# ============================================================================ validation
# The one set of argument converters of qprr: each names the argument (and the value where it is
# printable) in the error it raises, and refuses what numpy would silently coerce: complex (the
# imaginary part dropped), object, string and boolean data, None, ragged sequences.
_REAL_KINDS = "iuf"


def _preview(x) -> str:
    """A short printable form of a bad value for error messages."""
    try:
        text = repr(x.tolist() if isinstance(x, np.ndarray) else x)
    except Exception:
        text = f"<{type(x).__name__}>"
    return text if len(text) <= 80 else text[:77] + "..."


def as_array(x, name: str, *, finite: bool = False, ndim: int | None = None) -> np.ndarray:
    """``x`` as a float array; refuses None, complex, object, string and boolean data, naming ``name``.

    ``finite``: also refuse NaN and inf (:class:`NonFiniteError`); ``ndim``: the number of
    dimensions required (:class:`ShapeError`).
    """
    if x is None:
        raise InputError(f"{name} must be an array of real numbers, got None")
    if isinstance(x, np.ndarray):
        a = x
    else:
        try:
            a = np.asarray(x)
        except Exception as exc:  # ragged sequences and the like
            raise InputError(f"{name} must be an array of real numbers, got {_preview(x)}") from exc
    if a.dtype.kind not in _REAL_KINDS:
        what = {"c": "complex numbers", "b": "booleans", "O": "Python objects", "U": "strings", "S": "bytes"}.get(a.dtype.kind, f"dtype {a.dtype}")
        raise InputError(f"{name} must be real numbers, got {what} (dtype {a.dtype}): {_preview(a.ravel()[:4])}")
    if ndim is not None and a.ndim != ndim:
        raise ShapeError(f"{name} must be a {ndim}-D array, got shape {a.shape}")
    if a.dtype != np.float64:
        a = a.astype(float)
    if finite and not np.isfinite(a.sum()) and not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} must be finite, got {_preview(a)}")
    return a


def as_vector(x, n: int, name: str) -> np.ndarray:
    """``x`` as a finite float vector of length ``n``; raise naming ``name`` otherwise."""
    a = as_array(x, name)
    if a.shape != (n,):
        raise ShapeError(f"{name} must have shape ({n},), got shape {a.shape}")
    if not np.isfinite(a.sum()):  # a sum is finite iff every entry is (and far cheaper than isfinite().all())
        if not np.all(np.isfinite(a)):
            raise NonFiniteError(f"{name} must be finite, got {a.tolist()}")
    return a


def as_matrix(x, shape: tuple, name: str) -> np.ndarray:
    """``x`` as a finite float array of ``shape`` (an entry None matches any size, e.g. ``(None, 3)``)."""
    a = as_array(x, name, finite=True)
    if a.ndim != len(shape) or any(s is not None and s != k for s, k in zip(shape, a.shape)):
        want = "(" + ", ".join("m" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
        raise ShapeError(f"{name} must have shape {want}, got shape {a.shape}")
    return a


def as_interval(x, name: str, *, lo: float | None = None, unit: str = "s") -> tuple[float, float]:
    """``x`` as an interval (a, b) of two finite numbers with a < b (and a >= ``lo`` when given), e.g. a phase's times."""
    a, b = as_vector(x, 2, name).tolist()
    if not a < b or (lo is not None and a < lo):
        floor = f" and {lo!r} <= a" if lo is not None else ""
        raise InputError(f"{name} must be an interval (a, b) with a < b{floor} [{unit}], got {(a, b)!r}")
    return a, b


def as_real(
    x,
    name: str,
    *,
    positive: bool = False,
    nonnegative: bool = False,
    allow_inf: bool = False,
    lo: float | None = None,
    hi: float | None = None,
    unit: str = "",
) -> float:
    """``x`` as a Python float: a real number (not a bool, a string, a complex or None), finite unless
    ``allow_inf``, > 0 if ``positive``, >= 0 if ``nonnegative``, in [lo, hi] when given; else an
    :class:`InputError` naming ``name`` and the value (``unit`` completes the message, e.g. "s")."""
    if isinstance(x, float):
        v = x
    elif isinstance(x, (int, np.integer, np.floating)) and not isinstance(x, (bool, np.bool_)):
        v = float(x)
    elif isinstance(x, np.ndarray) and x.shape == () and x.dtype.kind in _REAL_KINDS:
        v = float(x)
    else:
        raise InputError(f"{name} must be a real number{' of ' + unit if unit else ''}, got {_preview(x)}")
    if not math.isfinite(v):
        if math.isnan(v) or not allow_inf:
            raise NonFiniteError(f"{name} must be {'a number' if allow_inf else 'finite'}, got {v!r}")
    if (positive and not v > 0.0) or (nonnegative and not v >= 0.0) or (lo is not None and v < lo) or (hi is not None and v > hi):
        bound = " and ".join(
            b
            for b in (
                ("> 0" if positive else ""),
                (">= 0" if nonnegative else ""),
                (f">= {lo!r}" if lo is not None else ""),
                (f"<= {hi!r}" if hi is not None else ""),
            )
            if b
        )
        raise InputError(f"{name} must be {bound}{' ' + unit if unit else ''}, got {v!r}")
    return v


def as_int(x, name: str, *, lo: int | None = None, hi: int | None = None) -> int:
    """``x`` as a Python int (an int or numpy integer, not a bool or a float), in [lo, hi] when given."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, np.integer)):
        raise InputError(f"{name} must be an integer, got {_preview(x)}")
    v = int(x)
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        bound = " and ".join(b for b in ((f">= {lo}" if lo is not None else ""), (f"<= {hi}" if hi is not None else "")) if b)
        raise InputError(f"{name} must be an integer {bound}, got {v!r}")
    return v


BOOL_WORDS = {"true": True, "yes": True, "1": True, "false": False, "no": False, "0": False}
"""The texts :func:`as_bool` reads as a boolean (case and surrounding spaces ignored)."""


def as_bool(x, name: str) -> bool:
    """``x`` as a bool: a bool, the integers 0 and 1, or one of the texts of :data:`BOOL_WORDS` (true/false, yes/no,
    1/0); anything else (``"maybe"``, ``"on"``, 2, None) raises an :class:`InputError` naming ``name`` - a non-empty
    text such as ``"no"`` is never taken for True."""
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)) and int(x) in (0, 1):
        return bool(int(x))
    if isinstance(x, str) and x.strip().lower() in BOOL_WORDS:
        return BOOL_WORDS[x.strip().lower()]
    raise InputError(f"{name} must be true or false (true/false, yes/no or 1/0), got {_preview(x)}")


def as_name(x, name: str, valid, kind: str | None = None) -> str:
    """``x`` if it is one of the strings ``valid``, else :class:`UnknownNameError` listing them (``kind`` names
    the thing in the message, default ``name``)."""
    valid = tuple(valid)
    if not isinstance(x, str) or x not in valid:
        raise UnknownNameError(f"{kind or name} ({name})" if kind else name, x, valid)
    return x


def as_file(x, name: str, *, what: str = "file") -> Path:
    """``x`` (a str or a path) as the Path of an existing regular file, else an :class:`InputError` naming ``name`` and the path."""
    if not isinstance(x, (str, os.PathLike)) or isinstance(x, bytes) or str(x) == "":
        raise InputError(f"{name} must be the path of a {what}, got {_preview(x)}")
    path = Path(x)
    if not path.is_file():
        state = "is a directory" if path.is_dir() else "does not exist"
        raise InputError(f"{name}: {what} {str(path)!r} {state}")
    return path


def read_toml(path, what: str, hint: str) -> dict:
    """The parsed TOML file at ``path``; a missing file or invalid TOML raises an :class:`InputError` naming ``what``
    (e.g. "mission file") and the path, with ``hint`` (what the file should hold) when it is missing."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10: the tomli backport, a dependency there
        import tomli as tomllib
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{what} {str(path)!r} does not exist ({hint})")
    with path.open("rb") as fh:
        try:
            return tomllib.load(fh)
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise InputError(f"{what} {str(path)!r}: not valid TOML ({exc})") from exc


def as_output_path(x, name: str, *, suffixes: tuple[str, ...] = ()) -> Path:
    """``x`` as the Path of a file to write: not a directory, its parent a directory or creatable (not under a file),
    its suffix one of ``suffixes`` when given.  Checked before the work that produces the file."""
    if not isinstance(x, (str, os.PathLike)) or isinstance(x, bytes) or str(x) == "":
        raise InputError(f"{name} must be a file path to write, got {_preview(x)}")
    path = Path(x)
    if path.is_dir():
        raise InputError(f"{name}: {str(path)!r} is a directory, not a file path")
    if suffixes and path.suffix.lower() not in suffixes:
        raise InputError(f"{name}: {str(path)!r} must end in {' or '.join(suffixes)}")
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"{name}: cannot write {str(path)!r}: {str(parent)!r} is a file, not a directory")
    return path


def as_settings(settings, cls: type, name: str = "settings", **fields):
    """``settings`` (an instance of the frozen dataclass ``cls``, or None for its defaults) with ``fields`` replacing
    its fields: how a function takes its configuration object and, for the callers that name them, its fields as
    keywords.  A ``settings`` of another type raises an :class:`InputError`, an unknown field a TypeError."""
    if settings is None:
        settings = cls()
    elif not isinstance(settings, cls):
        raise InputError(f"{name} must be a {cls.__name__} (or None), got {_preview(settings)}")
    unknown = [k for k in fields if k not in {f.name for f in dataclasses.fields(cls)}]
    if unknown:
        raise TypeError(f"unexpected keyword argument {unknown[0]!r}: {cls.__name__} has fields {', '.join(f.name for f in dataclasses.fields(cls))}")
    return dataclasses.replace(settings, **fields) if fields else settings


def check_fields(settings) -> None:
    """The fields of a frozen dataclass instance annotated ``float`` or ``int`` converted by :func:`as_real` /
    :func:`as_int` in place (call it from ``__post_init__``): a settings object checks its numbers as the
    function that takes them did its arguments (:func:`checked_args`)."""
    for f in dataclasses.fields(settings):
        if f.type in ("float", "int"):
            value = settings.__dict__[f.name]
            object.__setattr__(settings, f.name, as_real(value, f.name) if f.type == "float" else as_int(value, f.name))


def checked_args(fn=None, *, allow_inf: tuple[str, ...] = ()):
    """Decorator: the arguments of ``fn`` converted by their annotation before it runs.

    ``float`` goes through :func:`as_real` (finite unless the parameter is listed in ``allow_inf``),
    ``int`` through :func:`as_int`, a plain class name of the defining module (``QPRRParams``,
    ``Platform``, ``WheeledRobot``...) is an ``isinstance`` check; other annotations are left alone.
    For closed forms with scalar arguments (the printed thesis formulas, the lecture's): a NaN, a
    string or a complex number in gets an error naming the argument instead of a NaN out.
    """

    def wrap(f):
        sig = inspect.signature(f)
        names = list(sig.parameters)
        checks = {}
        for p in sig.parameters.values():
            ann = p.annotation if isinstance(p.annotation, str) else p.annotation.__name__ if isinstance(p.annotation, type) else ""
            if ann == "float":
                checks[p.name] = lambda v, n=p.name, inf=p.name in allow_inf: as_real(v, n, allow_inf=inf)
            elif ann == "int":
                checks[p.name] = lambda v, n=p.name: as_int(v, n)
            elif ann.isidentifier() and ann[:1].isupper():
                checks[p.name] = _instance_check(f, p.name, ann, p.default is None)
        if not checks:
            return f

        @functools.wraps(f)
        def checked(*args, **kwargs):
            if args:
                args = tuple(checks[n](a) if n in checks else a for n, a in zip(names, args)) + args[len(names) :]
            for k in kwargs.keys() & checks.keys():
                kwargs[k] = checks[k](kwargs[k])
            return f(*args, **kwargs)

        return checked

    return wrap if fn is None else wrap(fn)


def checked_module(namespace: dict, *, skip: tuple[str, ...] = ()) -> None:
    """:func:`checked_args` on every public function defined in a module (call it at the end of the module with
    ``globals()``): closed-form modules check their arguments without a decorator on each formula."""
    module = namespace["__name__"]
    for name, obj in list(namespace.items()):
        if inspect.isfunction(obj) and obj.__module__ == module and not name.startswith("_") and name not in skip:
            namespace[name] = checked_args(obj)


def _instance_check(f, name: str, cls_name: str, none_ok: bool):
    """A check that an argument is an instance of the class named ``cls_name`` in ``f``'s module (resolved at the first call)."""
    cache: list = []

    def check(v):
        if not cache:
            cls = f.__globals__.get(cls_name)
            cache.append(cls if isinstance(cls, type) else None)
        cls = cache[0]
        if cls is not None and not isinstance(v, cls) and not (none_ok and v is None):
            raise InputError(f"{name} must be a {cls_name}, got {type(v).__name__} {_preview(v)}")
        return v

    return check
