"""One causal model of the fine steering mirror for all levels (notebook 10, issue 53).

The model (:class:`piezolib.identification.BasisModel`): the mirror's
dynamics on a fixed basis, the union of the poles of the per-level linear
models (so that every level's resonances are in it), driven by the input
and by static functions of it, each branch multiplied by a power of a causal
amplitude a(k) (the RMS of the past inputs over a window that grows to
``window_samples``, then slides), so that the model is linear-parameter-
varying in the level it has seen so far.  One structure and one parameter
set for every input; its output at k uses the inputs up to k; it starts
from rest, as the metric simulates each record; it has no output feedback
and every filter is stable, so it cannot go unstable.  Linear in its
parameters: the fit is one least-squares solve.

:func:`derive_causal_model` chooses the branches and the window on held-out
training realisations (poles from the BLA of group 0 = realisations 0-2 at
the per-level orders, fit on realisations 0-2 of every level, validation on
3-5), then refits the chosen structure on all six realisations (poles from
the whole BLAs).  It takes minutes, so its end point is committed as
:data:`MODEL_FILE` (:func:`write_causal_model`, :func:`read_causal_model`);
the notebook scores the committed model (:func:`score_causal_model`) and the
slow test re-derives it.

Inputs [V], outputs [m], time in samples at 6400 Hz.
"""

import io
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from piezolib import files
from piezolib import identification as ident
from piezolib._checks import check_integers, check_path, check_type
from piezolib.problem import fsm_benchmark as fsm
from piezolib.problem import fsm_models, paths

__all__ = ["CAUSAL", "CANDIDATES", "WINDOWS_SAMPLES", "RIDGE", "MODEL_FILE", "CausalFit",
           "derive_causal_model", "fit_causal_model", "write_causal_model", "read_causal_model", "causal_model_path",
           "CausalScores", "score_causal_model"]

#: The model's name in the claim table.
CAUSAL = "causal all-levels model"
#: Candidate branch sets: (static function, power of the amplitude) per branch.
CANDIDATES = {
    "LTI on the levels' poles": (("u", 0),),
    "LPV: 1, a": (("u", 0), ("u", 1)),
    "LPV: 1, a, a^2": (("u", 0), ("u", 1), ("u", 2)),
    "LPV: 1, a, a^2 + u|u|": (("u", 0), ("u", 1), ("u", 2), ("u|u|", 0)),
    "LPV: 1, a, a^2 + u|u|, u^3": (("u", 0), ("u", 1), ("u", 2), ("u|u|", 0), ("u^3", 0)),
}
#: Candidate time constants of the amplitude [samples] (7.8, 31 and 125 ms at 6400 Hz).
WINDOWS_SAMPLES = (50.0, 200.0, 800.0)
#: Ridge on the normal equations scaled to unit diagonal (numerical only: no larger value
#: lowered the validation error in the exploration of issue 53).
RIDGE = 1e-9
#: The committed end point, relative to ``data/``.
MODEL_FILE = "models/fsm_causal_model.npz"
#: Realisations of the fitting and the validation group (the BLA's two orthogonal groups).
FIT_REALISATIONS, VALIDATION_REALISATIONS = (0, 1, 2), (3, 4, 5)


def causal_model_path():
    """Where the committed causal model lives.

    Examples
    --------
    >>> causal_model_path().relative_to(paths.data_dir()).as_posix()
    'models/fsm_causal_model.npz'
    """
    return paths.data_dir() / MODEL_FILE


def _orders(orders):
    if isinstance(orders, dict):
        if set(orders) != set(fsm.LEVELS_MV):
            raise ValueError(f"orders must give an order for each level {fsm.LEVELS_MV}, "
                             f"got {sorted(orders)}")
        values = check_integers("orders", [orders[lv] for lv in fsm.LEVELS_MV], minimum=1)
    else:
        values = check_integers("orders", orders, minimum=1)
        if len(values) != len(fsm.LEVELS_MV):
            raise ValueError(f"orders must hold one order per level {fsm.LEVELS_MV}, got "
                             f"{list(values)}")
    return dict(zip(fsm.LEVELS_MV, (int(v) for v in values)))


