"""Sweep specs: the TOML layout of a sweep, its parsing and validation, and its points
(a grid's combinations or a random sample over a base study).

A sweep spec is a small TOML file (``studies/sweeps/<name>.toml`` or any
path) that names a base study and the points to run::

    description = "omega_e, spread and order of the fitted-weight design"
    study = "reference"              # the base study: a name in studies/ or a .toml path

    [set]                            # choices every point shares (optional)
    uncertainty.weight = "fitted"
    design.max_iter = 3

    [grid]                           # Cartesian product: 3 x 2 x 2 = 12 points
    weights.omega_e = [1000.0, 1260.0, 1600.0]
    uncertainty.spread = [0.02, 0.03]
    design.order = [4, 6]

or, instead of ``[grid]``, a random sample::

    [random]
    samples = 20
    seed = 1
    weights.omega_e = [800.0, 2500.0]                        # uniform in [low, high]
    design.order = [4, 8]                                    # integer field: 4 ... 8
    uncertainty.spread = {low = 0.01, high = 0.05, scale = "log"}
    controller = {choices = ["fixed_order", "full_order"]}

A parameter is a study field, ``<section>.<field>`` (every field of
:class:`~piezolib.workbook.study.Study`), or ``controller``, the controller
whose numbers are reported (:data:`CONTROLLERS`).  Every value goes through
the study's own validation, so a bad one fails before anything runs, with the
spec, the parameter and the study's message.

:func:`load_spec` reads a spec by name or path, :func:`spec_from_dict` from the
dict layout; :meth:`SweepSpec.points` gives the points
(:mod:`piezolib.workbook.sweep` runs them).
"""

import collections
import functools
import itertools
import math
import os
import shutil
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from piezolib._checks import check_path
from piezolib.workbook import outputs
from piezolib.workbook import study as studies

__all__ = ["SweepSpec", "SweepPoint", "SweepError", "CONTROLLERS", "RECORD_FORMAT", "MAX_POINTS",
           "specs_dir", "load_spec", "spec_from_dict"]

#: Controllers a point can report: the deployed fixed-order one or the full-order DK one.
CONTROLLERS = ("fixed_order", "full_order")

#: Format version of the per-point records (part of each point's key).
RECORD_FORMAT = 1

#: Most points one sweep may hold (a grid's combinations, a random sample's ``samples``).
#: A point is a design of seconds to minutes, so 10,000 points are days of work on a
#: small cluster; setting them up (one study each) takes 4-10 s on a 2-core machine.
#: Larger sweeps are refused before any study is built, naming the key and this limit.
MAX_POINTS = 10_000
_TOP_KEYS = {"name", "description", "study", "set", "grid", "random"}
_CONTROLLER = "controller"


class SweepError(ValueError):
    """A sweep spec that cannot be run (names the file, the table and the parameter).

    Examples
    --------
    >>> try:
    ...     spec_from_dict({"name": "demo", "grid": {"weights.omega_x": [1.0]}})
    ... except SweepError as exc:
    ...     print(exc)
    [grid] unknown parameter 'weights.omega_x': [weights] has the fields ['M_e', 'M_y', 'eps_e', 'eps_y', 'omega_e', 'omega_y']
    """


@dataclass(frozen=True)
class SweepPoint:
    """One point of a sweep.

    Attributes
    ----------
    index : int
        Position in the sweep, from 1.
    params : dict
        The swept parameters' values, ``{"weights.omega_e": 1260.0, ...}``.
    study : piezolib.workbook.study.Study
        The point's whole study (base, ``[set]`` and ``params``).
    options : dict
        The evaluation's options (``{"controller": "fixed_order"}``).

    Examples
    --------
    >>> spec = spec_from_dict({"name": "demo", "grid": {"weights.omega_e": [1000.0, 1260.0]}})
    >>> point = spec.points()[0]
    >>> point.index, point.params, point.options
    (1, {'weights.omega_e': 1000.0}, {'controller': 'fixed_order'})
    >>> point.study.weights.omega_e, len(point.key("evaluate_point"))
    (1000.0, 16)
    """

    index: int
    params: dict
    study: studies.Study = field(repr=False)
    options: dict

    def key(self, evaluation):
        """Digest of the point's study choices, options and ``evaluation`` (a name):
        the file name of its record."""
        return studies.choices_digest({"study": self.study.choices(), "options": self.options,
                                       "evaluation": evaluation, "format": RECORD_FORMAT})


