"""The pipeline's products, computed once per study and reused by later notebooks.

The expensive and machine-sensitive product is the controller design (the
DK-iteration follows a path that depends on floating-point details).  It is

* for the ``reference`` study, the committed artifact
  ``data/controllers/reference_design.json`` (state-space matrices written
  with full precision): notebooks 04-06 use it, notebook 05 re-derives it and
  compares the mu values, so downstream numbers do not depend on the machine;
* for any other study, derived on first use and cached on disk with joblib
  (``runs/cache/``, keyed by the study's weights, design and loop choices,
  its uncertainty weight and the library's source), and written to ``runs/<study>/artifacts/`` with
  the choices it came from — so a change made for notebook 04 flows into 05,
  06 and 07, and re-running 06 does not redo the DK-iteration.

``PIEZOLIB_CACHE=off`` disables the disk cache; ``PIEZOLIB_CACHE=<folder>``
moves it.  Every cache entry carries a SHA-256 of its content
(:func:`checked_cache_call`): an entry that was corrupted on disk is computed
anew, never served.  The committed and written controller files carry one
too (:func:`write_controllers`), checked by :func:`read_controllers`.
"""

import copyreg
import functools
import hashlib
import inspect
import json
import logging
import os
import pickle
from dataclasses import dataclass, field
from pathlib import Path

import control as ct
import numpy as np

from piezolib._checks import check_path, check_type
from piezolib.problem import paper
from piezolib.problem.design import (MixedDesign, choose_mixed_design, design_controller,
                                     mixed_tradeoff)
from piezolib.problem.hysteresis_fits import write_workbook_dahl
from piezolib.files import CONTENT_KEY, atomic_write, seal, seal_problem
from piezolib.robust import export, frequency_grid
from piezolib.robust.discrete import discretize
from piezolib.uncertainty import fit_covering_weight, model_set, relative_error_envelope
from piezolib.workbook import outputs
from piezolib.workbook import study as studies
from piezolib.workbook.two_dof import dynamics_inverse

__all__ = ["StudyControllers", "study_problem", "study_uncertainty_weight",
           "study_controllers", "derive_controllers", "design_choices", "design_digest",
           "memory", "checked_cache_call", "library_fingerprint", "reference_design_path",
           "write_controllers", "read_controllers", "write_reference_design",
           "case_III_controllers", "discretized_controllers", "export_sections",
           "study_sections", "SECTION_FILES", "ArtifactError", "CACHE_ENV",
           "FEEDFORWARD_FILE", "export_feedforward_sections", "study_feedforward_sections",
           "MixedDesigns", "MIXED_FILE", "MIXED_SECTIONS_FILE", "mixed_design_path",
           "derive_mixed_designs", "write_mixed_designs", "read_mixed_designs",
           "write_reference_mixed_designs",
           "study_mixed_designs", "study_mixed_sections"]

logger = logging.getLogger(__name__)

#: Environment variable: ``off`` disables the disk cache, a folder moves it.
CACHE_ENV = "PIEZOLIB_CACHE"
#: Format version of the controller artifact files.
ARTIFACT_FORMAT = 1
_DESIGN_SECTIONS = ("weights", "design", "loop")
_CONTROLLERS = ("K_full", "K_reduced", "K_fixed", "K_nodelay_full", "K_nodelay_reduced")


class ArtifactError(ValueError):
    """A committed or cached artifact that does not fit the study asking for it (a
    ValueError: the file's content is the bad input).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "K.json"
    ...     _ = path.write_text("{}")
    ...     try:
    ...         read_controllers(path)
    ...     except ArtifactError as exc:
    ...         print(type(exc).__name__, isinstance(exc, ValueError))
    ArtifactError True
    """


