"""Case IV's feedforward: the dynamics inverse with preview, then the hysteresis inverse."""

import control as ct
import numpy as np
import pytest

from piezolib.hysteresis import PIModel
from piezolib.problem import paper
from piezolib.problem.stage import VirtualStage
from piezolib.workbook import experiments
from piezolib.workbook.loop import run_loop
from piezolib.workbook.two_dof import two_dof_feedforward

G = paper.plant()
PI = PIModel(thresholds=(0.0, 0.3, 0.6), weights=(0.8, 0.1, 0.05), x0=0.0)
FS = paper.SAMPLING_FREQUENCY_HZ


def smooth_reference(f_Hz=50.0, n=3000):
    t = np.arange(n) / FS
    return 2.0 * np.sin(np.pi * f_Hz * t) ** 2


def test_the_model_follows_the_reference_through_its_own_feedforward():
    """simulate(feedforward(r)) is the ZPETC response of r: within 0.1 % for a 50 Hz
    reference (the model's gain at 500 Hz is 0.984, at 50 Hz 0.9998)."""
    ff = two_dof_feedforward(G, PI, FS)
    r = smooth_reference()
    y = ff.simulate(ff.feedforward(r))
    assert np.abs(y - r).max() < 1e-3 * np.ptp(r)


def test_the_dynamics_inverse_runs_as_float32_sections():
    ff = two_dof_feedforward(G, PI, FS)
    r = smooth_reference()
    w32 = ff.dynamics_inverse(r)
    w64 = ff.dynamics.apply(r)
    assert ff.preview == 2
    assert 0 < np.abs(w32 - w64).max() < 1e-5 * np.abs(w64).max()       # float32, not float64


def test_the_linear_stage_is_tracked_open_loop_to_the_corner_rounding():
    """A stage without hysteresis or noise, open loop: the feedforward's only error is
    ZPETC's zero-phase smoothing, the FIR [c, 1 - 2c, c] with c = -z_u / (1 - z_u)^2 for the
    mirrored zero z_u, which rounds each corner of the triangle by c x slope jump x T."""
    stage = VirtualStage(hysteresis=None, noise_rms_V=0.0)
    identity = PIModel(thresholds=(0.0,), weights=(float(ct.dcgain(G)),), x0=0.0)
    ff = two_dof_feedforward(G, identity, FS)
    v_r = experiments.tracking_reference(50.0, 4)[1]
    err_2dof = run_loop(stage, v_r, feedforward=ff).tracking_error_percent(50.0, range_um=12.0)
    z_u = ff.dynamics.mirrored_zeros[0].real
    c = -z_u / (1 - z_u) ** 2
    slope_jump_um = 2 * (2 * 12.0 * 50.0) / FS           # per sample: 12 um up in half a period
    assert err_2dof == pytest.approx(100 * c * slope_jump_um / 12.0, rel=0.05)
    static = run_loop(stage, v_r, feedforward=identity).tracking_error_percent(50.0, range_um=12.0)
    assert static > 10 * err_2dof


def test_a_plant_without_dc_gain_is_refused():
    s = ct.tf("s")
    with pytest.raises(ValueError, match="G must have a finite nonzero DC gain"):
        two_dof_feedforward(s / (s + 1), PI, FS)


def test_given_sections_are_checked_against_the_zpetc_of_G():
    """The committed export is used as it is, float32 for float32; another filter is refused."""
    from piezolib.workbook import pipeline
    committed = pipeline.study_feedforward_sections("reference")
    ff = two_dof_feedforward(G, PI, FS, sections=committed)
    assert ff.sections is committed and ff.preview == 2
    other = two_dof_feedforward(G * ct.tf([1.0], [1e-3, 1.0]), PI, FS).sections
    with pytest.raises(ValueError, match="sections do not implement the ZPETC"):
        two_dof_feedforward(G, PI, FS, sections=other)
    with pytest.raises(ValueError, match="sections run at"):
        two_dof_feedforward(G, PI, 2 * FS, sections=committed)
