"""Honest mistakes: each message says what to fix, at the line (and column) to fix it."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest

import hybrid
from hybrid.cli import main as cli_main


@dataclass(frozen=True)
class Mistake:
    id: str
    spec: str
    line: int
    column: int
    says: tuple[str, ...]


BALL = """\
automaton: ball
parameters: {g: 9.81, e: 0.8}
state:
  height: {initial: 10.0}
  velocity: {initial: 0.0}
signals:
  energy: 0.5*velocity**2 + g*height
locations:
  falling:
    flow: {height: velocity, velocity: -g}
    invariant: height >= 0
edges:
  - from: falling
    to: falling
    guard: height <= 0 and velocity < 0
    reset: {velocity: -e*velocity}
"""


def ball(old: str, new: str) -> str:
    """The valid ``BALL`` spec with one mistake put in."""
    assert old in BALL, old
    return BALL.replace(old, new, 1)


MISTAKES = [
    # --- unknown keys, with the closest valid name ---
    Mistake(
        "unknown-key-location",
        ball("    flow: {height", "    flwo: {height"),
        10,
        5,
        ("unknown key 'flwo'", "locations.falling", "did you mean 'flow'?"),
    ),
    Mistake(
        "unknown-key-edge",
        ball("    guard:", "    gaurd:"),
        15,
        5,
        ("unknown key 'gaurd'", "edges[0]", "did you mean 'guard'?"),
    ),
    Mistake(
        "unknown-key-state",
        ball("height: {initial: 10.0}", "height: {intial: 10.0}"),
        4,
        12,
        ("unknown key 'intial'", "state.height", "did you mean 'initial'?"),
    ),
    Mistake(
        "unknown-key-top",
        ball("parameters:", "paramters:"),
        2,
        1,
        ("unknown key 'paramters'", "did you mean 'parameters'?"),
    ),
    Mistake(
        "unknown-key-no-close-name",
        ball("    to: falling\n", "    to: falling\n    colour: red\n"),
        15,
        5,
        ("unknown key 'colour'", "valid keys here:", "guard", "reset", "priority"),
    ),
    # --- unknown names in expressions, with the closest declared name ---
    Mistake(
        "unknown-variable-flow",
        ball("flow: {height: velocity,", "flow: {height: velocty,"),
        10,
        20,
        ("unknown name 'velocty'", "did you mean 'velocity'?"),
    ),
    Mistake(
        "unknown-variable-guard",
        ball("guard: height <= 0 and velocity < 0", "guard: height <= 0 and velcity < 0"),
        15,
        28,
        ("unknown name 'velcity'", "did you mean 'velocity'?"),
    ),
    Mistake(
        "unknown-parameter-reset",
        ball("reset: {velocity: -e*velocity}", "reset: {velocity: -ee*velocity}"),
        16,
        24,
        ("unknown name 'ee'", "did you mean 'e'?"),
    ),
    Mistake(
        "unknown-variable-signal",
        ball("energy: 0.5*velocity**2 + g*height", "energy: 0.5*velocity**2 + g*hieght"),
        7,
        31,
        ("unknown name 'hieght'", "did you mean 'height'?"),
    ),
    Mistake(
        "unknown-function",
        ball("invariant: height >= 0", "invariant: sqr(height) >= 0"),
        11,
        16,
        ("unknown function 'sqr'", "did you mean 'sqrt'?"),
    ),
    Mistake(
        "function-arity",
        ball("invariant: height >= 0", "invariant: atan2(height) >= 0"),
        11,
        16,
        ("atan2() takes 2 arguments, got 1",),
    ),
    Mistake(
        "caret-is-not-power",
        ball("0.5*velocity**2", "0.5*velocity^2"),
        7,
        11,
        ("'^' is not a power here: write '**'",),
    ),
    Mistake(
        "python-true",
        ball("invariant: height >= 0", "invariant: 'True'"),
        11,
        17,
        ("write 'true', not 'True'",),
    ),
    # --- references to locations, labels, state variables ---
    Mistake(
        "edge-to-missing-location",
        ball("    to: falling", "    to: fallen"),
        14,
        9,
        ("edge to unknown location 'fallen'", "did you mean 'falling'?"),
    ),
    Mistake(
        "edge-from-missing-location",
        ball("  - from: falling", "  - from: flying"),
        13,
        11,
        ("edge from unknown location 'flying'",),
    ),
    Mistake(
        "reset-of-undeclared-variable",
        ball("reset: {velocity: -e*velocity}", "reset: {velocty: -e*velocity}"),
        16,
        13,
        ("reset of 'velocty': not a state variable", "did you mean 'velocity'?"),
    ),
    Mistake(
        "flow-of-undeclared-variable",
        ball("flow: {height: velocity,", "flow: {heigth: velocity,"),
        10,
        12,
        ("flow of 'heigth': not a state variable", "did you mean 'height'?"),
    ),
    # a derivative written as other tools write it (before: "not a state variable",
    # or "the key must be a name")
    Mistake(
        "flow-keyed-as-matlab-derivative",
        ball("flow: {height: velocity,", "flow: {\"height'\": velocity,"),
        10,
        12,
        ("locations.falling.flow.height'", "a flow is keyed by the state variable itself",
         "write height: ..."),
    ),
    Mistake(
        "flow-keyed-as-modelica-derivative",
        ball("flow: {height: velocity,", "flow: {der(height): velocity,"),
        10,
        12,
        ("a flow is keyed by the state variable itself", "write height: ..."),
    ),
    Mistake(
        "flow-keyed-as-dot-name",
        ball("flow: {height: velocity,", "flow: {height_dot: velocity,"),
        10,
        12,
        ("flow of 'height_dot': not a state variable: a flow is keyed by the state "
         "variable itself, and its value is the derivative: write height: ...",),
    ),
    Mistake(
        "flow-of-a-variable-in-another-case",
        ball("flow: {height: velocity,", "flow: {Height: velocity,"),
        10,
        12,
        ("flow of 'Height': not a state variable; did you mean 'height'?",),
    ),
    # first specs written as other tools or textbooks write them (before: pydantic's
    # "valid dictionary or instance of StateVarSpec", "did you mean 'locations'?" for
    # `transitions`, 'unit' for `init`)
    Mistake(
        "state-variable-as-a-number",
        ball("  velocity: {initial: 0.0}", "  velocity: 0.0"),
        5,
        13,
        ("state.velocity: a state variable is a mapping: write velocity: {initial: 0.0}",),
    ),
    Mistake(
        "transitions-for-edges",
        ball("edges:", "transitions:"),
        12,
        1,
        ("unknown key 'transitions' in the top level; did you mean 'edges'?",),
    ),
    Mistake(
        "init-for-initial",
        ball("  height: {initial: 10.0}", "  height: {init: 10.0}"),
        4,
        12,
        ("unknown key 'init' in state.height; did you mean 'initial'?",),
    ),
    Mistake(
        "invariant-as-a-list",
        ball("invariant: height >= 0", "invariant: [height >= 0, velocity <= 100]"),
        11,
        16,
        ("locations.falling.invariant: one condition, not a list: join them with 'and': "
         "height >= 0 and velocity <= 100",),
    ),
    Mistake(
        "unit-in-a-value",
        ball("{g: 9.81,", "{g: 9.81 m/s^2,"),
        2,
        17,
        ("parameters.g: expected a number, got the text '9.81 m/s^2' (a unit goes under",),
    ),
    Mistake(
        "undeclared-label",
        ball("    to: falling\n", "    to: falling\n    label: bounce\n"),
        15,
        12,
        ("label 'bounce' is not declared in `labels`",),
    ),
    Mistake(
        "initial-location-missing",
        BALL + "initial: {location: faling}\n",
        17,
        21,
        ("initial location 'faling' is not a location", "did you mean 'falling'?"),
    ),
    Mistake(
        "property-unknown-location",
        BALL + "properties: {reachable: [fallin]}\n",
        17,
        26,
        ("reachable: unknown location 'fallin'", "did you mean 'falling'?"),
    ),
    Mistake(
        "location-signal-not-declared",
        ball("    invariant: height >= 0", "    signals: {enrgy: 0}\n    invariant: height >= 0"),
        11,
        15,
        ("signal 'enrgy' is not declared in `signals`", "did you mean 'energy'?"),
    ),
    # --- names ---
    Mistake(
        "name-declared-twice",
        ball("parameters: {g: 9.81, e: 0.8}", "parameters: {g: 9.81, e: 0.8, height: 1}"),
        4,
        3,
        ("'height' is declared twice", "state variable here", "parameter at line 2"),
    ),
    Mistake(
        "reserved-name",
        ball("parameters: {g: 9.81, e: 0.8}", "parameters: {g: 9.81, e: 0.8, sin: 1}"),
        2,
        31,
        ("'sin' is a reserved name",),
    ),
    # numbers written as other tools write them: said "Input should be a valid number"
    Mistake(
        "infinity-spelled-inf",
        ball("height: {initial: 10.0}", "height: {initial: 10.0, bounds: [0, inf]}"),
        4,
        39,
        ("expected a number, got the text 'inf': YAML writes it .inf",),
    ),
    Mistake(
        "minus-infinity",
        ball("height: {initial: 10.0}", "height: {initial: 10.0, bounds: [-Infinity, 20]}"),
        4,
        36,
        ("got the text '-Infinity': YAML writes it -.inf",),
    ),
    Mistake(
        "digit-separators",
        ball("parameters: {g: 9.81, e: 0.8}", "parameters: {g: 9.81, e: 0.8, n: 1_000}"),
        2,
        34,
        ("expected a number, got the text '1_000': write 1000 (no _)",),
    ),
    Mistake(  # said "syntax error: invalid syntax"
        "literal-block-expression",
        ball("    guard: height <= 0 and velocity < 0", "    guard: |\n      height <= 0 and\n      velocity < 0"),
        15,
        12,
        ("an expression is one line: a YAML literal block (|) keeps its line breaks; write it "
         "on one line or as a folded block (>)",),
    ),
    Mistake(  # said "Input should be a valid string (got True)"
        "boolean-for-a-name",
        ball("    to: falling\n", "    to: true\n"),
        14,
        9,
        ("edges[0].to: expected a name, got the boolean true: quote it ('true') for a name",),
    ),
    Mistake(  # said only "not a state variable"
        "reset-of-a-parameter",
        ball("reset: {velocity: -e*velocity}", "reset: {velocity: -e*velocity, e: 0.5}"),
        16,
        36,
        ("reset of 'e': not a state variable: 'e' is a parameter (a reset sets state variables)",),
    ),
    Mistake(  # pydantic's "Value error, " no longer starts it
        "infinite-expression",
        ball("    guard: height <= 0 and velocity < 0", "    guard: .inf"),
        15,
        12,
        ("edges[0].guard: an expression must be finite; write a number or a formula",),
    ),
    Mistake(  # validated before, and a run's table then had two 'j' columns
        "run-column-name",
        ball("  velocity: {initial: 0.0}", "  velocity: {initial: 0.0}\n  j: {initial: 0.0}"),
        6,
        3,
        ("'j' is a reserved name (a run's column of hybrid time); choose another",),
    ),
    # --- wrong types ---
    Mistake(
        "number-expected",
        ball("height: {initial: 10.0}", "height: {initial: ten}"),
        4,
        21,
        ("state.height.initial", "valid number", "got 'ten'"),
    ),
    Mistake(
        "integer-expected",
        ball("    to: falling\n", "    to: falling\n    priority: high\n"),
        15,
        15,
        ("edges[0].priority", "valid integer", "got 'high'"),
    ),
    Mistake(
        "parameter-not-a-number",
        ball("parameters: {g: 9.81,", "parameters: {g: fast,"),
        2,
        17,
        ("parameters.g", "valid number", "got 'fast'"),
    ),
    Mistake(
        "bool-expected",
        BALL + "properties: {deadlock_free: maybe}\n",
        17,
        29,
        ("properties.deadlock_free", "valid boolean", "got 'maybe'"),
    ),
    Mistake(
        "list-expected",
        BALL + "labels: bounce\n",
        17,
        9,
        ("labels", "valid list", "got 'bounce'"),
    ),
    Mistake(
        "bounds-not-a-pair",
        ball("height: {initial: 10.0}", "height: {initial: 10.0, bounds: 0}"),
        4,
        35,
        ("state.height.bounds", "got 0"),
    ),
    Mistake(
        "bad-name",
        ball("automaton: ball", "automaton: my ball"),
        1,
        12,
        ("automaton: must be a name", "got 'my ball'"),
    ),
    Mistake(
        "condition-expected",
        ball("guard: height <= 0 and velocity < 0", "guard: height - 1"),
        15,
        12,
        ("expected a condition", "compare it"),
    ),
    Mistake(
        "number-expected-in-flow",
        ball("flow: {height: velocity,", "flow: {height: velocity > 0,"),
        10,
        20,
        ("expected a number, got a condition",),
    ),
    Mistake(
        "empty-expression",
        ball("invariant: height >= 0", "invariant: ''"),
        11,
        17,
        ("locations.falling.invariant", "must not be empty"),
    ),
    Mistake(
        "initial-outside-bounds",
        ball("height: {initial: 10.0}", "height: {initial: -1.0, bounds: [0, .inf]}"),
        4,
        21,
        ("initial value -1.0 of 'height' is outside its bounds",),
    ),
    Mistake(
        "missing-required-key",
        ball("  - from: falling\n    to: falling", "  - to: falling"),
        13,
        5,
        ("missing key 'from' in edges[0]",),
    ),
    # --- circular signal definitions ---
    Mistake(
        "circular-signals",
        ball(
            "  energy: 0.5*velocity**2 + g*height\n",
            "  energy: 0.5*velocity**2 + g*height\n  p: q + 1\n  q: r * 2\n  r: p\n",
        ),
        8,
        3,
        ("circular definition", "p -> q -> r -> p"),
    ),
    Mistake(
        "self-referencing-signal",
        ball("energy: 0.5*velocity**2 + g*height", "energy: energy + 1"),
        7,
        3,
        ("circular definition", "energy -> energy"),
    ),
    Mistake(
        "circular-only-in-one-location",
        ball(
            "  energy: 0.5*velocity**2 + g*height\n",
            "  energy: 0.5*velocity**2 + g*height\n  power: velocity\n",
        ).replace(
            "    invariant: height >= 0",
            "    signals: {power: energy * power}\n    invariant: height >= 0",
        ),
        12,
        15,
        ("circular definition in location 'falling'", "power -> power"),
    ),
]


def test_ball_is_valid() -> None:
    model = hybrid.load_text(BALL)
    assert isinstance(model, hybrid.Automaton)


@pytest.mark.parametrize("mistake", MISTAKES, ids=[m.id for m in MISTAKES])
def test_mistake_is_explained_at_its_place(mistake: Mistake) -> None:
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load_text(mistake.spec, file="ball.yaml")
    err = info.value
    where = [(pos.line, pos.column, msg) for pos, msg in err.problems]
    match = [msg for line, column, msg in where if (line, column) == (mistake.line, mistake.column)]
    assert match, f"no problem at {mistake.line}:{mistake.column}; got {where}"
    assert any(all(f in msg for f in mistake.says) for msg in match), f"{mistake.says} vs {match}"
    assert err.file == "ball.yaml"


def test_every_problem_is_reported_in_file_order() -> None:
    """Several mistakes in one file: all of them, one located line each, sorted by line."""
    spec = (
        ball("    to: falling", "    to: fallen")
        .replace("reset: {velocity:", "reset: {velocty:")
        .replace("flow: {height: velocity,", "flow: {height: velocty,")
    )
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load_text(spec, file="ball.yaml")
    lines = str(info.value).splitlines()
    assert [line.split(": ", 1)[0] for line in lines] == [
        "ball.yaml:10:20",
        "ball.yaml:14:9",
        "ball.yaml:16:13",
    ]


def test_cli_prints_each_problem_on_its_own_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "ball.yaml"
    path.write_text(
        ball("    to: falling", "    to: fallen").replace("guard: height", "guard: heigth")
    )
    assert cli_main(["validate", str(path)]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{path}:14:9: edge to unknown location 'fallen'; did you mean 'falling'?",
        f"{path}:15:12: unknown name 'heigth'; did you mean 'height'?",
    ]


@pytest.mark.parametrize(
    ("library", "hint"),
    [
        ("uvms_model", "in the hybrid repository, pip install ./uvms_model (the UVMS case study's library)"),
        ("their_lib", "install the package that provides it"),
    ],
)
def test_a_missing_function_library_is_one_error_that_says_what_to_install(
    monkeypatch: pytest.MonkeyPatch, library: str, hint: str
) -> None:
    # every expression reading the library's functions used to add its own error (a
    # UVMS mission without the library: 64 lines, none of them saying what to install)
    import hybrid.reader.build as build

    def missing(name: str) -> None:
        raise LookupError(name)

    monkeypatch.setattr(build, "load_library", missing)
    monkeypatch.setattr(build, "available_libraries", list)
    spec = (
        f"automaton: arm\nuses: [{library}]\nstate: {{x: {{initial: 0.0}}}}\n"
        "signals: {q: 'quintic(t, 0, 0, 0, 1, 1, 0)'}\n"
        "locations: {l: {flow: {x: 'quintic(t, 0, 0, 0, 1, 1, 0) + bias[1]'}}}\n"
    )
    with pytest.raises(hybrid.SpecError) as caught:
        hybrid.load_text(spec)
    lines = str(caught.value).splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith(
        f"<string>:2:8: no installed package registers the function library '{library}' "
        "(entry-point group hybrid.functions; installed: none): "
    )
    assert lines[0].endswith(hint)


@pytest.mark.parametrize("start", ['<?xml version="1.0"?>\n<sspaceex>', "<sspaceex>", "\n  <!-- a model -->\n<sspaceex>"])
def test_a_spaceex_file_given_as_a_spec_says_to_import_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], start: str
) -> None:
    # it said "invalid YAML: mapping values are not allowed" or "got a str value"
    model = tmp_path / "bball.xml"
    model.write_text(start + '<component id="c"/></sspaceex>\n')
    for command in (("validate",), ("simulate", "--t-end", "1")):
        assert cli_main([command[0], str(model), *command[1:]]) == 2
        assert capsys.readouterr().err.strip() == (
            f"{model}:1:1: this is XML, not a YAML spec; a SpaceEx model is imported first: "
            f"hybrid import spaceex {model} --out DIR"
        )