@dataclass(frozen=True)
class StudyControllers:
    """The mu controllers of one study (continuous time, v_e [V] -> u_b [V]).

    Attributes
    ----------
    study : str
        Name of the study.
    digest : str
        :func:`design_digest` of the choices they were designed for.
    source : str
        Where they came from (the committed file, the cache or a fresh run).
    K_full, K_reduced, K_fixed : control.StateSpace
        Delay-aware design: DK-iteration, its reduction, and the fixed-order
        controller that is deployed.
    K_nodelay_full, K_nodelay_reduced : control.StateSpace
        The design for the paper's problem as printed (no delay).
    mu : dict
        mu_RP upper bounds reported by the syntheses: ``"delay-aware DK"``,
        ``"fixed order"``, ``"no-delay DK"``.
    design, nodelay : piezolib.problem.design.ControllerDesign or None
        The full design records (DK history, D-fits, reduction) when derived
        in this process or read from the cache; None when read from a file.

    Examples
    --------
    >>> controllers = read_controllers(reference_design_path())     # the committed ones
    >>> controllers.study, controllers.K_deployed is controllers.K_fixed
    ('reference', True)
    >>> controllers.K_fixed.nstates, sorted(controllers.mu)
    (6, ['delay-aware DK', 'fixed order', 'no-delay DK'])
    """

    study: str
    digest: str
    source: str
    K_full: ct.StateSpace
    K_reduced: ct.StateSpace
    K_fixed: ct.StateSpace
    K_nodelay_full: ct.StateSpace
    K_nodelay_reduced: ct.StateSpace
    mu: dict
    design: object = field(default=None, repr=False)
    nodelay: object = field(default=None, repr=False)

    @property
    def K_deployed(self):
        """The controller to implement (the fixed-order one)."""
        return self.K_fixed


def _rebuild_statespace(A, B, C, D, dt, inputs, outputs, states, name):
    return ct.ss(A, B, C, D, dt, inputs=inputs, outputs=outputs, states=states, name=name)


def _reduce_statespace(sys):
    # python-control's StateSpace holds lambdas (update/output functions) that pickle
    # cannot store; the matrices, the time base and the signal names are the whole model
    return _rebuild_statespace, (sys.A, sys.B, sys.C, sys.D, sys.dt, sys.input_labels,
                                 sys.output_labels, sys.state_labels, sys.name)


# the disk cache pickles the design records, which hold state-space models
copyreg.pickle(ct.StateSpace, _reduce_statespace)


def study_problem(study):
    """The design problem of ``study``: the published G and K, the study's H_m
    (:func:`study_uncertainty_weight`), H_e and H_y.

    Returns
    -------
    piezolib.problem.paper.DesignProblem

    Examples
    --------
    >>> G, H_m, H_e, H_y, K = study_problem("wide_error_weight")   # omega_e = 2000 rad/s
    >>> print(f"{1 / abs(H_e(2000j)):.2f}")                # the S template near 1 at omega_e
    0.89
    """
    study = studies.load(study)
    published = paper.problem()
    return published._replace(H_m=study_uncertainty_weight(study),
                              H_e=paper.error_weight(study.weights.error),
                              H_y=paper.output_weight(study.weights.output))


def study_uncertainty_weight(study):
    """The multiplicative uncertainty weight H_m of ``study`` (u_c -> y_Delta).

    The paper's H_m (eq. 8) when ``study.uncertainty.weight`` is
    ``"published"``; when ``"fitted"``, the covering weight of order
    ``weight_order`` fitted to the relative-error envelope of the stable
    members of the study's model set (spread, levels) around the published
    G, on the log-spaced ``weight_grid`` [rad/s]
    (:func:`piezolib.uncertainty.fit_covering_weight`).

    Examples
    --------
    >>> study_uncertainty_weight("reference").name                   # the paper's eq. 8
    'H_m'
    """
    return _uncertainty_weight(studies.load(study).uncertainty)


@functools.lru_cache(maxsize=8)
def _uncertainty_weight(choice):
    # keyed by the frozen UncertaintyChoice: notebooks 02, 04-06 and 09 ask for it repeatedly
    if choice.weight == "published":
        return paper.uncertainty_weight()
    omega = frequency_grid(*choice.weight_grid)
    members = model_set(paper.plant(), choice.spread, choice.levels)
    envelope = relative_error_envelope(members, omega, "stable")
    return fit_covering_weight(omega, envelope, choice.weight_order, inputs="u_c",
                               outputs="y_Delta", name="H_m")


def design_choices(study):
    """Every choice a controller design of ``study`` depends on: the weights,
    design and loop sections, and what its H_m depends on.

    Examples
    --------
    >>> sorted(design_choices("reference"))
    ['design', 'loop', 'uncertainty_weight', 'weights']
    """
    study = studies.load(study)
    return {**study.choices(*_DESIGN_SECTIONS),
            "uncertainty_weight": study.uncertainty.weight_choices()}