def _poles(blas, orders, group=None):
    models = []
    for lv in fsm.LEVELS_MV:
        bl = blas.blas[lv]
        G = bl.G if group is None else bl.G_groups[group]
        models.append(ident.fit_frf(G, bl.frequency_Hz, fsm.SAMPLING_FREQUENCY_HZ, orders[lv]))
    return ident.basis_poles(models)


def _records(blas, realisations):
    u, y, levels = [], [], []
    for lv in fsm.LEVELS_MV:
        ul, yl = blas.train[lv]
        for r in realisations:
            for p in range(ul.shape[3]):
                u.append(ul[:, :, r, p])
                y.append(yl[:, :, r, p])
                levels.append(lv)
    return u, y, np.array(levels)


def _input_scale(blas):
    """The training inputs' RMS averaged over the levels [V] (a(k) = 1 near 200 mV)."""
    return float(np.mean([ident.input_rms(blas.train[lv][0]).mean() for lv in fsm.LEVELS_MV]))


@dataclass(frozen=True)
class CausalFit:
    """The causal model and how it was chosen (:func:`derive_causal_model`).

    Attributes
    ----------
    model : identification.BasisModel
        Fitted on all six training realisations of every level.
    orders : dict {int: int}
        Per-level linear orders whose poles form the basis.
    candidate_names : tuple of str
        Keys of :data:`CANDIDATES` tried.
    windows_samples : tuple of float
    validation_nrmse : ndarray, shape (n_windows, n_candidates, n_records)
        NRMSE (fraction) of each candidate on each held-out record.
    validation_levels : ndarray of int
        The level [mV] of each held-out record.
    fit_nrmse : ndarray, shape (n_windows, n_candidates)
    chosen : str
        The chosen candidate's name.
    selection_s, fit_s : float
        Wall time of the selection and of the final fit [s].
    """

    model: object
    orders: dict
    candidate_names: tuple
    windows_samples: tuple
    validation_nrmse: np.ndarray
    validation_levels: np.ndarray
    fit_nrmse: np.ndarray
    chosen: str
    selection_s: float
    fit_s: float

    def validation_table(self):
        """Held-out NRMSE [%] per candidate and window (rows), per level and mean (columns)."""
        rows = {}
        for w, window in enumerate(self.windows_samples):
            for c, name in enumerate(self.candidate_names):
                row = {fsm_models.level_label(lv): 100 * float(
                    self.validation_nrmse[w, c, self.validation_levels == lv].mean())
                    for lv in fsm.LEVELS_MV}
                row["mean"] = 100 * float(self.validation_nrmse[w, c].mean())
                row["fitting records"] = 100 * float(self.fit_nrmse[w, c])
                rows[(name, f"{window:g}")] = row
        return pd.DataFrame(rows).T.rename_axis(["branches", "window [samples]"])

    def description(self):
        """One line: the chosen structure, its size and the times."""
        m = self.model
        return (f"chosen on realisations 3-5: {self.chosen}, window {m.window_samples:g} samples "
                f"({1e3 * m.window_samples / fsm.SAMPLING_FREQUENCY_HZ:.1f} ms); "
                f"{m.poles.size} basis poles (per-level orders "
                f"{', '.join(str(self.orders[lv]) for lv in fsm.LEVELS_MV)}), "
                f"{m.n_regressors} regressors per output; selection {self.selection_s:.0f} s, "
                f"final fit {self.fit_s:.0f} s")


