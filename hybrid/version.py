"""The version and distribution name of ``hybrid``: the one place each is written.

pyproject.toml reads the version here. The import name and the command are
``hybrid``; the distribution is ``hybrid-automata`` (the package index's ``hybrid``
is an unrelated project; ``hybrid-automata`` is not published there yet).

Examples
--------
>>> __version__.count(".")
2
>>> install_hint("plot")
"pip install 'matplotlib>=3.7' (the 'plot' extra)"
"""

__all__ = ["DISTRIBUTION", "__version__", "install_hint"]

__version__ = "0.2.0"

DISTRIBUTION = "hybrid-automata"
"""The distribution's name (in its metadata, and on the package index once published)."""


def install_hint(extra: str) -> str:
    """The command that installs what the optional extra ``extra`` adds (``plot``, ``fast``, ...).

    It names the packages themselves, read from the installed metadata, so that it
    works however ``hybrid`` was installed (from a checkout or a wheel: the
    distribution is not on the package index yet); without that metadata, the
    extra of the distribution.
    """
    packages = _extra_requirements(extra)
    if not packages:
        return f"pip install '{DISTRIBUTION}[{extra}]'"
    return "pip install " + " ".join(f"'{p}'" for p in packages) + f" (the '{extra}' extra)"


def _extra_requirements(extra: str) -> list[str]:
    import re
    from importlib.metadata import PackageNotFoundError, requires

    try:
        declared = requires(DISTRIBUTION) or []
    except PackageNotFoundError:
        return []
    marker = re.compile(r"""extra\s*==\s*["']([^"']+)["']""")
    found = []
    for requirement in declared:
        spec, _, condition = requirement.partition(";")
        named = marker.search(condition)
        if named is not None and named.group(1) == extra:
            found.append(spec.strip())
    return found
