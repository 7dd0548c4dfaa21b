"""`hybrid check` output formats, each parsed by a real consumer; exit codes of the contract."""

from __future__ import annotations

import glob
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import jsonschema
import pytest
from support import REPO as ROOT

from hybrid.analysis.findings import RULES
from hybrid.cli import main

DATA = Path(__file__).resolve().parents[1] / "data"

# one error (sink), warnings (dead edge, unreachable), a message with quotes and a colon
FAULTY = """\
automaton: faulty
state: {x: {initial: 0, bounds: [0, 10]}}
locations:
  stuck: {flow: {x: 1}, invariant: "x <= 1"}
  far: {}
edges:
  - {name: "jump", from: stuck, to: far, guard: "x >= 5 and x != 7"}
"""
WARNS = """\
automaton: warns
parameters: {unused_k: 1.0}
locations: {a: {}}
"""
CLEAN = """\
automaton: clean
locations: {a: {}}
"""
INVALID = """\
automaton: broken
locations: {a: {flow: {y: 1}}}
"""


@pytest.fixture
def specs(tmp_path: Path) -> dict[str, str]:
    files = {}
    for name, text in (
        ("faulty", FAULTY),
        ("warns", WARNS),
        ("clean", CLEAN),
        ("invalid", INVALID),
    ):
        path = tmp_path / f"{name}.yaml"
        path.write_text(text)
        files[name] = str(path)
    return files


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_text_format_and_exit_codes(specs, capsys):
    code, out, _ = run(capsys, "check", specs["clean"])
    assert code == 0 and out == f"{specs['clean']}: ok\n"
    code, out, _ = run(capsys, "check", specs["warns"])
    assert code == 0 and "warning unused-declaration: parameter 'unused_k'" in out
    code, _, _ = run(capsys, "check", "--strict", specs["warns"])
    assert code == 1
    code, out, _ = run(capsys, "check", specs["faulty"], specs["clean"])
    assert code == 1
    lines = out.splitlines()
    assert f"{specs['faulty']}:4:3: error sink-location: location 'stuck' is a sink" in out
    assert all(
        line.startswith(f"{specs['faulty']}:") or line == f"{specs['clean']}: ok" for line in lines
    )
    for line in lines[:-1]:
        _, row, col, rest = line.split(":", 3)
        assert row.isdigit() and col.isdigit()
        severity, rule = rest.split(":", 1)[0].split()
        assert severity in ("error", "warning", "note") and rule in RULES


def test_invalid_spec_exits_2_but_others_are_still_reported(specs, capsys):
    code, out, err = run(capsys, "check", specs["invalid"], specs["faulty"])
    assert code == 2
    assert err.startswith(f"{specs['invalid']}:2:")
    assert "flow of 'y': not a state variable" in err
    assert "sink-location" in out  # the valid file is still checked
    code, out, err = run(capsys, "check", "--format", "json", specs["invalid"], specs["clean"])
    assert code == 2
    report = json.loads(out)
    assert report["ok"] is False
    assert [f["rule"] for f in report["findings"]] == ["invalid-spec"]


def test_json_format(specs, capsys):
    code, out, _ = run(capsys, "check", "--format", "json", specs["faulty"], specs["clean"])
    assert code == 1
    report = json.loads(out)
    assert report["ok"] is False
    keys = {"rule", "severity", "file", "line", "column", "message", "where"}
    assert all(keys <= set(f) for f in report["findings"])
    rules = {(f["rule"], f["where"]) for f in report["findings"]}
    assert ("sink-location", "stuck") in rules and ("dead-edge", "jump") in rules
    code, out, _ = run(capsys, "check", "--format", "json", specs["clean"])
    assert code == 0 and json.loads(out) == {"ok": True, "findings": []}


def test_github_format(specs, capsys):
    code, out, _ = run(capsys, "check", "--format", "github", specs["faulty"], specs["warns"])
    assert code == 1
    lines = out.splitlines()
    assert any(
        line.startswith(f"::error file={specs['faulty']},line=4,col=3,title=sink-location::")
        for line in lines
    )
    assert any(line.startswith("::warning file=") for line in lines)
    for line in lines:
        level, rest = line[2:].split(" ", 1)
        props, message = rest.split("::", 1)
        assert level in ("error", "warning", "notice")
        assert dict(p.split("=", 1) for p in props.split(",")).keys() == {
            "file",
            "line",
            "col",
            "title",
        }
        assert "\n" not in message


