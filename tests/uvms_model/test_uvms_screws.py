"""Planar twists: the velocity field they generate, against first principles."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_model.screws import point_velocity, prismatic, revolute

coord = st.floats(-10.0, 10.0, allow_nan=False)


@given(coord, coord, coord, coord)
def test_revolute_fixes_its_axis_point(px: float, py: float, rx: float, ry: float) -> None:
    twist = revolute((px, py))
    assert twist == (1.0, py, -px)
    vx, vy = point_velocity(twist, (px, py))
    assert abs(vx) < 1e-12 and abs(vy) < 1e-12
    # Rigid rotation at unit rate about p: v(r) = z x (r - p).
    vx, vy = point_velocity(twist, (rx, ry))
    assert math.isclose(vx, -(ry - py), abs_tol=1e-12)
    assert math.isclose(vy, rx - px, abs_tol=1e-12)


@given(st.floats(-math.pi, math.pi), coord, coord)
def test_prismatic_is_uniform_translation(angle: float, rx: float, ry: float) -> None:
    u = (3.0 * math.cos(angle), 3.0 * math.sin(angle))
    twist = prismatic(u)
    assert twist[0] == 0.0
    assert math.isclose(math.hypot(twist[1], twist[2]), 1.0, rel_tol=1e-15)
    vx, vy = point_velocity(twist, (rx, ry))
    assert math.isclose(vx, math.cos(angle), abs_tol=1e-15)
    assert math.isclose(vy, math.sin(angle), abs_tol=1e-15)


def test_prismatic_rejects_zero_direction() -> None:
    with pytest.raises(ValueError):
        prismatic((0.0, 0.0))