def design_digest(study):
    """Digest of :func:`design_choices`: two studies with the same digest share controllers.

    Examples
    --------
    >>> seeds = studies.Study().replace(name="more_seeds", experiments={"noise_seeds": 4})
    >>> design_digest(seeds) == design_digest("reference")     # experiments: same controllers
    True
    >>> design_digest("wide_error_weight") == design_digest("reference")
    False
    """
    return studies.choices_digest(design_choices(study))


def library_fingerprint():
    """SHA-256 (16 hex digits) of every ``piezolib`` source file: part of each cache key,
    so a change anywhere in the library invalidates the cached products.

    Examples
    --------
    >>> len(library_fingerprint())
    16
    """
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def memory():
    """The joblib disk cache of the pipeline (``runs/cache/`` unless :data:`CACHE_ENV` says)."""
    import joblib

    setting = os.environ.get(CACHE_ENV, "")
    if setting.lower() in {"0", "off", "no", "false"}:
        return joblib.Memory(location=None, verbose=0)
    location = Path(setting) if setting else outputs.runs_dir() / "cache"
    return joblib.Memory(location=location, verbose=0)


def checked_cache_call(func, *args):
    """``func(*args)`` through the disk cache (:func:`memory`), each entry checked on reading.

    The cache stores the result pickled, together with the SHA-256 of the
    pickle, and unpickles it only when the bytes read match it: a cache
    entry that was corrupted on disk (a flipped bit, a truncated file) is
    computed anew and stored again, with a warning, instead of served.

    Parameters
    ----------
    func : callable
        A module-level function with a picklable result; its qualified name
        and its source key the entry, with ``args``.
    *args
        Its positional arguments (hashed by joblib).

    Returns
    -------
    value : object
        ``func(*args)``.
    source : str
        Where it came from: ``"disk cache"``, ``"derived (now cached)"``,
        ``"recomputed (cache entry failed its checksum)"``,
        ``"recomputed (cache entry unreadable)"`` or ``"derived (disk cache off)"``.
    """
    if not callable(func):
        raise TypeError(f"func must be a callable, got {func!r}")
    store = memory()
    if store.store_backend is None:
        return func(*args), "derived (disk cache off)"
    # `func` is passed but not hashed (its name and source are); `ran` tells whether
    # func ran in this call, which check_call_in_cache cannot: joblib silently
    # recomputes an entry it cannot load
    cached = store.cache(_sealed_call, ignore=["func", "ran"])
    key = (f"{func.__module__}.{func.__qualname__}", _source_digest(func), args)
    ran = []
    was_stored = cached.check_call_in_cache(*key, func, ran)
    entry = cached(*key, func, ran)
    if ran:
        if not was_stored:
            return _unsealed(entry, key)[0], "derived (now cached)"
        problem = "unreadable"
        value = _unsealed(entry, key)[0]
    else:
        value, problem = _unsealed(entry, key)
        if problem is None:
            return value, "disk cache"
        # overwrite the entry, so that the next call reads a good one
        value = _unsealed(cached.call(*key, func, ran)[0], key)[0]
    logger.warning("the disk cache entry of %s in %s %s: computed anew", key[0],
                   store.location, "could not be read" if problem == "unreadable" else problem)
    return value, f"recomputed (cache entry {problem})"


def _sealed_call(name, code, args, func, ran):
    """The computation :func:`checked_cache_call` caches: ``func(*args)`` pickled and the
    SHA-256 (hex) of the pickle together with the entry's key (``name``, ``code`` and
    ``args``), so that an entry is served only for the call it was computed for (``ran``
    records that it ran)."""
    ran.append(True)
    payload = pickle.dumps(func(*args), protocol=pickle.HIGHEST_PROTOCOL)
    return payload, _seal_digest(payload, (name, code, args))


def _seal_digest(payload, key):
    """SHA-256 (hex) of a pickled result bound to the key of its cache entry."""
    import joblib

    return hashlib.sha256(payload + joblib.hash(key).encode()).hexdigest()


