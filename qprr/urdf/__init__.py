"""URDF: the checks a robot's file goes through when it is read, and the writer of URDF text.

:mod:`qprr.urdf.inertia` (the physical validity of each link's inertial), :mod:`qprr.urdf.plausibility` (magnitudes a
real aerial manipulator has: masses, sizes, thrust to weight) and :mod:`qprr.urdf.writer` (URDF text of links,
joints and rotors, used by the nomenclature and the thesis's model).  :func:`qprr.model.from_urdf` reads a file and
runs them.
"""
