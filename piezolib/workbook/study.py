"""Studies: every choice the workbook's pipeline makes, in one serialisable object.

A :class:`Study` names the uncertainty set, the performance weights, the
controller design options, the real-time loop and the experiments.  The
paper's reproduction is the ``reference`` study (``studies/reference.toml``);
any other study is a TOML file in ``studies/`` or is derived in code::

    from piezolib.workbook import study
    wide = study.load("reference").replace(name="wide_He", weights={"omega_e": 2.5e3})

Each notebook starts with a cell tagged ``parameters`` that names the study
(``study = "reference"``) and passes it to
:func:`piezolib.workbook.session.start`, whose session writes the study's
figures and tables to its own folder: ``figures/`` and ``data/results/`` for
the reference study, ``runs/<name>/`` (git-ignored) for any other, so
exploring never overwrites the committed results.
"""

import dataclasses
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

from piezolib.problem import paper
from piezolib.problem.design import DESIGN_D_ORDER
from piezolib.workbook import outputs
from piezolib.workbook.loop import COMPUTATION_DELAY_SAMPLES

__all__ = ["Study", "UncertaintyChoice", "WeightChoice", "DesignChoice", "LoopChoice",
           "ExperimentChoice", "StudyError", "REFERENCE", "RESERVED_NAMES", "UNCERTAINTY_WEIGHTS",
           "load", "study_files", "from_dict", "studies_dir", "choices_digest",
           "section_fields"]

#: Name of the paper's reproduction; only this study writes the committed outputs.
REFERENCE = outputs.REFERENCE_STUDY
#: Names no study may take, with what their folder under ``runs/`` already holds.
RESERVED_NAMES = outputs.RESERVED_NAMES


class StudyError(ValueError):
    """A study file or a study change that cannot be used (names the field).

    Examples
    --------
    >>> try:
    ...     Study(name="no/slash")
    ... except StudyError as exc:
    ...     print(exc)
    study name must be letters, digits, '_' or '-', got 'no/slash'
    """


#: The uncertainty weights a study can design with: the paper's H_m of eq. 8,
#: or a covering weight fitted to the study's model set.
UNCERTAINTY_WEIGHTS = ("published", "fitted")


@dataclass(frozen=True)
class UncertaintyChoice:
    """The coefficient-uncertainty set of Sec. III-B and the weight H_m that
    stands for it in the design (notebooks 02, 04-06).

    Attributes
    ----------
    spread : float
        Relative spread of each denominator coefficient a0...a5 (0.05 = +-5 %).
    levels : int
        Values per coefficient in the model set (3 -> 3**6 = 729 members).
    weight : str
        ``"published"``: the paper's H_m (eq. 8), whatever the spread;
        ``"fitted"``: a stable, minimum-phase covering weight of order
        ``weight_order`` fitted to the relative-error envelope of the stable
        members of this model set on ``weight_grid``
        (:func:`piezolib.uncertainty.fit_covering_weight`).
    weight_order : int
        Order of the fitted weight (unused for the published one).
    weight_grid : tuple of (float, float, int)
        Lowest and highest frequency [rad/s] and number of log-spaced points
        of the grid the fitted weight covers the envelope on.

    Examples
    --------
    >>> UncertaintyChoice().spread, UncertaintyChoice().levels
    (0.05, 3)
    >>> UncertaintyChoice().weight_choices()      # the published H_m depends on nothing else
    {'weight': 'published'}
    """

    spread: float = paper.UNCERTAINTY_SPREAD
    levels: int = paper.UNCERTAINTY_LEVELS
    weight: str = "published"
    weight_order: int = 5
    weight_grid: tuple = (1.0, 1e6, 2000)

    def __post_init__(self):
        # TOML gives a list; a frozen study keeps a tuple so it stays hashable
        if isinstance(self.weight_grid, list):
            object.__setattr__(self, "weight_grid", tuple(self.weight_grid))

    def check(self):
        _positive("uncertainty.spread", self.spread, upper=1.0)
        _integer("uncertainty.levels", self.levels, 2, 6)
        if self.weight not in UNCERTAINTY_WEIGHTS:
            raise StudyError(f"uncertainty.weight must be one of {list(UNCERTAINTY_WEIGHTS)}, "
                             f"got {self.weight!r}")
        _integer("uncertainty.weight_order", self.weight_order, 1, 12)
        grid = self.weight_grid
        if not isinstance(grid, tuple) or len(grid) != 3:
            raise StudyError("uncertainty.weight_grid must be [lowest rad/s, highest rad/s, "
                             f"points], got {grid!r}")
        _positive("uncertainty.weight_grid[0]", grid[0])
        _positive("uncertainty.weight_grid[1]", grid[1])
        if not grid[0] < grid[1]:
            raise StudyError(f"uncertainty.weight_grid must rise, got {grid!r}")
        _integer("uncertainty.weight_grid[2]", grid[2], 50, 100_000)

    def weight_choices(self):
        """The choices H_m depends on: the weight's name alone when published,
        with the model set, order and grid when fitted."""
        if self.weight == "published":
            return {"weight": self.weight}
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class WeightChoice:
    """The performance weights H_e and H_y of eq. 15 (notebook 04); frequencies in rad/s.

    Examples
    --------
    >>> WeightChoice(omega_e=2e3).error
    ErrorWeightParameters(M_e=2.0, eps_e=0.003, omega_e=2000.0)
    """

    M_e: float = paper.ERROR_WEIGHT.M_e
    eps_e: float = paper.ERROR_WEIGHT.eps_e
    omega_e: float = paper.ERROR_WEIGHT.omega_e
    M_y: float = paper.OUTPUT_WEIGHT.M_y
    eps_y: float = paper.OUTPUT_WEIGHT.eps_y
    omega_y: float = paper.OUTPUT_WEIGHT.omega_y

    def check(self):
        for f in fields(self):
            _positive(f"weights.{f.name}", getattr(self, f.name))

    @property
    def error(self):
        """:class:`piezolib.problem.paper.ErrorWeightParameters` of these weights."""
        return paper.ErrorWeightParameters(M_e=self.M_e, eps_e=self.eps_e, omega_e=self.omega_e)

    @property
    def output(self):
        """:class:`piezolib.problem.paper.OutputWeightParameters` of these weights."""
        return paper.OutputWeightParameters(M_y=self.M_y, eps_y=self.eps_y, omega_y=self.omega_y)