@dataclass(frozen=True)
class SweepSpec:
    """A sweep: a base study and the points over its parameters.

    Attributes
    ----------
    name : str
        Names the output folder ``runs/sweeps/<name>/`` (a study name: letters,
        digits, ``_``, ``-``).
    base : piezolib.workbook.study.Study
        The base study with the spec's ``[set]`` choices applied.
    grid : dict or None
        ``{parameter: tuple of values}``: every combination is a point.
    random : dict or None
        ``{parameter: {"low", "high", "scale"} or {"choices"}}``: ``samples``
        points drawn with ``seed``.
    samples, seed : int or None
    description : str

    Examples
    --------
    >>> spec = spec_from_dict({"name": "demo", "random": {"samples": 5, "seed": 1,
    ...                                                   "weights.omega_e": [800.0, 2500.0]}})
    >>> spec.parameters, len(spec.points())
    (('weights.omega_e',), 5)
    >>> spec.directory.relative_to(outputs.project_root()).as_posix()
    'runs/sweeps/demo'
    """

    name: str
    base: studies.Study = field(repr=False)
    grid: dict = None
    random: dict = None
    samples: int = None
    seed: int = None
    description: str = ""

    @property
    def parameters(self):
        """The swept parameters, in spec order."""
        return tuple(self.grid if self.grid is not None else self.random)

    @property
    def directory(self):
        """``runs/sweeps/<name>/``: the sweep's table, figure and point records."""
        return outputs.sweep_output_dir(self.name)

    def clear_records(self):
        """Remove the stored point records (``points/`` of :attr:`directory`), so that the
        next :func:`~piezolib.workbook.sweep.run_sweep` evaluates every point again (a design
        may still come from the pipeline's disk cache); return how many were removed."""
        records = sorted((self.directory / "points").glob("*.json"))
        shutil.rmtree(self.directory / "points", ignore_errors=True)
        return len(records)

    def points(self):
        """The sweep's points (a random sample's repeats are dropped), as :class:`SweepPoint`.

        Raises
        ------
        SweepError
            A combination of values that the study refuses (naming the point).
        """
        return list(self._points)

    @functools.cached_property
    def _points(self):
        # built once: a spec is immutable and a large one takes seconds to set up
        rows = (self._grid_rows() if self.grid is not None else self._random_rows())
        points, seen = [], set()
        for params in rows:
            point = _point(self, len(points) + 1, params)
            digest = point.key("")
            if digest not in seen:          # a random draw can repeat an earlier point
                seen.add(digest)
                points.append(point)
        return tuple(points)

    def _grid_rows(self):
        names = list(self.grid)
        return [dict(zip(names, values)) for values in itertools.product(*self.grid.values())]

    def _random_rows(self):
        rng = np.random.default_rng(self.seed)
        # one column per parameter, in sorted order: the sample depends on the seed only
        columns = {name: _draw(rng, name, self.random[name], self.samples)
                   for name in sorted(self.random)}
        return [{name: columns[name][i] for name in self.random} for i in range(self.samples)]


# --------------------------------------------------------------------------- specs
def specs_dir():
    """``studies/sweeps/``: the sweep specs of the checkout.

    Examples
    --------
    >>> specs_dir().relative_to(outputs.project_root()).as_posix()
    'studies/sweeps'
    """
    return studies.studies_dir() / "sweeps"


