"""Bad input to the toolkit's public functions: a specific exception that names the argument.

Each entry of ``CASES`` is a valid call of one public function.  Every argument listed in
its ``corrupt`` map is replaced, one at a time, by each bad value of its kind (NaN, inf,
empty, wrong shape or dtype, non-positive, a discrete / improper / NaN-coefficient model,
absurd scale), and the call must raise ValueError or TypeError whose message names the
argument.  ``test_every_public_function_is_swept`` keeps the table complete: every public
function of the toolkit (the ``__all__`` of its packages) has a valid call and bad values here.
Classes are exempt: their constructors are exercised through the functions that build them.
"""

import importlib
import inspect
import pathlib
import re
from dataclasses import replace

import control as ct
import numpy as np
import pytest

from sweep import bad_calls

TOOLKIT = ("piezolib.robust", "piezolib.identification", "piezolib.hysteresis",
           "piezolib.uncertainty", "piezolib.signals", "piezolib.metrics")

FS = 1000.0
G = ct.ss(ct.tf([2.0], [1.0, 3.0, 2.0]))               # stable, strictly proper
K = ct.ss(ct.tf([1.0, 2.0], [1.0, 10.0]))              # stable, proper
P = ct.ss(G.A, np.c_[G.B, G.B], np.r_[G.C, -G.C], np.zeros((2, 2)))   # one w, z; one u, y
OMEGA = np.logspace(-1, 2, 30)
RNG = np.random.default_rng(0)
U = RNG.standard_normal(400)
Y = np.convolve(U, [0.0, 0.5, 0.25], mode="full")[:400] + 1e-3 * RNG.standard_normal(400)
G3 = ct.tf([1.0], [1.0, 3.0, 3.0, 1.0])                # the uncertainty tools' plant form
KD = ct.ss(ct.c2d(K, 1 / FS, "tustin"))                # a discrete controller
P_MU = ct.ss(G.A, np.c_[G.B, G.B, G.B], np.r_[G.C, G.C, -G.C], np.zeros((3, 3)))  # w1, w2, u; z1, z2, y
M3 = RNG.standard_normal((3, 3)) + 1j * RNG.standard_normal((3, 3))

MSET = importlib.import_module("piezolib.uncertainty").model_set(G3, 0.05)
G3_SIX = ct.tf([1.0, 3.0, 3.0, 1.0], np.poly([-1.0, -2.0, -3.0, -4.0, -5.0, -6.0]))  # 6 poles, 3 zeros
RECORD = importlib.import_module("piezolib.records").Record(U, Y, FS)
SOS = importlib.import_module("piezolib.robust").controller_sos(KD)
DATA = pathlib.Path(__file__).resolve().parents[1] / "data"

_hy = importlib.import_module("piezolib.hysteresis")
DAHL = _hy.DahlModel(alpha1=236.0, alpha2=335.4, beta1=0.0, beta2=2.56, gamma_a=30.0, g_a=1.28,
                     form="bliman_sorine", x0=-0.15, start="rest")
PI = _hy.PIModel((0.0, 0.5, 1.0), (0.8, 0.2, 0.1), x0=0.0)
V = 3 * np.sin(np.linspace(0, 13, 400))           # two and a bit periods [V]
X = DAHL.simulate(V)
FIT = _hy.fit_dahl([(V, X)], gamma_a=30.0, start="rest", starts=1, stride=10)
TABLE = _hy.validation_table({"Dahl": DAHL}, [(V, X)])
LOOPS = {"empty": [], "text": "abc", "not pairs": [V], "nan": [(np.r_[V[:-1], np.nan], X)],
         "complex": [(V + 1j, X)], "unequal lengths": [(V, X[:300])], "2-D": [(np.c_[V, V], X)]}

# periodic multisine records (N, channels, realisations, periods) and an FRF for identification
_X = np.zeros((33, 2), complex)
_X[1:12] = np.exp(2j * np.pi * RNG.random((11, 2)))
_MS = np.fft.irfft(_X, n=64, axis=0)
FRF_U = np.repeat(np.concatenate([np.einsum("nc,cr->ncr", _MS, [[1, 1], [1, -1]]),
                                  np.einsum("nc,cr->ncr", _MS, [[1, -1], [1, 1]])], axis=2)[..., None],
                  2, axis=3)
FRF_Y = 2 * FRF_U + 1e-6 * RNG.standard_normal(FRF_U.shape)
GD = ct.ss(ct.tf([0.2, 0.1], [1.0, -1.2, 0.5], 1 / FS))
FRF_F = np.linspace(5.0, 450.0, 40)
FRF_G = GD(np.exp(2j * np.pi * FRF_F / FS)).reshape(1, 1, -1)
PERIODIC = {"nan": np.where(FRF_U == FRF_U[0, 0, 0, 0], np.nan, FRF_U), "complex": FRF_U + 1j,
            "text": "abc", "5-D": FRF_U[..., None], "one period": FRF_U[..., :1]}
FRF_BAD = {"nan": np.where(FRF_G == FRF_G[0, 0, 0], np.nan, FRF_G), "text": "abc",
           "4-D": FRF_G[..., None], "too few lines": FRF_G[..., :5]}
FREQUENCIES = {"nan": np.r_[FRF_F[:-1], np.nan], "decreasing": FRF_F[::-1],
               "above Nyquist": FRF_F * 10, "text": "abc", "2-D": np.c_[FRF_F, FRF_F]}
ORDER = {"zero": 0, "text": "x", "float": 2.5, "too large": 10 ** 6}
WEIGHT = {"negative": -np.ones(40), "nan": np.full(40, np.nan), "wrong shape": np.ones(7),
          "text": "abc"}
DISCRETE = {"continuous": G, "not a model": np.ones((2, 2))}
BASIS_BAD = {"u": {"1-D": [U], "nan": [np.r_[U[:-1], np.nan][:, None]], "text": "abc"},
             "poles": {"on the circle": [1.0], "lower half": [0.3 - 0.4j], "empty": [],
                       "nan": [np.nan]},
             "branches": {"empty": [], "unknown function": [("tanh", 0)], "negative power": [("u", -1)],
                          "repeated": [("u", 0), ("u", 0)], "text": "u"},
             "window_samples": {"zero": 0.0, "below one": 0.5, "nan": np.nan},
             "input_scale": {"zero": 0.0, "negative": -1.0, "nan": np.nan}}



class InTmp(str):
    """A path inside the test's temporary directory (resolved by the test)."""


def resolve(kwargs, tmp_path):
    return {k: tmp_path / v if isinstance(v, InTmp) else v for k, v in kwargs.items()}


