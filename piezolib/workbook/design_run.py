"""The record of a study's design searches: what notebook 05 shows of how the controllers came.

The DK-iteration, the fixed-order search and the delay sweep (a DK-iteration
and a lower bound for each computation delay) take minutes, and their path
depends on floating-point details.  For the ``reference`` study their record —
the DK history, the optimal and fitted D-scaling of the last K-step, the
fixed-order history, the sweep's mu_RP and lower bounds — is committed beside
the controllers (``data/controllers/reference_design_run.json``), written by
``python -m piezolib controllers --write-reference`` from the same derivation as
the controllers, so notebook 05 shows the searches without re-running them.
The slow test step re-runs them from scratch and checks that they land within
:data:`~piezolib.problem.verification.RE_DERIVATION_RTOL` of the record
(``tests/workbook/test_design_rederivation.py``).  Any other study derives its
record on first use (disk cache, :func:`piezolib.workbook.pipeline.checked_cache_call`).
"""

import json
from dataclasses import dataclass

import control as ct
import numpy as np
import pandas as pd

from piezolib._checks import check_bool, check_path, check_type
from piezolib.files import atomic_write, seal, seal_problem
from piezolib.problem import design as problem_design
from piezolib.problem.verification import delay_sweep
from piezolib.workbook import outputs, pipeline
from piezolib.workbook import study as studies

__all__ = ["SearchRecord", "DesignRun", "SWEEP_DELAYS", "design_run_path", "study_design_run",
           "derive_design_run", "write_design_run", "write_reference_record",
           "read_design_run"]

#: Computation delays [samples] of the delay sweep.
SWEEP_DELAYS = (0, 1, 2)


@dataclass(frozen=True)
class SearchRecord:
    """What one search left: its history and why it stopped.

    Attributes
    ----------
    history : pandas.DataFrame
        One row per iteration (the search's ``history``).
    stop_reason : str
    mu_peak, mu_lower_peak : float
        Peak of the mu upper and lower bounds of the result (NaN where the
        search gives no lower bound).
    omega : ndarray
        The search's (final) frequency grid [rad/s].
    elapsed : float
        Its wall time [s] (information only).
    optimal_d : ndarray or None
        DK-iteration: the optimal d(omega) of the first full block for the final K.
    d_fit : ndarray or None
        DK-iteration: the response on ``omega`` of the fitted d(s) of the K-step that
        produced K (None when the first K-step, unscaled, was the best).
    d_fit_order : int
        The order of that fit.
    """

    history: pd.DataFrame
    stop_reason: str
    mu_peak: float
    mu_lower_peak: float
    omega: np.ndarray
    elapsed: float
    optimal_d: np.ndarray = None
    d_fit: np.ndarray = None
    d_fit_order: int = 0

    @classmethod
    def of_dk(cls, result):
        """The record of a :class:`~piezolib.robust.dk.MusynResult`."""
        omega = np.asarray(result.omega, float)
        fit, order = None, 0
        if result.d_scalings:
            fit = np.ravel(result.d_scalings[0](1j * omega))
            order = len(ct.poles(result.d_scalings[0]))
        return cls(result.history, result.stop_reason, float(result.mu_peak),
                   float(result.mu_lower_peak), omega, float(result.elapsed),
                   np.asarray(result.mu.d)[:, 0], fit, order)

    @classmethod
    def of_fixed_order(cls, result):
        """The record of a :class:`~piezolib.robust.fixed_order.FixedOrderResult`."""
        return cls(result.history, result.stop_reason, float(result.mu_peak),
                   float(result.mu_lower_peak), np.asarray(result.omega, float),
                   float(result.elapsed))

    def to_dict(self):
        """A JSON-ready dict (NaN as None)."""
        return {"history": {"columns": list(self.history.columns),
                            "rows": [[_json_number(x) for x in row]
                                     for row in self.history.itertuples(index=False)]},
                "stop_reason": self.stop_reason, "mu_peak": self.mu_peak,
                "mu_lower_peak": _json_number(self.mu_lower_peak),
                "omega": self.omega.tolist(), "elapsed": self.elapsed,
                "optimal_d": _complex_to_json(self.optimal_d),
                "d_fit": _complex_to_json(self.d_fit), "d_fit_order": self.d_fit_order}

    @classmethod
    def from_dict(cls, doc):
        """The inverse of :meth:`to_dict`."""
        history = pd.DataFrame([[np.nan if x is None else x for x in row]
                                for row in doc["history"]["rows"]],
                               columns=doc["history"]["columns"])
        return cls(history, str(doc["stop_reason"]), float(doc["mu_peak"]),
                   np.nan if doc["mu_lower_peak"] is None else float(doc["mu_lower_peak"]),
                   np.array(doc["omega"], float), float(doc["elapsed"]),
                   _complex_from_json(doc["optimal_d"]), _complex_from_json(doc["d_fit"]),
                   int(doc["d_fit_order"]))