@dataclass(frozen=True)
class DesignChoice:
    """Options of the mu controller design (notebook 05, :func:`~piezolib.problem.design.design_controller`).

    Attributes
    ----------
    order : int
        States of the reduced and fixed-order controllers (the paper's: 6).
    d_order : int
        Order of the fitted D-scaling.
    max_iter : int
        Maximum number of DK iterations.
    delay_samples : int
        Computation delay [samples] modelled in the synthesis plant.

    Examples
    --------
    >>> DesignChoice()
    DesignChoice(order=6, d_order=4, max_iter=8, delay_samples=1)
    """

    order: int = 6
    d_order: int = DESIGN_D_ORDER
    max_iter: int = 8
    delay_samples: int = 1

    def check(self):
        _integer("design.order", self.order, 1, 40)
        _integer("design.d_order", self.d_order, 0, 12)
        _integer("design.max_iter", self.max_iter, 1, 100)
        _integer("design.delay_samples", self.delay_samples, 0, 10)


@dataclass(frozen=True)
class LoopChoice:
    """The real-time loop of Fig. 1 (notebooks 05-06).

    Attributes
    ----------
    fs_Hz : float
        Sampling rate [Hz] of the loop and of the discretised controllers.
    delay_samples : int
        Computation delay [samples] of the simulated loop (u_b applied this
        many ticks after v_y is read).

    Examples
    --------
    >>> LoopChoice()
    LoopChoice(fs_Hz=10000.0, delay_samples=1)
    """

    fs_Hz: float = paper.SAMPLING_FREQUENCY_HZ
    delay_samples: int = COMPUTATION_DELAY_SAMPLES

    def check(self):
        _positive("loop.fs_Hz", self.fs_Hz)
        _integer("loop.delay_samples", self.delay_samples, 0, 10)