def test_junit_format(specs, capsys):
    code, out, _ = run(
        capsys, "check", "--format", "junit", specs["faulty"], specs["clean"], specs["invalid"]
    )
    assert code == 2
    root = ET.fromstring(out)
    assert root.tag == "testsuites"
    suites = root.findall("testsuite")
    assert [s.get("name") for s in suites] == [specs["faulty"], specs["clean"], specs["invalid"]]
    faulty, clean, invalid = suites
    assert int(faulty.get("failures")) == len(faulty.findall("testcase/failure")) >= 1
    failure = faulty.find("testcase/failure")
    assert failure.get("type") == "sink-location"
    assert int(clean.get("failures")) == 0 and int(clean.get("tests")) >= 7
    assert invalid.find("testcase/error") is not None
    assert int(root.get("tests")) == sum(int(s.get("tests")) for s in suites)
    # warnings are failures only with --strict
    _, out, _ = run(capsys, "check", "--format", "junit", specs["warns"])
    assert ET.fromstring(out).get("failures") == "0"
    _, out, _ = run(capsys, "check", "--strict", "--format", "junit", specs["warns"])
    assert ET.fromstring(out).get("failures") == "1"


def sarif_validator() -> jsonschema.Draft4Validator:
    """The official SARIF 2.1.0 schema (OASIS; tests/data/README.md says where it is from)."""
    schema = json.loads((DATA / "sarif-schema-2.1.0.json").read_text())
    jsonschema.Draft4Validator.check_schema(schema)
    return jsonschema.Draft4Validator(schema, format_checker=jsonschema.FormatChecker())


def test_sarif_format_validates_against_the_official_schema(specs, capsys):
    validator = sarif_validator()
    for files in ([specs["faulty"], specs["warns"]], [specs["clean"]], [specs["invalid"]]):
        _, out, _ = run(capsys, "check", "--format", "sarif", *files)
        log = json.loads(out)
        errors = sorted(validator.iter_errors(log), key=str)
        assert not errors, errors[0]
    _, out, _ = run(capsys, "check", "--format", "sarif", specs["faulty"])
    log = json.loads(out)
    run_ = log["runs"][0]
    rules = run_["tool"]["driver"]["rules"]
    assert [r["id"] for r in rules] == list(RULES)
    for result in run_["results"]:
        assert rules[result["ruleIndex"]]["id"] == result["ruleId"]
        region = result["locations"][0]["physicalLocation"]["region"]
        assert region["startLine"] >= 1 and region["startColumn"] >= 1
    assert {r["level"] for r in run_["results"]} <= {"error", "warning", "note"}


def test_the_official_schema_rejects_what_it_should():
    validator = sarif_validator()
    bad = {"version": "2.1.0", "runs": [{"tool": {"driver": {}}, "results": []}]}
    assert not validator.is_valid(bad)  # driver needs a name
    bad = {
        "version": "2.1.0",
        "runs": [
            {
                "tool": {"driver": {"name": "x"}},
                "results": [{"level": "fatal", "message": {"text": "m"}}],
            }
        ],
    }
    assert not validator.is_valid(bad)
    assert not validator.is_valid({"version": "2.0.0", "runs": []})


def test_every_spec_in_the_repository_passes(capsys):
    files = sorted(glob.glob(str(ROOT / "specs" / "*.yaml")))
    assert files
    code, out, err = run(capsys, "check", *files)
    assert code == 0, out + err
    assert out.splitlines() == [f"{f}: ok" for f in files]


def test_graph_command(specs, capsys):
    code, out, _ = run(capsys, "graph", specs["faulty"])
    assert code == 0 and out.startswith('digraph "faulty" {')
    code, out, _ = run(capsys, "graph", "--format", "mermaid", specs["faulty"])
    assert code == 0 and out.startswith("stateDiagram-v2")
    code, out, err = run(capsys, "graph", specs["invalid"])
    assert code == 2 and out == "" and f"{specs['invalid']}:2:" in err
