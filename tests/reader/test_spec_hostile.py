"""Hostile input: every case is a SpecError with a position, fast, with nothing executed.

Each case is checked three ways:

* the Python API (``hybrid.load`` on a file, and ``hybrid.load_text`` when the
  input is text): ``SpecError`` with ``.line``/``.column`` at the right place,
  within a bound of this process's CPU time far above what any case takes
  (a sanity bound on hostile input: never wall time, which a loaded machine
  stretches; bench/ measures speed);
* the command line in-process (``hybrid.cli.main``): exit code 2 and stderr
  starting with ``file:line:column:``;
* the real command line as a subprocess (``python -m hybrid validate``), all
  cases in one run plus a few single-file runs: exit code 2, one
  ``file:line:column:`` line per file, never a traceback.

"Nothing executed": cases that would create a marker file if any code ran
(``__import__('os').system('touch ...')``, ``open(...)``, ``!!python/object/apply``)
check that the marker does not exist afterwards.
"""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import pytest

import hybrid
from hybrid.cli import main as cli_main
from hybrid.reader.yamlpos import MAX_FILE_BYTES

CPU_LIMIT_S = 5.0
"""Process CPU seconds one refusal may take (each takes well under 0.1 s)."""


@dataclass(frozen=True)
class Case:
    """A hostile file: its bytes (given a marker path) and where the error must point."""

    id: str
    content: Callable[[str], bytes]
    line: int
    column: int
    says: tuple[str, ...]
    marker: bool = False  # True if executing anything would create the marker file


def text(source: str) -> Callable[[str], bytes]:
    return lambda marker: source.replace("{marker}", marker).encode("utf-8")


def flow(expr: str) -> Callable[[str], bytes]:
    """A spec whose flow of ``x`` is ``expr``: plain at line 6, column 10; quoted: column 11."""
    return text(
        "automaton: hostile\n"
        "state: {x: {initial: 1.0}, y: {initial: 2.0}}\n"
        "locations:\n"
        "  l:\n"
        "    flow:\n"
        f"      x: {expr}\n"
    )


def vector(expr: str) -> Callable[[str], bytes]:
    """A spec with a vector signal ``q`` (3 values); ``expr`` is the flow of ``x`` (line 8, col 10)."""
    return text(
        "automaton: hostile\n"
        "uses: [uvms_model]\n"
        "state: {x: {initial: 1.0}}\n"
        "signals: {q: 'quintic(t, 0, 0, 0, 1, 1, 0)'}\n"
        "locations:\n"
        "  l:\n"
        "    flow:\n"
        f"      x: {expr}\n"
    )


def laughs() -> str:
    """The classic billion-laughs document (9 levels of 9 aliases each)."""
    lines = ["automaton: lol", 'lol0: &lol0 "lol"']
    for i in range(1, 10):
        refs = ", ".join([f"*lol{i - 1}"] * 9)
        lines.append(f"lol{i}: &lol{i} [{refs}]")
    lines.append("locations: {l: {}}")
    return "\n".join(lines) + "\n"


ESCAPE = "__import__('os').system('touch {marker}')"

