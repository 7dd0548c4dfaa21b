"""docs/ci.md and .pre-commit-hooks.yaml: the documented commands run and their output parses."""

from __future__ import annotations

import glob
import json
import re
import shlex
import tomllib

import jsonschema
import pytest
import yaml
from support import REPO as ROOT

from hybrid.cli import main

DATA = ROOT / "tests" / "data"


def yaml_blocks(markdown: str) -> list[object]:
    return [yaml.safe_load(b) for b in re.findall(r"```yaml\n(.*?)```", markdown, re.S)]


def workflow() -> dict:
    block = yaml_blocks((ROOT / "docs" / "ci.md").read_text())[0]
    assert isinstance(block, dict)
    return block


def hybrid_commands(steps: list[dict]) -> list[list[str]]:
    """The `hybrid ...` command lines of the steps, up to any redirection or `||`."""
    commands = []
    for step in steps:
        run = step.get("run", "")
        if run.startswith("hybrid "):
            words = shlex.split(run)
            for stop in (">", "||"):
                if stop in words:
                    words = words[: words.index(stop)]
            commands.append(words[1:])
    return commands


def expand(args: list[str]) -> list[str]:
    out: list[str] = []
    for a in args:
        out.extend(sorted(glob.glob(a)) if "*" in a else [a])
    return out


def test_workflow_shape():
    wf = workflow()
    assert wf["permissions"]["security-events"] == "write"
    triggers = wf[True] if True in wf else wf["on"]  # YAML 1.1 reads `on` as true
    assert "pull_request" in triggers
    steps = wf["jobs"]["check"]["steps"]
    uses = [s.get("uses", "") for s in steps]
    assert any(u.startswith("github/codeql-action/upload-sarif@") for u in uses)
    upload = next(
        s for s in steps if s.get("uses", "").startswith("github/codeql-action/upload-sarif")
    )
    assert upload["with"]["sarif_file"] == "hybrid.sarif"
    assert upload["if"] == "${{ !cancelled() }}"
    formats = [c[c.index("--format") + 1] for c in hybrid_commands(steps)]
    assert formats == ["sarif", "github"]
    assert steps[-1]["run"].startswith("hybrid check --format github")


def test_workflow_commands_work_on_this_repository(capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    schema = json.loads((DATA / "sarif-schema-2.1.0.json").read_text())  # the official one
    for args in hybrid_commands(workflow()["jobs"]["check"]["steps"]):
        code = main(expand(args))
        out, err = capsys.readouterr()
        assert code == 0, err
        if "sarif" in args:
            jsonschema.Draft4Validator(schema).validate(json.loads(out))
        else:
            assert out == ""  # no findings: no annotations


def test_precommit_hooks():
    hooks = yaml.safe_load((ROOT / ".pre-commit-hooks.yaml").read_text())
    ids = {h["id"] for h in hooks}
    assert ids == {"hybrid-check", "hybrid-validate"}
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    for hook in hooks:
        assert {"id", "name", "entry", "language"} <= set(hook)
        assert hook["language"] == "python"
        command, *_ = shlex.split(hook["entry"])
        assert command in scripts
        pattern = re.compile(hook["files"])
        assert pattern.search("specs/thermostat.yaml") and pattern.search("robot/specs/arm.yml")
        assert not pattern.search("docs/schema.yaml") and not pattern.search("specs/notes.md")
    # documented use in docs/ci.md names existing hooks
    config = yaml_blocks((ROOT / "docs" / "ci.md").read_text())[1]
    assert {h["id"] for r in config["repos"] for h in r["hooks"]} <= ids


@pytest.mark.parametrize("hook_id", ["hybrid-check", "hybrid-validate"])
def test_precommit_entry_runs_on_the_specs(hook_id, capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    hook = next(
        h
        for h in yaml.safe_load((ROOT / ".pre-commit-hooks.yaml").read_text())
        if h["id"] == hook_id
    )
    files = [f for f in sorted(glob.glob("specs/*")) if re.search(hook["files"], f)]
    _, *sub = shlex.split(hook["entry"])
    assert main([*sub, *files]) == 0
    capsys.readouterr()
