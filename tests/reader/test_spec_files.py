"""Reading files from anyone: regular files only, bounded reads, OS errors at a place,
ASCII names, columns that count characters."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from support import assert_no_traceback, main_in_process, run_cli

import hybrid
from hybrid.reader.files import read_bytes

COMPONENT = "automaton: a\nlocations: {l: {}}\n"


def system_naming(spec: str) -> str:
    # the spec path as a double-quoted YAML scalar (escapes allowed: \0 is a NUL byte)
    return f'system: s\ncomponents:\n  - {{spec: "{spec}"}}\n'


@pytest.fixture
def folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a.yaml").write_text(COMPONENT)
    return tmp_path


@pytest.mark.parametrize(
    ("spec", "reason"),
    [
        ("a\\0.yaml", "the name holds a NUL byte"),
        ("x" * 5000 + ".yaml", "longer than the file system allows"),
        ("/dev/zero", "not a regular file (a character device)"),
        (".", "not a regular file (a directory)"),
        ("missing.yaml", "not found"),
    ],
)
def test_component_spec_paths_refused_at_the_spec_key(folder, capsys, spec, reason):
    (folder / "s.yaml").write_text(system_naming(spec))
    assert main_in_process("validate", "s.yaml") == 2
    err = capsys.readouterr().err
    assert err.startswith("s.yaml:3:13: "), err  # the value of `spec:` (inside its quotes)
    assert reason in err and len(err.splitlines()) == 1


def test_fifo_is_refused_at_once(folder, capsys):
    os.mkfifo(folder / "pipe.yaml")
    (folder / "s.yaml").write_text(system_naming("pipe.yaml"))
    # a blocking open would wait for a writer forever: the timeout turns a hang into a failure
    result = run_cli("validate", "pipe.yaml", "s.yaml", "/dev/zero", cwd=folder, timeout=60)
    assert result.returncode == 2
    lines = result.stderr.splitlines()
    assert lines[0] == "pipe.yaml:1:1: cannot read file: not a regular file (a FIFO)"
    assert lines[1].startswith("s.yaml:3:13: cannot read 'pipe.yaml': not a regular file (a FIFO)")
    assert lines[2] == "/dev/zero:1:1: cannot read file: not a regular file (a character device)"
    assert_no_traceback(result.stderr)


def test_read_is_bounded_by_bytes_read_not_by_the_size_claimed(folder):
    big = folder / "big.yaml"
    big.write_bytes(b"#" * 1001)
    with pytest.raises(hybrid.SpecError, match="over the limit of 1000 bytes"):
        read_bytes(big, max_bytes=1000)
    assert read_bytes(big, max_bytes=1001) == b"#" * 1001


def test_check_refuses_them_too_with_exit_2(folder, capsys):
    (folder / "s.yaml").write_text(system_naming("/dev/zero"))
    assert main_in_process("check", "--format", "json", "s.yaml") == 2
    captured = capsys.readouterr()
    assert captured.err.startswith("s.yaml:3:13: cannot read '/dev/zero'")
    assert '"invalid-spec"' in captured.out


@pytest.mark.parametrize(
    ("name", "column"),
    [("ｘ", 28), ("𝐱", 32)],  # fullwidth x, mathematical bold x: Python would read both as x
)
def test_non_ascii_names_are_refused_at_their_column(name, column):
    source = f"{name} + 1" if column == 28 else f"1 + {name}"
    text = f"automaton: a\nstate: {{x: {{}}}}\nlocations: {{l: {{flow: {{x: '{source}'}}}}}}\n"
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load_text(text, file="f.yaml")
    assert (info.value.line, info.value.column) == (3, column)
    assert f"character '{name}'" in info.value.message and "ASCII" in info.value.message


def test_columns_count_characters_not_bytes():
    # three two-byte characters before the mistake on the same line
    text = "automaton: a\nlocations: {l: {description: 'ééé', flwo: {}}}\n"
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load_text(text, file="f.yaml")
    assert info.value.column == text.splitlines()[1].index("flwo") + 1
    # in an expression: the unknown name after a quoted non-ASCII description
    text = "automaton: a\nstate: {x: {}}\nlocations: {l: {description: 'é', invariant: 'x > q'}}\n"
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load_text(text, file="f.yaml")
    assert info.value.column == text.splitlines()[2].index("q'") + 1


def test_non_ascii_keys_are_refused_at_the_key():
    text = "automaton: a\nstate: {x: {}, ｘ: {}}\nlocations: {l: {}}\n"
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load_text(text, file="f.yaml")
    assert (info.value.line, info.value.column) == (2, text.splitlines()[1].index("ｘ") + 1)
    assert "ASCII" in info.value.message
