"""Silencing rules: ``--ignore RULE``, ``checks: {ignore: [...]}`` in a spec, pyproject.toml.

A rule ignored by the run (the command line, or ``[tool.hybrid.check]`` in
``pyproject.toml``) is not reported at all. A rule a spec file ignores is not
reported for the findings placed in that file: a system file's list covers
the whole system, a component file's list the findings in that component's
file.

Examples
--------
>>> import hybrid
>>> from hybrid.analysis import check
>>> text = '''
... automaton: a
... parameters: {k: 1}
... locations: {l: {}}
... checks: {ignore: [unused-declaration]}
... '''
>>> check(hybrid.load_text(text)).findings
()
>>> [f.rule for f in check(hybrid.load_text(text.replace("checks", "# checks"))).findings]
['unused-declaration']
"""

from __future__ import annotations

from collections.abc import Iterable

from hybrid.analysis.findings import RULES, Finding
from hybrid.compose import System
from hybrid.errors import UsageError

__all__ = ["check_rule_ids", "silenced"]


def check_rule_ids(rules: Iterable[str]) -> tuple[str, ...]:
    """``rules`` as a tuple, or :class:`UsageError` naming one that is no rule."""
    known = [r for r in RULES if r != "invalid-spec"]
    result = tuple(rules)
    for rule in result:
        if rule not in known:
            raise UsageError(f"unknown rule '{rule}' to ignore; rules: {', '.join(known)}")
    return result


def silenced(
    findings: Iterable[Finding], system: System, ignore: Iterable[str] = ()
) -> list[Finding]:
    """``findings`` without those of an ignored rule (see the module's docstring)."""
    everywhere = set(check_rule_ids(ignore)) | set(system.properties.ignore)
    per_file: dict[str, set[str]] = {}
    for comp in system.components:
        automaton = comp.automaton
        per_file.setdefault(automaton.file, set()).update(automaton.properties.ignore)
    return [
        f
        for f in findings
        if f.rule not in everywhere and f.rule not in per_file.get(f.file, set())
    ]
