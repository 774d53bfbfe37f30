"""The QP IK's step-control constants: the one home of the numbers both Newton loops use.

The readable loop (``qprr.ik.solver``: ``_StepShaper``, ``_satisfiable_prefix``, ``_lexicographic_progress``,
``finish``) and the compiled one (``qprr.ik.newton_fast``) import them from here; this module imports nothing from
qprr, so either may import it without a cycle.

numba reads a module-level number as a compile-time constant and freezes it into its cache beside
``newton_fast.py``, which it checks only against that file's own time stamp: after changing one of these, delete the
``.nbi`` / ``.nbc`` files of ``newton_fast`` and of ``iteration_fast`` in ``qprr/ik/__pycache__``
(``find qprr -name "*.nbi" -o -name "*.nbc" | xargs rm -f``), or the compiled loop keeps the old value.
"""

from __future__ import annotations

STATIONARY_STEP = 1e-15
"""A step whose largest entry (max |dv_i|, rad or m) is below this has vanished: the solve stops without taking it
(converged if the pose holds, stalled otherwise)."""

PROGRESS_RTOL = 1e-9
"""Relative change below which a level's error counts as unchanged when the lower levels' errors are compared in
priority order with those of the previous step (``_lexicographic_progress``)."""

FLAT_STEPS = 3
"""Once the pose holds, the solve stops ("converged") after this many steps in a row without lexicographic progress of
the lower levels."""

LEVEL1_RATE = 0.5
"""Level 1 is progressing while each step at least multiplies its error by this (halves it; its Newton convergence is
quadratic); otherwise the lower levels' share of the step is scaled by :data:`REST_FACTOR`."""

REST_FACTOR = 0.5
"""Factor on the lower levels' share of the step each time level 1 fails to progress (divided by it again, up to 1,
when level 1 progresses)."""

FREEZE_SCALE = 0.25
"""When the lower levels' share of the step has been scaled down to this (two failures of level 1 in a row), the
lowest level still stepping is frozen (``_StepShaper._freeze``)."""

SATISFIABLE_RATIO = 0.5
"""A lower level counts as met by the linearisation when the step's linear model takes its error to at most this
fraction of it (||J_k dv - e_k|| <= ratio ||e_k||; ``_satisfiable_prefix``): such levels are never frozen."""

LIMITS_SLACK = 1e-12
"""[rad or m] rounding slack of the joint-limit test of an answer (and of a start): q_arm within [lower - slack,
upper + slack] counts as within the limits."""
