"""``hybrid validate`` and ``hybrid schema`` as a user runs them: a real subprocess."""

from __future__ import annotations

import json
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import jsonschema
import pytest
from support import REPO as ROOT

from hybrid.cli import main as cli_main
from hybrid.reader.jsonschema import spec_schema

SPECS = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "specs").glob("*.yaml"))

COMMANDS = {
    "validate-specs": ["validate", *SPECS],
    "bad-flag": ["validate", "--no-such-flag", *SPECS[:1]],
    "schema": ["schema"],
}


@pytest.fixture(scope="module")
def runs() -> dict[str, subprocess.CompletedProcess[str]]:
    """Each command once, concurrently (a run costs about a second of interpreter start-up)."""

    def run(args: list[str]) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [sys.executable, "-m", "hybrid", *args],
            capture_output=True,
            text=True,
            cwd=ROOT,
            timeout=120,
            check=False,
        )

    with ThreadPoolExecutor(max_workers=3) as pool:
        futures = {name: pool.submit(run, args) for name, args in COMMANDS.items()}
        return {name: f.result() for name, f in futures.items()}


def test_validate_every_spec_exits_0(runs: dict[str, subprocess.CompletedProcess[str]]) -> None:
    result = runs["validate-specs"]
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert result.stdout.splitlines() == [f"{spec}: ok" for spec in SPECS]


def test_bad_flag_exits_2_without_traceback(
    runs: dict[str, subprocess.CompletedProcess[str]],
) -> None:
    result = runs["bad-flag"]
    assert result.returncode == 2
    assert result.stdout == ""
    assert "Traceback" not in result.stderr
    assert result.stderr.splitlines() == ["hybrid: error: unrecognized argument --no-such-flag"]


@pytest.mark.parametrize(
    "argv, says",
    [
        ([], "the following arguments are required: COMMAND"),
        (["validate"], "the following arguments are required: FILE"),
        (["no-such-command"], "invalid choice: 'no-such-command'"),
        (["simulate", "specs/bouncing_ball.yaml", "--t-end", "-1"], "must be > 0"),
    ],
)
def test_usage_errors_exit_2(
    argv: list[str], says: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as info:
        cli_main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert says in err
    assert "Traceback" not in err


def test_missing_file_is_a_located_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli_main(["validate", "specs/no_such_spec.yaml"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("specs/no_such_spec.yaml:1:1: cannot read file")


def test_validate_checks_every_file_even_after_a_bad_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("automaton: a\nlocations: {l: {flwo: {}}}\n")
    good = ROOT / "specs" / "bouncing_ball.yaml"
    assert cli_main(["validate", str(bad), str(good)]) == 2
    out, err = capsys.readouterr()
    assert out == f"{good}: ok\n"
    assert err.startswith(f"{bad}:2:17: unknown key 'flwo'")


def test_schema_prints_a_draft_07_schema(
    runs: dict[str, subprocess.CompletedProcess[str]],
) -> None:
    result = runs["schema"]
    assert result.returncode == 0
    assert result.stderr == ""
    printed = json.loads(result.stdout)
    jsonschema.Draft7Validator.check_schema(printed)
    assert printed == spec_schema()