def derive_causal_model(blas, orders, candidates=None, windows_samples=WINDOWS_SAMPLES):
    """Choose the causal model's branches and window on held-out realisations, then fit it.

    Parameters
    ----------
    blas : fsm_models.LevelBLAs
        The training records and their BLAs.
    orders : dict {level_mV: int} or sequence of 3 int
        Per-level linear orders whose models' poles form the basis (e.g. the
        orders chosen by validation, ``LinearModels.selections``).
    candidates : dict {str: branches}, optional
        Default :data:`CANDIDATES`.
    windows_samples : sequence of float, optional
        Candidate amplitude windows [samples].

    Returns
    -------
    CausalFit
    """
    check_type("blas", blas, fsm_models.LevelBLAs, "a LevelBLAs (fsm_models.level_blas)")
    orders = _orders(orders)
    candidates = dict(CANDIDATES if candidates is None else candidates)
    if not candidates:
        raise ValueError("candidates must name at least one branch set")
    scale = _input_scale(blas)
    t0 = time.perf_counter()
    u_fit, y_fit, _ = _records(blas, FIT_REALISATIONS)
    u_val, y_val, val_levels = _records(blas, VALIDATION_REALISATIONS)
    selection = ident.select_basis_model(u_fit, y_fit, u_val, y_val, _poles(blas, orders, 0),
                                         list(candidates.values()), windows_samples, scale,
                                         n_init=fsm.N_INIT, ridge=RIDGE)
    t1 = time.perf_counter()
    model, fit_s = fit_causal_model(blas, orders, selection.branches, selection.window_samples)
    names = tuple(candidates)
    chosen = names[[tuple(b) for b in selection.candidates].index(selection.branches)]
    return CausalFit(model=model, orders=orders, candidate_names=names,
                     windows_samples=selection.windows_samples,
                     validation_nrmse=selection.validation_nrmse, validation_levels=val_levels,
                     fit_nrmse=selection.fit_nrmse, chosen=chosen, selection_s=t1 - t0,
                     fit_s=fit_s)


def fit_causal_model(blas, orders, branches, window_samples):
    """The causal model of given structure fitted on all six training realisations.

    Parameters
    ----------
    blas : fsm_models.LevelBLAs
    orders : dict {level_mV: int} or sequence of 3 int
        Per-level linear orders whose models' poles (fitted to each level's
        whole BLA) form the basis.
    branches : sequence of (str, int)
        E.g. a value of :data:`CANDIDATES`.
    window_samples : float
        The amplitude's window [samples].

    Returns
    -------
    model : identification.BasisModel
    seconds : float
        Wall time of the poles and the least-squares fit [s].
    """
    check_type("blas", blas, fsm_models.LevelBLAs, "a LevelBLAs (fsm_models.level_blas)")
    orders = _orders(orders)
    t0 = time.perf_counter()
    u_all, y_all, _ = _records(blas, FIT_REALISATIONS + VALIDATION_REALISATIONS)
    model = ident.fit_basis_model(u_all, y_all, _poles(blas, orders), branches, window_samples,
                                  _input_scale(blas), n_init=fsm.N_INIT, ridge=RIDGE)
    return model, time.perf_counter() - t0


def write_causal_model(fit, path=None):
    """Save a :class:`CausalFit` as ``.npz`` (default :func:`causal_model_path`).

    Parameters
    ----------
    fit : CausalFit
    path : str or Path, optional

    Returns
    -------
    Path
    """
    check_type("fit", fit, CausalFit, "a CausalFit (derive_causal_model)")
    path = causal_model_path() if path is None else check_path("path", path)
    arrays = {f"model_{k}": v for k, v in fit.model.to_arrays().items()}
    arrays |= {"orders": np.array([fit.orders[lv] for lv in fsm.LEVELS_MV]),
               "candidate_names": np.array(fit.candidate_names),
               "windows_samples": np.array(fit.windows_samples),
               "validation_nrmse": fit.validation_nrmse,
               "validation_levels": fit.validation_levels, "fit_nrmse": fit.fit_nrmse,
               "chosen": np.array(fit.chosen), "selection_s": np.float64(fit.selection_s),
               "fit_s": np.float64(fit.fit_s),
               "about": np.array("piezolib.problem.fsm_causal.derive_causal_model on the FSM "
                                 "benchmark's training files; re-derived by the slow test "
                                 "tests/problem/test_fsm_causal.py")}
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    return files.atomic_write(path, buffer.getvalue())


