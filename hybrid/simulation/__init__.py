"""Event-detected simulation of hybrid automata and systems."""

from hybrid.simulation.engine import METHODS, simulate
from hybrid.simulation.result import CAUSES, Jump, Run, Termination

__all__ = ["CAUSES", "METHODS", "Jump", "Run", "Termination", "simulate"]
