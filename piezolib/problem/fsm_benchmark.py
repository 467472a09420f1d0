"""The CubeSpec Fine Steering Mirror benchmark: a real piezo data set with published baselines.

Three piezo actuators of a satellite's fine steering mirror (inputs: voltages
[V]) drive the mirror's displacement at three points (outputs [m]).  The data
(CC BY 4.0, (c) 2025 Merijn Floren, KU Leuven; attribution, citation and the
files' description in ``data/real/fsm_benchmark/README.md``) are orthogonal
random-phase multisines up to 3000 Hz at 100, 200 and 300 mV, sampled at
6400 Hz, as arrays (N = 8192 samples, 3 channels, R realisations, P = 2
steady-state periods): train R = 6 (two orthogonal groups of 3), test R = 3.

:func:`load` reads one level and split, checking each file against the
manifest (SHA-256, shape); :func:`score` is the benchmark's metric (simulate
the model on the test input from rest, drop the first :data:`N_INIT` samples,
RMSE and NRMSE per output averaged over realisations and periods, then over
outputs); :func:`noise_floor` the NRMSE that a perfect model would get given
the measurement noise (estimated from the difference of the two periods);
:data:`PUBLISHED_NRMSE_PERCENT` the published baselines.

Each record (one realisation, one period) is simulated on its own from a zero
state, the strict reading of "simulate the model on the test input": a
lightly damped model still rings from its start after the 100 samples dropped
and pays for it.
"""

import hashlib
import json
from dataclasses import dataclass

import control as ct
import numpy as np

from piezolib import metrics
from piezolib._checks import (check_bool, check_integer, check_positive, check_proper, check_siso,
                              check_stable, check_type)
from piezolib.identification import freqfit
from piezolib.robust.lti import balance
from piezolib.problem import paths
from piezolib.problem.genplant import effective_delay

__all__ = ["axis_design_plant", "SAMPLING_FREQUENCY_HZ", "LEVELS_MV", "SPLITS", "SAMPLES_PER_PERIOD", "N_INIT",
           "INPUT_LABELS", "OUTPUT_LABELS", "PUBLISHED_NRMSE_PERCENT", "PUBLISHED_RMSE_UM",
           "BASELINE_SOURCE", "data_folder", "file_name", "load", "check_files",
           "write_manifest", "Score", "score", "score_simulation", "noise_floor"]

#: Sampling frequency of every record [Hz].
SAMPLING_FREQUENCY_HZ = 6400.0
#: Excitation levels (multisine RMS per input) [mV].
LEVELS_MV = (100, 200, 300)
#: The data sets and their realisations R.
SPLITS = {"train": 6, "test": 3}
#: Samples per period N.
SAMPLES_PER_PERIOD = 8192
#: Periods per realisation P.
PERIODS = 2
#: Samples dropped at the start of each simulated record by the official metric.
N_INIT = 100
INPUT_LABELS = ["v_a1", "v_a2", "v_a3"]
OUTPUT_LABELS = ["d_1", "d_2", "d_3"]

#: Where the baselines are published.
BASELINE_SOURCE = ("M. Floren, 'Baseline models for the Fine Steering Mirror benchmark dataset', "
                   "Zenodo v2026.04.15, doi:10.5281/zenodo.19591136; table of "
                   "baseline_results/analyze_models.ipynb in merijnfloren/fsm-benchmark-data")

#: Published test NRMSE [%] per model and level [mV].
PUBLISHED_NRMSE_PERCENT = {
    "BLA (28th order) trained at the same level": {100: 8.38, 200: 7.95, 300: 5.63},
    "BLA (28th order) trained at 100 mV": {100: 8.38, 200: 20.50, 300: 32.71},
    "BLA (28th order) trained at 200 mV": {100: 21.78, 200: 7.95, 300: 17.34},
    "BLA (28th order) trained at 300 mV": {100: 32.84, 200: 15.17, 300: 5.63},
    "one BLA on all levels": {100: 18.61, 200: 6.61, 300: 16.28},
    "nonlinear LFR (neural network), all levels": {100: 6.37, 200: 4.84, 300: 4.19},
}
#: Published test RMSE [um] where the source gives it.
PUBLISHED_RMSE_UM = {
    "BLA (28th order) trained at the same level": {100: 0.1142, 200: 0.2161, 300: 0.2277},
    "nonlinear LFR (neural network), all levels": {100: 0.0866, 300: 0.1686},
}

