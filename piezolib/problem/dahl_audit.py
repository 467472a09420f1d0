"""The published Dahl parameters audited (Sec. III-C): units, steady state, loops, invertibility.

:func:`unit_conventions` is the static gain of the stage's chain in the natural
conventions of v and x, beside the published g_a; :func:`published_models` the
paper's model in both placements of the sign term; :func:`steady_state_table`
what H settles to after long strokes; :func:`audit_published` drives the
published model, exactly as printed, by the 40 V Table 4 stroke in each unit
of x and says whether it gives loops like Fig. 7 (:class:`DahlAudit`, with its
``checks``).  Notebook 03, sections 1-2; background in ``docs/hysteresis.md``.
"""

from dataclasses import dataclass

import numpy as np
import pandas as pd

from piezolib import signals
from piezolib._checks import check_type
from piezolib.hysteresis.dahl import (FORMS, DahlModel, NotInvertibleError, dahl_hysteresis,
                                      feedforward, simulate_dahl)
from piezolib.hysteresis.measure import hysteresis_percent
from piezolib.problem import paper
from piezolib.problem.hysteresis_fits import published_dahl

__all__ = ["AUDIT_AMPLITUDE_V", "unit_conventions", "published_models", "steady_state_table",
           "DahlAudit", "audit_published"]

#: Actuator amplitude [V] of the Table 4 stroke the audit drives (the largest loop).
AUDIT_AMPLITUDE_V = 40.0


def _period():
    """Samples per 10 Hz period of the Table 4 triangle at the DAQ rate."""
    return int(paper.SAMPLING_FREQUENCY_HZ / paper.HYSTERESIS_TEST["frequency_Hz"])


def _chain_gain():
    """DC gain of G(s) (eq. 4): amplifier input u_c [V] -> sensor output v_y [V]."""
    return paper.PLANT.b[0] / paper.PLANT.a[0]


def _stroke(periods):
    """The 40 V Table 4 reference: a 10 Hz triangle from 0 to 4 V at the DAQ rate."""
    return signals.triangle(AUDIT_AMPLITUDE_V / paper.AMPLIFIER_GAIN,
                            paper.HYSTERESIS_TEST["frequency_Hz"], periods=periods,
                            fs=paper.SAMPLING_FREQUENCY_HZ)


def unit_conventions():
    """The static gain x/v of the stage's chain in each natural unit convention.

    Eq. 13 makes g_a the static displacement per input volt; G(s) (eq. 4)
    gives the chain's, from u_c [V] to v_y [V] (0.8976), the amplifier gains
    10 and the sensor reads 3 um/V.

    Returns
    -------
    pandas.DataFrame
        Columns ``v``, ``x``, ``static gain x/v of the chain`` and
        ``published g_a / static gain``: one row per convention.

    Examples
    --------
    >>> table = unit_conventions()
    >>> row = table[table["published g_a / static gain"].between(0.9, 1.1)]
    >>> row[["v", "x"]].values.tolist()
    [['u_c (amplifier input) [V]', 'v_y (sensor) [V]']]
    """
    dc_gain, um, gain = _chain_gain(), paper.UM_PER_VOLT, paper.AMPLIFIER_GAIN
    conventions = pd.DataFrame(
        [("v_a (actuator) [V]", "x [um]", dc_gain * um / gain),
         ("u_c (amplifier input) [V]", "v_y (sensor) [V]", dc_gain),
         ("u_c (amplifier input) [V]", "x [um]", dc_gain * um),
         ("v_a (actuator) [V]", "x [nm]", dc_gain * um / gain * 1e3),
         ("v_a (actuator) [V]", "x [m]", dc_gain * um / gain * 1e-6)],
        columns=["v", "x", "static gain x/v of the chain"])
    conventions["published g_a / static gain"] = paper.DAHL.g_a / conventions.iloc[:, 2]
    return conventions


def published_models():
    """The published Dahl model in both placements of the sign term.

    Returns
    -------
    dict
        {form: DahlModel} for every form of :data:`piezolib.hysteresis.FORMS`
        (:func:`piezolib.problem.hysteresis_fits.published_dahl`).
    """
    return {form: published_dahl(form) for form in FORMS}


def _check_models(models):
    models = check_type("models", models, dict, "a dict {form: DahlModel}")
    if not models:
        raise ValueError("models must hold at least one DahlModel")
    for form, model in models.items():
        check_type(f"models[{form!r}]", model, DahlModel, "a DahlModel")
    return models


def steady_state_table(models):
    """What H settles to after long strokes, the damping and the transient length.

    Parameters
    ----------
    models : dict
        {form: DahlModel}, e.g. :func:`published_models`.

    Returns
    -------
    pandas.DataFrame
        One column per model; rows: H after a long rising and a long falling
        stroke [x-unit], the damping zeta and the transient length 2/alpha1
        [x-unit].

    Examples
    --------
    >>> table = steady_state_table(published_models())
    >>> round(float(table.loc["H after a long falling stroke", "printed"]), 2)
    26.97
    """
    return pd.DataFrame({form: {"H after a long rising stroke": m.steady_state(1),
                                "H after a long falling stroke": m.steady_state(-1),
                                "damping zeta": m.damping,
                                "transient length 2/alpha1 [x-unit]": m.transient_length}
                         for form, m in _check_models(models).items()})