def _complex_to_json(x):
    """[real parts, imaginary parts] of an array (None for None), exact in JSON."""
    return None if x is None else [np.real(x).tolist(), np.imag(x).tolist()]


def _complex_from_json(doc):
    """The inverse of :func:`_complex_to_json` (a real array when the parts are zero)."""
    if doc is None:
        return None
    real, imag = (np.array(part, float) for part in doc)
    return real if not imag.any() else real + 1j * imag


def _json_number(x):
    """x for JSON: a numpy scalar as a Python one, NaN and infinities as None."""
    if isinstance(x, (np.integer, int)) and not isinstance(x, bool):
        return int(x)
    if isinstance(x, (np.floating, float)):
        return float(x) if np.isfinite(x) else None
    return x


@dataclass(frozen=True)
class DesignRun:
    """The record of a study's design searches (see the module docstring).

    Attributes
    ----------
    study, digest : str
        The study and the :func:`~piezolib.workbook.pipeline.design_digest` of its choices.
    source : str
        Where the record came from (the committed file, the cache, a fresh run).
    dk, fixed_order : SearchRecord
        The delay-aware DK-iteration and the fixed-order search.
    mu : dict
        mu_RP of the designs, as :attr:`StudyControllers.mu`.
    delay_sweep : dict
        ``{delay [samples]: (DK mu_RP, lower bound)}`` for :data:`SWEEP_DELAYS` (the
        lower bound NaN where its H-inf search failed).
    K_full, K_fixed : control.StateSpace
        The DK-iteration's and the fixed-order controller the searches gave (compared
        with the controllers the notebooks use by
        :func:`~piezolib.problem.verification.compare_rederived`).
    """

    study: str
    digest: str
    source: str
    dk: SearchRecord
    fixed_order: SearchRecord
    mu: dict
    delay_sweep: dict
    K_full: ct.StateSpace
    K_fixed: ct.StateSpace


def design_run_path():
    """``data/controllers/reference_design_run.json``: the committed record.

    Examples
    --------
    >>> design_run_path().relative_to(outputs.project_root()).as_posix()
    'data/controllers/reference_design_run.json'
    """
    return outputs.study_controllers_dir(studies.REFERENCE) / "reference_design_run.json"


def _sweep_values(problem, design_choices, delays, fingerprint):
    """{d: (DK mu_RP, lower bound)} of the delay sweep (the cached computation;
    ``fingerprint`` only keys the cache)."""
    G, H_m, H_e, H_y, _ = problem
    table = delay_sweep(G, H_m, H_e, H_y, fs=design_choices["fs"],
                        d_order=design_choices["d_order"], grid=problem_design.DESIGN_GRID,
                        delays=delays).table
    return {int(d): (float(row["DK mu_RP"]), float(row["lower bound"]))
            for d, row in table.iterrows()}


def _check_derived(derived):
    check_type("derived", derived, pipeline.StudyControllers,
               "the StudyControllers of pipeline.derive_controllers")


def derive_design_run(study, cache=True, derived=None):
    """Run the study's searches (or read them from the disk cache) and record them.

    Parameters
    ----------
    study : Study, str or path
    cache : bool
        Use the disk cache; False always recomputes.
    derived : StudyControllers, optional
        The study's controllers as :func:`~piezolib.workbook.pipeline.derive_controllers`
        returned them (with their design records), if already derived.

    Returns
    -------
    DesignRun
    """
    cache = check_bool("cache", cache)
    if derived is not None:
        _check_derived(derived)
    study = studies.load(study)
    if derived is None or derived.design is None:
        derived = pipeline.derive_controllers(study, cache=cache)
    problem = pipeline.study_problem(study)
    choices = {"fs": study.loop.fs_Hz, "d_order": study.design.d_order}
    args = (tuple(problem), choices, SWEEP_DELAYS, pipeline.library_fingerprint())
    if cache:
        sweep, _ = pipeline.checked_cache_call(_sweep_values, *args)
    else:
        sweep = _sweep_values(*args)
    return DesignRun(study.name, derived.digest, derived.source,
                     SearchRecord.of_dk(derived.design.musyn),
                     SearchRecord.of_fixed_order(derived.design.fixed_order),
                     dict(derived.mu), sweep, derived.K_full, derived.K_fixed)


