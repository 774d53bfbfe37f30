"""Building blocks of campaign targets: parameters a registered scenario does not expose.

:func:`scale_bandwidth` turns one factor into a controller's gains.  The thesis's flight with
its mission, gains, disturbances and model errors as parameters is
:func:`qprr.thesis.flight.flight` (``callable = "qprr.thesis.flight:flight"``).

A callable target takes ``(params, seed)`` or ``(params, seed, platform)``: the three-argument
form receives the campaign's platform (the specification's ``platform``: a name or a URDF with its
rotor file), built once per worker.  A target that returns the flight of another platform (other
coordinates) gets an ``error`` row saying so: its errors would have no column.
"""

from __future__ import annotations

import dataclasses

from ..control import IDCGains, MFCGains
from ..errors import InputError
from ..validation import as_int, as_name, as_real

_GROUPS = {"position": (0, 1, 2), "attitude": (3, 4, 5), "arm": None}


def scale_bandwidth(gains, group: str, s: float, n_xi: int):
    """Gains with the loop bandwidth of ``group`` (position, attitude, arm) times ``s``: k_P s^2, k_D s, k_I s^3.

    The error polynomial e''' + k_D e'' + k_P e' + k_I e of every loop of the group has its
    roots multiplied by ``s`` (same damping, same stability: Routh-Hurwitz is scale-free).
    Works on :class:`~qprr.control.IDCGains` and :class:`~qprr.control.MFCGains` (explicit vectors).
    """
    group = as_name(group, "group", tuple(_GROUPS), kind="bandwidth group")
    s = as_real(s, f"bandwidth.{group}", positive=True)
    n_xi = as_int(n_xi, "n_xi", lo=6)
    if not isinstance(gains, (IDCGains, MFCGains)) or not all(len(getattr(gains, k)) == n_xi for k in ("kp", "kd", "ki")):
        raise InputError(f"gains must be IDCGains or MFCGains with explicit vectors kp, kd, ki of n_xi = {n_xi} entries, got {type(gains).__name__}")
    idx = _GROUPS[group] if _GROUPS[group] is not None else tuple(range(6, n_xi))
    changes = {}
    for name, power in (("kp", 2), ("kd", 1), ("ki", 3)):
        k = list(getattr(gains, name))
        for i in idx:
            k[i] *= s**power
        changes[name] = tuple(k)
    return dataclasses.replace(gains, **changes)
