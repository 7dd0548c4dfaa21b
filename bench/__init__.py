"""Benchmarks (``make bench``): each contender against its baseline in the same run.

They report numbers and are not timed tests: no absolute time is a pass or a
fail. ``python -m bench`` runs them all and writes ``bench/results.json``.
"""