def _unsealed(entry, key):
    """(value, None) from an entry of :func:`_sealed_call` made for ``key``, or (None, what
    is wrong with it): unreadable, failing its checksum, or another call's (a swapped file)."""
    if not (isinstance(entry, tuple) and len(entry) == 2 and isinstance(entry[0], bytes)
            and isinstance(entry[1], str)):
        return None, "unreadable"
    payload, digest = entry
    if _seal_digest(payload, key) != digest:
        return None, "failed its checksum"
    try:
        return pickle.loads(payload), None
    except Exception:       # the bytes it was stored with, yet no longer loadable here
        return None, "unreadable"


def _source_digest(func):
    """SHA-256 (16 hex digits) of ``func``'s source: a changed function misses the cache."""
    try:
        text = inspect.getsource(func)
    except (OSError, TypeError):        # no source (a builtin): its name keys it alone
        text = ""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def _design_pair(uncertainty, weights, design, loop, fingerprint):
    """Both designs for the given choices (the cached computation; ``fingerprint``
    only keys the cache)."""
    choice = studies.Study().replace(name="cache_key", uncertainty=uncertainty, weights=weights,
                                     design=design, loop=loop)
    G, H_m, H_e, H_y, _ = study_problem(choice)
    options = dict(order=choice.design.order, d_order=choice.design.d_order,
                   max_iter=choice.design.max_iter, fs=choice.loop.fs_Hz)
    logger.info("designing the delay-aware controllers (%s)", json.dumps(design_choices(choice)))
    delay_aware = design_controller(G, H_m, H_e, H_y, delay_samples=choice.design.delay_samples,
                                    **options)
    logger.info("designing the no-delay controllers")
    nodelay = design_controller(G, H_m, H_e, H_y, delay_samples=None, fixed_order=False,
                                **options)
    return delay_aware, nodelay


def derive_controllers(study, cache=True):
    """Design the study's controllers (DK-iteration, reduction, fixed order), cached on disk.

    Parameters
    ----------
    study : Study, str or path
    cache : bool
        Use the disk cache (:func:`memory`, through :func:`checked_cache_call`);
        False always recomputes.

    Returns
    -------
    StudyControllers
        With ``design`` and ``nodelay`` set; ``source`` says whether they were
        read from the cache, derived, or recomputed for a corrupted cache entry.
    """
    study = studies.load(study)
    # the model set enters the cache key only when H_m is fitted to it
    uncertainty = (study.choices("uncertainty")["uncertainty"]
                   if study.uncertainty.weight == "fitted" else {})
    args = (uncertainty, *(study.choices(s)[s] for s in _DESIGN_SECTIONS),
            library_fingerprint())
    if cache:
        (delay_aware, nodelay), source = checked_cache_call(_design_pair, *args)
    else:
        delay_aware, nodelay = _design_pair(*args)
        source = "derived"
    return StudyControllers(
        study=study.name, digest=design_digest(study), source=source,
        K_full=delay_aware.K_full, K_reduced=delay_aware.K_reduced, K_fixed=delay_aware.K_fixed,
        K_nodelay_full=nodelay.K_full, K_nodelay_reduced=nodelay.K_reduced,
        mu={"delay-aware DK": float(delay_aware.musyn.mu_peak),
            "fixed order": float(delay_aware.fixed_order.mu_peak),
            "no-delay DK": float(nodelay.musyn.mu_peak)},
        design=delay_aware, nodelay=nodelay)


def reference_design_path():
    """``data/controllers/reference_design.json``: the committed reference controllers.

    Examples
    --------
    >>> reference_design_path().relative_to(outputs.project_root()).as_posix()
    'data/controllers/reference_design.json'
    """
    return outputs.study_controllers_dir(studies.REFERENCE) / "reference_design.json"