def load_spec(spec):
    """A sweep spec from a name in ``studies/sweeps/``, a path to a TOML file, or a SweepSpec.

    Raises
    ------
    SweepError
        Unknown name, missing file, TOML error, or anything :func:`spec_from_dict`
        refuses (the message names the file).

    Examples
    --------
    >>> spec = load_spec("omega_spread_order")      # studies/sweeps/omega_spread_order.toml
    >>> spec.parameters, len(spec.points()), spec.base.uncertainty.weight
    (('weights.omega_e', 'uncertainty.spread', 'design.order'), 12, 'fitted')
    """
    if isinstance(spec, SweepSpec):
        return spec
    if isinstance(spec, bool) or not isinstance(spec, (str, os.PathLike)):
        raise SweepError(f"spec must be a sweep name, a .toml path or a SweepSpec, got "
                         f"{type(spec).__name__}")
    path = Path(spec)
    if path.suffix != ".toml":
        path = specs_dir() / f"{spec}.toml"
        if not path.is_file():
            known = ", ".join(p.stem for p in sorted(specs_dir().glob("*.toml"))) or "none"
            raise SweepError(f"spec: no sweep named {str(spec)!r} in {specs_dir()} "
                             f"(known: {known})")
    if not path.is_file():
        raise SweepError(f"spec: sweep file {path} does not exist")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:       # e.g. saved as latin-1: TOML files are UTF-8
        raise SweepError(f"{path}: not UTF-8 text (byte {exc.start}: {exc.reason}); save "
                         "the sweep file as UTF-8") from None
    except tomllib.TOMLDecodeError as exc:
        raise SweepError(f"{path}: not valid TOML ({exc})") from None
    if isinstance(data.get("name"), str) and data["name"] != path.stem:
        raise SweepError(f"{path}: the sweep is named {data['name']!r} but its file "
                         f"{path.name!r}; name the file {data['name']}.toml or drop the name")
    try:
        return spec_from_dict({"name": path.stem, **data}, relative_to=path.parent)
    except SweepError as exc:
        raise SweepError(f"{path}: {exc}") from None


def spec_from_dict(data, relative_to=None):
    """A sweep spec from the dict layout of a spec file (see the module's docstring).

    Parameters
    ----------
    data : dict
        ``name`` (required here), ``description``, ``study`` (default
        ``"reference"``), ``set``, and one of ``grid`` or ``random``.
    relative_to : path, optional
        Folder a relative ``study = "....toml"`` path is read from (a spec
        file's folder); default the working directory.

    Raises
    ------
    SweepError
        Naming the key: an unknown key, table or parameter, an empty or
        repeated list of values, a bad range, or a value the study refuses.

    Examples
    --------
    >>> spec = spec_from_dict({"name": "demo", "set": {"design": {"max_iter": 2}},
    ...                        "grid": {"weights": {"omega_e": [1000.0, 1260.0]},
    ...                                 "design": {"order": [4, 6]}}})
    >>> len(spec.points()), spec.points()[-1].params              # nothing is evaluated
    (4, {'weights.omega_e': 1260.0, 'design.order': 6})
    >>> spec.base.design.max_iter
    2
    """
    if not isinstance(data, dict):
        raise SweepError(f"data must be a sweep spec, a dict of keys, got {type(data).__name__}")
    relative_to = None if relative_to is None else check_path("relative_to", relative_to)
    unknown = set(data) - _TOP_KEYS
    if unknown:
        raise SweepError(f"unknown key(s) {sorted(unknown)}; a sweep spec has "
                         f"{sorted(_TOP_KEYS)}")
    name = data.get("name")
    problem = outputs.study_name_problem(name)
    if problem:
        raise SweepError(f"sweep name {problem}")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise SweepError(f"description must be text, got {description!r}")
    base = _base_study(name, data.get("study", studies.REFERENCE), data.get("set", {}),
                       relative_to)
    if ("grid" in data) == ("random" in data):
        raise SweepError("give either a [grid] or a [random] table (not both, not neither)")
    if "grid" in data:
        grid = _grid(base, data["grid"])
        spec = SweepSpec(name, base, grid=grid, description=description)
    else:
        ranges, samples, seed = _random(base, data["random"])
        spec = SweepSpec(name, base, random=ranges, samples=samples, seed=seed,
                         description=description)
    spec.points()            # combinations the study refuses fail here, before anything runs
    return spec


