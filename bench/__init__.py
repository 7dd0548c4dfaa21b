"""Benchmarks: they report numbers and are not timed tests (see each module)."""