def call(qualname, kwargs):
    if qualname == "robust.time_scale_of":            # the one *args function
        return function(qualname)(*kwargs["systems"])
    return function(qualname)(**kwargs)

# bad values by kind of argument
SIGNAL = {"nan": np.r_[U[:-1], np.nan], "inf": np.r_[U[:-1], np.inf], "empty": np.array([]),
          "2-D": np.c_[U, U], "complex": U + 1j, "text": "abc"}
GRID = {"nan": np.r_[OMEGA[:-1], np.nan], "inf": np.r_[OMEGA[:-1], np.inf],
        "empty": np.array([]), "2-D": np.c_[OMEGA, OMEGA], "complex": OMEGA + 1j, "text": "abc"}
POSITIVE = {"zero": 0.0, "negative": -1.0, "nan": np.nan, "inf": np.inf, "text": "x"}
LTI = {"nan coefficient": ct.ss([[np.nan]], [[1.0]], [[1.0]], [[0.0]]),
       "discrete": ct.ss(ct.tf([1.0], [1.0, -0.5], 0.001)),
       "not a model": np.ones((2, 2))}
LTI_PROPER = {**LTI, "improper": ct.tf([1.0, 0.0, 0.0], [1.0, 1.0])}
LTI_STABLE = {**LTI_PROPER, "unstable": ct.ss(ct.tf([1.0], [1.0, -1.0]))}
LTI_DISCRETE = {"nan coefficient": ct.ss([[np.nan]], [[1.0]], [[1.0]], [[0.0]], 1 / FS),
                "continuous": K, "not a model": np.ones((2, 2))}
SAMPLED_CONTROLLER = {**LTI_DISCRETE, "another sample time": ct.ss(ct.c2d(K, 2 / FS, "tustin"))}
L2 = ct.append(G, K * G)                                 # a 2 x 2 loop, stable closed loop
I2 = ct.ss([], [], [], np.eye(2))
LOOP_PAIR = {"nan coefficient": ct.ss([[np.nan]], [[1.0]], [[1.0]], [[0.0]]),
             "not a model": np.ones((2, 2))}
LOOP = {**LOOP_PAIR, "not square": ct.ss(G.A, G.B, np.r_[G.C, G.C], np.zeros((2, 1))),
        "unstable closed loop": ct.append(ct.ss(ct.tf([20.0], [1.0, 3.0, 3.0, 1.0])), G),
        "ill-posed": ct.ss([], [], [], -np.eye(2))}
SKEW = {"nan": np.nan, "inf": np.inf, "text": "x"}
MATRIX_STACK = {"nan": np.where(np.eye(3) == 1, np.nan, M3), "empty": np.zeros((0, 3, 3)),
                "1-D": np.ones(3), "text": "abc"}

