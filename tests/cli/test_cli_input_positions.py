"""An input given no value is named with the place of its declaration, as every spec error is.

The tank declares ``inputs: [u]`` on its line 2, so ``u`` is at column 10. (A
system cannot leave an input without a range free: loading or composing it is
refused, at the same place, before any run.) Every way of running the
model without a value for ``u`` (the commands in a subprocess, the API on both
backends) must start its message with that ``file:line:column``.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from support import assert_no_traceback, run_cli

import hybrid

TANK = "automaton: tank\ninputs: [u]\nstate: {x: {initial: 0.0}}\nlocations: {filling: {flow: {x: u}}}\n"
PLACE = (2, 10)  # line 2, the 'u' of 'inputs: [u]' (columns count from 1)


@pytest.fixture
def tank(tmp_path: Path) -> Path:
    path = tmp_path / "tank.yaml"
    path.write_text(TANK)
    return path


@pytest.mark.parametrize(
    "words",
    [
        ["simulate", "{spec}", "--t-end", "1"],
        ["sweep", "{spec}", "--t-end", "1", "--grid", "init.x=0:1:2", "--out", "{dir}/s.csv"],
        ["falsify", "{spec}", "--requirement", "r", "--vary", "init.x=0:1", "--t-end", "1"],
    ],
    ids=["simulate", "sweep", "falsify"],
)
def test_the_commands_name_the_declaration(words: list[str], tank: Path) -> None:
    spec = tank
    if words[0] == "falsify":  # falsify needs a requirement to look for
        text = tank.read_text() + "requirements: [{name: r, always: 'x <= 5'}]\n"
        tank.write_text(text)
    args = [w.format(spec=spec, dir=tank.parent) for w in words]
    done = run_cli(*args)
    assert_no_traceback(done.stderr)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith(f"{tank}:{PLACE[0]}:{PLACE[1]}: input 'u' needs a value"), (
        done.stderr
    )


@pytest.mark.parametrize("backend", ["scipy", "compiled"])
def test_the_api_names_the_declaration(backend: str, tank: Path) -> None:
    if backend == "compiled":
        pytest.importorskip("numba")
    model = hybrid.load(tank)
    with pytest.raises(hybrid.UsageError) as info:
        hybrid.simulate(model, t_end=1.0, backend=backend)
    assert info.value.at == hybrid.Position(str(tank), *PLACE)
    assert str(info.value).startswith(f"{tank}:2:10: input 'u'")

