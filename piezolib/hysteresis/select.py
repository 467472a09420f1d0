"""Model choice by validation: fit on one part, score on another; feedforward cross-check.

:func:`split_record` cuts one record at a turning point of the input into a
fitting part and a validation part, :func:`validation_table` scores fitted
models on records they were not fitted to (RMS and max error in % of the
stroke, the hysteresis measure of eq. 25-26 and the loop width at mid-input,
of the data and of the model), and :func:`cross_check` applies the
feedforward of each model to every other model (and to any measured plant)
as the plant: the check that tells whether a compensation generalises
beyond the model it was derived from.  Models are any
:class:`~piezolib.hysteresis.common.HysteresisModel` (Dahl, PI).
"""

import math
from collections.abc import Mapping

import numpy as np

from piezolib._checks import check_finite_array, check_integer, check_positive, check_signals
from piezolib.hysteresis.common import HysteresisModel
from piezolib.hysteresis.dahl import strokes
from piezolib.hysteresis.measure import hysteresis_measure

__all__ = ["split_record", "loop_scores", "validation_table", "pooled_rms", "cross_check"]


def split_record(v, x, fraction=0.5):
    """Split one record at the turning point of v nearest to ``fraction`` of its length.

    Parameters
    ----------
    v, x : array_like
        Input [v-unit] and output [x-unit], 1-D, same length.
    fraction : float, optional
        Where to cut, 0 < fraction < 1.

    Returns
    -------
    fit_part : (v, x)
        The samples before the cut: fit the model on these.
    validation : (v, x, first)
        The whole record and the index of the first validation sample: the
        model runs through the fitting part (so its state at the cut is its
        own), and only samples from ``first`` on are scored.

    Examples
    --------
    >>> from piezolib.hysteresis import PIModel
    >>> from piezolib.signals import triangle
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)
    >>> x = pi.simulate(v)
    >>> (v_fit, x_fit), (v_all, x_all, first) = split_record(v, x, 0.5)
    >>> len(v_fit), first, float(v[first])              # cut at the minimum after one period
    (41, 40, 0.0)
    """
    v, x = check_signals(8, v=v, x=x)
    fraction = check_positive("fraction", fraction)
    if not 0 < fraction < 1:
        raise ValueError(f"fraction must lie strictly between 0 and 1, got {fraction!r}")
    turns = np.array([stop for start, stop, s in strokes(v)][:-1], dtype=int)
    if turns.size == 0:
        raise ValueError("v has no turning point: a record without reversals cannot be split")
    k = int(turns[np.argmin(np.abs(turns - fraction * v.size))])
    return (v[:k + 1], x[:k + 1]), (v, x, k)


def _models(what, models, callables=False):
    """``models`` checked to be a non-empty dict of hysteresis models (or callables)."""
    if not isinstance(models, Mapping):
        raise TypeError(f"{what} must be a dict {{name: model}}, got {type(models).__name__}")
    if not models:
        raise ValueError(f"{what} must hold at least one model")
    for name, model in models.items():
        if not (isinstance(model, HysteresisModel) or (callables and callable(model))):
            need = "a model or a callable v -> x" if callables else \
                "a model with simulate() and feedforward()"
            raise TypeError(f"{what}[{name!r}] must be {need}, got {type(model).__name__}")
    return models


def _triples(records, what):
    if isinstance(records, (str, np.ndarray)) or not hasattr(records, "__iter__"):
        raise TypeError(f"{what} must be a sequence of (v, x) or (v, x, first)")
    records = list(records)
    if not records:
        raise ValueError(f"{what} must hold at least one record")
    out = []
    for i, rec in enumerate(records):
        if not isinstance(rec, (tuple, list)) or len(rec) not in (2, 3):
            raise TypeError(f"{what}[{i}] must be (v, x) or (v, x, first)")
        v, x = check_signals(8, **{f"{what}[{i}] v": rec[0], f"{what}[{i}] x": rec[1]})
        first = check_integer(f"{what}[{i}] first", rec[2] if len(rec) == 3 else 0, minimum=0)
        if first > v.size - 8:
            raise ValueError(f"{what}[{i}]: first = {first} leaves fewer than 8 samples")
        out.append((v, x, first))
    return out