CASES = {
    # robust
    "robust.frequency_grid": (dict(omega_min=1.0, omega_max=10.0, n=20),
                              {"omega_min": POSITIVE, "omega_max": POSITIVE,
                               "n": {"zero": 0, "one point": 1, "fraction": 20.5, "text": "x",
                                     "too many": 10 ** 9}}),
    "robust.balance": (dict(sys=G), {"sys": {k: v for k, v in LTI.items() if k != "discrete"}}),  # any dt
    "robust.realize": (dict(sys=G), {"sys": LTI}),
    "robust.scale_time": (dict(sys=G, omega_s=10.0), {"sys": LTI, "omega_s": POSITIVE}),
    "robust.max_singular_value": (dict(sys=G, omega=OMEGA), {"sys": LTI, "omega": GRID}),
    "robust.hinf_norm": (dict(sys=G, omega=OMEGA), {"sys": LTI_STABLE, "omega": GRID}),
    "robust.bandwidth": (dict(sys=G, omega=OMEGA), {"sys": LTI, "omega": GRID}),
    "robust.loop_functions": (dict(G=G, K=K), {"G": LTI, "K": LTI}),
    "robust.closed_loop_poles": (dict(G=G, K=K), {"G": LTI, "K": LTI}),
    "robust.is_stable": (dict(G=G, K=K), {"G": LTI, "K": LTI}),
    "robust.lower_lft": (dict(P=P, K=K), {"P": LTI, "K": LTI, "omega_s": POSITIVE}),
    "robust.lft_response": (dict(P=P, K=K, omega=OMEGA),
                            {"P": LTI, "K": LTI, "omega": GRID, "omega_s": POSITIVE}),
    "robust.lft_hinf_norm": (dict(P=P, K=K, omega=OMEGA), {"P": LTI, "K": LTI, "omega": GRID}),
    "robust.mussv": (dict(M=M3, blk=[(1, 1), (2, 2)]),
                     {"M": MATRIX_STACK, "blk": {"too large": [(2, 2), (2, 2)],
                                                 "zero size": [(0, 0), (3, 3)],
                                                 "text": "abc"},
                      "omega": {"negative": [-1.0], "complex": [1j], "nan": [np.nan]},
                      "tol": {**POSITIVE, "one": 1.0}}),
    "robust.hinfsyn": (dict(P=P), {"P": LTI_PROPER}),
    "robust.fit_magnitude": (dict(omega=OMEGA, magnitude=1 / np.abs(1j * OMEGA + 1), order=1),
                             {"omega": GRID, "magnitude": SIGNAL}),
    "robust.reduce_controller": (dict(K=K, order=1), {"K": LTI}),
    "robust.hankel_singular_values": (dict(K=K), {"K": LTI}),
    "robust.discretize": (dict(K=K, fs=FS, check_Hz=100.0),
                          {"K": LTI, "fs": POSITIVE,
                           "G": {"nan coefficient": LTI["nan coefficient"], "not a model": np.ones(2),
                                 "wrong shape": L2}}),
    "robust.loop_margins": (dict(G=G, K=K), {"G": LTI, "K": LTI}),
    "robust.disk_margin_mimo": (dict(L=L2), {"L": LOOP, "omega": GRID, "skew": SKEW}),
    "robust.loop_at_a_time_disk_margins": (dict(L=L2), {"L": LOOP, "omega": GRID,
                                                         "skew": SKEW}),
    "robust.export_mimo": (dict(Kd=KD, name="K_test"),
                           {"Kd": LTI_DISCRETE, "name": {"not an identifier": "1 K", "number": 3},
                            "form": {"unknown": "balanced"}, "rtol": POSITIVE,
                            "n_time": {"zero": 0, "too large": 10 ** 7, "text": "x"},
                            "seed": {"negative": -1, "text": "x"}}),
    "robust.c_header": (dict(controller=importlib.import_module("piezolib.robust").export_mimo(KD)),
                        {"controller": {"not an export": np.ones(3), "a model": KD,
                                        "sections": SOS}}),
    "robust.loop_margins_mimo": (dict(P=L2, K=I2),
                                 {"P": {**LOOP_PAIR, "wrong shape": ct.ss(G.A, G.B, np.r_[G.C, G.C, G.C], np.zeros((3, 1)))},
                                  "K": {**LOOP_PAIR, "positive feedback": ct.ss([], [], [], -5 * np.eye(2))},
                                  "omega": GRID, "skew": SKEW,
                                  "input_output": {"text": "yes", "number": 1}}),
    # identification
    "identification.fit_arx": (dict(u=U, y=Y, fs=FS, na=2, nb=2),
                               {"u": SIGNAL, "y": SIGNAL, "fs": POSITIVE}),
    "identification.fit_output_error": (dict(u=U, y=Y, fs=FS, na=2, nb=2),
                                        {"u": SIGNAL, "y": SIGNAL, "fs": POSITIVE}),
    "identification.identify": (dict(u=U, y=Y, fs=FS, n_poles=2, n_zeros=1),
                                {"u": SIGNAL, "y": SIGNAL, "fs": POSITIVE}),
    "identification.fit_percent": (dict(y=Y, y_hat=Y + 0.01), {"y": SIGNAL, "y_hat": SIGNAL}),
    "identification.excitation_band": (dict(u=U, fs=FS),
                                       {"u": SIGNAL, "fs": POSITIVE,
                                        "share": {**POSITIVE, "one": 1.0}}),
    "identification.whiteness": (dict(residual=U), {"residual": SIGNAL}),
    "identification.empirical_frequency_response": (dict(u=U, y=Y, fs=FS, nperseg=128),
                                                    {"u": SIGNAL, "y": SIGNAL, "fs": POSITIVE}),
    # signals and metrics
    "signals.time_vector": (dict(duration_s=1.0, fs=FS), {"duration_s": POSITIVE, "fs": POSITIVE}),
    "signals.triangle": (dict(peak=1.0, frequency_Hz=5.0, fs=FS),
                         {"frequency_Hz": POSITIVE, "fs": POSITIVE}),
    "signals.chirp": (dict(amplitude=1.0, f0_Hz=1.0, f1_Hz=10.0, duration_s=1.0, fs=FS),
                      {"f0_Hz": POSITIVE, "f1_Hz": POSITIVE, "duration_s": POSITIVE,
                       "fs": POSITIVE}),
    "metrics.tracking_error": (dict(x_r=U, x=Y), {"x_r": SIGNAL, "x": SIGNAL}),
    "metrics.tracking_error_percent": (dict(x_r=U, x=Y), {"x_r": SIGNAL, "x": SIGNAL}),
    "metrics.peak_to_peak_error_percent": (dict(x_r=U, x=Y), {"x_r": SIGNAL, "x": SIGNAL}),
    "metrics.tracking_errors_percent": (dict(x_r=U, X=np.column_stack([Y, Y])),
                                        {"x_r": SIGNAL,
                                         "X": {"nan": np.column_stack([Y, np.r_[Y[:-1], np.nan]]),
                                               "1-D": Y, "rows": np.column_stack([Y, Y])[:-1],
                                               "text": "abc"}}),
    # uncertainty
    "uncertainty.model_set": (dict(G=ct.tf([1.0], [1.0, 3.0, 2.0]), spread=0.05),
                              {"G": LTI_PROPER, "spread": POSITIVE}),   # unstable G allowed
    "uncertainty.parametric_stability_margin": (dict(G=ct.tf([1.0], [1.0, 3.0, 2.0])),
                                                {"G": LTI_PROPER}),
    # hysteresis
    "hysteresis.hysteresis_measure": (dict(v=np.sin(np.linspace(0, 13, 400)),
                                           x=np.sin(np.linspace(0, 13, 400) - 0.1)),
                                      {"v": SIGNAL, "x": SIGNAL}),
    # second batch
    "robust.to_scaled": (dict(sys=G, omega_s=10.0), {"sys": LTI, "omega_s": POSITIVE}),
    "robust.least_damped_frequency": (dict(K=K, omega_max=100.0),
                                      {"K": LTI, "omega_max": POSITIVE}),
    "robust.sampled_loop_radius": (dict(G=G, Kd=KD), {"G": LTI, "Kd": LTI_DISCRETE}),
    "robust.delay_tolerance": (dict(G=G, Kd=KD), {"G": LTI, "Kd": LTI_DISCRETE}),
    "robust.controller_sos": (dict(Kd=KD), {"Kd": LTI_DISCRETE}),
    "identification.rls": (dict(regressors=np.c_[U, np.roll(U, 1)], y=Y),
                           {"regressors": {"nan": np.c_[SIGNAL["nan"], U], "1-D": U,
                                           "complex": np.c_[U, U] + 1j, "text": "abc",
                                           "huge": 1e200 * np.c_[U, np.roll(U, 1)],
                                           "tiny": 1e-200 * np.c_[U, np.roll(U, 1)]},
                            "y": SIGNAL, "initial_gain": POSITIVE}),
    "identification.arx_regressors": (dict(u=U, y=Y, na=2, nb=2), {"u": SIGNAL, "y": SIGNAL}),
    "identification.zoh_simulate": (dict(sys=G, u=U, fs=FS),
                                    {"sys": LTI, "u": SIGNAL, "fs": POSITIVE}),
    "metrics.improvement_percent": (dict(before=2.0, after=1.0),
                                    {"before": POSITIVE, "after": {"nan": np.nan, "text": "x"}}),
    "metrics.mean_interval": (dict(values=[1.0, 2.0, 4.0]),
                              {"values": {"nan": [1.0, np.nan], "one draw": [1.0], "scalar": 2.0,
                                          "complex": [1j, 2.0], "text": "abc"},
                               "axis": {"out of range": 1, "text": "x"},
                               "confidence": {**POSITIVE, "one": 1.0}}),
    "uncertainty.perturbed_plant": (dict(G=G3, spread=0.05, offsets=[1, -1, 0]),
                                    {"G": LTI_PROPER, "spread": POSITIVE,
                                     "offsets": {"nan": [np.nan, 0, 0], "wrong length": [1, 1],
                                                 "text": "abc"}}),
    "uncertainty.relative_error_bound": (dict(G=G3, spread=0.05, omega=OMEGA),
                                         {"G": LTI_PROPER, "spread": POSITIVE, "omega": GRID}),
    "uncertainty.stability_gauge": (dict(G=G3, K=K, omega=OMEGA),
                                    {"G": LTI_PROPER, "K": LTI, "omega": GRID}),
    "uncertainty.small_gain_spread": (dict(G=G3, K=K, omega=OMEGA),
                                      {"G": LTI_PROPER, "K": LTI, "omega": GRID,
                                       "rtol": {**POSITIVE, "below float resolution": 1e-300}}),
    "uncertainty.fit_covering_weight": (dict(omega=OMEGA, envelope=0.1 + OMEGA / 100, order=1),
                                        {"omega": GRID, "envelope": SIGNAL}),
    "uncertainty.inverse_notch_weight": (
        dict(gain=0.02, notches=[(10.0, 3.5, 0.05)], lowpass_rad_s=5.0, lowpass_dc_gain=1.0,
             lowpass_hf_gain=1e-3),
        {"gain": POSITIVE, "lowpass_rad_s": POSITIVE, "lowpass_dc_gain": POSITIVE,
         "lowpass_hf_gain": {k: v for k, v in POSITIVE.items() if k != "zero"},
         "notches": {"nan": [(np.nan, 3.5, 0.05)], "text": "abc", "not triples": [(10.0, 3.5)],
                     "zero pole damping": [(10.0, 3.5, 0.0)], "negative frequency": [(-1.0, 1, 1)]}}),
    "robust.sensitivity_weight": (
        dict(low_frequency_bound=0.003, high_frequency_bound=2.0, bandwidth_rad_s=10.0, order=1),
        {"low_frequency_bound": POSITIVE, "high_frequency_bound": POSITIVE,
         "bandwidth_rad_s": POSITIVE, "order": {"zero": 0, "fraction": 1.5, "text": "x"}}),
    "robust.complementary_sensitivity_weight": (
        dict(low_frequency_bound=1.5, high_frequency_bound=1e-4, bandwidth_rad_s=10.0, order=2),
        {"low_frequency_bound": POSITIVE, "high_frequency_bound": POSITIVE,
         "bandwidth_rad_s": POSITIVE, "order": {"zero": 0, "fraction": 1.5, "text": "x"}}),
    "hysteresis.hysteresis_percent": (dict(v=np.sin(np.linspace(0, 13, 400)),
                                           x=np.sin(np.linspace(0, 13, 400) - 0.1)),
                                      {"v": SIGNAL, "x": SIGNAL}),
    # third batch
    "robust.musyn": (dict(P=P_MU, blk=[(1, 1), (1, 1)], omega=OMEGA, max_iter=1),
                     {"P": LTI_PROPER, "omega": GRID,
                      "blk": {"too large": [(2, 2), (2, 2)], "text": "abc"}}),
    "identification.pole_pairs": (dict(sys=G), {"sys": LTI}),
    "identification.d2c": (dict(sysd=KD), {"sysd": {"continuous": K, "not a model": np.ones(2),
                                                     "nan coefficient": LTI_DISCRETE["nan coefficient"]}}),
    "identification.least_squares": (dict(phi=np.c_[U, np.roll(U, 1)], target=Y),
                                     {"phi": {"nan": np.c_[SIGNAL["nan"], U], "1-D": U, "text": "abc"},
                                      "target": SIGNAL}),
    "uncertainty.coverage": (dict(weight=ct.tf([1.0, 1.0], [0.1, 1.0]), omega=OMEGA,
                                  envelope=0.5 * np.ones(OMEGA.size)),
                             {"weight": LTI_STABLE, "omega": GRID,
                              "envelope": {**SIGNAL, "wrong length": np.ones(3)}}),
    "uncertainty.relative_errors": (dict(mset=MSET, omega=OMEGA), {"omega": GRID}),
    "uncertainty.relative_error_envelope": (dict(mset=MSET, omega=OMEGA), {"omega": GRID}),
    "uncertainty.envelope_peak": (dict(mset=MSET, omega=OMEGA), {"omega": GRID}),
    "uncertainty.member_closed_loop_poles": (dict(mset=MSET, K=K), {"K": LTI_PROPER}),
    "uncertainty.unstable_members": (dict(mset=MSET, K=K), {"K": LTI_PROPER}),
    # tracking over a model set: sampled members and loops, reference feedforward
    "uncertainty.random_model_set": (dict(G=G3, spread=0.05, count=5),
                                     {"G": LTI_PROPER, "spread": POSITIVE,
                                      "count": {"zero": 0, "fraction": 2.5, "text": "x"},
                                      "seed": {"negative": -1, "text": "x"}}),
    "uncertainty.member_zoh_coefficients": (dict(mset=MSET, dt=1 / FS),
                                            {"mset": {"a plant": G3, "text": "x"},
                                             "dt": POSITIVE}),
    "uncertainty.sampled_loop_poles": (dict(mset=MSET, Kd=KD, dt=1 / FS),
                                       {"mset": {"a plant": G3}, "Kd": SAMPLED_CONTROLLER,
                                        "dt": POSITIVE,
                                        "delay_samples": {"negative": -1, "fraction": 1.5}}),
    "uncertainty.sampled_loop_unstable": (dict(mset=MSET, Kd=KD, dt=1 / FS),
                                          {"mset": {"a plant": G3}, "Kd": SAMPLED_CONTROLLER,
                                           "dt": POSITIVE, "delay_samples": {"negative": -1}}),
    "uncertainty.sampled_loop_spread": (dict(G=G3, Kd=KD, dt=1 / FS),
                                        {"G": LTI_PROPER, "Kd": SAMPLED_CONTROLLER,
                                         "dt": POSITIVE, "levels": {"one": 1, "text": "x"},
                                         "spread_max": {**POSITIVE, "one": 1.0},
                                         "rtol": POSITIVE}),
    "uncertainty.sampled_parametric_margin": (dict(G=G3, Kd=KD, samples=50),
                                              {"G": LTI_PROPER, "Kd": LTI_DISCRETE,
                                               "delay_samples": {"negative": -1, "fraction": 1.5,
                                                                 "huge": 10 ** 6},
                                               "spread_max": POSITIVE, "rtol": POSITIVE,
                                               "samples": {"negative": -1, "fraction": 2.5,
                                                           "huge": 10 ** 9},
                                               "known": {"pair": (0.1, 0.2), "text": "abc",
                                                         "reversed": (0.2, 0.1, np.zeros(3)),
                                                         "offsets": (0.1, 0.2, np.ones(2))}}),
    "robust.expm_stack": (dict(A=np.zeros((2, 3, 3))),
                          {"A": {"nan": np.full((2, 2), np.nan), "1-D": np.ones(3),
                                 "not square": np.ones((2, 3)), "text": "abc"}}),
    "robust.zpetc": (dict(Gd=ct.c2d(G3, 1 / FS, "zoh")),
                     {"Gd": {"continuous": G3, "not a model": np.ones((2, 2)),
                             "zero at z = 1": ct.tf([1.0, -1.0], [1.0, -0.5], 1 / FS),
                             "improper": ct.tf([1.0, 0.0, 0.0], [1.0, -0.5], 1 / FS),
                             "no sample time": ct.tf([1.0], [1.0, -0.5], True)},
                      "radius": {**POSITIVE, "above one": 2.0}}),
    "hysteresis.simulate_dahl": (dict(model=DAHL, v=3 * np.sin(np.linspace(0, 13, 400))),
                                 {"v": SIGNAL}),
    "hysteresis.feedforward": (dict(model=DAHL, x_r=3 * np.sin(np.linspace(0, 13, 400))),
                               {"x_r": SIGNAL}),
    "hysteresis.check_hysteresis_model": (dict(name="model", model=DAHL),
                                          {"model": {"number": 2.0, "text": "dahl",
                                                     "a class": _hy.DahlModel, "none": None}}),
    # fourth batch
    "robust.scaled_coefficients": (dict(num=[1.0, 2.0], den=[1.0, 3.0, 2.0], omega_s=10.0),
                                   {"omega_s": POSITIVE}),
    "robust.from_scaled": (dict(sys=G, omega_s=10.0), {"sys": LTI, "omega_s": POSITIVE}),
    "robust.modal_controller": (dict(K=K), {"K": LTI}),
    "robust.pointwise_lower_bound": (dict(P=P_MU, nmeas=1, ncon=1, omega=OMEGA),
                                     {"P": LTI_PROPER, "omega": GRID}),
    "identification.check_io": (dict(u=U, y=Y), {"u": SIGNAL, "y": SIGNAL}),
    "identification.zoh_coefficients": (dict(sys=G, dt=1 / FS), {"sys": LTI, "dt": POSITIVE}),
    "identification.monic_coefficients": (dict(sys=G, n_poles=2, n_zeros=0), {"sys": LTI}),
    "uncertainty.set_response": (dict(mset=MSET, omega=OMEGA), {"omega": GRID}),
    "uncertainty.weight_certified_spread": (
        dict(weight=ct.tf([1.0, 1.0], [0.1, 1.0]), G=G3, K=K, omega=OMEGA),
        {"weight": LTI_STABLE, "G": LTI_PROPER, "K": LTI_PROPER, "omega": GRID}),
    "hysteresis.strokes": (dict(u=np.sin(np.linspace(0, 13, 400))), {"u": SIGNAL}),
    "hysteresis.dahl_hysteresis": (dict(model=DAHL, x=np.sin(np.linspace(0, 13, 400))), {"x": SIGNAL}),
    "hysteresis.monotone_path": (dict(v=np.sin(np.linspace(0, 13, 400)), x=np.sin(np.linspace(0, 13, 400))), {"v": SIGNAL, "x": SIGNAL}),
    "hysteresis.split_record": (dict(v=np.sin(np.linspace(0, 13, 400)), x=np.sin(np.linspace(0, 13, 400))), {"v": SIGNAL, "x": SIGNAL,
                                                      "fraction": {"zero": 0.0, "one": 1.0,
                                                                   "nan": np.nan, "text": "x"}}),
    "hysteresis.loop_scores": (dict(x_model=np.sin(np.linspace(0, 13, 400)), v=np.sin(np.linspace(0, 13, 400)), x=np.sin(np.linspace(0, 13, 400))),
                               {"x_model": SIGNAL, "v": SIGNAL, "x": SIGNAL}),
    # fifth batch
    "robust.time_scale_of": (dict(systems=(G, K)), {"systems": {"nan coefficient": (G, LTI["nan coefficient"]),
                                                               "not a model": (G, np.ones(2))}}),
    "robust.with_signals": (dict(sys=G, inputs=["u"], outputs=["y"], name="G"),
                            {"sys": {k: v for k, v in LTI.items() if k != "discrete"},   # keeps dt
                             "inputs": {"wrong count": ["a", "b"], "not names": [1.5]},
                             "outputs": {"wrong count": ["a", "b"], "not names": [1.5]},
                             "name": {"number": 3.0}}),
    "robust.parse_blk": (dict(blk=[(1, 1), (2, 0)], p=3, q=3),
                         {"blk": {"text": "abc", "empty": [], "not pairs": [(1, 2, 3)],
                                  "fractional": [(1.5, 1)], "nan": [(np.nan, 1)]},
                          "p": {"negative": -1, "text": "x", "fractional": 2.5, "mismatch": 4},
                          "q": {"negative": -1, "text": "x", "mismatch": 4}}),
    "robust.block_slices": (dict(blocks=importlib.import_module("piezolib.robust").parse_blk([(1, 1), (2, 0)])),
                            {"blocks": {"text": "abc", "empty": [], "not pairs": [(1, 2, 3)]}}),
    "robust.scaled_plant": (dict(P=P_MU, blk=[(1, 1), (1, 1)], d_tfs=[ct.tf([1.0, 2.0], [1.0, 1.0])],
                                 nmeas=1, ncon=1),
                            {"P": LTI_PROPER, "blk": {"text": "abc", "too large": [(2, 2), (2, 2)]},
                             "d_tfs": {"too many": [ct.tf([1.0, 2.0], [1.0, 1.0])] * 3, "one model": ct.tf([1.0], [1.0, 1.0]), "not a model": [np.ones(2)],
                                       "unstable": [ct.tf([1.0, 2.0], [1.0, -1.0])],
                                       "nan coefficient": [ct.tf([np.nan, 1.0], [1.0, 1.0])]},
                             "nmeas": {"zero": 0, "text": "x", "too many": 5},
                             "ncon": {"zero": 0, "text": "x", "too many": 5}}),
    "robust.fixed_order_musyn": (dict(P=P_MU, blk=[(1, 1), (1, 1)], K0=K, omega=np.logspace(-1, 2, 16),
                                      max_iter=1, refinements=0, k_step_iterations=2),
                                 {"P": LTI_PROPER, "K0": LTI_PROPER, "omega": GRID,
                                  "blk": {"text": "abc", "too large": [(2, 2), (2, 2)]},
                                  "rtol": POSITIVE, "trust_radius": POSITIVE,
                                  "max_iter": {"zero": 0, "text": "x"}}),
    "robust.mixed_musyn": (dict(P=P_MU, blk=[(-1, 0), (1, 1)], omega=np.logspace(-1, 2, 16), K0=K,
                                dg_steps=1, refinements=0),
                           {"P": LTI_PROPER, "K0": LTI_PROPER, "omega": GRID,
                            "blk": {"text": "abc", "too large": [(2, 2), (2, 2)],
                                    "repeated real": [(-2, 0)], "real last": [(1, 1), (-1, 0)]},
                            "order": {"zero": 0, "text": "x"},
                            "dg_steps": {"zero": 0, "text": "x"}}),
    "robust.performance_lower_bound": (dict(P=P_MU, nmeas=1, ncon=1, perf_outputs=[0],
                                            perf_inputs=[0], omega=OMEGA),
                                       {"P": LTI_PROPER, "omega": GRID,
                                        "nmeas": {"zero": 0, "text": "x", "too many": 5},
                                        "perf_outputs": {"empty": [], "out of range": [7],
                                                         "unknown name": ["nope"], "text": 1.5},
                                        "perf_inputs": {"empty": [], "out of range": [7]},
                                        "rtol": POSITIVE}),
    "robust.structured_lower_bound": (dict(P=P_MU, blk=[(1, 1), (1, 1)], nmeas=1, ncon=1, omega=OMEGA),
                                      {"P": LTI_PROPER, "omega": GRID,
                                       "blk": {"text": "abc", "too large": [(2, 2), (2, 2)],
                                               "no full block": [(-1, 0), (-1, 0)]},
                                       "ncon": {"zero": 0, "text": "x"}}),
    "robust.achievable_range": (dict(lower=0.5, achieved=1.0),
                                {"lower": POSITIVE, "achieved": POSITIVE,
                                 "what": {"number": 3.0}}),
    "robust.sos_filter": (dict(controller=SOS, x=U),
                          {"controller": {"not a controller": np.ones(3), "text": "abc"},
                           "x": SIGNAL, "dtype": {"unknown": "float16", "number": 3}}),
    "robust.write_json": (dict(controller=SOS, path=InTmp("k.json")),
                          {"controller": {"not a controller": np.ones(3)},
                           "path": {"none": None, "number": 3.5, "directory": InTmp("")},
                           "meta": {"not a dict": [1, 2], "not JSON": {"a": object()}}}),
    "robust.read_json": (dict(path=DATA / "controllers" / "K_ours.json"),
                         {"path": {"none": None, "not JSON": DATA / "README.md",
                                   "other JSON": DATA / "manifest.json"},
                          "dtype": {"unknown": "float16"}}),
    "robust.write_c_header": (dict(controller=SOS, path=InTmp("k.h")),
                              {"controller": {"not a controller": np.ones(3)},
                               "path": {"none": None, "number": 3.5, "directory": InTmp("")}}),
    "robust.export_controller": (dict(Kd=KD, directory=InTmp(""), name="K_test"),
                                 {"Kd": LTI_DISCRETE,
                                  "directory": {"none": None, "a file": DATA / "README.md"},
                                  "name": {"not an identifier": "1 K", "number": 3},
                                  "meta": {"not a dict": [1, 2]},
                                  "dtype": {"unknown": "float16"}, "rtol": POSITIVE}),
    "identification.refit_numerator": (dict(poles=[-1.0, -5.0], u=U, y=Y, fs=FS, n_zeros=1),
                                       {"poles": {"nan": [np.nan, -5.0], "unstable": [1.0, -5.0],
                                                  "unpaired complex": [-1 + 1j, -5.0],
                                                  "empty": [], "text": "abc"},
                                        "u": SIGNAL, "y": SIGNAL, "fs": POSITIVE,
                                        "n_zeros": {"negative": -1, "too many": 2, "text": "x"},
                                        "time_scale": POSITIVE}),
    "identification.identify_record": (dict(record=RECORD, n_poles=2, n_zeros=0),
                                       {"record": {"pair": (U, Y), "text": "abc"},
                                        "n_poles": {"zero": 0, "text": "x"},
                                        "n_zeros": {"negative": -1, "too many": 2},
                                        "initial_gain": POSITIVE}),
    "identification.coefficient_table": (dict(identified=G3_SIX, reference=G3_SIX),
                                         {"identified": {**LTI, "wrong order": G3},
                                          "reference": {**LTI, "wrong order": G3},
                                          "names": {"one name": ("a",), "text": "abc"}}),
    "uncertainty.level_offsets": (dict(levels=3, n=2),
                                  {"levels": {"one": 1, "text": "x", "fractional": 2.5},
                                   "n": {"zero": 0, "negative": -1, "text": "x"}}),
    "uncertainty.member_poles": (dict(mset=MSET), {"mset": {"text": "abc", "array": np.ones(3)}}),
    "uncertainty.largest_covered_spread": (
        dict(weight=ct.tf([1.0, 1.0], [0.1, 1.0]), G=G3, omega=OMEGA, levels=2),
        {"weight": LTI_STABLE, "G": LTI_PROPER, "omega": GRID,
         "levels": {"one": 1, "text": "x"}, "spread_max": POSITIVE,
         "rtol": {**POSITIVE, "below float resolution": 1e-300, "one": 1.0},
         "members": {"unknown": "some"}, "scan": {"zero": 0, "text": "x"}}),
    "hysteresis.simulate_dahl_records": (dict(model=DAHL, records=[V, V[:200]]),
                                         {"model": {"text": "abc", "pi model": PI},
                                          "records": {"empty": [], "text": "abc",
                                                      "nan record": [V, SIGNAL["nan"]],
                                                      "2-D record": [np.c_[V, V]]}}),
    "hysteresis.min_stroke_slope": (dict(model=DAHL, z0=[0.0, 0.0], direction=1, length=1.0),
                                    {"model": {"text": "abc"},
                                     "z0": {"nan": [np.nan, 0.0], "wrong length": [0.0], "text": "ab"},
                                     "direction": {"zero": 0, "text": "x"},
                                     "length": POSITIVE}),
    "hysteresis.check_dahl_model": (dict(model=DAHL), {"model": {"text": "abc", "pi model": PI}}),
    "hysteresis.check_fit_options": (dict(form="bliman_sorine", offset=False, start="rest"),
                                     {"form": {"unknown": "x", "number": 1},
                                      "offset": {"text": "yes", "number": 2},
                                      "start": {"unknown": "x", "number": 1}}),
    "hysteresis.fit_dahl": (dict(loops=[(V, X)], gamma_a=30.0, start="rest", starts=1, stride=10),
                            {"loops": LOOPS, "gamma_a": POSITIVE,
                             "form": {"unknown": "x"}, "start": {"unknown": "x"},
                             "discard": {"negative": -1, "text": "x", "whole record": V.size},
                             "stride": {"zero": 0, "text": "x"},
                             "starts": {"zero": 0, "text": "x"},
                             "initial": {"text": "abc", "pi model": PI}}),
    "hysteresis.rescore_dahl": (dict(fit=FIT, model=FIT.model, loops=[(V, X)]),
                                {"fit": {"text": "abc", "a model": DAHL},
                                 "model": {"text": "abc", "pi model": PI,
                                           "other form": replace(FIT.model, form="printed")},
                                 "loops": LOOPS,
                                 "discard": {"negative": -1, "whole record": V.size}}),
    "hysteresis.choose_fit": (dict(fits={"a": FIT}), {"fits": {"empty": {}, "text": "abc",
                                                                 "list": [FIT], "not fits": {"a": DAHL}}}),
    "hysteresis.play_outputs": (dict(v=V, thresholds=np.array([0.0, 0.5]), y0=np.zeros(2)),
                                {"v": {**{k: v for k, v in SIGNAL.items() if k != "2-D"},
                                       "3-D": np.zeros((4, 2, 2))},   # (N, m): m records
                                 "thresholds": {"nan": [0.0, np.nan], "negative": [-1.0, 0.5],
                                                "empty": [], "2-D": np.zeros((2, 2)), "text": "ab"},
                                 "y0": {"nan": [np.nan, 0.0], "wrong length": [0.0], "text": "ab"}}),
    "hysteresis.fit_pi": (dict(loops=[(V, X)], n_plays=4),
                          {"loops": LOOPS, "n_plays": {"zero": 0, "text": "x"},
                           "start": {"unknown": "x"}, "offset": {"text": "yes"},
                           "discard": {"negative": -1, "whole record": V.size},
                           "thresholds": {"nan": [0.0, np.nan], "negative": [-1.0, 0.5],
                                          "empty": [], "text": "ab"}}),
    "hysteresis.fit_hammerstein": (dict(loops=[(V, X)], fs=FS, order=(2, 2), n_plays=3),
                                   {"loops": LOOPS, "fs": POSITIVE,
                                    "order": {"text": "x", "one number": 3, "zero": (0, 2),
                                              "negative": (2, -1)},
                                    "n_plays": {"zero": 0, "text": "x", "too many": 10 ** 6},
                                    "dynamics": {"text": "abc", "unstable": ct.tf([1.0], [1.0, -1.0]),
                                                 "another rate": ct.tf([1.0], [1.0, -0.5], 2 / FS)},
                                    "delay": {"negative": -1, "text": "x"},
                                    "offset": {"text": "yes"}, "start": {"unknown": "x"},
                                    "discard": {"negative": -1, "whole record": V.size},
                                    "thresholds": {"nan": [0.0, np.nan], "negative": [-1.0, 0.5],
                                                   "empty": [], "text": "ab"},
                                    "iterations": {"zero": 0, "text": "x"}, "tol": POSITIVE,
                                    "operator": {"unknown": "plays", "number": 3},
                                    "levels": {"one": 1, "text": "x", "too many": 10 ** 6}}),
    "hysteresis.fit_preisach": (dict(loops=[(V, X)], levels=4),
                                {"loops": LOOPS, "levels": {"one": 1, "text": "x", "float": 2.5,
                                                            "too many": 10 ** 6},
                                 "start": {"unknown": "x"}, "offset": {"text": "yes"},
                                 "discard": {"negative": -1, "whole record": V.size},
                                 "v_range": {"nan": (0.0, np.nan), "reversed": (1.0, -1.0),
                                             "one number": 3.0, "text": "ab"}}),
    "hysteresis.unit_dc_dynamics": (dict(dynamics=G, fs=FS),
                                    {"dynamics": {"text": "abc", "unstable": ct.tf([1.0], [1.0, -1.0]),
                                                  "MIMO": P, "zero gain": ct.tf([1.0, 0.0], [1.0, 1.0]),
                                                  "another rate": ct.tf([1.0], [1.0, -0.5], 2 / FS)},
                                     "fs": POSITIVE}),
    "hysteresis.validation_table": (dict(models={"Dahl": DAHL}, records=[(V, X)]),
                                    {"models": {"empty": {}, "not a mapping": [DAHL],
                                                "not a model": {"x": object()}},
                                     "records": LOOPS,
                                     "names": {"wrong count": ["a", "b"], "text": 3}}),
    "hysteresis.pooled_rms": (dict(table=TABLE), {"table": {"text": "abc", "array": np.ones(3),
                                                            "no pooled column": TABLE.drop(columns="pooled RMS %")}}),
    "hysteresis.cross_check": (dict(compensators={"Dahl": DAHL}, plants={"Dahl": DAHL}, x_r=V),
                               {"compensators": {"empty": {}, "not a model": {"x": object()},
                                                 "not a mapping": [DAHL]},
                                "plants": {"empty": {}, "not callable": {"x": 3.0},
                                           "not a mapping": [DAHL]},
                                "x_r": SIGNAL,
                                "first": {"negative": -1, "past the end": V.size, "text": "x"}}),
    # identification: periodic multisines, FRF fits
    "identification.excited_lines": (dict(u=FRF_U), {"u": {"nan": PERIODIC["nan"], "text": "abc",
                                                           "empty": np.array([])},
                                                     "relative_threshold": {**POSITIVE, "one": 1.0}}),
    "identification.bla_periodic": (dict(u=FRF_U, y=FRF_Y, fs=FS),
                                    {"u": PERIODIC, "y": {"nan": PERIODIC["nan"], "text": "abc",
                                                          "short": FRF_Y[:32]},
                                     "fs": POSITIVE, "lines": {"zero": [0, 1], "text": "abc",
                                                               "fraction": [1.5]}}),
    "identification.fit_frf": (dict(G=FRF_G, frequency_Hz=FRF_F, fs=FS, order=2),
                               {"G": FRF_BAD, "frequency_Hz": FREQUENCIES, "fs": POSITIVE,
                                "order": ORDER, "weight": WEIGHT,
                                "n_rows": {"too few": 2, "text": "x"}}),
    "identification.frf_error": (dict(model=GD, G=FRF_G, frequency_Hz=FRF_F),
                                 {"model": DISCRETE, "G": FRF_BAD, "frequency_Hz": FREQUENCIES,
                                  "weight": WEIGHT}),
    "identification.select_order": (dict(G_fit=FRF_G, G_validation=FRF_G, frequency_Hz=FRF_F,
                                         fs=FS, orders=[1, 2]),
                                    {"G_fit": FRF_BAD, "G_validation": FRF_BAD,
                                     "frequency_Hz": FREQUENCIES, "fs": POSITIVE,
                                     "orders": {"empty": [], "zero": [0], "text": "x",
                                                "fraction": [1.5]}}),
    "identification.simulate_discrete": (dict(model=GD, u=U[:, None]),
                                         {"model": DISCRETE,
                                          "u": {"nan": np.r_[U[:-1], np.nan][:, None],
                                                "1-D": U, "text": "abc", "complex": U[:, None] + 1j}}),
    "identification.play_operators": (dict(u=U[:, None], thresholds=[0.0, 0.5]),
                                      {"u": {"nan": np.r_[U[:-1], np.nan][:, None], "1-D": U,
                                             "text": "abc"},
                                       "thresholds": {"negative": [-0.1, 0.5],
                                                      "not increasing": [0.5, 0.1],
                                                      "empty": [], "nan": [0.0, np.nan]}}),
    "identification.fit_play_weights": (dict(linear=ct.ss(GD * np.eye(2)), u=FRF_U, y=FRF_Y,
                                             thresholds=[0.0, 0.5], lines=[1, 2, 3]),
                                        {"linear": DISCRETE,
                                         "u": {"nan": PERIODIC["nan"], "3-D": FRF_U[..., 0],
                                               "1 channel": FRF_U[:, :1]},
                                         "y": {"short": FRF_Y[:32], "nan": PERIODIC["nan"],
                                               "list": [FRF_Y]},
                                         "thresholds": {"negative": [-0.1, 0.5], "empty": []},
                                         "lines": {"zero": [0, 1], "fraction": [1.5],
                                                   "past Nyquist": [10 ** 6], "text": "abc"}}),
    "identification.input_rms": (dict(u=U[:, None]),
                                 {"u": {"1-D": U, "nan": np.r_[U[:-1], np.nan][:, None],
                                        "text": "abc"}}),
    "identification.basis_poles": (dict(models=[GD]),
                                   {"models": {"empty": [], "one model": GD, "continuous": [G],
                                               "unstable": [ct.ss(ct.tf([1.0], [1.0, -1.5], 1 / FS))],
                                               "static": [ct.ss([], [], [], [[1.0]], 1 / FS)]},
                                    "merge_tolerance": {"negative": -1.0, "nan": np.nan}}),
    "identification.running_rms": (dict(u=U[:, None], window_samples=20.0),
                                   {"u": {"1-D": U, "nan": np.r_[U[:-1], np.nan][:, None],
                                          "text": "abc"},
                                    "window_samples": {**POSITIVE, "below one": 0.5}}),
    "identification.basis_regressors": (dict(u=U[:, None], poles=[0.5, 0.3 + 0.4j],
                                             branches=[("u", 0), ("u|u|", 1)],
                                             window_samples=20.0, input_scale=1.0),
                                        BASIS_BAD),
    "identification.fit_basis_model": (dict(u=[U[:, None]], y=[Y[:, None]], poles=[0.5],
                                            branches=[("u", 0)], window_samples=20.0,
                                            input_scale=1.0, n_init=10),
                                       {**BASIS_BAD,
                                        "y": {"nan": [np.r_[Y[:-1], np.nan][:, None]],
                                              "short": [Y[:300, None]], "two records": [Y[:, None]] * 2,
                                              "constant": [np.ones((400, 1))]},
                                        "n_init": {"negative": -1, "too large": 400, "float": 1.5},
                                        "ridge": {"negative": -1.0, "nan": np.nan}}),
    "identification.select_basis_model": (dict(u_fit=[U[:, None]], y_fit=[Y[:, None]],
                                               u_validation=[U[:, None]], y_validation=[Y[:, None]],
                                               poles=[0.5], candidates=[[("u", 0)]],
                                               windows_samples=[20.0], input_scale=1.0),
                                          {"u_fit": {"empty": [], "nan": [np.r_[U[:-1], np.nan][:, None]]},
                                           "y_validation": {"short": [Y[:300, None]],
                                                            "two records": [Y[:, None]] * 2},
                                           "u_validation": {"1-D": U, "text": "abc"},
                                           "poles": BASIS_BAD["poles"],
                                           "candidates": {"empty": [], "text": "u",
                                                          "unknown function": [[("tanh", 0)]]},
                                           "windows_samples": {"empty": [], "below one": [0.5],
                                                               "nan": [np.nan]},
                                           "input_scale": POSITIVE}),
    "metrics.simulation_error": (dict(y_model=np.c_[Y, Y] + 0.1, y=np.c_[Y, Y], n_init=10),
                                 {"y_model": {"nan": np.c_[np.r_[Y[:-1], np.nan], Y],
                                              "wrong shape": np.c_[Y], "text": "abc"},
                                  "y": {"1-D": Y, "nan": np.c_[np.r_[Y[:-1], np.nan], Y]},
                                  "n_init": {"negative": -1, "too large": 10 ** 6, "float": 1.5,
                                             "text": "x"}}),
}

