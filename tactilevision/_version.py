"""The package version, at the bottom of the import graph (no imports)."""

__version__ = "0.1.0"
