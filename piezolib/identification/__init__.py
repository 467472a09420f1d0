"""System identification: RLS (eq. 1-3), ARX/output-error, exact ZOH inverse.

The four steps of the paper's Fig. 3 on sampled input/output data ``u``,
``y`` [V] at the sampling frequency ``fs`` [Hz]: recursive least squares
(:func:`rls`) on ARX regressors (:func:`fit_arx`), Steiglitz-McBride passes to
the output-error estimate (:func:`fit_output_error`), the exact inverse of the
ZOH discretisation (:func:`d2c`), a numerator refit with the poles fixed
(:func:`refit_numerator`), all in :func:`identify`; validation by simulated
fit (:func:`fit_percent`), residual whiteness (:func:`whiteness`) and an
empirical frequency response.  Returned models have the neutral signal names
``u`` -> ``y``.  Time in seconds, frequencies in rad/s.

arx         recursive least squares (eq. 1-3) and ARX models
oe          output-error models (Steiglitz-McBride passes)
continuous  d2c, ZOH discretisation, numerator refit, :func:`identify`, coefficients
validation  fit, whiteness, empirical frequency response, coefficient table
frf         best linear approximation of a MIMO system from periodic multisines, with its
            noise and nonlinear-distortion variances (robust method)
freqfit     discrete MIMO state-space models fitted to an FRF (frequency-domain subspace)
mimo_hammerstein
            Prandtl-Ishlinskii operators ahead of MIMO linear dynamics, weights by least squares
scheduled   linear models blended by the input's measured RMS level
basis_model
            fixed-pole basis models: causal, nonlinear, LPV in a running input RMS, linear in
            their parameters (one least-squares fit)

Why output-error passes follow ARX, and why the numerator is refitted:
``docs/stage.md``.

Examples
--------
Noise-free data of a known resonance give it back:

>>> import control as ct, numpy as np
>>> G = ct.tf([2e6], [1.0, 200.0, 1e6])
>>> u = np.random.default_rng(0).standard_normal(4000)
>>> y = zoh_simulate(G, u, fs=10e3)
>>> model = identify(u, y, fs=10e3, n_poles=2, n_zeros=0).model
>>> model.input_labels, model.output_labels, round(float(model.dcgain()), 6)
(['u'], ['y'], 2.0)
"""

from piezolib.identification.arx import *          # noqa: F401,F403
from piezolib.identification.oe import *           # noqa: F401,F403
from piezolib.identification.continuous import *   # noqa: F401,F403
from piezolib.identification.validation import *   # noqa: F401,F403
from piezolib.identification.frf import *          # noqa: F401,F403
from piezolib.identification.freqfit import *      # noqa: F401,F403
from piezolib.identification.mimo_hammerstein import *  # noqa: F401,F403
from piezolib.identification.scheduled import *    # noqa: F401,F403
from piezolib.identification.basis_model import *  # noqa: F401,F403
from piezolib.identification import (arx, continuous, oe, validation, frf, freqfit,
                                    mimo_hammerstein, scheduled, basis_model)

__all__ = [*arx.__all__, *oe.__all__, *continuous.__all__, *validation.__all__, *frf.__all__,
           *freqfit.__all__, *mimo_hammerstein.__all__, *scheduled.__all__,
           *basis_model.__all__]
