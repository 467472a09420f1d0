"""A hysteresis model of one's own (any class with simulate, feedforward and static_part) runs
through the experiments, the loop and the model selection with no edit elsewhere."""

import numpy as np
import pytest

from piezolib import hysteresis as hy
from piezolib import paper
from piezolib.problem.stage import VirtualStage
from piezolib.workbook import experiments as ex


class Backlash:
    """x = x0 + w0 v + w1 F_r[v]: a two-play operator written from scratch, not a PIModel."""

    def __init__(self, w0=0.6, w1=0.3, r=0.2, x0=0.05):
        self.w0, self.w1, self.r, self.x0 = w0, w1, r, x0

    def _play(self, v, r, y):
        out = np.empty_like(v)
        for k, vk in enumerate(v):
            y = min(max(y, vk - r), vk + r)
            out[k] = y
        return out

    def simulate(self, v):
        v = np.asarray(v, float)
        return self.x0 + self.w0 * v + self.w1 * self._play(v, self.r, v[0] + self.r)

    def feedforward(self, x_r):
        # the exact inverse of a two-play PI operator is another one (thresholds scaled by
        # the slope of the first branch)
        x_r = np.asarray(x_r, float) - self.x0
        W = self.w0 + self.w1
        r_hat = self.w0 * self.r
        z = self._play(x_r, r_hat, x_r[0] + r_hat)
        return x_r / self.w0 - self.w1 / (self.w0 * W) * z

    @property
    def static_part(self):
        return self.w0 + self.w1, self.x0


@pytest.fixture(scope="module")
def stage():
    return VirtualStage(seed=5)


def test_the_toy_model_is_its_own_exact_inverse():
    model = Backlash()
    x_r = 0.5 + 0.4 * np.sin(np.linspace(0, 6 * np.pi, 400))
    np.testing.assert_allclose(model.simulate(model.feedforward(x_r)), x_r, atol=1e-12)


def test_cases_I_to_III_take_a_model_of_ones_own(stage):
    model = Backlash()
    _, v_r = ex.table4_reference(20.0, periods=2)
    I, II, III = (ex.run_case(c, stage, v_r, model, controller=paper.controller())
                  for c in ("I", "II", "III"))
    g, x0 = model.static_part
    assert np.array_equal(I.u_f_V, (v_r - x0) / g)               # Case I: its static part
    assert np.array_equal(II.u_f_V, model.feedforward(v_r))       # Case II: its feedforward
    assert np.array_equal(III.u_f_V, II.u_f_V) and np.any(III.u_b_V != 0)
    assert "Backlash.feedforward" in II.feedforward
    result = ex.hysteresis_test(stage, model, paper.controller(), amplitudes_V=[20.0],
                                periods=3)
    assert np.isfinite(result.table.to_numpy(float)).all()


def test_model_selection_ranks_a_model_of_ones_own():
    truth = Backlash(w0=0.55, w1=0.35, r=0.25)
    v = 1.0 + np.sin(np.linspace(0, 8 * np.pi, 2000))
    x = truth.simulate(v)
    table = hy.validation_table({"own": truth, "linear": Backlash(w0=0.9, w1=0.0)},
                                [(v, x)])
    scores = hy.pooled_rms(table)
    assert scores["own"] < 1e-9 < scores["linear"]


def test_a_model_without_the_protocol_is_refused_by_name(stage):
    _, v_r = ex.table4_reference(10.0, periods=1)
    with pytest.raises(TypeError, match="HysteresisModel"):
        ex.run_case("II", stage, v_r, object())
