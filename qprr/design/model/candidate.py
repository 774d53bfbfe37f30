"""A candidate design: an architecture of (2.1) and its parameter values, built into a platform.

:func:`build_candidate` turns ``("Q-PRR", {"reach": 0.28, ...})`` into a
:class:`~qprr.model.Platform` with :func:`qprr.nomenclature.build`: the revolute links share
``reach`` in the ratio ``taper`` (link k+1 = taper x link k), a prismatic joint gets the
``slider_link`` length and +-``slider_stroke``/2 limits, every link's mass comes from the
:class:`~qprr.design.spec.MassModel`, and the rotors are sized so that every design has the same
total maximum thrust ``thrust_to_weight * total_mass * g`` (a hexarotor splits it over six).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from ...errors import InputError
from ...nomenclature import LinkSpec, build, parse
from ..spec.mass import MassModel

G = 9.81


@dataclass(frozen=True)
class Candidate:
    """An architecture (a (2.1) name) and its parameters (name -> value, SI units)."""

    architecture: str
    params: Mapping[str, float]


def link_lengths(joints: str, params: Mapping[str, float]) -> list[float]:
    """Lengths [m] of the links after each joint: the revolute ones share ``reach`` in the ratio ``taper``."""
    n_r = joints.count("R")
    w = [params["taper"] ** k for k in range(n_r)]
    rev = iter(params["reach"] * x / sum(w) for x in w)
    return [params["slider_link"] if k == "P" else next(rev) for k in joints]


def arm_links(joints: str, params: Mapping[str, float], mass: MassModel) -> list[LinkSpec]:
    """The :class:`~qprr.nomenclature.LinkSpec` of each joint (masses from ``mass``)."""
    stroke = params["slider_stroke"]
    out = []
    for kind, length in zip(joints, link_lengths(joints, params)):
        m = mass.link_mass(kind, length, stroke if kind == "P" else 0.0)
        if kind == "P":
            out.append(LinkSpec("P", length=length, mass=m, lower=-stroke / 2.0, upper=stroke / 2.0))
        else:
            out.append(LinkSpec("R", length=length, mass=m))
    return out


def build_candidate(candidate: Candidate, mass: MassModel):
    """The platform of ``candidate`` (module docstring); an :class:`InputError` if the arm outweighs the mass budget."""
    d = parse(candidate.architecture)
    p = candidate.params
    links = arm_links(d.joints, p, mass)
    m_arm = sum(k.mass for k in links)
    if mass.mode == "equal-total":
        body = p["total_mass"] - m_arm
        if body <= 0.0:
            raise InputError(
                f"{candidate.architecture}: the arm ({m_arm:.3f} kg) leaves no body mass within total_mass = "
                f"{p['total_mass']!r} kg; raise total_mass or shorten the arm"
            )
    else:
        body = mass.body
    total = body + m_arm
    # build() sizes f_max on its own total mass: scale so that the thrust is the study's, the same for every design
    ttw = p["thrust_to_weight"] * p["total_mass"] / total
    arm_len = p["rotor_arm_length"] or None
    return build(
        candidate.architecture, links=links, body_mass=body, arm_length=arm_len, mount_xyz=(0.0, 0.0, p["mount_height"]), thrust_to_weight=ttw, g=G
    )