CASES = [
    # --- expressions: code execution and Python features outside the language ---
    Case("import-system", flow(ESCAPE), 6, 10, ("attribute access", "not allowed"), marker=True),
    Case("import-system-inside", flow(f"x + {ESCAPE}"), 6, 14, ("attribute access",), True),
    Case("import-bare", flow("__import__('os')"), 6, 10, ("unknown function '__import__'",)),
    Case("open-file", flow("open('{marker}', 'w')"), 6, 10, ("unknown function 'open'",), True),
    Case("eval", flow("eval('1')"), 6, 10, ("unknown function 'eval'",)),
    Case(
        "class-escape",
        flow("x + ().__class__.__bases__[0].__subclasses__()"),
        6,
        14,
        ("attribute access", "not allowed"),
    ),
    Case("attribute", flow("().__class__"), 6, 10, ("attribute access",)),
    Case("attribute-of-name", flow("x.real"), 6, 10, ("attribute access",)),
    Case("lambda", flow('"x + (lambda: 0)"'), 6, 16, ("lambda is not allowed",)),
    Case("lambda-called", flow('"(lambda: 0)()"'), 6, 11, ("only named functions",)),
    Case("list-comprehension", flow("min([i for i in (1, 2)], 0)"), 6, 14, ("comprehension",)),
    Case("generator", flow("hypot(x, (i for i in (1, 2)))"), 6, 19, ("comprehension",)),
    Case("conditional", flow("x + (1 if x > 0 else 2)"), 6, 15, ("conditional expression",)),
    Case("walrus", flow("(y := 1)"), 6, 11, ("assignment expression",)),
    Case("string", flow("x + 'a'"), 6, 14, ("str literals are not allowed",)),
    Case("f-string", flow("f'{x}'"), 6, 10, ("f-string",)),
    Case("keyword-argument", flow("max(x, y, key=abs)"), 6, 10, ("positional arguments only",)),
    Case("power-tower", flow("9**9**9**9"), 6, 13, ("overflows",)),
    # --- subscripts: only vector_signal[integer literal] ---
    Case("subscript-name-index", vector("q[x]"), 8, 10, ("whole-number literal",)),
    Case("subscript-slice", vector("q[0:2]"), 8, 10, ("whole-number literal",)),
    Case("subscript-negative", vector("q[-1]"), 8, 10, ("whole-number literal",)),
    Case("subscript-float", vector("q[0.5]"), 8, 10, ("whole-number literal",)),
    Case("subscript-string", vector("q['a']"), 8, 10, ("whole-number literal",)),
    Case("subscript-nested", vector("q[0][0]"), 8, 10, ("only a vector signal",)),
    Case("subscript-call", vector("sin(x)[0]"), 8, 10, ("only a vector signal",)),
    Case("subscript-out-of-range", vector("q[3]"), 8, 10, ("out of range", "3 values")),
    Case("subscript-scalar", vector("x[0]"), 8, 10, ("single value",)),
    Case("subscript-function", vector("sin[0]"), 8, 10, ("'sin' is a function",)),
    # --- size and depth ---
    Case(
        "parens-100k-deep",
        flow("(" * 100_000 + "x" + ")" * 100_000),
        6,
        10,
        ("200001 characters", "limit of 4000"),
    ),
    Case("minus-100k-deep", flow("-" * 100_000 + "x"), 6, 10, ("limit of 4000",)),
    Case("minus-100-deep", flow("-" * 100 + "x"), 6, 10 + 64, ("more than 64 levels",)),
    Case("sin-70-deep", flow("sin(" * 70 + "x" + ")" * 70), 6, 10 + 4 * 64, ("64 levels",)),
    Case("minus-3000-deep", flow("-" * 3000 + "x"), 6, 10, ("nested too deeply",)),
    Case(
        "yaml-100k-deep",
        text("automaton: deep\nlocations: " + "[" * 100_000 + "]" * 100_000 + "\n"),
        2,
        12 + 63,
        ("YAML is nested more than 64 levels",),
    ),
    Case(
        "expression-1MB",
        flow("x+" * 500_000 + "x"),
        6,
        10,
        ("1000001 characters", "limit of 4000"),
    ),
    Case(
        "signal-1MB",
        text(
            "automaton: big\nstate: {x: {}}\nsignals:\n  s: "
            + "x+" * 500_000
            + "x\nlocations: {l: {}}\n"
        ),
        4,
        6,
        ("1000001 characters", "limit of 4000"),
    ),
    Case(
        "file-20MB",
        lambda marker: b"automaton: big\n# " + b"x" * (20 * 1024 * 1024) + b"\n",
        1,
        1,
        ("over the limit", str(MAX_FILE_BYTES)),
    ),
    # --- YAML features that are refused ---
    Case("billion-laughs", text(laughs()), 2, 7, ("anchors (&name) are not allowed",)),
    Case(
        "alias",
        text("automaton: a\nlocations: *somewhere\n"),
        2,
        12,
        ("aliases (*name) are not allowed",),
    ),
    Case(
        "merge-key",
        text("automaton: a\nbase: &b {flow: {}}\nlocations: {l: {<<: *b}}\n"),
        2,
        7,
        ("anchors",),
    ),
    Case(
        "python-object-apply",
        text("automaton: !!python/object/apply:os.system ['touch {marker}']\nlocations: {l: {}}\n"),
        1,
        12,
        ("YAML tags", "python/object/apply:os.system", "not allowed"),
        marker=True,
    ),
    Case(
        "python-object",
        text("automaton: a\nlocations: !!python/object:builtins.dict {}\n"),
        2,
        12,
        ("YAML tags", "python/object:builtins.dict"),
    ),
    Case(
        "python-name",
        text("automaton: !!python/name:os.system ''\nlocations: {l: {}}\n"),
        1,
        12,
        ("python/name:os.system",),
    ),
    Case(
        "tag-directive",
        text(
            "%TAG ! tag:yaml.org,2002:python/object/apply:\n---\n"
            "automaton: !os.system ['touch {marker}']\nlocations: {l: {}}\n"
        ),
        3,
        12,
        ("YAML tags", "python/object/apply:os.system"),
        marker=True,
    ),
    Case("local-tag", text("automaton: !mine a\nlocations: {l: {}}\n"), 1, 12, ("(!mine)",)),
    Case("binary-tag", text("automaton: a\nlocations: !!binary aGk=\n"), 2, 12, ("binary",)),
    Case("set-tag", text("automaton: a\nlocations: !!set {l}\n"), 2, 12, ("2002:set",)),
    Case("str-tag", text("automaton: !!str a\nlocations: {l: {}}\n"), 1, 12, ("YAML tags",)),
    # --- duplicate keys name both lines ---
    Case(
        "duplicate-key",
        text(
            "automaton: dup\nstate: {x: {}}\nlocations:\n  l:\n"
            "    flow: {x: 1}\n    invariant: x > 0\n    flow: {x: 2}\n"
        ),
        7,
        5,
        ("duplicate key 'flow'", "line 5", "line 7"),
    ),
    Case(
        "duplicate-top-key",
        text("automaton: a\nlocations: {l: {}}\nautomaton: b\n"),
        3,
        1,
        ("duplicate key 'automaton'", "line 1", "line 3"),
    ),
    Case(
        "duplicate-quoted-key",
        text("automaton: a\nparameters: {g: 1, 'g': 2}\nlocations: {l: {}}\n"),
        2,
        20,
        ("duplicate key 'g'",),
    ),
    # --- encodings and bytes ---
    Case("not-utf8", lambda m: b"automaton: a\n\xff\xfe", 2, 1, ("not valid UTF-8", "0xff")),
    Case(
        "latin1-comment",
        lambda m: b"# caf\xe9\nautomaton: a\nlocations: {l: {}}\n",
        1,
        6,
        ("not valid UTF-8", "0xe9"),
    ),
    Case(
        "utf16",
        lambda m: "automaton: a\n".encode("utf-16"),
        1,
        1,
        ("not valid UTF-8",),
    ),
    Case(
        "nul-byte",
        text("automaton: a\nlocations: {l: {}}\x00\n"),
        2,
        19,
        ("U+0000", "not allowed"),
    ),
    # --- empty and wrong shape ---
    Case("empty", lambda m: b"", 1, 1, ("file is empty",)),
    Case("only-comments", text("# nothing here\n\n"), 1, 1, ("file is empty",)),
    Case("only-document-start", text("---\n"), 1, 1, ("file is empty",)),
    Case("list-at-top", text("- automaton: a\n  locations: {l: {}}\n"), 1, 1, ("got a list",)),
    Case("scalar-at-top", text("hello\n"), 1, 1, ("must be a mapping", "str")),
    Case(
        "list-for-locations",
        text("automaton: a\nlocations: [falling, rising]\n"),
        2,
        12,
        ("locations", "expected a mapping of names", "got a list"),
    ),
    Case(
        "list-for-state",
        text("automaton: a\nstate: [h, v]\nlocations: {l: {}}\n"),
        2,
        8,
        ("state", "expected a mapping of names"),
    ),
    Case(
        "list-for-flow",
        text("automaton: a\nstate: {h: {}}\nlocations:\n  l:\n    flow: [h]\n"),
        5,
        11,
        ("locations.l.flow", "expected a mapping of names"),
    ),
    Case(
        "two-documents",
        text("automaton: a\nlocations: {l: {}}\n---\nautomaton: b\n"),
        3,
        1,
        ("another document",),
    ),
    Case(
        "key-is-a-list",
        text("automaton: a\nlocations: {l: {}}\n? [a, b]\n: 1\n"),
        3,
        3,
        ("mapping keys must be plain names",),
    ),
]

