"""``hybrid --help`` lists every command, each with what it does."""

from __future__ import annotations

import argparse

from support import assert_no_traceback, run_cli

from hybrid.cli.main import build_parser

# The commands of the contract (CONTRACT.md): each must be offered.
CONTRACT = {"validate", "check", "simulate", "graph", "schema", "import", "export", "sweep", "falsify"}


def _commands() -> dict[str, str]:
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return {choice.dest: choice.help or "" for choice in sub._choices_actions}


def test_help_lists_every_command_with_its_line() -> None:
    commands = _commands()
    assert set(commands) >= CONTRACT
    result = run_cli("--help")
    assert result.returncode == 0
    assert_no_traceback(result.stderr)
    lines = result.stdout.splitlines()
    for name, said in commands.items():
        assert said, f"{name} has no help line"
        assert any(line.split() == [name, *said.split()] for line in lines), (name, result.stdout)
    assert "hybrid COMMAND --help" in result.stdout
