"""The package's version (``oscillator.__version__``; the build reads it here)."""

__version__ = "0.2.0"