def _base_study(name, spec, changes, relative_to):
    """The base study with the ``[set]`` changes, named after the sweep."""
    if isinstance(spec, str) and spec.endswith(".toml") and relative_to is not None \
            and not Path(spec).is_absolute():
        spec = Path(relative_to) / spec
    try:
        base = studies.load(spec)
    except studies.StudyError as exc:
        raise SweepError(f"study = {str(spec)!r}: {exc}") from None
    sections, options = _by_section(_flat("set", changes))
    if options:
        raise SweepError(f"[set] {_CONTROLLER}: the controller is a sweep parameter; give it "
                         "in [grid] or [random] (default: fixed_order)")
    try:
        return base.replace(name=name, description=f"base of sweep {name}", **sections)
    except studies.StudyError as exc:
        raise SweepError(f"[set]: {exc}") from None


def _flat(table, values):
    """``{"section.field": value}`` of a table written with dotted keys (or quoted ones)."""
    if not isinstance(values, dict):
        raise SweepError(f"[{table}] must be a table of parameters, got {values!r}")
    flat = {}
    for key, value in values.items():
        if key in studies.section_fields() and isinstance(value, dict) and not _is_range(value):
            flat.update({f"{key}.{f}": v for f, v in value.items()})
        else:
            flat[key] = value
    for key in flat:
        _parameter(table, key)
    return flat


def _is_range(value):
    return isinstance(value, dict) and bool({"low", "high", "choices"} & set(value))


def _parameter(table, key):
    """(section, field) of a parameter name, or (None, "controller"); raise if unknown."""
    if key == _CONTROLLER:
        return None, _CONTROLLER
    section, _, name = key.partition(".")
    sections = studies.section_fields()
    if section not in sections or not name:
        raise SweepError(f"[{table}] unknown parameter {key!r}: a parameter is "
                         f"'<section>.<field>' with a section of {sorted(sections)}, "
                         f"or {_CONTROLLER!r}")
    names = sections[section]
    if name not in names:
        raise SweepError(f"[{table}] unknown parameter {key!r}: [{section}] has the fields "
                         f"{sorted(names)}")
    return section, name


def _by_section(params):
    """``({section: {field: value}}, {option: value})`` of flat parameters."""
    sections, options = {}, {}
    for key, value in params.items():
        section, name = _parameter("grid", key)
        if section is None:
            options[name] = value
        else:
            sections.setdefault(section, {})[name] = value
    return sections, options


def _check_value(base, table, key, value):
    """Raise a SweepError naming ``key`` when the study (or the controller list) refuses ``value``."""
    section, name = _parameter(table, key)
    if section is None:
        if value not in CONTROLLERS:
            raise SweepError(f"[{table}] {key} = {value!r}: the controller must be one of "
                             f"{list(CONTROLLERS)}")
        return
    try:
        base.replace(name=base.name, **{section: {name: value}})
    except studies.StudyError as exc:
        raise SweepError(f"[{table}] {key} = {value!r}: {exc}") from None


def _grid(base, table):
    flat = _flat("grid", table)
    for key, values in flat.items():
        if not isinstance(values, list) or not values:
            raise SweepError(f"[grid] {key} must be a non-empty list of values, got {values!r}")
    if not flat:
        raise SweepError("[grid] names no parameter")
    _check_grid_size(flat)              # before any value is checked (each builds a study)
    grid = {}
    for key, values in flat.items():
        canonical = [studies.choices_digest({"value": v}) for v in values]
        repeated = [c for c, n in collections.Counter(canonical).items() if n > 1]
        if repeated:
            twice = next(v for v, c in zip(values, canonical) if c == repeated[0])
            raise SweepError(f"[grid] {key} lists the value {twice!r} more than once")
        for value in values:
            _check_value(base, "grid", key, value)
        grid[key] = tuple(values)
    return grid


def _check_grid_size(grid):
    """Raise a SweepError naming [grid] and :data:`MAX_POINTS` when the grid has more points."""
    count = math.prod(len(values) for values in grid.values())
    if count > MAX_POINTS:
        sizes = " x ".join(f"{len(values)} ({key})" for key, values in grid.items())
        raise SweepError(f"[grid] gives {count} points ({sizes}); a sweep holds at most "
                         f"{MAX_POINTS} points (sweep_spec.MAX_POINTS): split it into "
                         "smaller sweeps")