IDS = [c.id for c in CASES]
assert len(set(IDS)) == len(IDS), "case ids must be unique"


@pytest.fixture(scope="module")
def case_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Every case written to ``<id>.yaml``, with its marker path ``<id>.marker``."""
    root = tmp_path_factory.mktemp("hostile")
    for case in CASES:
        (root / f"{case.id}.yaml").write_bytes(case.content(str(root / f"{case.id}.marker")))
    return root


def _case_path(root: Path, case: Case) -> Path:
    return root / f"{case.id}.yaml"


def _no_marker(root: Path, case: Case) -> None:
    assert not (root / f"{case.id}.marker").exists(), f"{case.id}: something was executed"


def _check_error(err: hybrid.SpecError, case: Case, file: str) -> None:
    assert (err.file, err.line, err.column) == (file, case.line, case.column), str(err)
    for fragment in case.says:
        assert fragment in err.message, f"{fragment!r} not in {err.message!r}"
    assert str(err).startswith(f"{file}:{case.line}:{case.column}: ")


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_api_load_refuses(case: Case, case_dir: Path) -> None:
    path = _case_path(case_dir, case)
    start = time.process_time()
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load(path)
    cpu = time.process_time() - start
    _check_error(info.value, case, str(path))
    assert cpu < CPU_LIMIT_S, f"{case.id} took {cpu:.2f} s of CPU"
    _no_marker(case_dir, case)


TEXT_CASES = [c for c in CASES if c.id not in ("not-utf8", "latin1-comment", "utf16")]


@pytest.mark.parametrize("case", TEXT_CASES, ids=[c.id for c in TEXT_CASES])
def test_api_load_text_refuses(case: Case, case_dir: Path) -> None:
    source = case.content(str(case_dir / f"{case.id}.marker")).decode("utf-8")
    start = time.process_time()
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load_text(source, file="hostile.yaml")
    cpu = time.process_time() - start
    if case.id == "file-20MB":  # as text, the cap counts characters
        assert info.value.message.startswith("spec is ")
        assert "over the limit" in info.value.message
        assert (info.value.line, info.value.column) == (1, 1)
    else:
        _check_error(info.value, case, "hostile.yaml")
    assert cpu < CPU_LIMIT_S, f"{case.id} took {cpu:.2f} s of CPU"
    _no_marker(case_dir, case)


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_cli_in_process_exits_2(
    case: Case, case_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _case_path(case_dir, case)
    code = cli_main(["validate", str(path)])
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    assert err.startswith(f"{path}:{case.line}:{case.column}: "), err[:300]
    assert "Traceback" not in err
    _no_marker(case_dir, case)


def _run_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "hybrid", *args],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


def test_cli_subprocess_refuses_every_case_in_one_run(case_dir: Path) -> None:
    """One real ``hybrid validate`` over all hostile files: one located error line each."""
    paths = [_case_path(case_dir, c) for c in CASES]
    result = _run_cli("validate", *map(str, paths))
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stdout == ""  # no file was reported "ok"
    lines = result.stderr.splitlines()
    for case, path in zip(CASES, paths, strict=True):
        prefix = f"{path}:{case.line}:{case.column}: "
        matching = [line for line in lines if line.startswith(prefix)]
        assert matching, f"{case.id}: no line starts with {prefix!r}"
        assert all(fragment in matching[0] for fragment in case.says), matching[0]
        _no_marker(case_dir, case)
    # every stderr line is a located problem of one of the files
    assert all(any(line.startswith(f"{p}:") for p in paths) for line in lines)


# Each subprocess costs about a second (interpreter, numpy, scipy, pydantic), so the
# single-file runs are a representative few; the batch run above covers every case.
SINGLE = ["import-system", "python-object-apply"]


@pytest.fixture(scope="module")
def single_runs(case_dir: Path) -> dict[str, subprocess.CompletedProcess[str]]:
    """``hybrid validate <one file>`` for a representative case of each kind, run concurrently."""
    by_id = {c.id: c for c in CASES}
    with ThreadPoolExecutor(max_workers=4) as pool:
        futures = {
            cid: pool.submit(_run_cli, "validate", str(_case_path(case_dir, by_id[cid])))
            for cid in SINGLE
        }
        return {cid: f.result() for cid, f in futures.items()}


@pytest.mark.parametrize("case_id", SINGLE)
def test_cli_subprocess_single_file(
    case_id: str, case_dir: Path, single_runs: dict[str, subprocess.CompletedProcess[str]]
) -> None:
    case = next(c for c in CASES if c.id == case_id)
    result = single_runs[case_id]
    path = _case_path(case_dir, case)
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr.startswith(f"{path}:{case.line}:{case.column}: "), result.stderr[:300]
    assert "Traceback" not in result.stderr
    _no_marker(case_dir, case)


@pytest.mark.parametrize(
    "where, spec",
    [
        ("signal", 'automaton: a\nstate: {x: {}}\nsignals: {s: "{escape}"}\nlocations: {l: {}}\n'),
        (
            "guard",
            "automaton: a\nstate: {x: {}}\nlocations: {l: {}}\n"
            'edges: [{from: l, to: l, guard: "x > {escape}"}]\n',
        ),
        (
            "reset",
            "automaton: a\nstate: {x: {}}\nlocations: {l: {}}\n"
            'edges: [{from: l, to: l, reset: {x: "{escape}"}}]\n',
        ),
        ("invariant", 'automaton: a\nstate: {x: {}}\nlocations: {l: {invariant: "{escape}"}}\n'),
        (
            "location-signal",
            "automaton: a\nstate: {x: {}}\nsignals: {s: x}\n"
            'locations: {l: {signals: {s: "{escape}"}}}\n',
        ),
    ],
)
def test_no_expression_slot_executes_code(where: str, spec: str, tmp_path: Path) -> None:
    """Every place an expression can stand refuses the escape, and nothing runs."""
    marker = tmp_path / "executed"
    escape = ESCAPE.replace("{marker}", str(marker))
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load_text(spec.replace("{escape}", escape), file="x.yaml")
    assert "attribute access is not allowed" in info.value.message, where
    before = spec[: spec.index("{escape}")]
    line = before.count("\n") + 1
    column = len(before) - (before.rfind("\n") + 1) + 1
    assert (info.value.line, info.value.column) == (line, column), str(info.value)
    assert not marker.exists()
