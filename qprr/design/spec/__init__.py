"""Design study specifications: :class:`DesignSpec` (TOML/JSON), parameters, mass model."""

from .mass import MATERIALS, MODES, MassModel
from .metrics import DESIGN_METRICS
from .parameters import PARAMETERS, Parameter
from .study import OPTIMISERS, SEARCH_METHODS, ClosedLoop, DesignSpec, Effort, Search

__all__ = [
    "MATERIALS",
    "DESIGN_METRICS",
    "MODES",
    "OPTIMISERS",
    "PARAMETERS",
    "SEARCH_METHODS",
    "ClosedLoop",
    "DesignSpec",
    "Effort",
    "MassModel",
    "Parameter",
    "Search",
]
