"""Writers of `hybrid check` reports: text, json, github, junit, sarif.

Each writer takes the reports of all files checked (an invalid file is a
report holding its ``invalid-spec`` findings) and returns the whole output as
one string. The text writer leaves ``invalid-spec`` findings out: the command
prints those to stderr, as ``hybrid validate`` does. The ``github``, ``junit``
and ``sarif`` writers give every path relative to the current directory when
it is under it: code scanning and pull-request annotations attach only to
paths relative to the workspace.

Examples
--------
>>> from hybrid.errors import Position
>>> f = Finding.at("dead-edge", Position("a.yaml", 3, 5), "edge 'e' can never fire")
>>> print(write("text", [Report((f,), "a", "a.yaml"), Report((), "b", "b.yaml")]))
a.yaml:3:5: warning dead-edge: edge 'e' can never fire
b.yaml: ok
>>> print(write("github", [Report((f,), "a", "a.yaml")]))
::warning file=a.yaml,line=3,col=5,title=dead-edge::edge 'e' can never fire
"""

from __future__ import annotations

import json
import os
import xml.etree.ElementTree as ET
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import PurePath
from typing import Any
from urllib.parse import quote

from hybrid.analysis.findings import CAMPAIGN_RULES, RULES, Finding, Report
from hybrid.version import __version__

__all__ = ["FORMATS", "SARIF_SCHEMA", "relative", "write"]

SARIF_SCHEMA = "https://json.schemastore.org/sarif-2.1.0.json"
_GITHUB_LEVEL = {"error": "error", "warning": "warning", "note": "notice"}


def _all(reports: Sequence[Report]) -> list[Finding]:
    return [f for r in reports for f in r.findings]


def relative(file: str) -> str:
    """``file`` relative to the current directory when it is under it (as CI annotations need).

    Examples
    --------
    >>> import os
    >>> relative(os.path.abspath("specs/thermostat.yaml")), relative("/elsewhere/a.yaml")
    ('specs/thermostat.yaml', '/elsewhere/a.yaml')
    """
    if file.startswith("<"):
        return file
    here = os.path.abspath(os.curdir)
    full = os.path.abspath(file)
    if full == here or full.startswith(here.rstrip(os.sep) + os.sep):
        return PurePath(os.path.relpath(full, here)).as_posix()
    return file


def _placed(reports: Sequence[Report]) -> list[Report]:
    """The reports with every file relative to the current directory when under it."""
    return [
        replace(
            r, findings=tuple(replace(f, file=relative(f.file)) for f in r.findings),
            file=relative(r.file),
        )
        for r in reports
    ]  # fmt: skip


def text(reports: Sequence[Report], strict: bool = False) -> str:
    """One ``file:line:column: severity rule-id: message`` line per finding; ``file: ok`` if none."""
    lines: list[str] = []
    for report in reports:
        shown = [f for f in report.findings if f.rule != "invalid-spec"]
        lines.extend(f.text() for f in shown)
        if report.repeated and not report.findings:
            lines.append(f"{report.file}: {report.repeated} finding(s), shown above")
        elif not report.findings:
            lines.append(f"{report.file}: ok" + (f" ({report.bounded})" if report.bounded else ""))
        elif report.bounded and not any(f.where.startswith("forbidden: ") for f in shown):
            # every forbidden entry proved, beside other findings: what the proofs hold for
            lines.append(f"{report.file}: {report.bounded.replace(': ', ' proved ', 1)}")
    return "\n".join(lines)


def json_report(reports: Sequence[Report], strict: bool = False) -> str:
    """``{"ok": bool, "findings": [...]}``; ``ok`` is false if any finding is an error (with
    ``strict``, a warning too: what the exit code says)."""
    findings = _all(reports)
    failing = ("error", "warning") if strict else ("error",)
    ok = not any(f.severity in failing for f in findings)
    return json.dumps({"ok": ok, "findings": [f.to_dict() for f in findings]}, indent=2)


def _escape_data(value: str) -> str:
    return value.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def _escape_property(value: str) -> str:
    return _escape_data(value).replace(":", "%3A").replace(",", "%2C")


def github(reports: Sequence[Report], strict: bool = False) -> str:
    """GitHub Actions workflow commands: ``::error file=…,line=…,col=…,title=rule::message``."""
    lines = []
    for f in _all(_placed(reports)):
        props = ",".join(
            f"{k}={_escape_property(str(v))}"
            for k, v in (("file", f.file), ("line", f.line), ("col", f.column), ("title", f.rule))
        )
        lines.append(f"::{_GITHUB_LEVEL[f.severity]} {props}::{_escape_data(f.message)}")
    return "\n".join(lines)