def read_causal_model(path=None):
    """The committed :class:`CausalFit` (default :func:`causal_model_path`).

    Parameters
    ----------
    path : str or Path, optional

    Returns
    -------
    CausalFit

    Examples
    --------
    >>> fit = read_causal_model()
    >>> fit.model.n_inputs, fit.model.n_outputs
    (3, 3)
    """
    path = causal_model_path() if path is None else check_path("path", path)
    try:
        with np.load(path, allow_pickle=False) as f:
            d = {k: f[k] for k in f.files}
    except (OSError, ValueError) as exc:
        raise ValueError(f"path: cannot read a causal model from {path} ({exc})") from None
    try:
        model = ident.BasisModel.from_arrays({k[6:]: v for k, v in d.items()
                                              if k.startswith("model_")})
        return CausalFit(model=model, orders=dict(zip(fsm.LEVELS_MV, map(int, d["orders"]))),
                         candidate_names=tuple(str(x) for x in d["candidate_names"]),
                         windows_samples=tuple(float(x) for x in d["windows_samples"]),
                         validation_nrmse=d["validation_nrmse"],
                         validation_levels=d["validation_levels"], fit_nrmse=d["fit_nrmse"],
                         chosen=str(d["chosen"]), selection_s=float(d["selection_s"]),
                         fit_s=float(d["fit_s"]))
    except (KeyError, ValueError, TypeError) as exc:
        raise ValueError(f"path: {path} is not a causal model file ({exc})") from None


@dataclass(frozen=True)
class CausalScores:
    """The causal model on the test sets beside the other models (:func:`score_causal_model`).

    Attributes
    ----------
    fit : CausalFit
    scores : dict {int: fsm_benchmark.Score}
        The official metric per test level.
    floors, drift_free_floors : dict {int: fsm_benchmark.Score}
        The metric's noise floor on the test sets, with and without the
        periods' constant offset (drift).
    linear : dict {int: float}
        The per-level linear models' test NRMSE [%] (each on its own level).
    scheduled : dict {int: float}
        The amplitude-scheduled model's (input RMS of the whole record: not causal) [%].
    """

    fit: CausalFit
    scores: dict
    floors: dict
    drift_free_floors: dict
    linear: dict
    scheduled: dict

    def nrmse(self, level_mV):
        """Test NRMSE [%] of the causal model at ``level_mV``."""
        return self.scores[level_mV].nrmse_percent

    def table(self):
        """Test NRMSE [%] per level: the causal model, the LFR, the linear and scheduled
        models, the floors, and the share of each model's squared error the floors explain."""
        levels, lfr = fsm.LEVELS_MV, fsm.PUBLISHED_NRMSE_PERCENT[fsm_models.LFR]
        models = {CAUSAL: [self.nrmse(lv) for lv in levels],
                  "published nonlinear LFR": [lfr[lv] for lv in levels],
                  "linear per level (own level)": [self.linear[lv] for lv in levels],
                  "amplitude-scheduled (not causal)": [self.scheduled[lv] for lv in levels]}
        t = pd.DataFrame(models, index=[fsm_models.level_label(lv) for lv in levels]).T
        floor = np.array([self.floors[lv].nrmse_percent for lv in levels])
        free = np.array([self.drift_free_floors[lv].nrmse_percent for lv in levels])
        t.loc["noise floor [%]"] = floor
        t.loc["noise floor without drift [%]"] = free
        for name, values in models.items():
            t.loc[f"{name}: share of the squared error the floor explains [%]"] = \
                100 * floor ** 2 / np.array(values) ** 2
            t.loc[f"{name}: ... the drift-free floor explains [%]"] = \
                100 * free ** 2 / np.array(values) ** 2
        t.loc[f"{CAUSAL}: below the LFR by [points]"] = \
            np.array([lfr[lv] for lv in levels]) - np.array(models[CAUSAL])
        t.loc[f"{CAUSAL}: times the drift-free floor"] = np.array(models[CAUSAL]) / free
        return t

    def summary_line(self):
        """One line: the causal model against the LFR and the floors."""
        levels, lfr = fsm.LEVELS_MV, fsm.PUBLISHED_NRMSE_PERCENT[fsm_models.LFR]
        below = [lv for lv in levels if self.nrmse(lv) < lfr[lv]]
        return (f"one causal model for all levels ({self.fit.chosen}, window "
                f"{self.fit.model.window_samples:g} samples, {self.fit.model.n_regressors} "
                f"coefficients per output, one least-squares fit of {self.fit.fit_s:.0f} s): "
                f"test NRMSE {' / '.join(f'{self.nrmse(lv):.2f}' for lv in levels)} % against "
                f"the neural LFR's {' / '.join(f'{lfr[lv]:.2f}' for lv in levels)} %: below it at "
                f"{', '.join(f'{lv} mV' for lv in below) or 'no level'}; "
                f"{' / '.join(f'{self.nrmse(lv) / self.drift_free_floors[lv].nrmse_percent:.1f}' for lv in levels)}"
                f" times the drift-free noise floor "
                f"({' / '.join(f'{self.drift_free_floors[lv].nrmse_percent:.2f}' for lv in levels)} %)")

    @property
    def checks(self):
        """Causal (the future does not move the past), above the floor, below the linear
        per-level models (where they were given)."""
        u = fsm.load(200, "test")[0][:, :, 0, 0]
        v = u.copy()
        v[4000:] = -v[4000:]
        m = self.fit.model
        causal = bool(np.array_equal(m.simulate(u)[:4000], m.simulate(v)[:4000]))
        out = {"the causal model's output up to k does not change with the inputs after k":
               causal}
        for lv in fsm.LEVELS_MV:
            out[f"{lv} mV: causal model above the drift-free noise floor"] = bool(
                self.nrmse(lv) > self.drift_free_floors[lv].nrmse_percent)
            if np.isfinite(self.linear[lv]):
                out[f"{lv} mV: causal model below the linear model of its level"] = bool(
                    self.nrmse(lv) < self.linear[lv])
        return out

    @property
    def reference_checks(self):
        """The causal model below the published neural LFR at every level (issue 53's goal)."""
        lfr = fsm.PUBLISHED_NRMSE_PERCENT[fsm_models.LFR]
        return {f"{lv} mV: causal model below the published LFR ({lfr[lv]} %)": bool(
            self.nrmse(lv) < lfr[lv]) for lv in fsm.LEVELS_MV}


