"""The version and distribution name of ``hybrid``: the one place each is written.

pyproject.toml reads the version here. The import name and the command are
``hybrid``; the distribution on the package index is ``hybrid-automata``
(``hybrid`` there is an unrelated project).

Examples
--------
>>> __version__.count(".")
2
>>> install_hint("plot")
"pip install 'hybrid-automata[plot]'"
"""

__all__ = ["DISTRIBUTION", "__version__", "install_hint"]

__version__ = "0.2.0"

DISTRIBUTION = "hybrid-automata"
"""The name to install from the package index."""


def install_hint(extra: str) -> str:
    """The command that installs ``hybrid`` with an optional extra (``plot``, ``fast``, ...)."""
    return f"pip install '{DISTRIBUTION}[{extra}]'"
