"""Meta-tests of the public API: every keyword documented, unknown keywords refused.

Like python-control's tests: a keyword a user can pass must be explained in the
docstring, and a misspelt one must fail loudly instead of being ignored.
"""

from __future__ import annotations

import inspect
import subprocess
import sys

import pytest

import hybrid

PUBLIC_FUNCTIONS = ["load", "load_text", "simulate", "check", "compose", "reach"]


@pytest.mark.parametrize("name", PUBLIC_FUNCTIONS)
def test_every_keyword_is_documented(name: str) -> None:
    fn = getattr(hybrid, name)
    doc = inspect.getdoc(fn) or ""
    assert doc, f"hybrid.{name} has no docstring"
    assert "Examples" in doc or ">>>" in doc, f"hybrid.{name} has no example"
    for param in inspect.signature(fn).parameters.values():
        if param.kind in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
            continue
        assert param.name in doc, f"hybrid.{name}: keyword '{param.name}' is not documented"


@pytest.mark.parametrize("name", PUBLIC_FUNCTIONS)
def test_unknown_keywords_raise(name: str) -> None:
    with pytest.raises(TypeError, match="unexpected keyword"):
        getattr(hybrid, name)(no_such_keyword=1)


def test_all_names_resolve() -> None:
    for name in hybrid.__all__:
        assert getattr(hybrid, name) is not None
    with pytest.raises(AttributeError):
        hybrid.no_such_thing  # noqa: B018


def test_the_submodules_the_docs_name_are_reached_from_the_package() -> None:
    # hybrid.progress.TerminalLine (simulation-api.md) and hybrid.export.figures_of
    # (plots.md) raised AttributeError unless something had imported them first
    code = (
        "import hybrid\n"
        "print(hybrid.progress.TerminalLine.__name__, hybrid.export.figures_of.__name__,\n"
        "      hybrid.errors.UnknownName.__name__, hybrid.analysis.__name__)\n"
        "try:\n"
        "    hybrid.nothing_of_that_name\n"
        "except AttributeError as e:\n"
        "    print(e)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.splitlines() == [
        "TerminalLine figures_of UnknownName hybrid.analysis",
        "module 'hybrid' has no attribute 'nothing_of_that_name'",
    ]


@pytest.mark.parametrize(
    "spec", ["specs/bouncing_ball.yaml", "docs/examples/tank_system.yaml", "specs/uvms_mission_2.yaml"]
)
def test_a_model_pickles_and_deep_copies_into_one_that_runs_alike(spec: str) -> None:
    # "cannot pickle 'mappingproxy' object": no model could go to another process
    import copy
    import pickle
    from pathlib import Path

    model = hybrid.load(Path(__file__).resolve().parents[2] / spec)
    run = hybrid.simulate(model, t_end=2.0)
    for other in (pickle.loads(pickle.dumps(model)), copy.deepcopy(model)):
        assert type(other) is type(model) and other.name == model.name
        again = hybrid.simulate(other, t_end=2.0)
        assert again.t.tolist() == run.t.tolist() and again.states.tolist() == run.states.tolist()