MANIFEST_NAME = "manifest.json"


def data_folder():
    """``data/real/fsm_benchmark/`` of the checkout.

    Examples
    --------
    >>> data_folder().relative_to(paths.data_dir()).as_posix()
    'real/fsm_benchmark'
    """
    return paths.data_dir() / "real" / "fsm_benchmark"


def _level(level_mV):
    if isinstance(level_mV, bool) or level_mV not in LEVELS_MV:
        raise ValueError(f"level_mV must be one of {LEVELS_MV}, got {level_mV!r}")
    return int(level_mV)


def _split(split):
    if not isinstance(split, str) or split not in SPLITS:
        raise ValueError(f"split must be one of {tuple(SPLITS)}, got {split!r}")
    return split


def file_name(signal, level_mV, split):
    """File name of one array, e.g. ``u_100mV_train.npy``.

    Parameters
    ----------
    signal : {"u", "y"}
        Inputs [V] or outputs [m].
    level_mV : int
        One of :data:`LEVELS_MV`.
    split : {"train", "test"}

    Examples
    --------
    >>> file_name("u", 100, "train"), file_name("y", 300, "test")
    ('u_100mV_train.npy', 'y_300mV_test.npy')
    """
    if signal not in ("u", "y"):
        raise ValueError(f"signal must be 'u' or 'y', got {signal!r}")
    return f"{signal}_{_level(level_mV)}mV_{_split(split)}.npy"


def _folder(folder):
    return data_folder() if folder is None else paths.check_directory(folder, "folder")