def _loop_width(v, x):
    """Hysteresis % of a (v, x) record, NaN when v never sweeps through V_M both ways."""
    try:
        return hysteresis_percent(v, x)
    except ValueError:
        return np.nan


@dataclass(frozen=True)
class DahlAudit:
    """The published Dahl model driven exactly as printed (:func:`audit_published`).

    Attributes
    ----------
    models : dict
        {form: DahlModel} audited.
    table : pandas.DataFrame
        One row per unit of x and form: the 40 V stroke's range, H's range in
        the second period, the loop's hysteresis % (eq. 25-26, NaN when there
        is no loop to measure) and whether v rises along a rising stroke.
    x_ranges : dict
        {unit of x: the 40 V stroke in that unit [x-unit]}.
    steady_state : float
        beta2 gamma_a / alpha2 of the published parameters [x-unit].
    not_invertible : str
        The message of the :class:`~piezolib.hysteresis.NotInvertibleError`
        raised when the voltage-driven printed model is simulated on the 40 V
        Table 4 input ("" when it can be simulated).
    """

    models: dict
    table: pd.DataFrame
    x_ranges: dict
    steady_state: float
    not_invertible: str

    @property
    def fig7_like(self):
        """True when some form in some unit gives a Fig. 7-like loop: 1-30 % wide, with v
        rising along a rising stroke."""
        return bool((self.table["hysteresis %"].between(1, 30)
                     & self.table["v rises with x"]).any())

    @property
    def note(self):
        """One line for the claim table: what H does as printed."""
        return (f"as printed H -> {self.steady_state:.2f} x-units in both directions; "
                "no loop in um, V or nm")

    @property
    def checks(self):
        """What the audit states of H and the loops of the printed form, each with whether
        it holds."""
        printed = self.table[self.table.form == "printed"]
        natural = printed[printed["x range"] > 1e-2]        # um, sensor V, nm
        meter = printed[printed["x unit"] == "x [m]"].iloc[0]
        return {
            "as printed, H stays at beta2 gamma_a / alpha2 (um, sensor V, nm)":
                bool(np.allclose(natural[["H min", "H max"]], self.steady_state, rtol=1e-9)),
            "as printed, no loop at all (um, sensor V, nm)":
                bool((natural["hysteresis %"] < 1e-6).all()),
            "in metres H exceeds the motion a thousandfold":
                bool(meter["H max"] > 1e3 * meter["x range"]),
        }

    @property
    def simulation_checks(self):
        """That the voltage-driven printed model cannot be simulated, and whether it holds."""
        return {"the voltage-driven printed model cannot be simulated (x + H(x) not monotone)":
                bool(self.not_invertible)}


def audit_published(models=None):
    """Drive the published Dahl model by the 40 V Table 4 stroke in each unit of x.

    The displacement of the 40 V loop (two 10 Hz periods) is scaled to its
    range in um, sensor volts, nm and m; each model gives H and v = (x + H)/g_a
    (eq. 13), measured in the second period.  The voltage-driven printed model
    is also simulated on the 40 V input (three periods), which fails when x + H(x)
    is not monotone along a stroke.

    Parameters
    ----------
    models : dict, optional
        {form: DahlModel}; default :func:`published_models`.

    Returns
    -------
    DahlAudit
    """
    models = published_models() if models is None else _check_models(models)
    dc_gain, um, period = _chain_gain(), paper.UM_PER_VOLT, _period()
    span_V = AUDIT_AMPLITUDE_V / paper.AMPLIFIER_GAIN
    x_ranges = {"x [um]": span_V * dc_gain * um, "v_y (sensor) [V]": span_V * dc_gain,
                "x [nm]": span_V * dc_gain * um * 1e3, "x [m]": span_V * dc_gain * um * 1e-6}
    rows = []
    late = slice(period, None)                                 # second period
    for unit, span in x_ranges.items():
        t, x_path = _stroke(periods=2)
        x_path *= span / x_path.max()
        for form, m in models.items():
            H = dahl_hysteresis(m, x_path)
            v = feedforward(m, x_path)                         # v = (x + H)/g_a, eq. 13
            rows.append((unit, span, form, H[late].min(), H[late].max(),
                         _loop_width(v[late], x_path[late]),
                         bool(np.all(np.diff(v[period:period + period // 2]) > 0))))
    table = pd.DataFrame(rows, columns=["x unit", "x range", "form", "H min", "H max",
                                        "hysteresis %", "v rises with x"])
    message = ""
    if "printed" in models:
        try:
            simulate_dahl(models["printed"], _stroke(periods=3)[1])
        except NotInvertibleError as exc:
            message = str(exc)
    steady = paper.DAHL.beta2 * paper.DAHL.gamma_a / paper.DAHL.alpha2
    return DahlAudit(models, table, x_ranges, steady, message)