def study_controllers(study, cache=True):
    """The controllers every notebook of ``study`` uses.

    The reference study reads the committed artifact (:func:`reference_design_path`)
    and checks that it was designed for the reference's current choices.  Any
    other study uses the same committed controllers when its design choices
    equal the reference's (same :func:`design_digest`), and
    derives them otherwise (:func:`derive_controllers`); either way they are
    written to ``runs/<study>/artifacts/controllers.json``.

    Raises
    ------
    ArtifactError
        The committed artifact is missing or was designed for other choices.
    """
    study = studies.load(study)
    if study.is_reference:
        path = reference_design_path()
        if not path.is_file():
            raise ArtifactError(f"{path} is missing: run `python -m piezolib controllers "
                                "--write-reference` to derive and commit it")
        found = read_controllers(path)
        if found.digest != design_digest(study):
            raise ArtifactError(
                f"{path} was designed for other choices (digest {found.digest}, the reference "
                f"study's is {design_digest(study)}): re-derive it with `python -m piezolib "
                "controllers --write-reference`")
        return found
    path = reference_design_path()
    if _has_reference_design(study):
        # the reference's design choices: its committed controllers, so
        # that the study differs from the reference only by what it changes
        found = read_controllers(path)
    else:
        found = derive_controllers(study, cache=cache)
    write_controllers(found, study.output_dir / "artifacts" / "controllers.json", study)
    return found


def _has_reference_design(study):
    """Whether ``study`` makes the reference's design choices (its committed controllers
    and mixed designs then serve it)."""
    path = reference_design_path()
    return path.is_file() and read_controllers(path).digest == design_digest(study)


def write_reference_design(cache=False):
    """Re-derive the reference study's optimisation products and write the committed artifacts.

    The workbook Dahl model (:func:`piezolib.problem.hysteresis_fits.write_workbook_dahl`),
    the controllers (:func:`reference_design_path`) and their exported sections
    (:func:`export_sections`) and the mixed-mu designs: inputs of the reference study that
    no rerun rewrites.  Returns the controllers' path and the :class:`StudyControllers`
    derived (with their design records, for
    :func:`piezolib.workbook.design_run.write_reference_record`).
    """
    write_workbook_dahl()
    reference = studies.load(studies.REFERENCE)
    found = derive_controllers(reference, cache=cache)
    path = write_controllers(found, reference_design_path(), reference)
    export_sections(reference, outputs.study_controllers_dir(reference.name), found)
    export_feedforward_sections(reference, outputs.study_controllers_dir(reference.name))
    write_reference_mixed_designs(found)
    return path, found


def write_reference_mixed_designs(controllers=None):
    """Design the reference study's mixed-mu trade-off and write the committed files.

    ``data/controllers/mixed_design.json`` and the chosen controller's sections
    ``K_mixed.json`` / ``.h``; returns the path of the first.
    """
    reference = studies.load(studies.REFERENCE)
    mixed = derive_mixed_designs(reference, controllers)
    path = write_mixed_designs(mixed, mixed_design_path(), reference)
    _export_mixed_sections(reference, mixed)
    return path


#: File stems of the Case III controllers exported as sections (``<stem>.json`` and ``.h``).
SECTION_FILES = ("K_ours", "K_ours_full", "K_published")


def case_III_controllers(study, controllers=None):
    """The continuous controllers of Case III, {file stem: (label, K)}.

    Our deployed (fixed-order) and full-order mu controllers of the study and
    the published K of eq. 24, each v_e [V] -> u_b [V].
    """
    study = studies.load(study)
    found = study_controllers(study) if controllers is None else _check_controllers(controllers)
    K_pub = study_problem(study).K
    return {"K_ours": (f"ours, {found.K_deployed.nstates}th order (deployed)", found.K_deployed),
            "K_ours_full": (f"ours, full order ({found.K_full.nstates})", found.K_full),
            "K_published": ("published K (eq. 24)", K_pub)}


def discretized_controllers(study, controllers=None):
    """{file stem: DiscreteController}: Tustin at the study's loop rate, pre-warped
    (:func:`piezolib.robust.discrete.discretize`), checked against the study's G."""
    study = studies.load(study)
    G = study_problem(study).G
    return {stem: discretize(K, study.loop.fs_Hz, G=G)
            for stem, (_, K) in case_III_controllers(study, controllers).items()}


def export_sections(study, directory, controllers=None):
    """Export the Case III controllers as second-order sections (JSON + C header).

    Returns
    -------
    dict
        {file stem: SOSController}, read back in float32 as a target runs them.
    """
    study = studies.load(study)
    labels = {stem: label for stem, (label, _) in case_III_controllers(study, controllers).items()}
    return {stem: export.export_controller(
                d.K, directory, stem,
                meta={"controller": labels[stem], "states": d.K.nstates,
                      "discretisation": "Tustin", "prewarp_rad_s": d.prewarp_frequency})
            for stem, d in discretized_controllers(study, controllers).items()}