def _random(base, table):
    if not isinstance(table, dict):
        raise SweepError(f"[random] must be a table, got {table!r}")
    table = dict(table)
    samples, seed = table.pop("samples", None), table.pop("seed", None)
    if isinstance(samples, bool) or not isinstance(samples, int) \
            or not 1 <= samples <= MAX_POINTS:
        raise SweepError(f"[random] samples must be an integer in [1, {MAX_POINTS}] (a sweep "
                         f"holds at most {MAX_POINTS} points, sweep_spec.MAX_POINTS), got "
                         f"{samples!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise SweepError(f"[random] seed must be a non-negative integer, got {seed!r}")
    ranges = {key: _range(base, key, value) for key, value in _flat("random", table).items()}
    if not ranges:
        raise SweepError("[random] names no parameter")
    return ranges, samples, seed


def _range(base, key, value):
    """The normalised range of one [random] parameter (its ends checked by the study)."""
    section, name = _parameter("random", key)
    kind = str if section is None else studies.section_fields()[section][name]
    if isinstance(value, dict) and "choices" in value:
        extra = set(value) - {"choices"}
        choices = value["choices"]
        if extra or not isinstance(choices, list) or not choices:
            raise SweepError(f"[random] {key} = {value!r}: choices must be the only key and "
                             "a non-empty list")
        for v in choices:
            _check_value(base, "random", key, v)
        return {"choices": tuple(choices)}
    if kind not in (int, float):
        raise SweepError(f"[random] {key} takes no range of numbers; give "
                         f"{{choices = [...]}}, got {value!r}")
    if isinstance(value, list) and len(value) == 2:
        value = {"low": value[0], "high": value[1]}
    if not isinstance(value, dict) or set(value) - {"low", "high", "scale"} \
            or not {"low", "high"} <= set(value):
        raise SweepError(f"[random] {key} must be [low, high], {{low, high, scale}} or "
                         f"{{choices = [...]}}, got {value!r}")
    low, high, scale = value["low"], value["high"], value.get("scale", "linear")
    for end in (low, high):
        if isinstance(end, bool) or not isinstance(end, (int, float)) or not math.isfinite(end) \
                or (kind is int and not float(end).is_integer()):
            raise SweepError(f"[random] {key}: the range ends must be finite "
                             f"{'integers' if kind is int else 'numbers'}, got {value!r}")
    if not low < high:
        raise SweepError(f"[random] {key}: the range must rise (low < high), got "
                         f"[{low}, {high}]")
    if scale not in ("linear", "log") or (scale == "log" and low <= 0):
        raise SweepError(f"[random] {key}: scale must be 'linear' or 'log' (log needs "
                         f"low > 0), got {scale!r} with low {low}")
    cast = int if kind is int else float
    for end in (low, high):
        _check_value(base, "random", key, cast(end))
    return {"low": cast(low), "high": cast(high), "scale": scale}


def _draw(rng, key, spec, n):
    """``n`` values of one [random] parameter."""
    if "choices" in spec:
        return [spec["choices"][i] for i in rng.integers(0, len(spec["choices"]), n)]
    low, high = spec["low"], spec["high"]
    if spec["scale"] == "log":
        values = np.exp(rng.uniform(np.log(low), np.log(high), n))
    else:
        values = rng.uniform(low, high, n)
    if isinstance(low, int):
        return [int(v) for v in np.clip(np.rint(values), low, high)]
    return [float(v) for v in values]


def _point(spec, index, params):
    sections, options = _by_section(params)
    try:
        study = spec.base.replace(name=f"{spec.name}-{index:04d}",
                                  description=f"point {index} of sweep {spec.name}", **sections)
    except studies.StudyError as exc:
        shown = ", ".join(f"{k} = {v!r}" for k, v in params.items())
        raise SweepError(f"point {index} ({shown}): {exc}") from None
    return SweepPoint(index, dict(params), study, {_CONTROLLER: "fixed_order", **options})
