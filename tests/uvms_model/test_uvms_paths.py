"""Mission paths: arc length, start point, closure and velocity = d(position)/dt."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from scipy.integrate import quad

from uvms_model.chain import Chain, forward_kinematics
from uvms_model.paths import DeformedCircle, mission1_path, mission2_path, smoothstep5

START_CFG = (0.0, 0.0, 0.0, 0.6, 1.2, -0.9)


def chain_start() -> tuple[tuple[float, float], float]:
    pose = forward_kinematics(Chain(), START_CFG)
    return pose.e, pose.phie


def speed_integral(path: DeformedCircle) -> float:
    def speed(t: float) -> float:
        s = path(t)
        return math.hypot(s.vxe, s.vye)

    value, _ = quad(speed, path.t_start, path.t_end, epsabs=1e-13, epsrel=1e-12, limit=500)
    return float(value)


def polyline_length(path: DeformedCircle, n: int = 400_000) -> float:
    pts = np.array([path(float(t))[:2] for t in np.linspace(path.t_start, path.t_end, n)])
    return float(np.sum(np.hypot(*np.diff(pts, axis=0).T)))


@pytest.mark.parametrize(("factory", "n_pi"), [(mission1_path, 2.0), (mission2_path, 3.0)])
def test_arc_length(factory: Callable[..., DeformedCircle], n_pi: float) -> None:
    start, heading = chain_start()
    path = factory(start, heading)
    assert path.length == pytest.approx(n_pi * math.pi * path.r, rel=1e-12)
    assert speed_integral(path) == pytest.approx(n_pi * math.pi * path.r, rel=1e-6)


def test_r_is_the_perimeter_over_two_pi() -> None:
    start, _ = chain_start()
    path = mission1_path(start, epsilon=0.15)
    assert polyline_length(path) == pytest.approx(2.0 * math.pi * path.r, rel=1e-8)
    circle = mission1_path(start, epsilon=0.0)
    assert circle.r == pytest.approx(math.hypot(1.25, 0.5), rel=1e-13)


def test_start_centre_and_end_points() -> None:
    start, heading = chain_start()
    p1, p2 = mission1_path(start, heading), mission2_path(start, heading, direction=-1)
    for path, offset in ((p1, (1.25, 0.5)), (p2, (1.25, 0.0))):
        s0 = path(0.0)
        assert (s0.xe, s0.ye) == pytest.approx(start, abs=1e-12)
        assert (s0.vxe, s0.vye, s0.wphie) == (0.0, 0.0, 0.0)
        assert path.centre == pytest.approx((start[0] + offset[0], start[1] + offset[1]))
        assert s0.phie == heading
        s_end = path(60.0)
        assert (s_end.vxe, s_end.vye) == (0.0, 0.0)
        assert path(75.0) == s_end
    end1, end2 = p1(60.0), p2(60.0)
    assert (end1.xe, end1.ye) == pytest.approx(start, abs=1e-12)  # one closed lap
    assert (end2.xe, end2.ye) == pytest.approx((start[0] + 2.5, start[1]), abs=1e-12)


@pytest.mark.parametrize("direction", [1, -1])
def test_velocity_is_derivative_of_position(direction: int) -> None:
    start, heading = chain_start()
    h = 1e-4
    for path in (
        mission1_path(start, heading, direction=direction),
        mission2_path(start, heading, direction=direction),
    ):
        for t in np.linspace(0.0, 60.0, 241):
            s = path(float(t))
            sp, sm = path(float(t) + h), path(float(t) - h)
            fd = ((sp.xe - sm.xe) / (2 * h), (sp.ye - sm.ye) / (2 * h))
            assert fd == pytest.approx((s.vxe, s.vye), abs=1e-7)
            assert (sp.phie - sm.phie) / (2 * h) == s.wphie == 0.0


def test_smoothstep_and_validation() -> None:
    assert smoothstep5(0.0) == (0.0, 0.0) and smoothstep5(1.0) == (1.0, 0.0)
    assert smoothstep5(0.5) == (0.5, 1.875)
    with pytest.raises(ValueError):
        DeformedCircle((0.0, 0.0), (1.0, 0.0), turns=1.2)
    with pytest.raises(ValueError):
        DeformedCircle((0.0, 0.0), (0.0, 0.0), turns=1.0)
    with pytest.raises(ValueError):
        DeformedCircle((0.0, 0.0), (1.0, 0.0), turns=1.0, epsilon=1.0)