def function(qualname):
    package, name = qualname.split(".")
    return getattr(importlib.import_module(f"piezolib.{package}"), name)


def public_functions():
    names = set()
    for module in TOOLKIT:
        mod = importlib.import_module(module)
        short = module.split(".")[1]
        names |= {f"{short}.{n}" for n in mod.__all__
                  if callable(getattr(mod, n)) and not inspect.isclass(getattr(mod, n))}
    return names


def test_every_public_function_is_swept():
    public = public_functions()
    assert not (set(CASES) - public), "cases for names that are not public"
    missing = public - set(CASES)
    assert not missing, f"public functions with no bad-input cases: {sorted(missing)}"


@pytest.mark.parametrize("qualname", sorted(CASES))
def test_the_valid_call_works(qualname, tmp_path):
    valid, _ = CASES[qualname]
    call(qualname, resolve(valid, tmp_path))


@pytest.mark.parametrize("qualname, valid, argument, value", list(bad_calls(CASES)))
def test_bad_input_raises_naming_the_argument(qualname, valid, argument, value, tmp_path):
    with pytest.raises((ValueError, TypeError)) as info:
        call(qualname, resolve({**valid, argument: value}, tmp_path))
    assert re.search(rf"\b{re.escape(argument)}\b", str(info.value), re.I), str(info.value)
