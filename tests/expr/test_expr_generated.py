"""Generated functions: each computes what its source says, and those defined with the
same scope share one namespace (a large system keeps thousands of them)."""

from __future__ import annotations

import math

from hybrid.expr.generated import define


def test_functions_of_one_scope_share_a_namespace_and_compute_their_own_source() -> None:
    scope = {"_sqrt": math.sqrt}
    root = define("root", "def root(x):\n    return _sqrt(x)\n", scope)
    halved = define("halved", "def halved(x):\n    return 0.5 * _sqrt(x)\n", dict(scope))
    assert root(16.0) == 4.0 and halved(16.0) == 2.0
    assert root.__globals__ is halved.__globals__
    assert set(root.__globals__) == {"__builtins__", "_sqrt"}  # neither keeps itself there
    assert root.__name__ == "root" and halved.__name__ == "halved"
    assert root.__code__.co_filename == "<hybrid:root>"  # the frame name the simulator reads


def test_another_object_under_the_same_name_gets_its_own_namespace() -> None:
    double = define("twice", "def twice(x):\n    return _f(x)\n", {"_f": lambda x: 2.0 * x})
    triple = define("thrice", "def thrice(x):\n    return _f(x)\n", {"_f": lambda x: 3.0 * x})
    assert double(1.0) == 2.0 and triple(1.0) == 3.0
    assert double.__globals__ is not triple.__globals__


def test_a_source_that_defines_more_than_its_function_keeps_its_namespace() -> None:
    source = "def _half(x):\n    return 0.5 * x\ndef quarter(x):\n    return _half(_half(x))\n"
    quarter = define("quarter", source, {})
    plain = define("plain", "def plain(x):\n    return x\n", {})
    assert quarter(8.0) == 2.0 and plain(8.0) == 8.0
    assert "_half" in quarter.__globals__ and quarter.__globals__ is not plain.__globals__


def test_closures_and_defaults_survive_the_shared_namespace() -> None:
    source = "def make(k, b=1.0):\n    def f(x):\n        return k * x + b\n    return f\n"
    define("make", source, {})  # the first of this scope: its namespace is the shared one
    make = define("make", source, {})
    assert make(3.0)(2.0) == 7.0 and make(3.0, b=0.0)(2.0) == 6.0
