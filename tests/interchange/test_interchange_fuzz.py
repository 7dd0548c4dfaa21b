"""Nothing but SpecError escapes the importer, whatever the SpaceEx text.

Hypothesis mutates the bouncing-ball model and its ``.cfg`` (inserting,
deleting and replacing characters, XML and expression syntax included):
importing either works, and the YAML it writes reads back, or ends in one
SpecError with a position in one of the two files.
"""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from support import REPO, mutate

from hybrid.errors import SpecError
from hybrid.interchange import import_spaceex_text
from hybrid.reader.yamlpos import read_yaml_text

FOLDER = REPO / "tests" / "data" / "spaceex" / "bball_nondet_revised"
XML = (FOLDER / "bball_nondet_revised.xml").read_text(encoding="latin-1")
CFG = (FOLDER / "bball_nondet_revised.cfg").read_text()
ALPHABET = st.sampled_from(list("<>/=\"'&;!-[]{}():|^*+.,# \n\t0123456789xvwgcth_ael"))


def _mutate(draw: st.DrawFn, text: str) -> str:
    return mutate(draw, text, ALPHABET, st.integers(0, 3))


@st.composite
def mutated(draw: st.DrawFn) -> tuple[str, str]:
    return _mutate(draw, XML), _mutate(draw, CFG)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutated_models_import_or_fail_with_a_position(pair: tuple[str, str]) -> None:
    xml, cfg = pair
    try:
        result = import_spaceex_text(xml, cfg, xml_file="m.xml", cfg_file="m.cfg")
    except SpecError as exc:
        assert exc.file in ("m.xml", "m.cfg")
        assert exc.line >= 1 and exc.column >= 1
        return
    for name, text in result.files.items():
        read_yaml_text(text, name)
