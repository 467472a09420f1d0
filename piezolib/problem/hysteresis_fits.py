"""The paper's Dahl model and the workbook's Dahl fit to the virtual stage's Case I loops.

:func:`published_dahl` is the model of Sec. III-C with the printed parameters.
:data:`CASE_I_CANDIDATES` are the (form, offset, start) fits that notebook 03
compares, :func:`fit_case_I_loops` fits one of them (cached in-process), and
:func:`workbook_dahl_fit` is the one feedforward model shared by notebooks 03
and 06 and :mod:`piezolib.workbook.experiments` (:data:`WORKBOOK_DAHL`, the choice of
:func:`piezolib.hysteresis.choose_fit`).  :func:`workbook_pi_fit` is the
Prandtl-Ishlinskii model fitted to the same loops, and :func:`validation_loops`
records of the virtual stage that neither model was fitted to (model choice by
validation, notebook 03).  Background: ``docs/hysteresis.md``.
"""

import functools
import hashlib
import json
from dataclasses import fields
from pathlib import Path

import numpy as np


from piezolib.problem import paper
from piezolib._checks import check_integer, check_path, check_type
from piezolib.hysteresis.dahl import FORMS, STARTS, DahlModel
from piezolib.hysteresis.fit import check_fit_options, fit_dahl, rescore_dahl
from piezolib.problem.paths import check_directory, data_dir
from piezolib.files import CONTENT_KEY, atomic_write, seal, seal_problem
from piezolib.hysteresis.pi import fit_pi

__all__ = ["share_stored_model_check", "published_dahl", "CASE_I_CANDIDATES", "WORKBOOK_DAHL", "fit_case_I_loops",
           "workbook_dahl_fit", "workbook_dahl_path", "read_dahl_model", "write_dahl_model",
           "write_workbook_dahl", "PI_PLAYS", "workbook_pi_fit",
           "VALIDATION_AMPLITUDES_V", "validation_loops"]

#: Play operators of the workbook's Prandtl-Ishlinskii model (linear one included).
PI_PLAYS = 10
#: Actuator amplitudes [V] of the validation triangles (between Table 4's 10-40 V).
VALIDATION_AMPLITUDES_V = (15.0, 25.0, 35.0)

#: Candidate (form, offset, start) fits to the Case I loops.  From rest the
#: printed form's H is constant (both directions share one steady state), so
#: that form is fitted from the virgin state only.
CASE_I_CANDIDATES = tuple((form, offset, start) for form in FORMS for offset in (False, True)
                          for start in STARTS if not (form == "printed" and start == "rest"))
#: The candidate that :func:`piezolib.hysteresis.choose_fit` selects on the
#: virtual stage's Case I loops (checked in notebook 03); the model behind
#: :func:`workbook_dahl_fit`.
WORKBOOK_DAHL = ("bliman_sorine", True, "rest")


def published_dahl(form="printed", params=paper.DAHL):
    """The paper's identified Dahl model (Sec. III-C) in the given form.

    Parameters
    ----------
    form : {"printed", "bliman_sorine"}, optional
        Where the sign of the velocity enters (``docs/hysteresis.md``).
    params : paper.DahlParameters, optional
        The parameters (default: the published ones, :data:`piezolib.problem.paper.DAHL`).

    Returns
    -------
    DahlModel
        With offset x0 = 0 and a virgin start: eq. 10-13 exactly.

    Examples
    --------
    >>> model = published_dahl()                    # eq. 10-13 as printed
    >>> model.form, model.alpha1, model.g_a
    ('printed', 1760.0, 0.925)
    >>> published_dahl("bliman_sorine").form
    'bliman_sorine'
    """
    if not isinstance(params, paper.DahlParameters):
        raise TypeError("params must be a paper.DahlParameters instance")
    return DahlModel(**{f.name: getattr(params, f.name) for f in fields(params)}, form=form)


def fit_case_I_loops(form, offset, start, directory=None, stride=10):
    """Joint fit of one candidate to the Table 4 Case I loops (cached in-process).

    The four 10 Hz loops of :func:`piezolib.problem.stage_data.load_hysteresis_loops`
    (v = u_c [V], x = v_y [V]), the first period left out of the residuals
    (the model still runs through it), every ``stride``-th sample used in the
    fit, gamma_a held at the published 30.  The result is cached per argument
    set (:func:`_clear_cache` empties the cache): treat it as read-only.

    Parameters
    ----------
    form : {"printed", "bliman_sorine"}
    offset : bool
        Fit the output offset x0.
    start : {"virgin", "rest"}
        The model's initial state.
    directory : str or Path, optional
        Where the experiment files are (default: the workbook's ``data/``).
    stride : int, optional

    Returns
    -------
    DahlFit
    """
    form, offset, start = check_fit_options(form, offset, start)
    directory = _directory_key(directory)
    return _fit_case_I_loops(form, offset, start, directory,
                             check_integer("stride", stride, minimum=1))


