"""``hybrid sweep`` and ``hybrid simulate`` with requirements: outputs, CI formats, exit codes."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import jsonschema
import pytest
from support import REPO, assert_no_traceback, main_in_process, read_json

HEATER = """automaton: heater
parameters: {k: 0.1}
state: {x: {initial: 20.0}}
locations: {cooling: {flow: {x: -k*x}}}
requirements:
  - {name: warm, always: "x >= 15"}
  - {name: positive, always: "x >= 0"}
"""
SCHEMA = json.loads((REPO / "tests" / "data" / "sarif-schema-2.1.0.json").read_text())


@pytest.fixture
def spec(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "heater.yaml"
    path.write_text(HEATER)
    return Path("heater.yaml")


def _sweep(*args: str | Path) -> int:
    return main_in_process("sweep", *args, "--t-end", "5", "--workers", "0", "--quiet")


def test_summary_table_and_exit_codes(spec: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _sweep(spec, "--grid", "k=0.01:0.03:3", "--out", "low.csv", "--summary", "min:x") == 0
    out = capsys.readouterr().out
    assert "3 runs (3 t_end); results in low.csv" in out and "requirement-held" in out
    lines = Path("low.csv").read_text().splitlines()
    assert lines[0] == (
        "run,k,cause,t,j,jumps,zeno_time,message,warm.holds,warm.robustness,warm.violated_at,"
        "positive.holds,positive.robustness,positive.violated_at,min:x"
    )
    first = lines[1].split(",")
    assert first[:3] == ["0", "0.01", "t_end"] and first[8] == "true"
    assert float(first[9]) == pytest.approx(20 * math.exp(-0.05) - 15, abs=1e-6)
    assert _sweep(spec, "--grid", "k=0.01:0.1:4", "--out", "all.csv") == 1
    assert "requirement-violated" in capsys.readouterr().out


def test_parquet_holds_what_csv_holds(spec: Path) -> None:
    pq = pytest.importorskip("pyarrow.parquet", reason="pyarrow is in the test extra")
    assert _sweep(spec, "--grid", "k=0.01:0.1:4", "--out", "r.parquet") == 1
    assert _sweep(spec, "--grid", "k=0.01:0.1:4", "--out", "r.csv") == 1
    table = pq.read_table("r.parquet").to_pydict()
    assert table["run"] == [0, 1, 2, 3] and table["warm.holds"] == [True, True, False, False]
    assert table["warm.violated_at"][:2] == [None, None]
    lines = Path("r.csv").read_text().splitlines()[1:]
    assert [float(line.split(",")[9]) for line in lines] == table["warm.robustness"]


def test_ci_formats(spec: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = (spec, "--grid", "k=0.01:0.1:4", "--out", "r.csv")
    assert _sweep(*args, "--format", "sarif") == 1
    sarif = json.loads(capsys.readouterr().out)
    jsonschema.Draft4Validator(SCHEMA).validate(sarif)  # the official SARIF 2.1.0 schema
    results = sarif["runs"][0]["results"]
    violated = [r for r in results if r["ruleId"] == "requirement-violated"]
    assert len(violated) == 1 and violated[0]["level"] == "error"
    region = violated[0]["locations"][0]["physicalLocation"]
    assert region["artifactLocation"]["uri"] == "heater.yaml"
    assert region["region"]["startLine"] == 6
    assert "at k=0.1 (run 3" in violated[0]["message"]["text"]
    assert _sweep(*args, "--format", "github", "--resume") == 1
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("::error file=heater.yaml,line=6,col=5,title=requirement-violated::")
    assert lines[1].startswith("::notice file=heater.yaml,line=7,")
    assert _sweep(*args, "--format", "junit") == 1
    root = ET.fromstring(capsys.readouterr().out)
    cases = root.findall(".//testcase")
    assert [c.get("name") for c in cases] == [
        "requirement-violated: warm",
        "requirement-held: positive",
    ]
    assert root.get("failures") == "1"


def test_invalid_usage_is_exit_2_with_one_line(
    spec: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cases = [
        (("--grid", "k=0:1", "--out", "r.csv"), "expected NAME=LO:HI:N"),
        (("--grid", "q=0:1:2", "--out", "r.csv"), "unknown parameter 'q'"),
        (("--grid", "k=1:0:2", "--out", "r.csv"), "is empty"),
        (("--grid", "k=0:1:2", "--out", "r.txt"), ".csv or .parquet"),
        (("--vary", "k=0:1", "--out", "r.csv"), "add --sample N"),
        (("--grid", "k=0:1:2", "--out", "r.csv", "--summary", "top:x"), "KIND:NAME"),
        (("--vary", "k=0:1", "--sample", "3", "--seed", "-1", "--out", "r.csv"),
         "the seed must be a whole number >= 0, got -1"),
        # -1 said ">= 0", then 0 said "from 1 to 10000000"
        (("--vary", "k=0:1", "--sample", "-1", "--out", "r.csv"), "--sample: must be >= 1, got -1"),
        (("--vary", "k=0:1", "--sample", "0", "--out", "r.csv"), "--sample: must be >= 1, got 0"),
        # the last value used to win silently
        (("--grid", "k=0:1:2", "--param", "k=1", "--param", "k=2", "--out", "r.csv"),
         "--param k is given twice (1.0 and 2.0): give it once"),
    ]
    for args, message in cases:
        assert _sweep(spec, *args) == 2, args
        err = capsys.readouterr().err
        assert message in err, (args, err)
        assert_no_traceback(err)
        assert len(err.strip().splitlines()) == 1
    falsify = ("falsify", spec, "--requirement", "warm", "--vary", "k=0:1", "--t-end", "5", "--quiet")
    assert main_in_process(*falsify, "--input", "u=t", "--input", "u=2*t") == 2
    err = capsys.readouterr().err
    assert "--input u is given twice (t and 2*t): give it once" in err, err
    assert len(err.strip().splitlines()) == 1


def test_a_grid_of_listed_values_runs_them_in_their_order(
    spec: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--grid k=0.1,0.01,[...]``: the values as given (the API's grid={"k": [...]}).
    The heater cools as x = 20 e^(-k t): the requirement x >= 15 fails by t = 5 exactly
    when 20 e^(-5k) < 15, k > ln(4/3) / 5 = 0.0575 (k = 0.1, not 0.01 or 0.05)."""
    assert _sweep(spec, "--grid", "k=0.1,0.01,0.05", "--out", "listed.csv") == 1
    rows = Path("listed.csv").read_text().splitlines()
    header = rows[0].split(",")
    table = [dict(zip(header, line.split(","), strict=True)) for line in rows[1:]]
    assert [float(r["k"]) for r in table] == [0.1, 0.01, 0.05]
    assert [r["warm.holds"] for r in table] == ["false", "true", "true"]
    assert float(table[0]["warm.violated_at"]) == pytest.approx(10 * math.log(4 / 3), abs=1e-5)
    assert _sweep(spec, "--grid", "k=[0.02, 0.03]", "--out", "bracketed.csv") == 0
    capsys.readouterr()
    assert _sweep(spec, "--grid", "k=0.1,x", "--out", "r.csv") == 2
    assert "'k=0.1,x': the listed values must be numbers" in capsys.readouterr().err