@dataclass(frozen=True)
class ExperimentChoice:
    """Trajectories and noise of the tracking experiments (notebook 06, Sec. V).

    Attributes
    ----------
    amplitudes_V : tuple of float
        Actuator amplitudes [V] of the hysteresis test (Table 4).
    frequencies_Hz : tuple of float
        Triangle frequencies [Hz] of the tracking test (Table 5).
    range_um : float
        Peak-to-peak range [um] of the tracking triangle.
    stage_seed : int
        Seed of the virtual stage's sensor noise (the first of ``noise_seeds``).
    noise_seeds : int
        Number of noise seeds, ``stage_seed``, ``stage_seed + 1``, ...: each
        Table 4-5 entry is reported as the mean over them with its 95 %
        interval (at least 2).

    Examples
    --------
    >>> ExperimentChoice(noise_seeds=3).seeds
    (0, 1, 2)
    >>> ExperimentChoice().frequencies_Hz
    (1.0, 10.0, 20.0, 30.0, 40.0, 50.0)
    """

    amplitudes_V: tuple = paper.HYSTERESIS_TEST["actuator_amplitudes_V"]
    frequencies_Hz: tuple = paper.TRACKING_TEST["frequencies_Hz"]
    range_um: float = paper.TRACKING_TEST["amplitude_um"]
    stage_seed: int = 0
    noise_seeds: int = 16

    @property
    def seeds(self):
        """The noise seeds of the experiments, a tuple of ``noise_seeds`` ints."""
        return tuple(range(self.stage_seed, self.stage_seed + self.noise_seeds))

    def __post_init__(self):
        # TOML gives lists; a frozen study keeps tuples so it stays hashable
        for name in ("amplitudes_V", "frequencies_Hz"):
            value = getattr(self, name)
            if isinstance(value, (list, tuple)):
                # numbers become floats; anything else (true, "a") is left for check() to name
                object.__setattr__(self, name, tuple(
                    float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else v
                    for v in value))

    def check(self):
        for name in ("amplitudes_V", "frequencies_Hz"):
            values = getattr(self, name)
            if not isinstance(values, tuple) or not values:
                raise StudyError(f"experiments.{name} must be a non-empty list of numbers, "
                                 f"got {values!r}")
            for v in values:
                _positive(f"experiments.{name}", v)
        _positive("experiments.range_um", self.range_um)
        _integer("experiments.stage_seed", self.stage_seed, 0, 2 ** 32 - 1)
        _integer("experiments.noise_seeds", self.noise_seeds, 2, 1000)
        if self.stage_seed + self.noise_seeds > 2 ** 32:
            raise StudyError("experiments.stage_seed + noise_seeds must stay below 2**32, got "
                             f"{self.stage_seed} + {self.noise_seeds}")


_SECTIONS = {"uncertainty": UncertaintyChoice, "weights": WeightChoice, "design": DesignChoice,
             "loop": LoopChoice, "experiments": ExperimentChoice}