@functools.lru_cache(maxsize=None)
def _fit_case_I_loops(form, offset, start, directory, stride):
    """:func:`fit_case_I_loops` with normalised arguments (one cache entry per fit)."""
    return fit_dahl(_case_I_loops(directory), gamma_a=paper.DAHL.gamma_a, form=form,
                    offset=offset, start=start, discard=_period(), stride=stride)


def _case_I_loops(directory):
    """The Case I loops as (u_c [V], v_y [V]) pairs."""
    from piezolib.problem import stage_data     # lazy: the stage modules are heavier than this one
    loops = stage_data.load_hysteresis_loops(None if directory is None else Path(directory))
    return [(rec.u_c_V, rec.v_y_V) for rec in loops.values()]


def _directory_key(directory):
    """``directory`` as the str the caches key on, checked first: ``str()`` would make a
    number a folder name and fail later as a missing file."""
    return None if directory is None else str(check_directory(directory))


def _clear_cache():
    """Forget every cached :func:`fit_case_I_loops` / :func:`workbook_pi_fit` result."""
    _fit_case_I_loops.cache_clear()
    _stored_fit.cache_clear()
    _workbook_pi_fit.cache_clear()


def _period():
    return int(round(paper.SAMPLING_FREQUENCY_HZ / paper.HYSTERESIS_TEST["frequency_Hz"]))


def workbook_pi_fit(directory=None, n_plays=PI_PLAYS):
    """Prandtl-Ishlinskii model fitted to the Case I loops (cached in-process).

    The same four loops, samples and residual weights as the Dahl fits
    (v = u_c [V], x = v_y [V], first period left out of the residuals),
    ``n_plays`` plays with thresholds evenly spaced up to half the largest
    input range, output offset fitted, plays at rest at the first sample.

    Returns
    -------
    PIFit
    """
    directory = _directory_key(directory)
    return _workbook_pi_fit(directory, check_integer("n_plays", n_plays, minimum=1))


@functools.lru_cache(maxsize=None)
def _workbook_pi_fit(directory, n_plays):
    from piezolib.problem import stage_data
    loops = stage_data.load_hysteresis_loops(None if directory is None else Path(directory))
    return fit_pi([(rec.u_c_V, rec.v_y_V) for rec in loops.values()], n_plays=n_plays,
                  offset=True, start="rest", discard=_period())


def validation_loops(stage=None):
    """Virtual-stage records that no model was fitted to, for model choice by validation.

    Three 10 Hz triangles of :data:`VALIDATION_AMPLITUDES_V` (three periods)
    and one record with nested minor loops (a 5 Hz sine of 1.5 V plus a
    23 Hz sine of 0.4 V about 2 V at the amplifier input, 0.6 s), each
    from rest, scored after its first 0.1 s.

    Parameters
    ----------
    stage : VirtualStage, optional
        Default: ``VirtualStage(seed=1)`` (other noise than the Case I files).

    Returns
    -------
    dict
        {label: (u_c [V], v_y [V], first scored sample)}.

    Raises
    ------
    TypeError
        ``stage`` is not a :class:`~piezolib.problem.stage.VirtualStage`.

    Examples
    --------
    >>> loops = validation_loops()                  # VirtualStage(seed=1), 10 kHz
    >>> list(loops)
    ['triangle 15 V', 'triangle 25 V', 'triangle 35 V', 'minor loops']
    >>> u_c, v_y, first = loops["triangle 25 V"]
    >>> u_c.shape == v_y.shape, first              # scored from the second period
    (True, 1000)
    """
    from piezolib import signals
    from piezolib.problem.stage import VirtualStage
    stage = VirtualStage(seed=1) if stage is None else check_type("stage", stage, VirtualStage,
                                                                  "a VirtualStage")
    fs = stage.fs
    f = paper.HYSTERESIS_TEST["frequency_Hz"]
    first = int(round(fs / f))
    out = {}
    for A in VALIDATION_AMPLITUDES_V:
        t, u = signals.triangle(A / paper.AMPLIFIER_GAIN, f, periods=3, fs=fs)
        out[f"triangle {A:.0f} V"] = (u, stage.run(u).v_y_V, first)
    t = np.arange(int(0.6 * fs)) / fs
    u = 2.0 - 1.5 * np.cos(2 * np.pi * 5 * t) + 0.4 * np.sin(2 * np.pi * 23 * t) - \
        0.5 * (1 - np.exp(-t / 0.05))
    u = np.maximum(u - u[0], 0.0)
    out["minor loops"] = (u, stage.run(u).v_y_V, first)
    return out


