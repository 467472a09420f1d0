"""Committed end points of notebook 09's two searches, keyed by what each search was given.

Two results of notebook 09 come out of searches that cost seconds each and
land on the same end point every run:

* the trade-off's bound no controller can cross at a performance scale
  (an H-infinity gamma-iteration,
  :func:`piezolib.robust.achievable.performance_lower_bound`): shown, never
  asserted, so it is read from the file;
* the sampled loop's parametric margin of a controller with d samples of delay
  (a bisection over the box, :func:`piezolib.uncertainty.sampled_parametric_margin`):
  asserted, so its bracket is read from the file and **verified** in the
  notebook (every member tried stable at the lower end, a member unstable at
  the upper end), the search running only when it does not verify.

Each entry is keyed by a SHA-256 of its inputs (every coefficient written with
12 significant digits), so a study with other models, controllers or options
finds no entry and searches.  ``data/controllers/mixed_end_points.json`` is
written by :func:`write_end_points` from
:func:`piezolib.problem.coefficient_box.searched_end_points` (about 15 CPU-s;
``python -m piezolib controllers --write-mixed`` does not touch it)::

    from piezolib.problem import coefficient_box as box, mixed_end_points as ep
    from piezolib.workbook import pipeline, study
    st = study.load("reference")
    G, _, H_e, H_y, _ = pipeline.study_problem(st)
    sections = {box.DEPLOYED: pipeline.study_sections(st)["K_ours"],
                box.MIXED: pipeline.study_mixed_sections(st)}
    ep.write_end_points(*box.searched_end_points(
        pipeline.study_mixed_designs(st).designs, pipeline.study_controllers(st).K_deployed,
        sections, G, H_e, H_y, st.loop.fs_Hz))

and the slow test ``tests/problem/test_mixed_end_points.py`` re-derives it from scratch.
Write it anew when the mixed designs, the deployed sections or a search change (a
changed input finds no entry: the notebook then searches and stays right, only slower).
"""

import hashlib
import json

import control as ct
import numpy as np

from piezolib._checks import (check_finite_lti, check_integer, check_model, check_path,
                              check_positive, check_siso, check_type)
from piezolib.files import atomic_write
from piezolib.problem.paths import data_dir
from piezolib.uncertainty import SampledMargin

__all__ = ["end_points_path", "read_end_points", "bound_key", "margin_key",
           "committed_bounds", "committed_bracket", "write_end_points", "FORMAT"]

#: Format version of the file.
FORMAT = 1


def end_points_path():
    """``data/controllers/mixed_end_points.json``.

    Examples
    --------
    >>> end_points_path().relative_to(data_dir()).as_posix()
    'controllers/mixed_end_points.json'
    """
    return data_dir() / "controllers" / "mixed_end_points.json"


def _numbers(x):
    """Every number of ``x`` (floats, arrays, models) as text with 12 significant digits."""
    if isinstance(x, ct.LTI):
        if isinstance(x, ct.StateSpace):
            return ["ss", *(_numbers(np.asarray(m, float)) for m in (x.A, x.B, x.C, x.D)),
                    _numbers(0.0 if x.dt is None else float(x.dt))]
        tf = ct.tf(x)
        return ["tf", _numbers(np.asarray(tf.num[0][0], float)),
                _numbers(np.asarray(tf.den[0][0], float)), _numbers(float(tf.dt or 0.0))]
    if isinstance(x, (list, tuple)):
        return [_numbers(v) for v in x]
    if isinstance(x, (str, bool)):
        return x
    a = np.asarray(x, dtype=float)
    return [list(a.shape), [f"{v:.12g}" for v in a.ravel()]]