def junit(reports: Sequence[Report], strict: bool = False) -> str:
    """JUnit XML: a test suite per file, a test case per finding and per rule with none.

    Errors are ``<failure>`` (warnings too with ``strict``), an invalid spec is an
    ``<error>``; other findings pass with the message in ``<system-out>``.
    """
    command = "hybrid reach" if reports and all(r.ran for r in reports) else "hybrid check"
    root = ET.Element("testsuites", name=command)
    total = failed = errored = 0
    for report in _placed(reports):
        suite = ET.SubElement(root, "testsuite", name=report.file)
        tests = failures = errors = 0
        for f in report.findings:
            case = ET.SubElement(
                suite,
                "testcase",
                classname=report.file,
                name=f"{f.rule}: {f.where}" if f.where else f.rule,
                file=f.file,
                line=str(f.line),
            )
            tests += 1
            if f.rule == "invalid-spec":
                ET.SubElement(case, "error", message=f.message, type=f.rule).text = f.text()
                errors += 1
            elif f.severity == "error" or (strict and f.severity == "warning"):
                ET.SubElement(case, "failure", message=f.message, type=f.rule).text = f.text()
                failures += 1
            else:
                ET.SubElement(case, "system-out").text = f.text()
        if not any(f.rule == "invalid-spec" for f in report.findings):
            hit = {f.rule for f in report.findings}
            campaign = any(f.rule in CAMPAIGN_RULES for f in report.findings)
            for rule in report.ran or RULES:
                if rule not in hit and rule not in ("invalid-spec", "analysis-incomplete"):
                    if campaign or rule in CAMPAIGN_RULES:  # a sweep's or a check's rules only
                        continue
                    ET.SubElement(suite, "testcase", classname=report.file, name=rule)
                    tests += 1
        suite.set("tests", str(tests))
        suite.set("failures", str(failures))
        suite.set("errors", str(errors))
        suite.set("skipped", "0")
        total, failed, errored = total + tests, failed + failures, errored + errors
    root.set("tests", str(total))
    root.set("failures", str(failed))
    root.set("errors", str(errored))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True)


def _uri(file: str) -> str:
    path = PurePath(file)
    if path.is_absolute():
        return path.as_uri()
    return quote(path.as_posix())


def sarif(reports: Sequence[Report], strict: bool = False) -> str:
    """SARIF 2.1.0: one run, every rule described, one result per finding."""
    rule_ids = list(RULES)
    rules = [
        {
            "id": r.id,
            "name": "".join(w.capitalize() for w in r.id.split("-")),
            "shortDescription": {"text": r.summary},
            "fullDescription": {"text": r.description},
            "defaultConfiguration": {"level": r.severity},
            "help": {"text": r.description},
        }
        for r in RULES.values()
    ]
    results: list[dict[str, Any]] = []
    for f in _all(_placed(reports)):
        location: dict[str, Any] = {
            "physicalLocation": {
                "artifactLocation": {"uri": _uri(f.file)},
                "region": {"startLine": max(f.line, 1), "startColumn": max(f.column, 1)},
            }
        }
        if f.where:
            location["logicalLocations"] = [{"name": f.where, "fullyQualifiedName": f.where}]
        result: dict[str, Any] = {
            "ruleId": f.rule,
            "ruleIndex": rule_ids.index(f.rule),
            "level": f.severity,
            "message": {"text": f.message},
            "locations": [location],
        }
        if f.witness:
            result["properties"] = {"witness": [{"transition": t, "mode": m} for t, m in f.witness]}
        results.append(result)
    invalid = any(f.rule == "invalid-spec" for f in _all(reports))
    log = {
        "$schema": SARIF_SCHEMA,
        "version": "2.1.0",
        "runs": [
            {
                "tool": {
                    "driver": {
                        "name": "hybrid",
                        "version": __version__,
                        "rules": rules,
                    }
                },
                "invocations": [{"executionSuccessful": not invalid}],
                "columnKind": "unicodeCodePoints",
                "results": results,
            }
        ],
    }
    return json.dumps(log, indent=2)


FORMATS: dict[str, Callable[[Sequence[Report], bool], str]] = {
    "text": text,
    "json": json_report,
    "github": github,
    "junit": junit,
    "sarif": sarif,
}


def write(fmt: str, reports: Sequence[Report], *, strict: bool = False) -> str:
    """The reports in format ``fmt`` (one of :data:`FORMATS`)."""
    return FORMATS[fmt](reports, strict)