#: File stem of Case IV's dynamics inverse exported as sections (``.json`` and ``.h``).
FEEDFORWARD_FILE = "F_zpetc"


def export_feedforward_sections(study, directory):
    """Export Case IV's dynamics inverse (ZPETC of the study's G / G(0)) as sections.

    Returns
    -------
    SOSController
        Read back in float32, as a target runs it.
    """
    study = studies.load(study)
    dynamics = dynamics_inverse(study_problem(study).G, study.loop.fs_Hz)
    return export.export_controller(
        ct.ss(dynamics.F), directory, FEEDFORWARD_FILE,
        meta={"input": "v_r [V], preview samples ahead", "output": "w [V], the input of the "
              "hysteresis feedforward",
              "filter": "ZPETC of the ZOH model of G / G(0): w[k] = F(z) v_r[k + preview]",
              "preview_samples": dynamics.preview, "states": len(dynamics.F.den[0][0]) - 1})


def study_feedforward_sections(study):
    """The float32 sections of Case IV's dynamics inverse for ``study``.

    The reference study reads the committed export ``data/controllers/F_zpetc.json``
    (an input, like the controllers' sections of :func:`study_sections`: the
    factorisation's float32 coefficients are not the same on every machine);
    any other study exports its own to ``runs/<study>/controllers/``.

    Raises
    ------
    ArtifactError
        The committed export of the reference study is missing.
    """
    study = studies.load(study)
    if not study.is_reference:
        return export_feedforward_sections(study, outputs.study_controllers_dir(study.name))
    return _committed_sections(study, FEEDFORWARD_FILE)


def _committed_sections(study, stem):
    """The reference study's committed ``<stem>.json`` sections, read in float32."""
    path = outputs.study_controllers_dir(study.name) / f"{stem}.json"
    if not path.is_file():
        raise ArtifactError(f"{path} is missing: run `{_WRITE_REFERENCE}` to derive and export "
                            "the reference study's committed sections")
    return export.read_json(path, "float32")


def study_sections(study):
    """The float32 sections every Case III run of ``study`` uses, {file stem: SOSController}.

    The reference study reads the committed exports in ``data/controllers/``
    (inputs, like :func:`reference_design_path`: only ``python -m piezolib
    controllers --write-reference`` rewrites them, so a rerun on another
    machine runs the same float32 coefficients); any other study exports its
    own to ``runs/<study>/controllers/``.

    Raises
    ------
    ArtifactError
        A committed export of the reference study is missing.
    """
    study = studies.load(study)
    if not study.is_reference:
        return export_sections(study, outputs.study_controllers_dir(study.name))
    return {stem: _committed_sections(study, stem) for stem in SECTION_FILES}


#: Command that writes the committed reference artifacts anew.
_WRITE_REFERENCE = "python -m piezolib controllers --write-reference"


def _check_controllers(controllers):
    return check_type("controllers", controllers, StudyControllers,
                      "StudyControllers (from study_controllers or derive_controllers)")


def write_controllers(controllers, path, study):
    """Write ``controllers`` as JSON (matrices with full float precision); return the path.

    The file carries the SHA-256 of its content (:func:`piezolib.files.seal`),
    which :func:`read_controllers` checks.
    """
    _check_controllers(controllers)
    path = check_path("path", path)
    study = studies.load(study)
    doc = {"format": ARTIFACT_FORMAT, "study": study.name, "digest": controllers.digest,
           "choices": design_choices(study),
           "library": library_fingerprint(),
           "versions": {"numpy": np.__version__, "control": ct.__version__},
           "mu": controllers.mu,
           "controllers": {name: _ss_to_dict(getattr(controllers, name))
                           for name in _CONTROLLERS}}
    path.parent.mkdir(parents=True, exist_ok=True)
    # json writes floats with repr: they read back bit for bit, so the checksum of the
    # document read back is the one written
    return atomic_write(path, json.dumps(seal(doc), indent=1) + "\n")


