"""The package's version (one home: :data:`qprr.__version__` and ``qprr --version`` read it)."""

__version__ = "0.2.0"
