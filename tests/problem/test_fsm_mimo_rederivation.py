"""The committed 3 x 3 design re-derived from scratch (slow: the DK-iteration and three SISO
designs, several minutes): it must land within its stated precision of the committed mu_RP."""

import pytest

from piezolib.problem import fsm_mimo, fsm_models

#: The precision the notebook states for the 3 x 3 mu_RP (its claim rows' precision).
MU_PRECISION = 0.01
#: ... and relative to a mu_RP far above 1 (the loops together, not the design).
MU_RELATIVE = 0.005


@pytest.mark.slow
def test_the_dk_design_lands_on_the_committed_mu():
    committed = fsm_mimo.read_mirror_record()
    data = fsm_models.level_blas()
    linear = fsm_models.fit_linear_models(data, (24, 32, 40, 48), 28)
    fresh = fsm_mimo.derive_mirror_design(linear, data.frequency_Hz, committed.params)
    assert fresh.mu_dk == pytest.approx(committed.mu_dk, abs=MU_PRECISION)
    assert fresh.mu_reduced == pytest.approx(committed.mu_reduced, abs=MU_PRECISION)
    assert fresh.K_w.nstates == committed.K_w.nstates
    for i in range(3):
        assert fresh.siso_mu[i] == pytest.approx(committed.siso_mu[i], abs=MU_PRECISION)
    # and the fresh controller verifies like the committed one
    nominal = fsm_mimo.mirror_nominal(linear, data.frequency_Hz, committed.params["nominal_order"])
    a = fsm_mimo.verify_mirror(nominal, committed).table()
    b = fsm_mimo.verify_mirror(nominal, fresh).table()
    for name in a.columns:
        # the three SISO loops together are far from robust (mu_RP about 36): there the
        # precision is relative, as two SISO designs whose own mu agree to 0.01 gave 35.53
        # and 35.59 (0.16 %)
        assert float(b.loc["mu_RP upper", name]) == pytest.approx(
            float(a.loc["mu_RP upper", name]), abs=MU_PRECISION, rel=MU_RELATIVE)
        assert bool(b.loc["stable with every model", name]) == bool(
            a.loc["stable with every model", name])
