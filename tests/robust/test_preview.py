"""Zero-phase-error tracking feedforward (ZPETC) with preview."""

import control as ct
import numpy as np
import pytest

from piezolib.robust import zpetc


def response(sys, f, dt):
    return np.ravel(sys(np.exp(2j * np.pi * np.asarray(f) * dt)))


def test_a_plant_with_stable_zeros_is_inverted_exactly():
    """No zero outside the circle: G F z^preview = 1 at every frequency."""
    dt = 0.1
    Gd = ct.c2d(ct.tf([1.0], [1.0, 2.0, 1.0]), dt, "zoh")
    ff = zpetc(Gd)
    f = np.linspace(0.01, 4.9, 50)
    z = np.exp(2j * np.pi * f * dt)
    np.testing.assert_allclose(response(Gd, f, dt) * response(ff.F, f, dt) * z ** ff.preview, 1.0,
                               atol=1e-10)
    assert ff.preview == 1 and ff.mirrored_zeros.size == 0


def test_a_sampling_zero_outside_the_circle_leaves_zero_phase_and_unit_dc():
    """Relative degree three at a fast rate: one sampling zero near -3.7 is mirrored."""
    dt = 1e-3
    Gd = ct.c2d(ct.tf([1e6], [1.0, 300.0, 3e4, 1e6]), dt, "zoh")
    ff = zpetc(Gd)
    assert ff.mirrored_zeros.size == 1 and ff.mirrored_zeros[0].real < -3
    assert ff.preview == 2                    # relative degree 1 + one mirrored zero
    f = np.linspace(0.0, 490.0, 80)
    z = np.exp(2j * np.pi * f * dt)
    overall = response(Gd, f, dt) * response(ff.F, f, dt) * z ** ff.preview
    np.testing.assert_allclose(overall.imag, 0.0, atol=1e-9)            # zero phase
    assert overall[0].real == pytest.approx(1.0, abs=1e-12)             # unit DC gain
    np.testing.assert_allclose(overall, response(ff.tracking, f, dt), atol=1e-9)
    assert np.all(np.diff(overall.real) <= 1e-12) and overall.real[-1] > 0   # falls to Nyquist


def test_apply_makes_the_model_follow_a_smooth_reference():
    """The model driven by the feedforward reproduces a slow reference (with preview)."""
    dt = 1e-3
    Gd = ct.c2d(ct.tf([1e6], [1.0, 300.0, 3e4, 1e6]), dt, "zoh")
    ff = zpetc(Gd)
    t = np.arange(4000) * dt
    r = np.sin(2 * np.pi * 2.0 * t) ** 2                   # starts at rest
    y = ct.forced_response(Gd, T=t, U=ff.apply(r)).outputs
    assert np.abs(y - r).max() < 1e-4 * np.abs(r).max() + 1e-12


def test_the_shifted_reference_holds_its_last_value():
    ff = zpetc(ct.c2d(ct.tf([1e6], [1.0, 300.0, 3e4, 1e6]), 1e-3, "zoh"))
    np.testing.assert_array_equal(ff.shifted([1.0, 2.0, 3.0, 4.0]), [3.0, 4.0, 4.0, 4.0])


def test_a_smaller_radius_mirrors_a_lightly_damped_zero():
    dt = 1e-3
    Gd = ct.c2d(ct.tf([1.0, 2.0, 1e4], [1.0, 300.0, 3e4, 1e6]) * 1e2, dt, "zoh")
    exact, mirrored = zpetc(Gd), zpetc(Gd, radius=0.99)
    assert mirrored.mirrored_zeros.size > exact.mirrored_zeros.size
    assert np.all(np.abs(np.roots(np.asarray(mirrored.F.den[0][0]))) < 0.99 + 1e-12)


def test_a_plant_that_blocks_dc_is_refused():
    with pytest.raises(ValueError, match="zero at z = 1"):
        zpetc(ct.tf([1.0, -1.0], [1.0, -0.5], 0.1))


@pytest.mark.parametrize("distance", [1e-12, 1e-8, 1e-7])
def test_a_zero_next_to_one_is_refused_not_inverted(distance):
    # a zero at 1 + 1e-8 passed the old check (within 1e-9): F's gain reached 4e16 and the
    # returned "zero-phase" tracking differed from G F z^p by 17
    G = ct.tf([1, -(1 + distance)], [1, -0.5, 0.06], 0.01)
    with pytest.raises(ValueError, match="zero at z = 1"):
        zpetc(G)


def test_the_returned_tracking_is_what_the_feedforward_achieves():
    G = ct.tf([1, -(1 + 1e-3)], [1, -0.5, 0.06], 0.01)     # near 1, yet well defined
    res = zpetc(G)
    z = np.exp(1j * np.linspace(0, np.pi, 50))
    achieved = np.ravel(G(z)) * np.ravel(res.F(z)) * z ** res.preview
    np.testing.assert_allclose(achieved, np.ravel(res.tracking(z)), rtol=1e-6, atol=1e-9)
