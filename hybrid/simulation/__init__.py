"""Event-detected simulation of hybrid automata and systems."""

from hybrid.simulate.engine import METHODS, simulate
from hybrid.simulate.result import CAUSES, Jump, Run, Termination

__all__ = ["CAUSES", "METHODS", "Jump", "Run", "Termination", "simulate"]