@dataclass(frozen=True)
class Study:
    """One consistent set of choices for the whole pipeline.

    Attributes
    ----------
    name : str
        Short identifier (letters, digits, ``_`` and ``-``): the output folder
        is ``runs/<name>/`` unless the name is ``reference``.
    description : str
        One sentence on what the study changes and why.
    uncertainty, weights, design, loop, experiments
        The choices of each pipeline stage (see their classes).

    Examples
    --------
    >>> s = Study()                                 # the paper's reproduction
    >>> s.name, s.is_reference, s.weights.omega_e
    ('reference', True, 1260.0)
    >>> wide = s.replace(name="wide_He", weights={"omega_e": 2.5e3})
    >>> wide.weights.omega_e, wide.is_reference, wide.digest("design") == s.digest("design")
    (2500.0, False, True)
    >>> wide.figures_dir.relative_to(outputs.project_root()).as_posix()
    'runs/wide_He/figures'
    """

    name: str = REFERENCE
    description: str = "The paper's reproduction: every choice as published."
    uncertainty: UncertaintyChoice = field(default_factory=UncertaintyChoice)
    weights: WeightChoice = field(default_factory=WeightChoice)
    design: DesignChoice = field(default_factory=DesignChoice)
    loop: LoopChoice = field(default_factory=LoopChoice)
    experiments: ExperimentChoice = field(default_factory=ExperimentChoice)

    def __post_init__(self):
        problem = outputs.study_name_problem(self.name)
        if problem:
            raise StudyError(f"study name {problem}")
        for section, cls in _SECTIONS.items():
            value = getattr(self, section)
            if not isinstance(value, cls):
                raise StudyError(f"study section {section!r} must be a {cls.__name__}, "
                                 f"got {type(value).__name__}")
            value.check()

    # -- derived studies --------------------------------------------------------
    def replace(self, name=None, description=None, **sections):
        """A new study with some choices changed.

        Parameters
        ----------
        name : str, optional
            Name of the new study (required unless only the description
            changes: a changed study must not keep the reference's name).
        description : str, optional
        **sections : dict
            Per section, the fields to change, e.g.
            ``weights={"omega_e": 2.5e3}, design={"max_iter": 2}``.

        Raises
        ------
        StudyError
            Unknown section or field, an invalid value, or a changed study
            that keeps the name ``reference``.
        """
        changes = {}
        for section, values in sections.items():
            if section not in _SECTIONS:
                raise StudyError(f"unknown study section {section!r}; expected one of "
                                 f"{sorted(_SECTIONS)}")
            if not isinstance(values, dict):
                raise StudyError(f"{section}= must be a dict of field values, got {values!r}")
            changes[section] = _section(section, {**dataclasses.asdict(getattr(self, section)),
                                                  **values})
        new = dataclasses.replace(self, name=self.name if name is None else name,
                                  description=(self.description if description is None
                                               else description), **changes)
        if new.name == REFERENCE and new.choices() != Study().choices():
            raise StudyError("a study that changes the reference's choices needs its own name "
                             "(replace(name=...)): 'reference' writes the committed results")
        return new

    # -- serialisation ------------------------------------------------------------
    def choices(self, *sections):
        """The choices of ``sections`` (default: all) as a plain dict."""
        names = sections or tuple(_SECTIONS)
        for s in names:
            if s not in _SECTIONS:
                raise StudyError(f"unknown study section {s!r}")
        return {s: dataclasses.asdict(getattr(self, s)) for s in names}

    def digest(self, *sections):
        """Short SHA-256 of the choices of ``sections`` (default: all).

        Two studies that agree on those sections have the same digest, so a
        stage's product can be shared between them.
        """
        return choices_digest(self.choices(*sections))

    def to_toml(self):
        """The study as TOML text (what :func:`load` reads back)."""
        lines = [f"name = {_toml_value(self.name)}",
                 f"description = {_toml_value(self.description)}"]
        for section, values in self.choices().items():
            lines += ["", f"[{section}]"]
            lines += [f"{key} = {_toml_value(value)}" for key, value in values.items()]
        return "\n".join(lines) + "\n"

    def save(self, path):
        """Write :meth:`to_toml` to ``path``; return the path."""
        path = Path(path)
        path.write_text(self.to_toml(), encoding="utf-8")
        return path

    @property
    def results_dir(self):
        """Folder of this study's paper-versus-reproduced tables."""
        return outputs.study_results_dir(self.name)

    @property
    def figures_dir(self):
        """Folder of this study's figures."""
        return outputs.study_figures_dir(self.name)

    @property
    def is_reference(self):
        """True for the paper's reproduction (the study whose results are committed)."""
        return self.name == REFERENCE

    @property
    def output_dir(self):
        """Folder of this study's figures, tables, artifacts and executed notebooks."""
        return outputs.study_output_dir(self.name)


def studies_dir():
    """``studies/``: the study files of the checkout.

    Examples
    --------
    >>> studies_dir().relative_to(outputs.project_root()).as_posix()
    'studies'
    """
    return outputs.project_root() / "studies"


def study_files():
    """The ``studies/*.toml`` files, the reference's first, the others by name.

    Examples
    --------
    >>> study_files()[0].name
    'reference.toml'
    """
    return sorted(studies_dir().glob("*.toml"), key=lambda path: (path.stem != REFERENCE, path.stem))


def load(spec=REFERENCE):
    """A study from a name in ``studies/``, a path to a TOML file, or a :class:`Study`.

    Raises
    ------
    StudyError
        Unknown name, missing file, TOML error, unknown section or field, or
        an invalid value (each message names the file and the field).

    Examples
    --------
    >>> load("reference") == Study()
    True
    >>> load("wide_error_weight").weights.omega_e       # studies/wide_error_weight.toml
    2000.0
    >>> load("studies/uncertainty_3pct.toml").uncertainty.spread
    0.03
    """
    if isinstance(spec, Study):
        return spec
    if not isinstance(spec, (str, Path)):
        raise StudyError(f"study must be a name, a path or a Study, got {type(spec).__name__}")
    path = Path(spec)
    if path.suffix != ".toml":
        path = studies_dir() / f"{spec}.toml"
        if not path.is_file():
            if str(spec) == REFERENCE:
                return Study()
            known = ", ".join(s.stem for s in sorted(studies_dir().glob("*.toml"))) or "none"
            raise StudyError(f"no study named {spec!r} in {studies_dir()} (known: {known})")
    if not path.is_file():
        raise StudyError(f"study file {path} does not exist")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:       # e.g. saved as latin-1: TOML files are UTF-8
        raise StudyError(f"{path}: not UTF-8 text (byte {exc.start}: {exc.reason}); save "
                         "the study file as UTF-8") from None
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{path}: not valid TOML ({exc})") from None
    try:
        study = from_dict(data)
    except StudyError as exc:
        raise StudyError(f"{path}: {exc}") from None
    # the name decides the output folder: a file must not write under another study's name
    if study.name != path.stem:
        raise StudyError(f"{path}: the study is named {study.name!r} but its file "
                         f"{path.name!r}; name the file {study.name}.toml (outputs go to "
                         "the folder of the study's name)")
    if study.is_reference and study.choices() != Study().choices():
        raise StudyError(f"{path}: a study named 'reference' must keep the paper's choices "
                         "(it writes the committed results); give a changed study its own name")
    return study