def workbook_dahl_fit(directory=None):
    """The workbook's feedforward model: :data:`WORKBOOK_DAHL` fitted to the Case I loops.

    One shared, cached fit for notebooks 03 and 06 and :mod:`piezolib.workbook.experiments`,
    so that they cannot diverge.  Notebook 03 checks that
    :func:`piezolib.hysteresis.choose_fit` picks :data:`WORKBOOK_DAHL` among
    :data:`CASE_I_CANDIDATES`.

    On the workbook's own data the model is the committed one,
    :func:`workbook_dahl_path` (written by ``python -m piezolib controllers
    --write-reference``), after a check that the refit reaches the same
    optimum: the end point along the fit's flat valley depends on the
    machine's rounding, the committed model does not.

    Returns
    -------
    DahlFit

    Raises
    ------
    ValueError
        The committed model is not an optimum of the current fit (the
        experiment files or the fit changed).
    """
    if directory is not None or not workbook_dahl_path().is_file():
        return fit_case_I_loops(*WORKBOOK_DAHL, directory=directory)
    return _stored_fit(str(workbook_dahl_path()))


#: Agreement of the stored and the refitted workbook model on the Case I loops: their pooled
#: RMS error, the criterion the fit minimises (its cost stops changing at 1e-10 relative; the
#: pooled RMS over every sample, not only the fitted ones, moved 6e-8 between BLAS kernels,
#: another noise draw of the data moves it by about 1e-3), and their outputs, relative to the
#: smallest loop's misfit (5e-5 between kernels: far below what the fit can resolve).
_STORED_RMS_RTOL = 1e-6
_STORED_OUTPUT_RTOL = 1e-3


def workbook_dahl_path():
    """``data/models/workbook_dahl.json``: the committed workbook Dahl model.

    Examples
    --------
    >>> workbook_dahl_path().relative_to(data_dir()).as_posix()
    'models/workbook_dahl.json'
    """
    return data_dir() / "models" / "workbook_dahl.json"


#: ``call(func, *args) -> func(*args)`` through a cache shared between processes, or None
#: (each process refits to check the stored model): :func:`share_stored_model_check`.
_shared_check = None


def share_stored_model_check(call):
    """Let every process of a run share the stored workbook model's refit check.

    :func:`workbook_dahl_fit` refits the Case I loops to check that the
    committed model is the fit's optimum (a few seconds); each notebook's
    kernel did it again.  With ``call`` set (the workbook passes its disk
    cache), the check runs once per content of its inputs: the stored file's
    bytes and the loops' samples are part of the key, so an edited model or
    changed experiment files are checked anew.

    Parameters
    ----------
    call : callable or None
        ``call(func, *args)`` returning ``func(*args)``, possibly from a cache
        keyed on ``func`` and ``args``; None: check in every process.

    Examples
    --------
    >>> share_stored_model_check(lambda func, *args: func(*args))
    >>> share_stored_model_check(None)
    """
    global _shared_check
    if call is not None and not callable(call):
        raise TypeError(f"call must be a callable or None, got {call!r}"[:200])
    _shared_check = call
    _stored_fit.cache_clear()


def _check_key(path):
    """What the stored model's check depends on: the file's and the loops' SHA-256."""
    h = hashlib.sha256(Path(path).read_bytes())
    for u, v in _case_I_loops(None):
        h.update(np.ascontiguousarray(u).tobytes())
        h.update(np.ascontiguousarray(v).tobytes())
    return h.hexdigest()


@functools.lru_cache(maxsize=None)
def _stored_fit(path):
    """:func:`_checked_stored_fit`, through the shared check when one is set."""
    if _shared_check is None:
        return _checked_stored_fit(path)
    return _shared_check(_checked_stored_fit, path, _check_key(path))