def _width(v, x):
    """Eq. 25-26 on (v, x): (hysteresis %, loop width |x_up - x_lo| at V_M), NaN if no loop."""
    try:
        m = hysteresis_measure(v, x)
    except ValueError:
        return math.nan, math.nan
    return m.percent, abs(m.x_up - m.x_lo)


def loop_scores(x_model, v, x):
    """Validation scores of one model output against one measured record.

    Returns
    -------
    dict
        ``RMS %`` and ``max %`` (of the measured stroke, max - min of x),
        ``hysteresis % data`` / ``model`` (eq. 26) and ``loop width data`` /
        ``model`` (|x_up - x_lo| at the mid input V_M, eq. 25, [x-unit]).

    Examples
    --------
    >>> from piezolib.hysteresis import PIModel
    >>> from piezolib.signals import triangle
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)
    >>> x = pi.simulate(v)
    >>> s = loop_scores(x + 0.01, v, x)                  # a model 0.01 too high
    >>> round(s["RMS %"], 3), round(s["hysteresis % data"], 2), round(s["loop width data"], 3)
    (0.177, 12.92, 0.7)
    """
    x_model, v, x = check_signals(8, x_model=x_model, v=v, x=x)
    r = x_model - x
    stroke = float(np.ptp(x))
    h_data, w_data = _width(v, x)
    h_model, w_model = _width(v, x_model)
    return {"RMS %": 100 * math.sqrt(float(np.mean(r ** 2))) / stroke,
            "max %": 100 * float(np.max(np.abs(r))) / stroke,
            "hysteresis % data": h_data, "hysteresis % model": h_model,
            "loop width data": w_data, "loop width model": w_model}


def validation_table(models, records, names=None):
    """Score fitted models on validation records (one row per model and record).

    Parameters
    ----------
    models : dict
        {name: HysteresisModel} (e.g. ``fit.model`` of a Dahl and a PI fit).
    records : sequence of (v, x) or (v, x, first)
        Validation records; each model is simulated over the whole input
        from its own start, and scored on the samples from ``first`` on.
    names : sequence, optional
        A label per record (default 0, 1, ...).

    Returns
    -------
    pandas.DataFrame
        Indexed by (model, record), columns of :func:`loop_scores` plus
        ``pooled RMS %`` (RMS over the records of the per-record RMS, the
        same in every row of a model).

    Examples
    --------
    >>> from piezolib.hysteresis import PIModel
    >>> from piezolib.signals import triangle
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)
    >>> x = pi.simulate(v)
    >>> class Line:                                  # a model without hysteresis
    ...     def simulate(self, v): return 1.5 * np.asarray(v) + 0.3
    ...     def feedforward(self, x_r): return (np.asarray(x_r) - 0.3) / 1.5
    >>> table = validation_table({"PI": pi, "line": Line()}, [(v, x)])
    >>> table["RMS %"].round(1).tolist(), table.index.names
    ([0.0, 7.8], FrozenList(['model', 'record']))
    """
    import pandas as pd
    models = _models("models", models)
    records = _triples(records, "records")
    if names is None:
        names = list(range(len(records)))
    elif isinstance(names, str) or not hasattr(names, "__iter__"):
        raise TypeError(f"names must be a sequence of labels, got {names!r}")
    names = list(names)
    if len(names) != len(records):
        raise ValueError(f"names must hold one label per record ({len(records)})")
    rows, index = [], []
    for mname, model in models.items():
        scores = [loop_scores(model.simulate(v)[k:], v[k:], x[k:]) for v, x, k in records]
        pooled = math.sqrt(float(np.mean([s["RMS %"] ** 2 for s in scores])))
        for label, s in zip(names, scores):
            rows.append({**s, "pooled RMS %": pooled})
            index.append((mname, label))
    return pd.DataFrame(rows, index=pd.MultiIndex.from_tuples(index, names=["model", "record"]))