def from_dict(data):
    """A study from the dict layout of :meth:`Study.to_toml` (unknown keys are errors).

    Examples
    --------
    >>> s = from_dict({"name": "explore", "weights": {"M_e": 3.0}})
    >>> s.weights.M_e, s.design == DesignChoice()
    (3.0, True)
    >>> from_dict(Study().replace(name="x", loop={"fs_Hz": 5e3}).choices() | {"name": "x"}).loop.fs_Hz
    5000.0
    """
    if not isinstance(data, dict):
        raise StudyError(f"a study is a table of sections, got {type(data).__name__}")
    unknown = set(data) - set(_SECTIONS) - {"name", "description"}
    if unknown:
        raise StudyError(f"unknown key(s) {sorted(unknown)}; a study has name, description "
                         f"and the sections {sorted(_SECTIONS)}")
    if "name" not in data:
        raise StudyError("the study has no name")
    sections = {s: _section(s, data.get(s, {})) for s in _SECTIONS}
    return Study(name=data["name"], description=data.get("description", ""), **sections)


def section_fields():
    """``{section: {field: type}}`` of every choice a study holds (``int``, ``float``,
    ``str`` or ``tuple``): what a sweep can vary, and how to draw it.

    Examples
    --------
    >>> section_fields()["loop"]
    {'fs_Hz': <class 'float'>, 'delay_samples': <class 'int'>}
    """
    return {section: {f.name: f.type for f in fields(cls)} for section, cls in _SECTIONS.items()}


def choices_digest(choices):
    """Short SHA-256 (16 hex digits) of a dict of choices; numbers hash as floats,
    so 2500 and 2500.0 give the same digest.

    Examples
    --------
    >>> choices_digest({"omega_e": 2500}) == choices_digest({"omega_e": 2500.0})
    True
    >>> len(choices_digest({"omega_e": 2500}))
    16
    """
    if not isinstance(choices, dict):
        raise TypeError(f"choices must be a dict, got {type(choices).__name__}")
    try:
        text = json.dumps(_canonical(choices), sort_keys=True)
    except TypeError as exc:      # a value JSON cannot hold: it could not key a design
        raise TypeError(f"choices must hold numbers, text, lists and dicts only ({exc})") \
            from None
    return hashlib.sha256(text.encode()).hexdigest()[:16]


# -- helpers ------------------------------------------------------------------
def _section(section, values):
    cls = _SECTIONS[section]
    if not isinstance(values, dict):
        raise StudyError(f"[{section}] must be a table of fields, got {values!r}")
    names = {f.name for f in fields(cls)}
    unknown = set(values) - names
    # a unit suffix is spelled with its SI case (fs_Hz); a study file written before that
    # convention (fs_hz) gets the new spelling named instead of a bare "unknown field"
    by_case = {n.lower(): n for n in names}
    respelled = {key: by_case[key.lower()] for key in sorted(unknown) if key.lower() in by_case}
    if respelled:
        raise StudyError(f"[{section}] " + ", ".join(
            f"{old!r} is now spelled {new!r}" for old, new in respelled.items())
            + " (unit suffixes keep their SI case: _Hz, _V, _s, _um)")
    if unknown:
        raise StudyError(f"unknown field(s) {sorted(unknown)} in [{section}]; "
                         f"expected some of {sorted(names)}")
    return cls(**values)


def _positive(name, value, upper=math.inf):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
            0 < value < upper) or not math.isfinite(value):
        bound = "" if upper == math.inf else f" and below {upper:g}"
        raise StudyError(f"{name} must be a finite number above 0{bound}, got {value!r}")


def _integer(name, value, low, high):
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise StudyError(f"{name} must be an integer in [{low}, {high}], got {value!r}")


def _canonical(value):
    """Numbers as floats (so 2500 and 2500.0 hash alike), containers recursively."""
    if isinstance(value, dict):
        return {k: _canonical(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return value


def _toml_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)          # a JSON string is a valid TOML basic string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise StudyError(f"cannot write {value!r} to TOML")
