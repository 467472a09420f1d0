"""Design sweeps: many studies at once, on local workers or on a dask cluster.

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

Each point is a study run through the pipeline (:func:`evaluate_point`: the
cached design of :func:`piezolib.workbook.pipeline.derive_controllers`, its
margins, Case III tracking on the virtual stage).  Points run with joblib on
``jobs`` local processes, or through dask.distributed's joblib backend on a
cluster (``scheduler``).  Each finished point is stored at once in
``runs/sweeps/<name>/points/<key>.json`` (written atomically, sealed with a
SHA-256 of its content), keyed by a digest of the point's whole study, its
options and the evaluation: a sweep that is killed and run again computes
only the points it has no record of.  The table of every point
(``results.csv``, also ``results.parquet`` when pyarrow is installed) and
the Pareto figure (``extra_sweep_pareto.png``) are written under
``runs/sweeps/<name>/``, never to ``figures/`` or ``data/results/``.
"""

import functools
import itertools
import json
import math
import os
import shutil
import socket
import sys
import time
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from piezolib import files, progress
from piezolib._checks import check_path, check_type
from piezolib.workbook import outputs
from piezolib.workbook import study as studies

__all__ = ["SweepSpec", "SweepPoint", "SweepResult", "SweepError", "CONTROLLERS", "METRICS",
           "TRACKING_FREQUENCIES_HZ", "RECORD_FORMAT", "specs_dir", "load_spec",
           "spec_from_dict", "evaluate_point", "run_sweep", "read_record", "pareto_front",
           "check_scheduler_address"]

#: Controllers a point can report: the deployed fixed-order one or the full-order DK one.
CONTROLLERS = ("fixed_order", "full_order")

#: Triangle frequencies [Hz] of the Case III tracking run of each point: the two
#: design goals of Sec. IV-B (< 1 % up to 10 Hz, < 5 % at 50 Hz).
TRACKING_FREQUENCIES_HZ = (10.0, 50.0)

#: The columns :func:`evaluate_point` gives, with their meaning and unit.
METRICS = {
    "mu_RP": "mu_RP upper bound of the reported controller, delay-aware design problem",
    "mu_RP_full_order": "mu_RP upper bound of the full-order DK controller (same problem)",
    "controller_states": "states of the reported controller",
    "gain_margin_dB": "gain margin of the continuous loop [dB]",
    "phase_margin_deg": "phase margin of the continuous loop [deg]",
    "delay_margin_samples": "delay margin of the sampled loop [samples]",
    "stable_with_loop_delay": "sampled loop stable with the study's loop.delay_samples",
    "tracking_error_10Hz_percent": "Case III tracking error at 10 Hz, mean over seeds [%]",
    "tracking_error_50Hz_percent": "Case III tracking error at 50 Hz, mean over seeds [%]",
    "tracking_error_50Hz_low_percent": "its 95 % interval, low end [%]",
    "tracking_error_50Hz_high_percent": "its 95 % interval, high end [%]",
    "case_III_saturated_samples": "most limited samples of a Case III run (DAC, amplifier, ADC)",
}

#: Format version of the per-point records.
RECORD_FORMAT = 1
_TOP_KEYS = {"name", "description", "study", "set", "grid", "random"}
_CONTROLLER = "controller"


