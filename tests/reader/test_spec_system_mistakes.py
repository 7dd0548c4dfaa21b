"""A first system spec's mistakes, each said at its place in words that say what to write.

Before: a component written as a file name was "Input should be a valid dictionary or
instance of ComponentSpec"; the same spec twice without ``as:`` was two lines of
clashing state variables before the one that mattered; ``file:`` for ``spec:``
listed the valid keys; ``components:`` under ``automaton:`` suggested 'properties';
a misspelt component file named no file beside it.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from support import SPECS

import hybrid

CASES = [
    # (system text, line:column, the whole message)
    ("system: s\ncomponents:\n  - thermostat.yaml\n", "3:5",
     "components[0]: a component is a mapping: write - spec: thermostat.yaml (with as:, "
     "parameters: and initial: if you like)"),
    ("system: s\ncomponents:\n  - {spec: thermostat.yaml}\n  - {spec: thermostat.yaml}\n", "4:5",
     "component name 'thermostat' is used twice (also at line 3): give each its own name "
     "(as: in a system file, names= in compose(); the automaton's name is the default)"),
    ("system: s\ncomponents:\n  - {file: thermostat.yaml}\n", "3:6",
     "unknown key 'file' in components[0]; did you mean 'spec'?"),
    ("system: s\ncomponents:\n  - spec: thermostatt.yaml\n", "3:11",
     "component spec 'thermostatt.yaml' not found (looked in {dir}); did you mean "
     "'thermostat.yaml'?"),
    ("automaton: s\ncomponents: [{spec: thermostat.yaml}]\n", "2:1",
     "unknown key 'components' in the top level: components belong to a system, which "
     "starts with `system: NAME` (this spec starts with `automaton:`)"),
]  # fmt: skip


@pytest.mark.parametrize(("text", "where", "said"), CASES, ids=[c[2][:30] for c in CASES])
def test_a_system_mistake_is_said_at_its_place(
    text: str, where: str, said: str, tmp_path: Path
) -> None:
    shutil.copy(SPECS / "thermostat.yaml", tmp_path / "thermostat.yaml")
    spec = tmp_path / "system.yaml"
    spec.write_text(text)
    with pytest.raises(hybrid.SpecError) as caught:
        hybrid.load(spec)
    found = [(f"{p.line}:{p.column}", m) for p, m in caught.value.problems if p.file == str(spec)]
    assert (where, said.format(dir=tmp_path)) in found, found
    assert len(caught.value.problems) == len(found), caught.value.problems  # nothing besides
