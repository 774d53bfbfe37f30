"""The identified robot written back for every other command: a rotor file with the identified thrust per rotor at
full command as each rotor's f_max (PX4's CT, :func:`qprr.rotors.rotors_to_toml`), and a TOML file of inertial
overrides that :func:`qprr.from_urdf` applies (``inertials=``; :func:`qprr.urdf.inertia.read_inertials`).

Only identified values are written, each with its std as a comment; a value the flight does not determine is left
out (the URDF's is kept).  The inertial values are those of each moving body (Pinocchio merges the links fixed to a
joint's link into it): the mass [kg], the centre of mass in the link's frame [m], the inertia about it in the link
frame's axes [kg m^2], URDF's order (ixx, ixy, ixz, iyy, iyz, izz).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from ..errors import InputError
from ..flightstack.px4 import rotors_from_geometry
from ..model import Platform
from ..rotors import rotors_to_toml
from ..validation import as_output_path
from .identify import Identification
from .inertial import body_names
from .record import FlightRecord

INERTIA_ORDER = ("xx", "xy", "xz", "yy", "yz", "zz")
"""URDF's order of the six inertia values."""


def identified_rotors(result: Identification, record: FlightRecord, platform: Platform | None = None) -> tuple:
    """The rotors of ``platform`` (or of the log's CA_* geometry, positions from the centre of gravity PX4 was told)
    with f_max = the identified ct [N]; ct not identified raises :class:`~qprr.errors.InputError` with the reason."""
    ct = result["ct"]
    if not ct.identified:
        raise InputError(f"write_rotors: ct is not identified ({ct.reason})")
    rotors = platform.rotors if platform is not None else rotors_from_geometry(record.geometry)
    return tuple(dataclasses.replace(r, f_max=float(ct.value)) for r in rotors)


def write_rotors(result: Identification, path, record: FlightRecord, platform: Platform | None = None) -> Path:
    """Write the rotor file of :func:`identified_rotors` to ``path`` (.toml)."""
    path = as_output_path(path, "write_rotors", suffixes=(".toml",))
    ct = result["ct"]
    header = (
        f"rotors identified by qprr log identify from {result.source}",
        f"f_max = the identified ct = {ct.value:.6g} ± {ct.std:.2g} N (PX4's CA_ROTOR*_CT); geometry from "
        + (f"platform {platform.name!r}" if platform is not None else "the log's CA_* parameters"),
    )
    path.write_text(rotors_to_toml(list(identified_rotors(result, record, platform)), header))
    return path


def inertial_overrides(result: Identification, platform: Platform) -> dict:
    """{link: {key: (value, std)}} of the identified inertial values of each moving body of ``platform`` (the free
    flyer's body is its root link): mass (unless given), com (when its three components are identified), inertia
    (when its six are)."""
    model = platform.model
    out = {}
    for body in body_names(model):
        link = model.frames[platform.base_frame].name if body == "base" else body
        est = result.estimates
        entry = {}
        mass = est.get(f"{body}.mass")
        if mass is not None and mass.identified and mass.reason != "given":
            entry["mass"] = (mass.value, mass.std)
        com = [est.get(f"{body}.cog_{k}") for k in "xyz"]
        if all(e is not None and e.identified for e in com):
            entry["com"] = ([e.value for e in com], [e.std for e in com])
        inertia = [est.get(f"{body}.inertia_{k}") for k in INERTIA_ORDER]
        if all(e is not None and e.identified for e in inertia):
            entry["inertia"] = ([e.value for e in inertia], [e.std for e in inertia])
        if entry:
            out[link] = entry
    return out


def write_inertials(result: Identification, path, platform: Platform) -> Path:
    """Write the :func:`inertial_overrides` of ``result`` to ``path`` (.toml, read by
    :func:`qprr.urdf.inertia.read_inertials`); nothing identified raises :class:`~qprr.errors.InputError` with the
    reasons of the base's values."""
    path = as_output_path(path, "write_inertials", suffixes=(".toml",))
    overrides = inertial_overrides(result, platform)
    if not overrides:
        why = "; ".join(f"{k}: {e.reason}" for k, e in result.estimates.items() if k.startswith("base.") and not e.identified)
        raise InputError(f"write_inertials: no inertial value of {platform.name!r} is identified by this flight ({why[:300]})")
    lines = [
        f"# inertial overrides identified by qprr log identify from {result.source} (platform {platform.name!r})",
        "# each moving body: mass [kg], com [m] in the link's frame, inertia [kg m^2] about the com in the link's axes",
        "# (ixx, ixy, ixz, iyy, iyz, izz); only identified values; the URDF's values are kept for the others.",
        "# Use: qprr.from_urdf(urdf, rotors, inertials=THIS_FILE), or --inertials THIS_FILE on the command line.",
    ]
    for link, entry in overrides.items():
        lines += ["", f"[link.{_toml_key(link)}]"]
        for key, (value, std) in entry.items():
            unit = {"mass": "kg", "com": "m", "inertia": "kg m^2"}[key]
            if key == "mass":
                lines.append(f"mass = {float(value)!r}  # ± {std:.2g} {unit}")
            else:
                stds = ", ".join(f"{s:.2g}" for s in std)
                lines.append(f"{key} = [{', '.join(repr(float(v)) for v in value)}]  # ± [{stds}] {unit}")
    path.write_text("\n".join(lines) + "\n")
    return path


def _toml_key(name: str) -> str:
    """A TOML key: bare when it can be, else quoted."""
    if name and all(ch.isalnum() or ch in "_-" for ch in name):
        return name
    return '"' + name.replace("\\", "\\\\").replace('"', '\\"') + '"'
