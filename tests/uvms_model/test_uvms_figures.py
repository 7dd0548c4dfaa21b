"""The demo's figures: three per mission, the analogues of the paper's Figs. 7-12."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image

from uvms_model.figures import write_figures
from uvms_model.missions import run_mission


def test_three_figures_per_mission(tmp_path: Path) -> None:
    result = run_mission("uvms_mission_2", dense=True)
    paths = write_figures(result, tmp_path, "m2")
    assert [p.name for p in paths] == ["m2_gamma.png", "m2_vehicle.png", "m2_joints.png"]
    for path in paths:
        height, width, _ = matplotlib.image.imread(path).shape
        assert width >= 700 and height >= 350