def _key(kind, *parts):
    text = json.dumps([kind, FORMAT, _numbers(list(parts))], separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def bound_key(G, H_e, H_y, performance_scale, spread, fs):
    """Key of the trade-off's bound at one performance scale (its plant's inputs).

    Examples
    --------
    >>> G = ct.tf([1.0], [1.0, 1.0])
    >>> bound_key(G, G, G, 0.5, 0.05, 1e4) == bound_key(G, G, G, 0.5, 0.05, 1e4 * (1 + 1e-15))
    True
    >>> bound_key(G, G, G, 0.5, 0.05, 1e4) == bound_key(G, G, G, 0.6, 0.05, 1e4)
    False
    """
    for name, sys in (("G", G), ("H_e", H_e), ("H_y", H_y)):
        check_siso(name, check_model(name, sys, proper=True))
    return _key("performance_lower_bound", G, H_e, H_y,
                check_positive("performance_scale", performance_scale),
                check_positive("spread", spread), check_positive("fs", fs))


def margin_key(G, Kd, delay_samples, samples, seed=0, spread_max=0.5, rtol=1e-3,
               float32=False):
    """Key of a sampled loop's parametric margin (the search's arguments).

    Examples
    --------
    >>> G, Kd = ct.tf([1.0], [1.0, 3.0, 3.0, 1.0]), ct.tf([2.0], [1.0], 0.05)
    >>> margin_key(G, Kd, 1, 200) == margin_key(G, Kd, 2, 200)
    False
    """
    check_siso("G", check_model("G", G, proper=True))
    check_siso("Kd", check_finite_lti("Kd", Kd))
    check_type("float32", float32, (bool, np.bool_), "True or False")
    return _key("sampled_parametric_margin", G, Kd,
                check_integer("delay_samples", delay_samples, minimum=0),
                check_integer("samples", samples, minimum=0),
                check_integer("seed", seed, minimum=0),
                check_positive("spread_max", spread_max), check_positive("rtol", rtol),
                bool(float32))


def read_end_points(path=None):
    """The committed file as {"bounds": {key: value}, "margins": {key: {...}}}; empty when
    there is no file.

    Examples
    --------
    >>> sorted(read_end_points())
    ['bounds', 'margins']
    """
    path = end_points_path() if path is None else check_path("path", path)
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        return {"bounds": {}, "margins": {}}
    if doc.get("format") != FORMAT:
        raise ValueError(f"{path}: format {doc.get('format')!r}, expected {FORMAT}")
    return {"bounds": dict(doc.get("bounds", {})), "margins": dict(doc.get("margins", {}))}


def committed_bounds(designs, G, H_e, H_y, fs, path=None):
    """{performance scale: committed bound} of the designs whose problem has an entry.

    Parameters
    ----------
    designs : sequence of piezolib.problem.design.MixedDesign
    G, H_e, H_y : control.LTI
        The problem the designs were made for.
    fs : float
        Loop rate [Hz].
    path : pathlib.Path, optional
        The file; default :func:`end_points_path`.

    Returns
    -------
    dict

    Examples
    --------
    >>> G = ct.tf([1.0], [1.0, 1.0])
    >>> committed_bounds([], G, G, G, 1e4)
    {}
    """
    if isinstance(designs, str) or not hasattr(designs, "__iter__"):
        raise TypeError(f"designs must be a sequence of MixedDesign, got {designs!r}"[:200])
    designs = list(designs)
    if not all(hasattr(d, "performance_scale") and hasattr(d, "spread") for d in designs):
        raise TypeError(f"designs must be a sequence of MixedDesign, got {designs!r}"[:200])
    fs = check_positive("fs", fs)
    stored = read_end_points(path)["bounds"]
    out = {}
    for d in designs:
        key = bound_key(G, H_e, H_y, d.performance_scale, d.spread, fs)
        if key in stored:
            out[d.performance_scale] = float(stored[key])
    return out


def committed_bracket(G, Kd, delay_samples, samples, path=None, **options):
    """(spread, spread_unstable, offsets) committed for this sampled-loop margin, or None.

    ``options`` are the remaining arguments of
    :func:`~piezolib.uncertainty.sampled_parametric_margin` (seed, spread_max, rtol,
    float32), part of the key.

    Examples
    --------
    >>> G, Kd = ct.tf([1.0], [1.0, 3.0, 3.0, 1.0]), ct.tf([2.0], [1.0], 0.05)
    >>> committed_bracket(G, Kd, 1, 200) is None
    True
    """
    key = margin_key(G, Kd, delay_samples, samples, **options)
    entry = read_end_points(path)["margins"].get(key)
    if entry is None:
        return None
    return (float(entry["spread"]), float(entry["spread_unstable"]),
            np.asarray(entry["offsets"], dtype=float))


def write_end_points(bounds, margins, path=None):
    """Write the file from searched results.

    Parameters
    ----------
    bounds : dict
        {bound_key: bound value}.
    margins : dict
        {margin_key: SampledMargin} (bounded results only).
    path : pathlib.Path, optional
        Default :func:`end_points_path`.

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     p = write_end_points({"k": 0.5}, {}, Path(folder) / "e.json")
    ...     read_end_points(p)["bounds"]
    {'k': 0.5}
    """
    check_type("bounds", bounds, dict, "a dict {key: bound}")
    check_type("margins", margins, dict, "a dict {key: SampledMargin}")
    for m in margins.values():
        check_type("margins", m, SampledMargin, "a dict {key: SampledMargin}")
    for v in bounds.values():
        check_positive("bounds", v)
    path = end_points_path() if path is None else check_path("path", path)
    doc = {"format": FORMAT,
           "note": "end points of notebook 09's searches; see piezolib/problem/mixed_end_points.py",
           "bounds": {k: float(v) for k, v in sorted(bounds.items())},
           "margins": {k: {"spread": float(m.spread), "spread_unstable": float(m.spread_unstable),
                           "offsets": [float(v) for v in m.offsets]}
                       for k, m in sorted(margins.items()) if m.bounded and m.nominal_stable}}
    return atomic_write(path, json.dumps(doc, indent=1) + "\n")