def _checked_stored_fit(path, *key):
    """``fit`` moved to the stored model, after checking that both are the same optimum
    (``key``: :func:`_check_key` and what else the shared check keys on; unused here).

    alpha1, alpha2 and beta2 are identifiable only in combination, so where
    along that valley the fit ends depends on rounding (relative 1e-4 between
    BLAS kernels), and the closed-loop experiments downstream amplify that
    through the 16-bit converters.  The committed model is the one input they
    all use; the refit only checks it.
    """
    fit = fit_case_I_loops(*WORKBOOK_DAHL)
    stored = read_dahl_model(path)
    moved = rescore_dahl(fit, stored, _case_I_loops(None), discard=_period())
    output_gap = max(float(np.max(np.abs(a - b))) for a, b in zip(moved.x_model, fit.x_model))
    pooled_gap = abs(moved.pooled_rms_percent / fit.pooled_rms_percent - 1)
    if not (pooled_gap <= _STORED_RMS_RTOL
            and output_gap <= _STORED_OUTPUT_RTOL * float(np.min(fit.rms))):
        raise ValueError(
            f"{path} no longer matches the fit of the Case I loops (pooled RMS "
            f"{moved.pooled_rms_percent:.6g} % against {fit.pooled_rms_percent:.6g} %, outputs "
            f"{output_gap:.2g} V apart): the "
            "experiment files or the fit changed; write it anew with `python -m piezolib "
            "controllers --write-reference`")
    return moved


def read_dahl_model(path):
    """A :class:`DahlModel` from a JSON file of :func:`write_dahl_model`.

    Raises
    ------
    TypeError
        ``path`` is not a str or path object.
    OSError
        The file cannot be read (missing, a folder), naming it.
    ValueError
        Naming the file: not a Dahl model file of this format, or its content
        fails its checksum (edited or corrupted), with the way to write it anew.

    Examples
    --------
    >>> model = read_dahl_model(workbook_dahl_path())     # the committed workbook model
    >>> model.form
    'bliman_sorine'
    """
    path = check_path("path", path)
    doc = _read_model_document(path)
    problem = seal_problem(doc)
    if problem is not None:
        what = (problem if CONTENT_KEY in doc else
                f"not a Dahl model file written by this version of piezolib ({problem})")
        raise ValueError(f"{path}: {what}; write it anew with {_rewrite_hint(path)}")
    try:
        return DahlModel(**doc["model"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{path}: not a Dahl model file ({exc})") from None


def _read_model_document(path):
    """The JSON object of a Dahl model file, after checking its format version."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(doc, dict):
            raise ValueError(f"a JSON {type(doc).__name__}, not an object")
        if doc.get("format") != _MODEL_FORMAT:
            raise ValueError(f"format {doc.get('format')!r}, expected {_MODEL_FORMAT}")
        return doc
    except ValueError as exc:
        raise ValueError(f"{path}: not a Dahl model file ({exc})") from None


def _rewrite_hint(path):
    """How to write the Dahl model file ``path`` anew."""
    if path.resolve() == workbook_dahl_path().resolve():
        return "`python -m piezolib controllers --write-reference`"
    return "piezolib.problem.hysteresis_fits.write_dahl_model"


def write_dahl_model(model, path, about=""):
    """Write ``model`` as JSON (floats at full precision: they read back bit for bit).

    The file carries the SHA-256 of its content (:func:`piezolib.files.seal`),
    which :func:`read_dahl_model` checks.

    Parameters
    ----------
    model : DahlModel
    path : str or os.PathLike
        The JSON file (written atomically).
    about : str, optional
        What the model is, stored with it.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    TypeError
        ``model`` not a DahlModel, ``path`` not a path or ``about`` not text (it would
        otherwise be written as whatever JSON makes of it).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = write_dahl_model(published_dahl(), Path(folder) / "dahl.json", about="eq. 10-13")
    ...     print(path.name, read_dahl_model(path) == published_dahl())
    dahl.json True
    """
    check_type("model", model, DahlModel, "a DahlModel")
    path = check_path("path", path)
    check_type("about", about, str, "text (str)")
    doc = {"format": _MODEL_FORMAT, "about": about,
           "model": {f.name: getattr(model, f.name) for f in fields(model)}}
    return atomic_write(path, json.dumps(seal(doc), indent=1) + "\n")


def write_workbook_dahl():
    """Refit the workbook model to the Case I loops and write :func:`workbook_dahl_path`."""
    _clear_cache()
    fit = fit_case_I_loops(*WORKBOOK_DAHL)
    return write_dahl_model(fit.model, workbook_dahl_path(),
                            about="the workbook's Dahl feedforward model "
                                  f"{WORKBOOK_DAHL} fitted to the Case I loops of data/ "
                                  "(piezolib.problem.hysteresis_fits.write_workbook_dahl)")


_MODEL_FORMAT = 1