def score_causal_model(fit, linear_scores=None, nonlinear=None):
    """The official metric of the causal model on every test set, beside the other models.

    Parameters
    ----------
    fit : CausalFit
        E.g. :func:`read_causal_model`.
    linear_scores : fsm_models.LinearScores, optional
        For the per-level linear models' scores (NaN without).
    nonlinear : fsm_models.NonlinearModels, optional
        For the amplitude-scheduled model's scores (NaN without).

    Returns
    -------
    CausalScores
    """
    check_type("fit", fit, CausalFit, "a CausalFit (read_causal_model)")
    if linear_scores is not None:
        check_type("linear_scores", linear_scores, fsm_models.LinearScores,
                   "a LinearScores (fsm_models.score_linear_models)")
    if nonlinear is not None:
        check_type("nonlinear", nonlinear, fsm_models.NonlinearModels,
                   "a NonlinearModels (fsm_models.fit_nonlinear_models)")
    levels = fsm.LEVELS_MV
    scores = {lv: fsm.score_simulation(fit.model.simulate, lv) for lv in levels}
    floors = {lv: fsm.noise_floor(lv) for lv in levels}
    free = {lv: fsm.noise_floor(lv, without_drift=True) for lv in levels}
    linear = {lv: linear_scores.own(lv) if linear_scores is not None else float("nan")
              for lv in levels}
    scheduled = {lv: nonlinear.scores[fsm_models.SCHEDULED][lv].nrmse_percent
                 if nonlinear is not None else float("nan") for lv in levels}
    return CausalScores(fit=fit, scores=scores, floors=floors, drift_free_floors=free,
                        linear=linear, scheduled=scheduled)
