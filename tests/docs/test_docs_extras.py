"""Every optional extra of the distribution is documented where a user installs.

The extras are read from pyproject.toml; getting-started's table must have a row
for each (but ``test``, the developers'), and the README's install line must name
each a user may want (all but ``test`` and ``docs``).
"""

from __future__ import annotations

import re
import tomllib

from support import DOCS, REPO


def _extras() -> set[str]:
    project = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    return set(project["optional-dependencies"])


def test_getting_started_has_a_row_per_extra() -> None:
    text = (DOCS / "getting-started.md").read_text(encoding="utf-8")
    rows = set(re.findall(r"^\| `([\w-]+)` \|", text, re.M))
    assert rows == _extras() - {"test"}


def test_the_readme_names_every_users_extra() -> None:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    found = re.search(r"# with extras \(([^)]*)\)", text)
    assert found is not None
    assert set(found.group(1).replace(" ", "").split(",")) == _extras() - {"test", "docs"}
