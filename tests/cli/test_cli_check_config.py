"""`hybrid check` in CI: paths that attach, each finding once, rules silenced three ways."""

from __future__ import annotations

import json
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import jsonschema
import pytest
from support import REPO, assert_no_traceback, main_in_process, run_cli

DATA = REPO / "tests" / "data"

HEATER = """
automaton: heater
state: {T: {initial: 20, bounds: [0, 40]}}
parameters: {unused: 1}
labels: [start]
locations: {cold: {flow: {T: -1}}, warm: {flow: {T: 1}}}
edges:
  - {name: heat, from: cold, to: warm, label: start}
  - {name: never, from: warm, to: cold, guard: T > 100}
"""
CTRL = """
automaton: ctrl
labels: [start]
locations: {idle: {}, busy: {}}
edges:
  - {name: go, from: idle, to: busy, label: start}
"""
PLANT = """
system: plant
components:
  - {spec: parts/heater.yaml}
  - {spec: parts/ctrl.yaml}
"""


@pytest.fixture
def project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A repository with a system file and its components in a sub-folder; cwd is its root."""
    (tmp_path / ".git").mkdir()
    (tmp_path / "specs" / "parts").mkdir(parents=True)
    (tmp_path / "specs" / "parts" / "heater.yaml").write_text(HEATER)
    (tmp_path / "specs" / "parts" / "ctrl.yaml").write_text(CTRL)
    (tmp_path / "specs" / "plant.yaml").write_text(PLANT)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def check_json(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, list[dict]]:
    code = main_in_process("check", "--format", "json", *args)
    return code, json.loads(capsys.readouterr().out)["findings"]


def test_component_findings_are_relative_and_reported_once(project, capsys):
    files = [
        str(project / "specs" / "plant.yaml"),
        str(project / "specs" / "parts" / "heater.yaml"),
    ]
    # absolute paths on the command line, as a glob in a workflow may give them
    code = main_in_process("check", "--format", "github", *files)
    out = capsys.readouterr().out.splitlines()
    assert code == 0
    assert out, "expected warnings"
    for line in out:
        assert "file=specs/parts/heater.yaml," in line or "file=specs/plant.yaml," in line, line
    places = [line.split("::", 2)[1].rsplit(",title=", 1) for line in out]
    keys = [(p[0], p[1]) for p in places]
    assert len(keys) == len(set(keys)), "a finding appears twice"
    # the dead edge of the heater appears once although two files include it
    assert sum("never" in line and "dead-edge" in line for line in out) == 1


def test_sarif_of_a_system_is_valid_relative_and_once(project, capsys):
    code = main_in_process(
        "check", "--format", "sarif", "specs/plant.yaml", "specs/parts/heater.yaml"
    )
    log = json.loads(capsys.readouterr().out)
    assert code == 0
    schema = json.loads((DATA / "sarif-schema-2.1.0.json").read_text())
    jsonschema.Draft4Validator(schema, format_checker=jsonschema.FormatChecker()).validate(log)
    results = log["runs"][0]["results"]
    uris = {r["locations"][0]["physicalLocation"]["artifactLocation"]["uri"] for r in results}
    assert uris == {"specs/parts/heater.yaml"}
    places = [
        (r["ruleId"], json.dumps(r["locations"][0]["physicalLocation"]["region"])) for r in results
    ]
    assert len(places) == len(set(places))


def test_junit_paths_are_relative(project, capsys):
    main_in_process("check", "--format", "junit", str(project / "specs" / "plant.yaml"))
    root = ET.fromstring(capsys.readouterr().out)
    files = {case.get("file") for case in root.iter("testcase") if case.get("file")}
    assert files == {"specs/parts/heater.yaml"}
    assert root.find("testsuite").get("name") == "specs/plant.yaml"


def test_text_says_where_repeated_findings_were_shown(project, capsys):
    main_in_process("check", "specs/plant.yaml", "specs/parts/heater.yaml")
    lines = capsys.readouterr().out.splitlines()
    assert lines[-1].startswith("specs/parts/heater.yaml: ") and "shown above" in lines[-1]


def test_ignore_on_the_command_line(project, capsys):
    _, findings = check_json(capsys, "specs/parts/heater.yaml")
    assert {"dead-edge", "unused-declaration"} <= {f["rule"] for f in findings}
    _, findings = check_json(
        capsys, "--ignore", "dead-edge", "--ignore", "unused-declaration", "specs/parts/heater.yaml"
    )
    assert {"dead-edge", "unused-declaration"}.isdisjoint({f["rule"] for f in findings})


def test_unknown_rule_to_ignore_is_a_usage_error(project):
    result = run_cli("check", "--ignore", "dead-edges", "specs/plant.yaml", cwd=project)
    assert result.returncode == 2
    assert "unknown rule 'dead-edges'" in result.stderr
    assert_no_traceback(result.stderr)


def test_ignore_in_a_spec_file_covers_the_findings_placed_in_it(project, capsys):
    heater = project / "specs" / "parts" / "heater.yaml"
    heater.write_text(HEATER + "checks: {ignore: [unused-declaration]}\n")
    _, findings = check_json(capsys, "specs/plant.yaml")
    rules = {f["rule"] for f in findings}
    assert "unused-declaration" not in rules and "dead-edge" in rules
    # the system file's list covers the whole system
    (project / "specs" / "plant.yaml").write_text(PLANT + "checks: {ignore: [dead-edge]}\n")
    _, findings = check_json(capsys, "specs/plant.yaml")
    assert {f["rule"] for f in findings}.isdisjoint({"dead-edge", "unused-declaration"})


def test_unknown_rule_in_a_spec_is_refused_with_its_place(project, capsys):
    heater = project / "specs" / "parts" / "heater.yaml"
    heater.write_text(HEATER + "checks: {ignore: [dead-edges]}\n")
    assert main_in_process("check", "specs/parts/heater.yaml") == 2
    assert capsys.readouterr().err.startswith("specs/parts/heater.yaml:10:19:")


def test_pyproject_gives_the_repository_defaults(project, capsys):
    (project / "pyproject.toml").write_text(
        '[project]\nname = "x"\n\n[tool.hybrid.check]\nignore = ["unused-declaration"]\nstrict = true\n'
    )
    code, findings = check_json(capsys, "specs/parts/heater.yaml")
    assert "unused-declaration" not in {f["rule"] for f in findings}
    assert code == 1  # strict: the dead edge (a warning) fails the run
    # found from a sub-folder too (up to the repository root)
    os.chdir(project / "specs")
    code, findings = check_json(capsys, "parts/heater.yaml")
    assert code == 1 and "unused-declaration" not in {f["rule"] for f in findings}


@pytest.mark.parametrize(
    ("table", "where", "message"),
    [
        ("[tool.hybrid.check]\nignore = 3\n", ":2:1:", "ignore must be a list"),
        ("[tool.hybrid.check]\nsrict = true\n", ":2:1:", "unknown key 'srict'"),
        ("[tool.hybrid.check]\nignore = [\n", ":3:1:", "invalid TOML"),
        # had no place in the file and no suggestion
        ('[tool.hybrid.check]\nignore = ["dead-edges"]\n', ":2:11:",
         "unknown rule 'dead-edges' in [tool.hybrid.check] ignore; did you mean 'dead-edge'?"),
    ],
)
def test_bad_pyproject_is_a_clear_exit_2(project, table, where, message, capsys):
    (project / "pyproject.toml").write_text(table)
    assert main_in_process("check", "specs/plant.yaml") == 2
    err = capsys.readouterr().err
    assert message in err and len(err.splitlines()) == 1
    if where:
        assert err.startswith(str(project / "pyproject.toml") + where), err
