"""Plain YAML scalars resolve as in the YAML 1.2 core schema, with positions kept."""

from __future__ import annotations

import math

import pytest

import hybrid
from hybrid.reader.yamlpos import read_yaml_text


@pytest.mark.parametrize(
    "scalar, value",
    [
        ("true", True),
        ("True", True),
        ("FALSE", False),
        # YAML 1.1 booleans stay strings
        ("on", "on"),
        ("off", "off"),
        ("yes", "yes"),
        ("no", "no"),
        ("y", "y"),
        ("n", "n"),
        # numbers
        ("17", 17),
        ("-3", -3),
        ("+4", 4),
        ("017", 17),  # decimal, not YAML 1.1 octal
        ("0o17", 15),
        ("0x1F", 31),
        ("1.5", 1.5),
        ("1e3", 1000.0),  # YAML 1.1 would keep these two as strings
        ("1.0e3", 1000.0),
        ("-.5e-3", -0.0005),
        ("1.", 1.0),
        (".inf", math.inf),
        ("-.inf", -math.inf),
        # YAML 1.1 numbers that are strings in 1.2
        ("1:30", "1:30"),  # 1.1: sexagesimal 90
        ("1_000", "1_000"),
        ("0b101", "0b101"),
        # no timestamps
        ("2001-12-14", "2001-12-14"),
        # null
        ("~", None),
        ("null", None),
        ('"017"', "017"),
    ],
)
def test_plain_scalars(scalar: str, value: object) -> None:
    data = read_yaml_text(f"a: {scalar}\n").data
    assert data["a"] == value
    assert type(data["a"]) is type(value)


def test_nan_is_a_float() -> None:
    assert math.isnan(read_yaml_text("a: .nan\n").data["a"])


def test_position_of_each_value_and_key() -> None:
    doc = read_yaml_text('a:\n  b: [1, "x"]\n  c: {d: 2}\n', "f.yaml")
    assert str(doc.positions.key(("a", "b"))) == "f.yaml:2:3"
    assert str(doc.positions.value(("a", "b", 0))) == "f.yaml:2:7"
    assert str(doc.positions.value(("a", "b", 1))) == "f.yaml:2:11"  # inside the quotes
    assert str(doc.positions.value(("a", "c", "d"))) == "f.yaml:3:10"


def test_too_many_digits_is_a_located_error() -> None:
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load_text("automaton: a\nparameters: {g: " + "9" * 5000 + "}\nlocations: {l: {}}\n")
    assert (info.value.line, info.value.column) == (2, 17)
    assert "cannot read number" in info.value.message


@pytest.mark.parametrize("word", ["on", "off", "yes", "no", "y", "n"])
def test_yaml_1_1_booleans_are_names_in_specs(word: str) -> None:
    """A location named ``on`` or ``off`` is a location, not a boolean."""
    model = hybrid.load_text(
        f"automaton: a\nlocations: {{{word}: {{}}, other: {{}}}}\n"
        f"edges: [{{from: {word}, to: other}}]\ninitial: {{location: {word}}}\n"
    )
    assert isinstance(model, hybrid.Automaton)
    assert list(model.locations) == [word, "other"]
    assert model.initial_location == word


def test_octal_looking_numbers_are_decimal_in_specs() -> None:
    model = hybrid.load_text(
        "automaton: a\nparameters: {k: 017, big: 1.0e3}\nstate: {x: {initial: 010}}\n"
        "locations: {l: {}}\n"
    )
    assert isinstance(model, hybrid.Automaton)
    assert dict(model.parameters) == {"k": 17.0, "big": 1000.0}
    assert model.initial_vector() == [10.0]


def test_true_and_false_are_booleans_in_specs() -> None:
    model = hybrid.load_text(
        "automaton: a\nlocations: {l: {invariant: true}}\nproperties: {deterministic: false}\n"
    )
    assert isinstance(model, hybrid.Automaton)
    assert model.properties.deterministic is False
