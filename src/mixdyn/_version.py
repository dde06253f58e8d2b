"""mixdyn's version, read by the layers that record it (written results) without importing
the package's top level."""

__version__ = "0.1.0"
