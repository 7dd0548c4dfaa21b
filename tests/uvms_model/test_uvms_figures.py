"""The demo's figures: five per mission, the analogues of the paper's Figs. 7-12 and the FM."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image

from uvms_model.figures import write_figures
from uvms_model.missions import run_mission


def test_five_figures_per_mission_including_the_xy_plane(tmp_path: Path) -> None:
    result = run_mission("uvms_mission_2", rtol=1e-6, atol=1e-9, dt=0.05)
    paths = write_figures(result, tmp_path, "m2")
    names = ["m2_xy.png", "m2_gamma.png", "m2_vehicle.png", "m2_joints.png", "m2_fm.png"]
    assert [p.name for p in paths] == names
    for path in paths:
        height, width, _ = matplotlib.image.imread(path).shape
        assert width >= 700 and height >= 350