def read_controllers(path):
    """Read a file of :func:`write_controllers` back into :class:`StudyControllers`.

    Raises
    ------
    ArtifactError
        Naming the file: not a controller file of this format, or its content
        fails its checksum (edited or corrupted).

    Examples
    --------
    >>> K = read_controllers(reference_design_path()).K_fixed
    >>> K.input_labels, K.output_labels, K.isctime()
    (['v_e'], ['u_b'], True)
    """
    path = check_path("path", path)
    doc = _read_artifact(path, "controller")
    try:
        systems = {name: _ss_from_dict(doc["controllers"][name]) for name in _CONTROLLERS}
        return StudyControllers(study=doc["study"], digest=doc["digest"], source=str(path),
                                mu={k: float(v) for k, v in doc["mu"].items()}, **systems)
    except (KeyError, TypeError, ValueError) as exc:
        raise ArtifactError(f"{path}: not a controller artifact ({exc})") from None


def _read_artifact(path, kind):
    """The JSON object of a sealed artifact file of this format, its checksum checked.

    Raises
    ------
    ArtifactError
        Naming the file and the ``kind`` of artifact expected.
    """
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except ValueError as exc:
        raise ArtifactError(f"{path}: not a {kind} artifact ({exc})") from None
    if not isinstance(doc, dict):
        raise ArtifactError(f"{path}: not a {kind} artifact (a JSON {type(doc).__name__}, "
                            "not an object)")
    if doc.get("format") != ARTIFACT_FORMAT:
        raise ArtifactError(f"{path}: format {doc.get('format')!r}, expected {ARTIFACT_FORMAT}")
    problem = seal_problem(doc)
    if problem is None:
        return doc
    name = doc.get("study") if isinstance(doc.get("study"), str) else "<study>"
    committed = Path(path).resolve() in (reference_design_path().resolve(),
                                         mixed_design_path().resolve())
    regenerate = (f"`{_WRITE_REFERENCE}`" if committed
                  else f"`python -m piezolib reproduce --study {name}`")
    if CONTENT_KEY in doc:
        raise ArtifactError(f"{path}: {problem}; write it anew with {regenerate}")
    raise ArtifactError(f"{path}: not a {kind} artifact written by this version of "
                        f"piezolib ({problem}); write it anew with {regenerate}")


def _ss_to_dict(sys):
    return {"name": sys.name, "inputs": list(sys.input_labels),
            "outputs": list(sys.output_labels),
            **{m: np.asarray(getattr(sys, m), dtype=float).tolist() for m in "ABCD"}}


def _ss_from_dict(d):
    n = len(d["A"])
    A = np.array(d["A"], dtype=float).reshape(n, n)
    B = np.array(d["B"], dtype=float).reshape(n, len(d["inputs"]))
    C = np.array(d["C"], dtype=float).reshape(len(d["outputs"]), n)
    D = np.array(d["D"], dtype=float).reshape(len(d["outputs"]), len(d["inputs"]))
    return ct.ss(A, B, C, D, inputs=d["inputs"], outputs=d["outputs"], name=d["name"])


# --- mixed-mu controllers for the coefficient box (notebook 09) ---------------------

#: The committed mixed-mu designs of the reference study, in ``data/controllers/``.
MIXED_FILE = "mixed_design.json"
#: File stem of the chosen mixed-mu controller's sections (``.json`` and ``.h``).
MIXED_SECTIONS_FILE = "K_mixed"


@dataclass(frozen=True)
class MixedDesigns:
    """The trade-off designs of :func:`~piezolib.problem.design.mixed_tradeoff`, as stored.

    Attributes
    ----------
    study : str
    designs : tuple of MixedDesign
        In the order of the performance scales (``steps`` is None when read
        from a file: only the results are stored).
    source : str
        Where the designs came from.
    """

    study: str
    designs: tuple
    source: str

    @property
    def chosen(self):
        """The design to deploy (:func:`~piezolib.problem.design.choose_mixed_design`),
        or None when no design is certified for the box."""
        return choose_mixed_design(self.designs)


def mixed_design_path():
    """``data/controllers/mixed_design.json``: the committed mixed-mu designs.

    Examples
    --------
    >>> mixed_design_path().relative_to(outputs.project_root()).as_posix()
    'data/controllers/mixed_design.json'
    """
    return outputs.study_controllers_dir(studies.REFERENCE) / MIXED_FILE


