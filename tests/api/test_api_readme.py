"""The README is true: its example command prints what the README shows.

The README's two entry points (`make demo`, `make test`) are run by CI itself;
this test runs the `hybrid simulate` example and its Python example.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

from support import REPO as ROOT

README = (ROOT / "README.md").read_text()


def test_readme_starts_with_the_two_commands() -> None:
    block = README.split("```")[0]
    code = [line.split("#")[0].strip() for line in block.splitlines() if line.startswith("    ")]
    assert code == ["make demo", "make test"]


def test_readme_console_example_prints_what_it_shows(tmp_path: Path) -> None:
    console = re.search(r"```console\n(.*?)```", README, re.S)
    assert console is not None
    lines = console.group(1).strip().splitlines()
    command = shlex.split(lines[0].removeprefix("$ "))
    assert command[0] == ".venv/bin/hybrid"
    args = [sys.executable, "-m", "hybrid", *command[1:]]
    args = [str(ROOT / a) if a.startswith("specs/") else a for a in args]
    result = subprocess.run(args, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    shown = "\n".join(lines[1:])
    printed = (result.stdout + result.stderr).replace(str(ROOT) + "/", "")
    assert printed.strip() == shown.strip()
    assert result.returncode == 1  # a zeno end: not t_end
    assert (tmp_path / "ball.csv").exists() and (tmp_path / "ball.json").exists()


def test_readme_python_example_runs() -> None:
    python = re.search(r"```python\n(.*?)```", README, re.S)
    assert python is not None
    namespace: dict[str, object] = {}
    exec(compile(python.group(1), "README.md", "exec"), namespace)  # our own README
    run = namespace["run"]
    assert run.termination.cause in ("t_end", "zeno")  # type: ignore[attr-defined]


def _relative_targets(text: str) -> list[str]:
    """Link and image targets of Markdown or HTML that name no scheme and no host."""
    targets = [m.group(1) for m in re.finditer(r"\]\(\s*<?([^)\s>]+)", text)]  # [x](t), ![x](t)
    targets += re.findall(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s|$)", text, re.M)  # [x]: t
    targets += re.findall(r"""\b(?:href|src)\s*=\s*["']([^"']+)""", text, re.I)  # <a href=...>
    return [t for t in targets if not re.match(r"[a-z][a-z0-9+.-]*:", t, re.I)]


def test_readme_links_work_from_the_package_index_page() -> None:
    # The README is the distribution's long description (pyproject's `readme`): on the
    # index's page a link relative to the repository leads nowhere.
    assert re.search(r'^readme = "README.md"$', (ROOT / "pyproject.toml").read_text(), re.M)
    assert _relative_targets(README) == []
    broken = "[a](docs/a.md) ![b](img/b.png) <a href='c.html'>\n[d]: docs/d.md\n"
    assert _relative_targets(broken) == ["docs/a.md", "img/b.png", "docs/d.md", "c.html"]
    fine = "[a](https://example.org/a) <a href=\"mailto:x@example.org\">\n"
    assert _relative_targets(fine) == []