def study_design_run(study):
    """The record notebook 05 shows: the committed one for the reference study (checked
    against its choices), derived (:func:`derive_design_run`) for any other.

    Raises
    ------
    ArtifactError
        The committed record is missing or was made for other choices.
    """
    study = studies.load(study)
    if not study.is_reference:
        return derive_design_run(study)
    path = design_run_path()
    if not path.is_file():
        raise pipeline.ArtifactError(f"{path} is missing: run `{pipeline._WRITE_REFERENCE}`")
    found = read_design_run(path)
    if found.digest != pipeline.design_digest(study):
        raise pipeline.ArtifactError(
            f"{path} was made for other choices (digest {found.digest}, the reference "
            f"study's is {pipeline.design_digest(study)}): `{pipeline._WRITE_REFERENCE}`")
    return found


def write_design_run(run, path):
    """Write ``run`` as sealed JSON; return the path."""
    check_type("run", run, DesignRun, "a DesignRun (derive_design_run)")
    path = check_path("path", path)
    doc = {"format": pipeline.ARTIFACT_FORMAT, "study": run.study, "digest": run.digest,
           "library": pipeline.library_fingerprint(),
           "mu": {k: _json_number(v) for k, v in run.mu.items()},
           "dk": run.dk.to_dict(), "fixed_order": run.fixed_order.to_dict(),
           "delay_sweep": {str(d): [_json_number(v) for v in pair]
                           for d, pair in run.delay_sweep.items()},
           "controllers": {"K_full": pipeline._ss_to_dict(run.K_full),
                           "K_fixed": pipeline._ss_to_dict(run.K_fixed)}}
    path.parent.mkdir(parents=True, exist_ok=True)
    return atomic_write(path, json.dumps(seal(doc), indent=1, allow_nan=False) + "\n")


def write_reference_record(derived):
    """Record the reference study's searches (the delay sweep run here) beside the
    controllers ``derived`` just derived (:func:`pipeline.write_reference_design`);
    return the path of :func:`design_run_path`."""
    _check_derived(derived)
    run = derive_design_run(studies.REFERENCE, derived=derived)
    return write_design_run(run, design_run_path())


def read_design_run(path):
    """Read a file of :func:`write_design_run`.

    Raises
    ------
    ArtifactError
        Naming the file: not a design record, or its checksum fails.
    OSError
        The file cannot be read (missing, a folder).

    Examples
    --------
    >>> run = read_design_run(design_run_path())
    >>> run.study, sorted(run.delay_sweep), run.dk.stop_reason != ""
    ('reference', [0, 1, 2], True)
    """
    path = check_path("path", path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except ValueError as exc:           # an unreadable file is the OSError naming it
        raise pipeline.ArtifactError(f"{path}: not a design record ({exc})") from None
    problem = seal_problem(doc) if isinstance(doc, dict) else "not a JSON object"
    if problem is not None:
        raise pipeline.ArtifactError(f"{path}: {problem}; write it anew with "
                                     f"`{pipeline._WRITE_REFERENCE}`")
    try:
        sweep = {int(d): tuple(np.nan if v is None else float(v) for v in pair)
                 for d, pair in doc["delay_sweep"].items()}
        return DesignRun(doc["study"], doc["digest"], str(path),
                         SearchRecord.from_dict(doc["dk"]),
                         SearchRecord.from_dict(doc["fixed_order"]),
                         {k: np.nan if v is None else float(v) for k, v in doc["mu"].items()},
                         sweep,
                         *(pipeline._ss_from_dict(doc["controllers"][name])
                           for name in ("K_full", "K_fixed")))
    except (KeyError, TypeError, ValueError) as exc:
        raise pipeline.ArtifactError(f"{path}: not a design record ({exc})") from None
