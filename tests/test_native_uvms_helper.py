from dataclasses import replace
import hybrid
from pathlib import Path
def without_requirements(name):
    mission = hybrid.load(Path("specs") / f"{name}.yaml")
    parts = tuple(replace(c, automaton=replace(c.automaton, requirements=())) for c in mission.components)
    return replace(mission, requirements=(), components=parts)