def test_seeded_samples_from_the_command_line(spec: Path) -> None:
    args = (spec, "--vary", "k=0:0.1", "--sample", "5", "--seed", "3")
    assert _sweep(*args, "--out", "a.csv") in (0, 1)
    assert _sweep(*args, "--out", "b.csv", "--sampler", "lhs") in (0, 1)
    assert Path("a.csv").read_text() == Path("b.csv").read_text()
    ks = sorted(float(line.split(",")[1]) for line in Path("a.csv").read_text().splitlines()[1:])
    assert [int(k / 0.02) for k in ks] == [0, 1, 2, 3, 4]  # one per fifth: a Latin hypercube


def test_simulate_reports_violations_and_exits_1(
    spec: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main_in_process("simulate", spec, "--t-end", "5", "--events", "ev.json")
    err = capsys.readouterr().err
    assert code == 1
    assert "requirement 'warm' violated at t=2.8768" in err and "robustness -2.8693" in err
    assert "positive" not in err
    requirements = read_json(Path("ev.json"))["requirements"]
    assert requirements["positive"]["holds"] is True
    assert requirements["warm"]["violated_at"] == pytest.approx(10 * math.log(4 / 3), abs=1e-5)
    code = main_in_process("simulate", spec, "--t-end", "2")
    assert code == 0
