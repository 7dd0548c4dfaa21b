"""The version of ``hybrid``: the one place it is written (pyproject.toml reads it here).

Examples
--------
>>> __version__.count(".")
2
"""

__all__ = ["DISTRIBUTION", "__version__"]

__version__ = "0.2.0"

DISTRIBUTION = "hybrid-automata"
"""The name to install from the package index (``pip install hybrid-automata``)."""