def derive_mixed_designs(study, controllers=None, n_jobs=2):
    """Design the mixed-mu trade-off of ``study`` from its deployed controller (minutes;
    ``n_jobs`` processes).

    Returns
    -------
    MixedDesigns
    """
    study = studies.load(study)
    found = study_controllers(study) if controllers is None else _check_controllers(controllers)
    G, _, H_e, H_y, _ = study_problem(study)
    designs = mixed_tradeoff(G, H_e, H_y, found.K_deployed, fs=study.loop.fs_Hz, n_jobs=n_jobs)
    return MixedDesigns(study=study.name, designs=tuple(designs), source="designed now")


#: The results of a MixedDesign that a file of :func:`write_mixed_designs` holds besides K.
_MIXED_FIELDS = ("performance_scale", "spread", "mu_peak", "mu_lower_peak", "start_mu_peak")


def write_mixed_designs(designs, path, study):
    """Write :class:`MixedDesigns` as sealed JSON (full float precision); return the path."""
    check_type("designs", designs, MixedDesigns, "MixedDesigns")
    path = check_path("path", path)
    study = studies.load(study)
    doc = {"format": ARTIFACT_FORMAT, "study": study.name, "library": library_fingerprint(),
           "designs": [{**{f: getattr(d, f) for f in _MIXED_FIELDS},
                        "margins": {str(k): m for k, m in d.margins.items()},
                        "K": _ss_to_dict(d.K)} for d in designs.designs]}
    path.parent.mkdir(parents=True, exist_ok=True)
    return atomic_write(path, json.dumps(seal(doc), indent=1) + "\n")


def read_mixed_designs(path):
    """Read a file of :func:`write_mixed_designs`.

    Raises
    ------
    ArtifactError
        Naming the file: not such a file, or its content fails its checksum.
    """
    path = check_path("path", path)
    doc = _read_artifact(path, "mixed-design")
    try:
        designs = tuple(MixedDesign(K=_ss_from_dict(r["K"]), steps=None,
                                    margins={int(k): float(m) for k, m in r["margins"].items()},
                                    **{f: float(r[f]) for f in _MIXED_FIELDS})
                        for r in doc["designs"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ArtifactError(f"{path}: not a mixed-design artifact ({exc})") from None
    return MixedDesigns(study=doc["study"], designs=designs, source=str(path))


def study_mixed_designs(study):
    """The mixed-mu designs of ``study``: committed for the reference, and for any study with
    the reference's design choices (same :func:`design_digest`: the designs depend on the
    plant, the weights, the deployed controller and the loop rate only, the box being the
    paper's); else designed (minutes) and written to
    ``runs/<study>/artifacts/mixed_design.json``, which later calls read."""
    study = studies.load(study)
    if study.is_reference or _has_reference_design(study):
        path = mixed_design_path()
        if not path.is_file():
            raise ArtifactError(f"{path} is missing: run `{_WRITE_REFERENCE}`")
        return read_mixed_designs(path)
    path = study.output_dir / "artifacts" / MIXED_FILE
    if path.is_file():
        return read_mixed_designs(path)
    designs = derive_mixed_designs(study)
    write_mixed_designs(designs, path, study)
    return designs


def _export_mixed_sections(study, designs):
    """Export the chosen mixed controller, Tustin at the loop rate, as sections."""
    chosen = designs.chosen
    if chosen is None:
        return None
    d = discretize(chosen.K, study.loop.fs_Hz, G=study_problem(study).G)
    return export.export_controller(
        d.K, outputs.study_controllers_dir(study.name), MIXED_SECTIONS_FILE,
        meta={"controller": f"mixed mu, {chosen.K.nstates}th order, performance scale "
                            f"{chosen.performance_scale:g}", "states": d.K.nstates,
              "discretisation": "Tustin", "prewarp_rad_s": d.prewarp_frequency})


def study_mixed_sections(study):
    """The chosen mixed controller's float32 sections (committed for the reference study).

    Returns
    -------
    SOSController or None
        None when no design of the study is certified for the box.
    """
    study = studies.load(study)
    if study.is_reference or _has_reference_design(study):
        return _committed_sections(studies.load(studies.REFERENCE), MIXED_SECTIONS_FILE)
    return _export_mixed_sections(study, study_mixed_designs(study))