class SweepError(ValueError):
    """A sweep spec that cannot be run (names the file, the table and the parameter)."""


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
        next :func:`run_sweep` evaluates every point again (a design may still come from
        the pipeline's disk cache); return how many were removed."""
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
        rows = (self._grid_rows() if self.grid is not None else self._random_rows())
        points, seen = [], set()
        for params in rows:
            point = _point(self, len(points) + 1, params)
            digest = point.key("")
            if digest not in seen:          # a random draw can repeat an earlier point
                seen.add(digest)
                points.append(point)
        return points

    def _grid_rows(self):
        names = list(self.grid)
        return [dict(zip(names, values)) for values in itertools.product(*self.grid.values())]

    def _random_rows(self):
        rng = np.random.default_rng(self.seed)
        # one column per parameter, in sorted order: the sample depends on the seed only
        columns = {name: _draw(rng, name, self.random[name], self.samples)
                   for name in sorted(self.random)}
        return [{name: columns[name][i] for name in self.random} for i in range(self.samples)]


@dataclass(frozen=True, eq=False)
class SweepResult:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    spec : SweepSpec
    table : pandas.DataFrame
        One row per point: ``point``, the parameters, :data:`METRICS`,
        ``pareto`` (on the front of mu_RP against the 50 Hz tracking error),
        ``error`` (empty when the point ran) and ``key``.
    evaluated, reused, failed : int
        Points computed in this run, read from their records, and failed.
    seconds : float
        Wall time of the run [s].
    paths : dict
        ``{"table": csv path, "parquet": path or None, "figure": png path or None}``.
    backend : str
        Where the points ran (``"1 local worker(s)"``, a scheduler's address).
    """

    spec: SweepSpec
    table: pd.DataFrame
    evaluated: int
    reused: int
    failed: int
    seconds: float
    paths: dict
    backend: str = ""

    def overview(self):
        """The table as a reader wants it: each point's parameters, μ_RP, the controller's
        states, margins, the 10 and 50 Hz tracking errors [%] and whether it is on the front
        (the columns the table has)."""
        columns = ["point", *self.spec.parameters, *_OVERVIEW_COLUMNS]
        return self.table[[c for c in columns if c in self.table.columns]]

    @property
    def checks(self):
        """What holds for every sweep, {what it states: bool}: every point ran, its numbers
        are consistent, and the Pareto front is the set of undominated points.

        Examples
        --------
        >>> spec = spec_from_dict({"name": "demo", "grid": {"design.order": [4, 6]}})
        >>> table = pd.DataFrame({"point": [1, 2], "design.order": [4, 6], "mu_RP": [1.2, 0.9],
        ...                       "controller_states": [4, 6],
        ...                       "tracking_error_50Hz_percent": [3.0, 4.0],
        ...                       "pareto": [True, True], "error": ["", ""]})
        >>> result = SweepResult(spec, table, 2, 0, 0, 1.0, {})
        >>> all(result.checks.values())
        True
        >>> result = SweepResult(spec, table.assign(pareto=[True, False]), 2, 0, 0, 1.0, {})
        >>> result.checks["the front holds every undominated point"]
        False
        """
        t = self.table
        column = functools.partial(_column, t)
        checks = {"every point ran": self.failed == 0 and len(t) == len(self.spec.points())}
        if "design.order" in self.spec.parameters:
            fixed = (t[_CONTROLLER] == "fixed_order" if _CONTROLLER in t
                     else pd.Series(True, index=t.index))
            checks["the deployed controller has the swept order"] = bool(
                (column("controller_states") == column("design.order"))[fixed].all())
        checks["mu_RP > 0 at every point"] = bool((column("mu_RP") > 0).all())
        if "stable_with_loop_delay" in t:
            checks["every sampled loop is stable with the loop's delay"] = bool(
                t["stable_with_loop_delay"].astype(bool).all())
        if {"tracking_error_50Hz_low_percent", "tracking_error_50Hz_high_percent"} <= set(t):
            y = column("tracking_error_50Hz_percent")
            checks["the 95 % interval of the 50 Hz error holds its mean"] = bool(
                ((t["tracking_error_50Hz_low_percent"] <= y)
                 & (y <= t["tracking_error_50Hz_high_percent"])).all())
        values = t[["mu_RP", "tracking_error_50Hz_percent"]].to_numpy(float)
        dominated = [bool(np.any(np.all(values <= v, axis=1) & np.any(values < v, axis=1)))
                     for v in values]
        on_front = (t["pareto"].astype(bool).to_numpy() if "pareto" in t
                    else np.zeros(len(t), dtype=bool))
        finite = np.isfinite(values).all(axis=1)
        checks["no point of the Pareto front is beaten in both numbers"] = \
            not any(np.asarray(dominated)[on_front])
        checks["the front holds every undominated point"] = bool(
            on_front[finite & ~np.asarray(dominated, dtype=bool)].all())
        checks["the front has a point"] = bool(on_front.any())
        return checks

    def resumed_checks(self, first):
        """{what it states: bool} of this run as a rerun of ``first`` (a SweepResult of
        the same spec): nothing computed again, every point read from its record, the
        same table."""
        check_type("first", first, SweepResult, "the SweepResult of the first run")
        try:
            pd.testing.assert_frame_equal(self.table, first.table)
            same = True
        except AssertionError:
            same = False
        return {"nothing computed again": self.evaluated == 0,
                "every point read from its record": self.reused == len(first.table),
                "the same table as the first run": same}

    def findings(self):
        """Markdown lines of what the sweep found: its designs, the lowest μ_RP, the lowest
        50 Hz tracking error and the Pareto front."""
        from piezolib.workbook.style import unit_text

        t, spec = self.table, self.spec
        names = {p: unit_text(n) for p, n in _short_names(spec.parameters).items()}
        over = " × ".join(
            f"{names[p]} ∈ {{{', '.join(_format(v) for v in dict.fromkeys(t[p]))}}}"
            for p in spec.parameters)
        iterations = ("" if "design.max_iter" in spec.parameters else
                      f" ({spec.base.design.max_iter} DK iteration(s) each)")
        lines = [f"**{len(t)} designs** over {over}{iterations} in {self.seconds:.1f} s on "
                 f"{self.backend or 'the workers'}; {self.reused} reused, {self.failed} failed."]
        where = functools.partial(_where, names)
        ok = t.dropna(subset=["mu_RP", "tracking_error_50Hz_percent"])
        if len(ok):
            best_mu = ok.loc[ok.mu_RP.idxmin()]
            best_e = ok.loc[ok.tracking_error_50Hz_percent.idxmin()]
            lines += [f"**Lowest μ_RP:** {best_mu.mu_RP:.3f} at {where(best_mu)} "
                      f"(50 Hz error {best_mu.tracking_error_50Hz_percent:.2f} %).",
                      f"**Lowest 50 Hz error:** {best_e.tracking_error_50Hz_percent:.2f} % at "
                      f"{where(best_e)} (μ_RP {best_e.mu_RP:.3f})."]
        if "pareto" in t:
            front = ", ".join(map(str, t.point[t.pareto.astype(bool)]))
            lines.append(f"**Pareto front:** points {front} of {len(t)}; table and figure in "
                         f"`{spec.directory}`.")
        return lines


#: The columns of :meth:`SweepResult.overview` after the point and its parameters.
_OVERVIEW_COLUMNS = ("mu_RP", "controller_states", "gain_margin_dB", "phase_margin_deg",
                     "delay_margin_samples", "tracking_error_10Hz_percent",
                     "tracking_error_50Hz_percent", "pareto")


def _column(table, name):
    """Column ``name`` of ``table``, or NaN throughout when it has none."""
    return table[name] if name in table else pd.Series(np.nan, index=table.index)


def _where(names, row):
    """``omega_e = 1000, order = 4``: the parameters of a table row."""
    return ", ".join(f"{names[p]} = {_format(row[p])}" for p in names)


# --------------------------------------------------------------------------- specs
def specs_dir():
    """``studies/sweeps/``: the sweep specs of the checkout."""
    return studies.studies_dir() / "sweeps"


def load_spec(spec):
    """A sweep spec from a name in ``studies/sweeps/``, a path to a TOML file, or a SweepSpec.

    Raises
    ------
    SweepError
        Unknown name, missing file, TOML error, or anything :func:`spec_from_dict`
        refuses (the message names the file).
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
    grid = {}
    for key, values in _flat("grid", table).items():
        if not isinstance(values, list) or not values:
            raise SweepError(f"[grid] {key} must be a non-empty list of values, got {values!r}")
        canonical = [studies.choices_digest({"value": v}) for v in values]
        repeated = sorted({v for v in canonical if canonical.count(v) > 1})
        if repeated:
            twice = next(v for v, c in zip(values, canonical) if c == repeated[0])
            raise SweepError(f"[grid] {key} lists the value {twice!r} more than once")
        for value in values:
            _check_value(base, "grid", key, value)
        grid[key] = tuple(values)
    if not grid:
        raise SweepError("[grid] names no parameter")
    return grid


def _random(base, table):
    if not isinstance(table, dict):
        raise SweepError(f"[random] must be a table, got {table!r}")
    table = dict(table)
    samples, seed = table.pop("samples", None), table.pop("seed", None)
    if isinstance(samples, bool) or not isinstance(samples, int) or not 1 <= samples <= 100_000:
        raise SweepError(f"[random] samples must be an integer in [1, 100000], got {samples!r}")
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


# --------------------------------------------------------------------------- one point
def evaluate_point(study, controller="fixed_order"):
    """The numbers of one sweep point: design, margins and Case III tracking.

    The design is :func:`piezolib.workbook.pipeline.derive_controllers`
    (DK-iteration, reduction, fixed order; through the disk cache, so a point
    a notebook or an earlier sweep designed is not designed again; derived
    also for a point whose choices equal the reference's, so that every
    point comes from the same design path).  The
    reported controller is analysed on the study's plant: margins of the
    continuous loop and of the sampled loop at ``loop.fs_Hz``
    (:func:`piezolib.problem.analysis.margins_table`), and Case III tracking
    of 12 um triangles (``experiments.range_um``) at
    :data:`TRACKING_FREQUENCIES_HZ` only, on the virtual stage sampled at the
    loop rate, running the controller's float32 second-order sections with
    the study's loop delay, the workbook's Dahl feedforward, and the study's
    noise seeds (mean and 95 % interval, as in notebook 06).

    Parameters
    ----------
    study : Study, str or path
    controller : {"fixed_order", "full_order"}
        The deployed fixed-order controller (``design.order`` states) or the
        full-order DK one.

    Returns
    -------
    dict
        The :data:`METRICS` of the point (floats, ints and bools).
    """
    from piezolib.hysteresis import FitWarning
    from piezolib.problem import analysis
    from piezolib.problem.hysteresis_fits import workbook_dahl_fit
    from piezolib.problem.stage import StageSaturationWarning, VirtualStage
    from piezolib.robust import export
    from piezolib.robust.discrete import discretize
    from piezolib.workbook import experiments, pipeline

    study = studies.load(study)
    if controller not in CONTROLLERS:
        raise ValueError(f"controller must be one of {list(CONTROLLERS)}, got {controller!r}")
    found = pipeline.derive_controllers(study)
    K = found.K_fixed if controller == "fixed_order" else found.K_full
    fs, delay = study.loop.fs_Hz, study.loop.delay_samples
    G = pipeline.study_problem(study).G
    margins = analysis.margins_table({"K": K}, G, fs, delays=tuple(range(max(3, delay) + 1)))["K"]
    sections = export.controller_sos(discretize(K, fs, G=G).K, "K")
    with warnings.catch_warnings():
        # notebook 03 chose this fit knowing which parameters are identifiable only together;
        # saturation is reported as a number of the point instead of a warning per run
        warnings.simplefilter("ignore", FitWarning)
        warnings.simplefilter("ignore", StageSaturationWarning)
        dahl = workbook_dahl_fit().model
        stage = VirtualStage(seed=study.experiments.stage_seed, sample_rate_Hz=fs)
        tracking = experiments.tracking_test(
            stage, dahl, sections, TRACKING_FREQUENCIES_HZ, study.experiments.range_um,
            delay_samples=delay, seeds=study.experiments.seeds)
    low, high = tracking.interval("case_III", 50.0)
    return {
        "mu_RP": found.mu["fixed order" if controller == "fixed_order" else "delay-aware DK"],
        "mu_RP_full_order": found.mu["delay-aware DK"],
        "controller_states": int(K.nstates),
        "gain_margin_dB": float(margins["gain margin [dB]"]),
        "phase_margin_deg": float(margins["phase margin [deg]"]),
        "delay_margin_samples": float(margins["sampled loop delay margin [samples]"]),
        "stable_with_loop_delay": bool(margins[f"stable, delay {delay}"]),
        "tracking_error_10Hz_percent": float(tracking.table.loc["case_III", 10.0]),
        "tracking_error_50Hz_percent": float(tracking.table.loc["case_III", 50.0]),
        "tracking_error_50Hz_low_percent": low,
        "tracking_error_50Hz_high_percent": high,
        "case_III_saturated_samples": int(tracking.saturation.loc["case_III"].max()),
    }


def _evaluate_task(evaluate, study, options, key):
    """Run one point where a worker runs it; never raises for the point's own failure.

    Returns ``(key, metrics or None, error text or None, seconds, host)``.
    """
    from threadpoolctl import threadpool_limits

    start = time.perf_counter()
    try:
        # one core per point: the same rounding whichever backend runs it, and no
        # oversubscription when every core already runs a point
        with threadpool_limits(1):
            metrics = evaluate(study, **options)
        _check_metrics(metrics)
        error = None
    except Exception as exc:      # the point failed; the sweep goes on and reports it
        metrics, error = None, f"{type(exc).__name__}: {exc}"
    return key, metrics, error, time.perf_counter() - start, socket.gethostname()


def _check_metrics(metrics):
    if not isinstance(metrics, dict) or not all(
            isinstance(k, str) and (v is None or isinstance(v, (int, float, bool, str)))
            for k, v in metrics.items()):
        raise TypeError(f"an evaluation must return a dict of named numbers, got {metrics!r}")


# --------------------------------------------------------------------------- records
def _record_path(spec, key):
    return spec.directory / "points" / f"{key}.json"


def _write_record(spec, point, key, evaluation, metrics, seconds, host):
    from piezolib.workbook import pipeline

    doc = {"format": RECORD_FORMAT, "key": key, "sweep": spec.name, "index": point.index,
           "params": point.params, "options": point.options, "study": point.study.choices(),
           "evaluation": evaluation, "metrics": metrics, "seconds": seconds, "host": host,
           "library": pipeline.library_fingerprint()}
    path = _record_path(spec, key)
    return files.atomic_write(path, json.dumps(files.seal(doc), indent=1) + "\n")


def read_record(path, key=None):
    """The metrics of a stored point, or None when the record is missing or unusable.

    Parameters
    ----------
    path : path
        A ``points/<key>.json`` record of a sweep.
    key : str, optional
        The key it must carry (a renamed or copied file is not used).

    Returns
    -------
    dict or None
        The record (``metrics``, ``seconds``, ``library``, ...) when it is
        intact (its SHA-256 matches), of this format and of ``key``.
    """
    path = Path(path) if isinstance(path, (str, os.PathLike)) else None
    if path is None:
        raise TypeError("path must be the path of a point record")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(doc, dict) or doc.get("format") != RECORD_FORMAT \
            or files.seal_problem(doc) is not None or (key is not None and doc.get("key") != key):
        return None
    return doc


# --------------------------------------------------------------------------- the sweep
def run_sweep(spec, jobs=None, scheduler=None, evaluate=evaluate_point, dry_run=False,
              stream=None):
    """Run every point of a sweep that has no record yet; write the table and the figure.

    Parameters
    ----------
    spec : SweepSpec, str or path
        A spec (:func:`load_spec`).
    jobs : int, optional
        Local worker processes (joblib); default one per core.  1 runs the
        points one by one in this process.  Ignored with ``scheduler``.
    scheduler : str or distributed.Client, optional
        A dask scheduler's address (``"tcp://host:8786"``) or a client: the
        points run on its workers through dask.distributed's joblib backend.
        Each worker needs this checkout (``PIEZOLIB_ROOT``) importable; the
        records are written here, by the process that runs the sweep.
    evaluate : callable, optional
        ``evaluate(study, controller=...) -> dict`` of numbers
        (default :func:`evaluate_point`); a module-level function when the
        points run in other processes.
    dry_run : bool
        List the points (and whether each is stored) and run nothing.
    stream : file-like, optional
        Where the progress lines go (default ``sys.stdout``).

    Returns
    -------
    SweepResult
    """
    stream = sys.stdout if stream is None else stream
    if not callable(evaluate):
        raise TypeError(f"evaluate must be a callable, got {evaluate!r}")
    jobs = _jobs(jobs)
    if isinstance(scheduler, str):
        check_scheduler_address(scheduler)      # before anything runs
    elif scheduler is not None:
        from distributed import Client

        check_type("scheduler", scheduler, Client,
                   "an address such as 'tcp://127.0.0.1:8786' or a distributed.Client")
    spec = load_spec(spec)
    evaluation = f"{evaluate.__module__}.{evaluate.__qualname__}"
    points = spec.points()
    keys = {p.index: p.key(evaluation) for p in points}
    files.remove_stale_temporaries(spec.directory)       # what a killed earlier run left
    stored = {p.index: read_record(_record_path(spec, keys[p.index]), keys[p.index])
              for p in points}
    names = _short_names(spec.parameters)
    if dry_run:
        return _dry_run(spec, points, keys, stored, names, stream)
    start = time.perf_counter()
    todo = [p for p in points if stored[p.index] is None]
    reused = len(points) - len(todo)
    backend = (f"{scheduler if isinstance(scheduler, str) else 'the dask cluster'}"
               if scheduler is not None else f"{jobs} local worker(s)")
    _say(stream, f"sweep {spec.name}: {len(points)} points, {reused} stored "
         f"(reused), {len(todo)} to run on {backend}")
    _warn_other_library(stored, stream)
    rows = {p.index: _row(p, stored[p.index]["metrics"], None, keys[p.index])
            for p in points if stored[p.index] is not None}
    by_key = {keys[p.index]: p for p in todo}
    failed = 0
    for k, (key, metrics, error, seconds, host) in enumerate(
            _results(evaluate, todo, keys, jobs, scheduler), reused + 1):
        point = by_key[key]
        if error is None:
            _write_record(spec, point, key, evaluation, metrics, seconds, host)
        failed += error is not None
        rows[point.index] = _row(point, metrics, error, key)
        _say(stream, _progress_line(k, len(points), point, names, metrics, error, seconds))
    table = _table([rows[i] for i in sorted(rows)])
    paths = _write_outputs(spec, table)
    seconds = time.perf_counter() - start
    _say(stream, f"sweep {spec.name}: {len(todo) - failed} evaluated, {reused} reused, "
         f"{failed} failed in {seconds:.1f} s; table {paths['table']}"
         + (f", figure {paths['figure']}" if paths["figure"] else ""))
    return SweepResult(spec, table, len(todo) - failed, reused, failed, seconds, paths, backend)


def _jobs(jobs):
    if jobs is None:
        return os.cpu_count() or 1
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
    return jobs


def _results(evaluate, todo, keys, jobs, scheduler):
    """``_evaluate_task`` results of the points, each as soon as it is done."""
    if not todo:
        return
    import joblib

    tasks = [joblib.delayed(_evaluate_task)(evaluate, p.study, p.options, keys[p.index])
             for p in todo]
    if scheduler is None:
        # batch_size=1: a point takes seconds to minutes, and its record is written as
        # soon as it is back (a batch would hold finished points back)
        yield from joblib.Parallel(n_jobs=jobs, batch_size=1,
                                   return_as="generator_unordered")(tasks)
        return
    client, own = _client(scheduler)
    try:
        with joblib.parallel_config(backend="dask"):
            yield from joblib.Parallel(n_jobs=-1, batch_size=1,
                                       return_as="generator_unordered")(tasks)
    finally:
        if own:
            client.close()


def _client(scheduler):
    """(distributed.Client, whether this call opened it) for an address or a client."""
    from distributed import Client

    if isinstance(scheduler, Client):
        return scheduler, False
    try:
        return Client(scheduler, timeout=30, set_as_default=True), True
    except (OSError, TimeoutError) as exc:
        raise OSError(f"scheduler: cannot reach the dask scheduler at {scheduler} ({exc})") \
            from None


def check_scheduler_address(address):
    """Raise a ValueError naming ``scheduler`` unless ``address`` looks like
    ``tcp://host:port`` (or another dask protocol)."""
    protocol, _, rest = address.partition("://") if isinstance(address, str) else ("", "", "")
    host, _, port = rest.rpartition(":")
    if protocol not in ("tcp", "tls", "inproc", "ws", "wss", "ucx") or not (
            protocol == "inproc" or (host and port.isdigit())):
        raise ValueError(f"scheduler must be a dask scheduler address such as "
                         f"'tcp://127.0.0.1:8786' or a distributed.Client, got {address!r}")
    return address


def _row(point, metrics, error, key):
    return {"point": point.index, **point.params, **point.options, **(metrics or {}),
            "error": error or "", "key": key}


def _table(rows):
    table = pd.DataFrame(rows)
    x, y = "mu_RP", "tracking_error_50Hz_percent"
    if {x, y} <= set(table.columns):
        table.insert(table.columns.get_loc("error"), "pareto", pareto_front(table, x, y))
    return table


def pareto_front(table, x, y):
    """Which rows are on the Pareto front when both ``x`` and ``y`` are minimised.

    A row is on the front when no other row is at least as good in both
    columns and better in one; rows with a missing value are not.

    Parameters
    ----------
    table : pandas.DataFrame
    x, y : str
        Column names.

    Returns
    -------
    pandas.Series of bool
        Indexed like ``table``.

    Examples
    --------
    >>> t = pd.DataFrame({"a": [1.0, 2.0, 3.0, 2.0], "b": [3.0, 1.0, 2.0, 2.0]})
    >>> pareto_front(t, "a", "b").tolist()
    [True, True, False, False]
    """
    if not isinstance(table, pd.DataFrame):
        raise TypeError(f"table must be a pandas DataFrame, got {type(table).__name__}")
    for name, column in (("x", x), ("y", y)):
        if column not in table.columns:
            raise ValueError(f"{name}: the table has no column {column!r}")
    values = table[[x, y]].apply(pd.to_numeric, errors="coerce").to_numpy(float)
    ok = np.isfinite(values).all(axis=1)
    front = np.zeros(len(table), dtype=bool)
    for i in np.flatnonzero(ok):
        others = values[ok]
        dominated = np.any(np.all(others <= values[i], axis=1)
                           & np.any(others < values[i], axis=1))
        front[i] = not dominated
    return pd.Series(front, index=table.index, name="pareto")


def _write_outputs(spec, table):
    """The table (CSV, Parquet when pyarrow is there) and the Pareto figure."""
    directory = spec.directory
    csv = files.atomic_write(directory / "results.csv", table.to_csv(index=False))
    parquet = None
    try:
        import pyarrow  # noqa: F401  (optional: only its presence is asked)
    except ImportError:
        pass
    else:
        with files.atomic_path(directory / "results.parquet") as tmp:
            table.to_parquet(tmp, index=False)
        parquet = directory / "results.parquet"
    figure = None
    if "pareto" in table and table["pareto"].any():
        import matplotlib.pyplot as plt

        from piezolib.workbook import plotting
        from piezolib.workbook.figures import sweeps as sweep_figures

        # no sweep name in the title: the units rule would respell a name like omega_e_sweep
        fig = sweep_figures.extra_sweep_pareto(table)
        figure = plotting.save_figure(fig, directory)
        plt.close(fig)
    return {"table": csv, "parquet": parquet, "figure": figure}


# --------------------------------------------------------------------------- lines
def _say(stream, line):
    progress.write(line, file=stream)


def _short_names(parameters):
    """The field name of each parameter, or its full name where two fields share one."""
    fields_ = [p.rpartition(".")[2] for p in parameters]
    return {p: f if fields_.count(f) == 1 else p for p, f in zip(parameters, fields_)}


def _format(value):
    return f"{value:g}" if isinstance(value, float) else str(value)


def _progress_line(k, n, point, names, metrics, error, seconds):
    params = " ".join(f"{names[p]}={_format(v)}" for p, v in point.params.items())
    if error is not None:
        result = f"FAILED: {error[:160]}"
    else:
        shown = [f"{label} {metrics[m]:.4g}{unit}" for m, label, unit in (
            ("mu_RP", "mu_RP", ""), ("tracking_error_50Hz_percent", "e(50 Hz)", " %"))
            if isinstance(metrics.get(m), (int, float))]
        result = "  ".join(shown) or "ok"
    return f"[{k}/{n}] {params}  {result}  {seconds:.1f} s"


def _dry_run(spec, points, keys, stored, names, stream):
    for p in points:
        params = " ".join(f"{names[q]}={_format(v)}" for q, v in p.params.items())
        state = "stored" if stored[p.index] is not None else "to run"
        _say(stream, f"[{p.index}/{len(points)}] {params}  ({state}, key {keys[p.index]})")
    reused = sum(s is not None for s in stored.values())
    _say(stream, f"sweep {spec.name}: {len(points)} points, {reused} stored, "
         f"{len(points) - reused} to run; outputs in {spec.directory}")
    table = pd.DataFrame([{"point": p.index, **p.params, **p.options,
                           "stored": stored[p.index] is not None, "key": keys[p.index]}
                          for p in points])
    return SweepResult(spec, table, 0, reused, 0, 0.0,
                       {"table": None, "parquet": None, "figure": None})


def _warn_other_library(stored, stream):
    from piezolib.workbook import pipeline

    here = pipeline.library_fingerprint()
    other = sum(1 for doc in stored.values() if doc is not None and doc.get("library") != here)
    if other:
        _say(stream, f"note: {other} stored point(s) were computed by another version of "
             "piezolib (library fingerprint); delete their records under points/ to "
             "recompute them")