def pooled_rms(table):
    """Pooled validation RMS [% of stroke] per model of a :func:`validation_table`.

    Returns
    -------
    pandas.Series
        Indexed by model, in the table's order; ``.idxmin()`` is the model chosen.

    Examples
    --------
    >>> from piezolib.hysteresis import PIModel
    >>> from piezolib.signals import triangle
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)
    >>> x = pi.simulate(v)
    >>> class Line:                                  # a model without hysteresis
    ...     def simulate(self, v): return 1.5 * np.asarray(v) + 0.3
    ...     def feedforward(self, x_r): return (np.asarray(x_r) - 0.3) / 1.5
    >>> table = validation_table({"PI": pi, "line": Line()}, [(v, x), (v[:41], x[:41])])
    >>> pooled = pooled_rms(table)
    >>> pooled.idxmin(), pooled.round(2).tolist()
    ('PI', [0.0, 7.98])
    """
    import pandas as pd
    if not isinstance(table, pd.DataFrame):
        raise TypeError(f"table must be a DataFrame of validation_table, got {type(table).__name__}")
    if "pooled RMS %" not in table.columns or "model" not in table.index.names:
        raise ValueError("table must be a DataFrame of validation_table (a 'pooled RMS %' "
                         "column and a 'model' index level)")
    return table["pooled RMS %"].groupby(level="model", sort=False).first()


def cross_check(compensators, plants, x_r, first=0):
    """Each model's feedforward applied to every plant: residual error and hysteresis.

    Parameters
    ----------
    compensators : dict
        {name: HysteresisModel} whose ``feedforward(x_r)`` gives the input.
    plants : dict
        {name: HysteresisModel or callable v -> x}: the plants driven by that
        input (the other models, and e.g. a measured stage).
    x_r : array_like
        Desired displacement [x-unit], 1-D.
    first : int, optional
        First sample scored (start-up left out).

    Returns
    -------
    pandas.DataFrame
        One row per (compensator, plant): ``RMS %`` and ``max %`` of x - x_r
        in % of the stroke of x_r, and ``hysteresis %`` of eq. 26 on the
        loop (x_r, x).  The diagonal of the model-on-itself pairs is the
        exactness of the feedforward (0 for an exact inverse).

    Examples
    --------
    >>> from piezolib.hysteresis import PIModel
    >>> from piezolib.signals import triangle
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)
    >>> x = pi.simulate(v)
    >>> class Line:                                  # a model without hysteresis
    ...     def simulate(self, v): return 1.5 * np.asarray(v) + 0.3
    ...     def feedforward(self, x_r): return (np.asarray(x_r) - 0.3) / 1.5
    >>> table = cross_check({"PI": pi, "line": Line()}, {"PI": pi, "line": Line()}, x_r=v)
    >>> table["RMS %"].round(1).tolist()                  # 0 on the diagonal: exact inverses
    [0.0, 10.9, 10.8, 0.0]
    """
    import pandas as pd
    compensators = _models("compensators", compensators)
    plants = _models("plants", plants, callables=True)
    x_r = check_finite_array("x_r", x_r, ndim=1, min_length=8, real=True)
    first = check_integer("first", first, minimum=0)
    if first > x_r.size - 8:
        raise ValueError(f"first = {first} leaves fewer than 8 samples of x_r")
    stroke = float(np.ptp(x_r[first:]))
    if stroke == 0:
        raise ValueError("x_r is constant: the cross-check needs a moving reference")
    rows = []
    for cname, comp in compensators.items():
        u = comp.feedforward(x_r)
        for pname, plant in plants.items():
            run = plant.simulate if isinstance(plant, HysteresisModel) else plant
            x = np.asarray(run(u), dtype=float)
            if x.shape != x_r.shape:
                raise ValueError(f"plants[{pname!r}] returned shape {x.shape}, "
                                 f"expected {x_r.shape}")
            e = x[first:] - x_r[first:]
            rows.append({"compensator": cname, "plant": pname,
                         "RMS %": 100 * math.sqrt(float(np.mean(e ** 2))) / stroke,
                         "max %": 100 * float(np.max(np.abs(e))) / stroke,
                         "hysteresis %": _width(x_r[first:], x[first:])[0]})
    return pd.DataFrame(rows).set_index(["compensator", "plant"])
