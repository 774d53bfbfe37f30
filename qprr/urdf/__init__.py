"""URDF: the one reader of a robot's file with the checks it goes through, and the writer of URDF text.

:mod:`qprr.urdf.reader` (the text parsed once into a :class:`~qprr.urdf.reader.UrdfFile`, its structure, serial arm and
inertials checked), :mod:`qprr.urdf.inertia` (the physical validity of a rigid body's mass and inertia),
:mod:`qprr.urdf.plausibility` (magnitudes a real aerial manipulator has: masses, sizes, thrust to weight) and
:mod:`qprr.urdf.writer` (URDF text of links, joints and rotors, used by the nomenclature and the thesis's model).
:func:`qprr.model.from_urdf` reads every file through :func:`qprr.urdf.reader.read_urdf`.
"""