def _sha256(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def write_manifest(folder=None):
    """Write ``manifest.json`` (SHA-256, shape, dtype of every array) into the folder.

    Parameters
    ----------
    folder : str or Path, optional
        Default :func:`data_folder`.

    Returns
    -------
    Path
    """
    from piezolib import files

    folder = _folder(folder)
    entries = {}
    for level in LEVELS_MV:
        for split in SPLITS:
            for signal in ("u", "y"):
                path = folder / file_name(signal, level, split)
                arr = np.load(path, mmap_mode="r")
                entries[path.name] = {"sha256": _sha256(path), "shape": list(arr.shape),
                                      "dtype": str(arr.dtype),
                                      "unit": "V" if signal == "u" else "m",
                                      "sample_rate_Hz": SAMPLING_FREQUENCY_HZ}
    for name in ("LICENSE", "README.md"):
        if (folder / name).exists():
            entries[name] = {"sha256": _sha256(folder / name)}
    doc = {"about": "SHA-256, shape and unit of every file of the FSM benchmark copy; written "
                    "by piezolib.problem.fsm_benchmark.write_manifest",
           "files": entries}
    return files.atomic_write(folder / MANIFEST_NAME, json.dumps(doc, indent=1) + "\n")


def _manifest(folder):
    path = folder / MANIFEST_NAME
    try:
        return json.loads(path.read_text())["files"]
    except (OSError, ValueError, KeyError) as exc:
        raise ValueError(f"folder: no valid {MANIFEST_NAME} in {folder} ({exc})") from None


def check_files(folder=None):
    """Every file of the manifest checked: ``{file name: problem}``, empty when all are intact.

    Parameters
    ----------
    folder : str or Path, optional
        Default :func:`data_folder`.

    Examples
    --------
    >>> check_files()                    # the committed arrays match their manifest
    {}
    """
    folder = _folder(folder)
    problems = {}
    for name, entry in _manifest(folder).items():
        path = folder / name
        if not path.exists():
            problems[name] = "missing"
        elif _sha256(path) != entry["sha256"]:
            problems[name] = "content differs from the manifest (SHA-256)"
    return problems


def load(level_mV, split, folder=None):
    """Input and output arrays of one level and split, checked against the manifest.

    Parameters
    ----------
    level_mV : int
        One of :data:`LEVELS_MV`.
    split : {"train", "test"}
    folder : str or Path, optional
        Default :func:`data_folder`.

    Returns
    -------
    u, y : ndarray, shape (8192, 3, R, 2)
        Inputs [V] and outputs [m]; R = 6 (train) or 3 (test).

    Raises
    ------
    ValueError
        A file missing, differing from its SHA-256 or of another shape.

    Examples
    --------
    >>> u, y = load(100, "test")          # data/real/fsm_benchmark/
    >>> u.shape, y.shape                  # (samples, channels, realisations, periods)
    ((8192, 3, 3, 2), (8192, 3, 3, 2))
    """
    level, split, folder = _level(level_mV), _split(split), _folder(folder)
    manifest = _manifest(folder)
    out = []
    for signal in ("u", "y"):
        name = file_name(signal, level, split)
        path = folder / name
        if name not in manifest or not path.exists():
            raise ValueError(f"folder: {name} is missing from {folder} or its manifest")
        if _sha256(path) != manifest[name]["sha256"]:
            raise ValueError(f"folder: {path} differs from its manifest (SHA-256): restore it "
                             f"from the original (data/real/fsm_benchmark/README.md)")
        arr = np.load(path, allow_pickle=False)
        shape = (SAMPLES_PER_PERIOD, 3, SPLITS[split], PERIODS)
        if arr.shape != shape or not np.all(np.isfinite(arr)):
            raise ValueError(f"folder: {path} has shape {arr.shape}, expected {shape} finite")
        out.append(arr)
    return out[0], out[1]


@dataclass(frozen=True)
class Score:
    """The benchmark metric of one model on one level.

    Attributes
    ----------
    level_mV : int
    rmse_um : ndarray, shape (3,)
        RMSE per output [um], averaged over realisations and periods.
    nrmse : ndarray, shape (3,)
        NRMSE per output (fraction).

    Examples
    --------
    >>> import numpy as np
    >>> s = Score(100, rmse_um=np.array([0.1, 0.2, 0.3]), nrmse=np.array([0.05, 0.1, 0.15]))
    >>> round(s.nrmse_percent, 6), round(s.mean_rmse_um, 6)
    (10.0, 0.2)
    """

    level_mV: int
    rmse_um: np.ndarray
    nrmse: np.ndarray

    @property
    def nrmse_percent(self):
        """NRMSE averaged over the outputs [%] (the number the baselines quote)."""
        return 100.0 * float(np.mean(self.nrmse))

    @property
    def mean_rmse_um(self):
        """RMSE averaged over the outputs [um]."""
        return float(np.mean(self.rmse_um))


def score(model, level_mV, split="test", folder=None):
    """The official metric of a discrete linear model on one level.

    Parameters
    ----------
    model : control.StateSpace
        Discrete at 6400 Hz, 3 inputs [V] -> 3 outputs [m].
    level_mV : int
        One of :data:`LEVELS_MV`.
    split : {"train", "test"}, optional
    folder : str or Path, optional

    Returns
    -------
    Score

    Examples
    --------
    >>> import numpy as np, control as ct
    >>> slow = ct.ss(0.5 * np.eye(3), np.eye(3), 1e-9 * np.eye(3), np.zeros((3, 3)), 1 / 6400)
    >>> round(score(slow, 100).nrmse_percent)        # an almost silent model: about 100 %
    100
    """
    check_type("model", model, ct.StateSpace, "a discrete StateSpace")
    if (model.ninputs, model.noutputs) != (3, 3):
        raise ValueError(f"model must have 3 inputs and 3 outputs, got {model.ninputs} and "
                         f"{model.noutputs}")
    if not model.isdtime(strict=True) or abs(model.dt * SAMPLING_FREQUENCY_HZ - 1) > 1e-9:
        raise ValueError(f"model must be discrete with dt = 1/{SAMPLING_FREQUENCY_HZ:g} s")
    # each (realisation, period) from rest
    return score_simulation(lambda u: freqfit.simulate_discrete(model, u), level_mV, split,
                            folder)


def score_simulation(simulate, level_mV, split="test", folder=None):
    """The official metric of any model given as a simulation function (e.g. a nonlinear one).

    Parameters
    ----------
    simulate : callable
        ``simulate(u) -> y_model``: inputs (8192, 3, R, 2) [V] to outputs of
        the same shape [m], each (realisation, period) simulated from rest.
        The model may use only ``u`` (e.g. to compute a schedule from it).
    level_mV : int
        One of :data:`LEVELS_MV`.
    split : {"train", "test"}, optional
    folder : str or Path, optional

    Returns
    -------
    Score

    Examples
    --------
    >>> import numpy as np
    >>> round(score_simulation(lambda u: np.zeros_like(u), 100).nrmse_percent)   # predicts 0
    100
    """
    if not callable(simulate):
        raise TypeError(f"simulate must be a callable u -> y, got {type(simulate).__name__}")
    u, y = load(level_mV, split, folder)
    y_model = np.asarray(simulate(u.copy()), dtype=float)
    if y_model.shape != y.shape:
        raise ValueError(f"simulate returned shape {y_model.shape}, expected {y.shape}")
    rmse, nrmse = metrics.simulation_error(y_model, y, N_INIT)
    return Score(level_mV=_level(level_mV), rmse_um=1e6 * rmse, nrmse=nrmse)


def noise_floor(level_mV, split="test", folder=None, without_drift=False):
    """The NRMSE a perfect model would get: the output noise over the output's spread.

    The noise variance per output is half the variance of the difference of
    the two periods (the steady-state periodic response cancels in it);
    a model that reproduced the noise-free output exactly would have an RMSE
    of its standard deviation.  With ``without_drift`` the difference's
    constant offset per record and output (a drift between the periods, which
    no model of the input can predict, but which is not noise within a
    period either) is removed first: the floor of the noise alone.

    Parameters
    ----------
    level_mV : int
    split : {"train", "test"}, optional
    folder : str or Path, optional
    without_drift : bool, optional
        Remove the mean of the periods' difference per record and output.

    Returns
    -------
    Score
        ``rmse_um`` the noise standard deviation [um], ``nrmse`` the floor.

    Examples
    --------
    >>> floor = noise_floor(100)
    >>> floor.level_mV, bool(0 < floor.nrmse_percent < 5)
    (100, True)
    >>> bool(noise_floor(100, without_drift=True).nrmse_percent < floor.nrmse_percent)
    True
    """
    without_drift = check_bool("without_drift", without_drift)
    u, y = load(level_mV, split, folder)
    kept = y[N_INIT:]
    diff = kept[..., 0] - kept[..., 1]                                            # (N, 3, R)
    if without_drift:
        diff = diff - diff.mean(axis=0)
    noise_std = np.sqrt(np.mean(diff ** 2, axis=0) / 2)                           # (3, R)
    nrmse = noise_std[..., None] / np.std(kept, axis=0)                           # (3, R, P)
    return Score(level_mV=_level(level_mV), rmse_um=1e6 * noise_std.mean(axis=1),
                 nrmse=nrmse.mean(axis=(1, 2)))


def _check_axis_models(**models):
    """Raise unless every model is a continuous-time (or static) SISO proper LTI system."""
    for name, sys in models.items():
        check_siso(name, sys)
        check_proper(name, sys)
        if sys.isdtime(strict=True):
            raise ValueError(f"{name} must be a continuous-time model, got dt = {sys.dt!r}")


def axis_design_plant(G, W_m, W_S, W_T, W_u, *, fs, delay_samples=1, pade_order=2):
    """Synthesis plant of one mirror axis: output-multiplicative uncertainty, delay, roll-off.

    For a SISO loop the input- and output-multiplicative sets G (1 + W_m Delta)
    are the same; placing Delta at the output (the measured displacement)
    makes the robust-performance matrix of the loop nearly rank one with a
    constant D-scaling, where the input placement of
    :func:`piezolib.problem.genplant.delay_aware_plant` needs D-scalings that
    follow the plant's lightly damped resonances (the mirror's |G| varies by a
    factor 50 between 5 Hz and 923 Hz), which low-order D fits cannot.  With
    u_a the controller output after the effective delay tau = (d + 1/2)/fs
    (Pade, order ``pade_order``; the hold and ``delay_samples``):

        v_y = G u_a + u_Delta,  y_Delta = W_m G u_a,  v_e = v_r - v_y,
        y1 = W_S v_e,  y2 = W_T v_y,  y_u = W_u u_b.

    Parameters
    ----------
    G : control.LTI
        Continuous SISO plant, actuator voltage [V] -> displacement [um].
    W_m : control.LTI
        Relative uncertainty weight [-].
    W_S, W_T : control.LTI
        Performance weights on S and T [-] (templates, e.g.
        :func:`piezolib.robust.sensitivity_weight`).
    W_u : control.LTI
        Weight on the controller output [um/V] (roll-off requirement, e.g.
        :func:`piezolib.problem.genplant.rolloff_weight`).
    fs : float
        Loop rate [Hz].
    delay_samples : int or None
        Computation delay [samples]; None leaves the delay out (u_a = u_b).
    pade_order : int
        Order of the Pade approximation of the delay.

    Returns
    -------
    control.StateSpace
        Inputs ``u_Delta, v_r, u_b``; outputs ``y_Delta, y1, y2, y_u, v_e``;
        block structure ((1, 1), (1, 3)).

    Examples
    --------
    >>> import control as ct
    >>> from piezolib.problem import paper, genplant
    >>> P = axis_design_plant(paper.plant(), ct.tf([0.1], [1]), paper.error_weight(),
    ...                       paper.output_weight(), genplant.rolloff_weight(), fs=10e3)
    >>> P.input_labels, P.output_labels
    (['u_Delta', 'v_r', 'u_b'], ['y_Delta', 'y1', 'y2', 'y_u', 'v_e'])
    """
    _check_axis_models(G=G, W_m=W_m, W_S=W_S, W_T=W_T, W_u=W_u)
    for name, W in (("W_m", W_m), ("W_S", W_S), ("W_T", W_T), ("W_u", W_u)):
        check_stable(name, W)       # an unstable weight leaves no stabilising controller
    fs = check_positive("fs", fs)
    pade_order = check_integer("pade_order", pade_order, minimum=1)
    if delay_samples is None:
        delay = ct.ss([], [], [], [[1.0]], inputs="u_b", outputs="u_a")
    else:
        num, den = ct.pade(effective_delay(fs, delay_samples), pade_order)
        delay = ct.ss(ct.tf(num, den), inputs="u_b", outputs="u_a")
    blocks = [delay,
              ct.ss(G, inputs="u_a", outputs="v_y0"),
              ct.ss(W_m, inputs="v_y0", outputs="y_Delta"),
              ct.summing_junction(["v_y0", "u_Delta"], "v_y"),
              ct.summing_junction(["v_r", "-v_y"], "v_e"),
              ct.ss(W_S, inputs="v_e", outputs="y1"),
              ct.ss(W_T, inputs="v_y", outputs="y2"),
              ct.ss(W_u, inputs="u_b", outputs="y_u")]
    return balance(ct.interconnect(blocks, inputs=["u_Delta", "v_r", "u_b"],
                                   outputs=["y_Delta", "y1", "y2", "y_u", "v_e"],
                                   name="P_axis"))
