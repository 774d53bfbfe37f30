"""Numeric (``math``) or symbolic (``sympy``) evaluation of the same formulas.

Every closed form of :mod:`qprr.wheeled` is written once against a namespace ``m`` that
provides ``sin``, ``cos``, ``tan``, ``atan2``, ``log``, ``sqrt``: the :mod:`math` module for
numbers, :mod:`sympy` for expressions.  sympy is optional (the ``symbolic`` extra): it is
imported only when a symbolic result is asked for.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from ..errors import MissingDependencyError

SYMPY_INSTALL = 'pip install "qprr[symbolic]"'


def sympy_module():
    """The sympy module, or :class:`~qprr.errors.MissingDependencyError` (an ImportError) with the install command."""
    try:
        import sympy
    except ImportError as exc:
        raise MissingDependencyError("sympy", "symbolic wheeled-robot analysis (Lie brackets, symbolic A and B)", SYMPY_INSTALL) from exc
    return sympy


def is_symbolic(m) -> bool:
    return m is not math


def _rational(value: float, max_den: int = 10**4):
    frac = Fraction(float(value)).limit_denominator(max_den)
    return frac if abs(float(frac) - float(value)) < 1e-14 * max(1.0, abs(float(value))) else None


def _pi_multiple(value: float):
    frac = Fraction(float(value) / math.pi).limit_denominator(48)
    return frac if abs(float(frac) * math.pi - float(value)) < 1e-12 else None


def is_exact(value: float, *, angle: bool = False) -> bool:
    """Whether :func:`exact` represents ``value`` exactly (a small multiple of pi or a rational)."""
    return (angle and _pi_multiple(value) is not None) or _rational(value) is not None


def exact(value: float, m, *, angle: bool = False):
    """``value`` as a number of namespace ``m``: a float, or an exact sympy number.

    For sympy, angles that are a small rational multiple of pi (pi/2, 2 pi/3, ...) become
    exact multiples of ``sympy.pi`` and other values exact rationals (0.3 -> 3/10), so that
    identities such as A^T B = 0 simplify to an exact zero; a value with neither form stays
    a sympy Float.
    """
    if not is_symbolic(m):
        return float(value)
    if angle:
        frac = _pi_multiple(value)
        if frac is not None:
            return m.Rational(frac.numerator, frac.denominator) * m.pi
    frac = _rational(value)
    if frac is not None:
        return m.Rational(frac.numerator, frac.denominator)
    return m.Float(value)


def matrix(rows, m):
    """A 2-D array of namespace ``m`` (numpy float array or sympy Matrix) from nested rows."""
    if is_symbolic(m):
        return m.Matrix(rows)
    return np.array(rows, dtype=float)


def zeros(n: int, k: int, m):
    return m.zeros(n, k) if is_symbolic(m) else np.zeros((n, k))
