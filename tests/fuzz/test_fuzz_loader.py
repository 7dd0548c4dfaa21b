"""Loader fuzz: mutated spec texts load or fail with a `SpecError` that has a position.

Every spec in specs/ and a system file are mutated (characters inserted,
deleted and replaced, from an alphabet of YAML punctuation, expression
characters, non-ASCII look-alikes such as ``ｘ`` and ``𝐱``, control characters
and line breaks). Loading must give a model or a :class:`hybrid.SpecError`
placed in the file (line and column at least 1, within the text); nothing else
may escape. ``make fuzz`` (``HYBRID_FUZZ=1``) runs :data:`FULL_EXAMPLES`.
"""

from __future__ import annotations

import os
import re

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from support import REPO

import hybrid

FULL_EXAMPLES = 100_000
IN_SUITE_EXAMPLES = 300


def examples(in_suite: int, full: int) -> int:
    """``full`` under ``make fuzz`` (env ``HYBRID_FUZZ`` set, not ``0``), else ``in_suite``."""
    return full if os.environ.get("HYBRID_FUZZ", "0") not in ("", "0") else in_suite


pytestmark = pytest.mark.fuzz

SYSTEM = """
system: plant
components:
  - {spec: thermostat.yaml, as: heater, parameters: {T_low: 17}}
  - {spec: bouncing_ball.yaml}
properties: {reachable: [heater.on], deadlock_free: true}
checks: {ignore: [dead-edge]}
"""
TEXTS = [p.read_text(encoding="utf-8") for p in sorted((REPO / "specs").glob("*.yaml"))]
TEXTS.append(SYSTEM)
PUNCTUATION = list(":{}[]-,. #'\"\n\t*&!|>%@`?0123456789abcxyzhvgte()+/<=_\\")
UNUSUAL = ["ｘ", "𝐱", "é", "\u00a0", "\u2028", "\x00", "\x07", "\ufeff", "\r", "ẍ", "①"]
ALPHABET = st.sampled_from([*PUNCTUATION, *UNUSUAL])


@st.composite
def mutated(draw: st.DrawFn) -> str:
    text = draw(st.sampled_from(TEXTS))
    for _ in range(draw(st.integers(1, 5))):
        at = draw(st.integers(0, len(text)))
        kind = draw(st.sampled_from(["insert", "delete", "replace", "duplicate"]))
        piece = draw(st.text(ALPHABET, min_size=1, max_size=4))
        if kind == "insert":
            text = text[:at] + piece + text[at:]
        elif kind == "delete":
            text = text[:at] + text[at + len(piece) :]
        elif kind == "replace":
            text = text[:at] + piece + text[at + len(piece) :]
        else:  # a line twice: duplicate keys, repeated edges
            start = text.rfind("\n", 0, at) + 1
            end = text.find("\n", at)
            end = len(text) if end < 0 else end + 1
            text = text[:end] + text[start:end] + text[end:]
    return text


@settings(
    max_examples=examples(IN_SUITE_EXAMPLES, FULL_EXAMPLES),
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(mutated())
def test_mutated_specs_load_or_fail_with_a_position(text: str) -> None:
    try:
        hybrid.load_text(text, file="m.yaml", base_dir=REPO / "specs")
    except hybrid.SpecError as exc:
        # YAML (1.1, as libyaml reads it) breaks lines at CR, LF, NEL, LS and PS
        lines = len(re.findall("\r\n|[\r\n\x85\u2028\u2029]", text)) + 2
        for position, message in exc.problems:
            assert position.file.endswith(".yaml"), position
            assert position.line >= 1 and position.column >= 1, (position, message)
            if position.file == "m.yaml":
                assert position.line <= lines, (position, message)
            assert message and "Traceback" not in message
