"""Performance indices: the paper's numbers and the algebraic identities."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_model.chain import Chain, det_ns
from uvms_model.indices import (
    THETA_SV,
    alpha,
    gamma,
    gamma_from_det,
    gamma_max,
    q2_for_gamma,
    w_hat,
)


def test_paper_values() -> None:
    assert THETA_SV == 0.78
    assert gamma(0.78) == pytest.approx(1.0, abs=1e-15)
    assert gamma_max() == pytest.approx(1.0 / math.sin(0.78), rel=1e-15)
    assert gamma_max() == pytest.approx(1.4219, abs=1e-4)
    assert gamma(math.pi / 2) == pytest.approx(gamma_max(), rel=1e-15)
    for g, q2 in ((0.65, 0.475), (1.0, 0.78), (1.05, 0.831)):
        assert q2_for_gamma(g) == pytest.approx(q2, abs=1e-3)
        assert gamma(q2_for_gamma(g)) == pytest.approx(g, rel=1e-14)
    assert w_hat(1.0) == 0.0 and alpha(1.0) == 1.0


@given(st.floats(0.05, 3.0), st.floats(0.2, 1.4))
def test_gamma_is_determinant_ratio(q2: float, theta_sv: float) -> None:
    chain = Chain(a1=0.7, a2=1.3)
    cfg = np.array([0.4, -1.0, 0.3, 0.2, q2, 0.1])
    cfg_sv = cfg.copy()
    cfg_sv[4] = theta_sv
    ratio = gamma_from_det(det_ns(chain, cfg), det_ns(chain, cfg_sv))
    assert ratio == pytest.approx(gamma(q2, theta_sv), rel=1e-10, abs=1e-12)


@given(st.floats(0.01, 1.5))
def test_w_hat_identity(g: float) -> None:
    assert alpha(g) * g == pytest.approx(1.0, rel=1e-15)
    assert w_hat(g) == pytest.approx(alpha(g) ** 2 - 1.0, rel=1e-12, abs=1e-12)
    assert (w_hat(g) > 0) == (g < 1.0) or g == 1.0


def test_q2_for_gamma_rejects_unreachable() -> None:
    with pytest.raises(ValueError):
        q2_for_gamma(1.5)
