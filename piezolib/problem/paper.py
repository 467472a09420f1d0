"""Published numbers of the reproduced paper, each stated once.

Ahmad, Ali and Ko, *Robust mu-synthesis with Dahl model based feedforward
compensator design for piezo-actuated micropositioning stage*, IEEE Access 8,
2020.  Every constant below is transcribed from the paper; notebooks and
library modules read published values from here and nowhere else.  Nothing in
this module is a reproduced or fitted value.

Units used throughout the workbook
----------------------------------

======  ==========================================  =======  ==================
symbol  signal                                      unit     range / relation
======  ==========================================  =======  ==================
u_c     control input = DAQ output = amplifier in   V        -2 ... 12
u_f     feedforward part of u_c (eq. 14)            V        u_c = u_f + u_b
u_b     feedback part of u_c (controller output)    V
v_a     actuator voltage = amplifier output         V        v_a = 10 u_c,
                                                             -20 ... 120 driven
v_y     measured sensor output                      V        0 ... 10
v_r     reference voltage                           V        x_r = 3 um/V * v_r
v_e     error voltage v_r - v_y                     V
x, x_r  stage displacement, desired displacement    um       x = 3 um/V * v_y
t       time                                        s        DAQ at 10 kHz
omega   angular frequency (all models, all grids)   rad/s
f       trajectory / excitation frequency           Hz
======  ==========================================  =======  ==================

G(s) maps u_c [V] to v_y [V] (DC gain 0.8976), so it contains the amplifier,
actuator, stage and sensor gains.  The paper gives 3 um/V for the reference
only; since the loop compares v_r with v_y directly (v_e = v_r - v_y), the same
3 um/V must hold for the sensor output, and the workbook uses it for both.
Hysteresis experiments (Table 4) quote the *actuator* voltage amplitude
(10 ... 40 V), i.e. 1 ... 4 V at the amplifier input.

Transcription notes
-------------------
* Eq. 24 prints ``d3`` three times.  Reading the coefficients in the printed
  order as d3, d4, d5 (``d3 = 7.86e14, d4 = 3.21e10, d5 = 4.69e5``) is the
  only assignment that keeps the denominator coefficients decreasing with
  power like every other polynomial in the paper, and it gives a stable
  controller and a stable closed loop with G.  :data:`CONTROLLER_NOTE` records
  this.
* The text of Sec. V-B gives the Case II improvement at 20 Hz as 52.31 %;
  Table 5 gives 53.31 %, which is what the Case I/II rows imply.  The table
  value is kept in :func:`table5`; :data:`TEXT_VARIANTS` records the other.
* The Dahl parameters (Sec. III-C) carry no units in the paper.
"""

from dataclasses import dataclass, fields
from typing import NamedTuple

import control as ct
import numpy as np
import pandas as pd

from piezolib._checks import check_positive, check_nonnegative
from piezolib.robust.performance_weights import (complementary_sensitivity_weight,
                                                 sensitivity_weight)
from piezolib.uncertainty.weight import inverse_notch_weight

__all__ = [
    "SAMPLING_FREQUENCY_HZ", "SAMPLE_TIME_S", "UM_PER_VOLT", "AMPLIFIER_GAIN",
    "AMPLIFIER_INPUT_RANGE_V", "AMPLIFIER_OUTPUT_RANGE_V",
    "ACTUATOR_DRIVE_RANGE_V", "AMPLIFIER_BANDWIDTH_HZ", "SENSOR_OUTPUT_RANGE_V",
    "SENSOR_BANDWIDTH_HZ", "SENSOR_RANGE_UM", "DAQ_BITS", "STAGE_TRAVEL_UM",
    "RESONANT_FREQUENCY_HZ",
    "PLANT", "PlantCoefficients", "plant",
    "UNCERTAINTY_SPREAD", "UNCERTAINTY_LEVELS", "UNCERTAINTY_WEIGHT",
    "UncertaintyWeightParameters", "uncertainty_weight",
    "DAHL", "DahlParameters",
    "ERROR_WEIGHT", "OUTPUT_WEIGHT", "ErrorWeightParameters",
    "OutputWeightParameters", "error_weight", "output_weight",
    "CONTROLLER", "ControllerCoefficients", "CONTROLLER_NOTE", "controller",
    "FIGURES_OF_MERIT", "DESIGN_GOALS", "HYSTERESIS_TEST", "TRACKING_TEST",
    "CONCLUSION_AVERAGES", "TEXT_VARIANTS",
    "CASE_ROWS", "case_rows_index", "table1", "table2", "table4", "table5",
    "DesignProblem", "problem",
]

# --- Sec. II and V: hardware and experimental settings ----------------------
SAMPLING_FREQUENCY_HZ = 10_000.0        #: DAQ / control rate, Sec. V
SAMPLE_TIME_S = 1.0 / SAMPLING_FREQUENCY_HZ
UM_PER_VOLT = 3.0                       #: 12 um <-> 4 V, Sec. IV-A
AMPLIFIER_GAIN = 10.0                   #: E-505, V/V
AMPLIFIER_INPUT_RANGE_V = (-2.0, 12.0)  #: E-505 input range
AMPLIFIER_OUTPUT_RANGE_V = (-30.0, 130.0)  #: E-505 output range
ACTUATOR_DRIVE_RANGE_V = (-20.0, 120.0)    #: Table 1, driven voltage
AMPLIFIER_BANDWIDTH_HZ = 3_000.0        #: E-505 bandwidth, Sec. II
SENSOR_OUTPUT_RANGE_V = (0.0, 10.0)     #: D-015 analog output range
SENSOR_BANDWIDTH_HZ = 10_000.0          #: D-015 bandwidth
SENSOR_RANGE_UM = 45.0                  #: D-015 extended measuring range
DAQ_BITS = 16                           #: PXIe-6361 resolution
STAGE_TRAVEL_UM = 35.0                  #: P-752.21 travel range, Sec. II
RESONANT_FREQUENCY_HZ = 2_100.0         #: P-752.21 resonance, Table 1


# --- Sec. III-A, eq. 4: identified plant -------------------------------------
@dataclass(frozen=True)
class PlantCoefficients:
    """Coefficients of G(s) = b(s)/a(s), eq. 4, lowest power first.

    ``a`` holds a0 ... a5 (the leading s^6 coefficient is 1) and ``b`` holds
    b0 ... b3.  Time unit: seconds; G maps u_c [V] to v_y [V].

    Examples
    --------
    >>> PLANT.den[:2]              # monic, highest power first
    array([1.00e+00, 1.08e+04])
    >>> len(PLANT.num), len(PLANT.den)
    (4, 7)
    """

    a: tuple = (2.05e23, 5.79e19, 1.65e16, 1.98e12, 2.95e8, 1.08e4)
    b: tuple = (1.84e23, 2.76e19, 4.74e15, 2.01e11)

    @property
    def den(self):
        """Denominator coefficients, highest power first (monic)."""
        return np.r_[1.0, self.a[::-1]]

    @property
    def num(self):
        """Numerator coefficients, highest power first."""
        return np.asarray(self.b[::-1], dtype=float)


PLANT = PlantCoefficients()


def plant(coefficients=PLANT):
    """Return the published plant G(s) of eq. 4.

    Parameters
    ----------
    coefficients : PlantCoefficients, optional
        Defaults to the published values :data:`PLANT`.

    Returns
    -------
    control.TransferFunction
        SISO model from ``u_c`` [V] to ``v_y`` [V], named ``G``.

    Examples
    --------
    >>> G = plant()
    >>> round(float(G.dcgain()), 4), G.input_labels, G.output_labels
    (0.8976, ['u_c'], ['v_y'])
    """
    if not isinstance(coefficients, PlantCoefficients):
        raise TypeError("coefficients must be a PlantCoefficients instance, "
                        f"got {type(coefficients).__name__}")
    for name, values in (("a", coefficients.a), ("b", coefficients.b)):
        if not np.all(np.isfinite(values)):
            raise ValueError(f"coefficients.{name} must be finite, got {values}")
    if len(coefficients.a) != 6 or len(coefficients.b) != 4:
        raise ValueError("coefficients must hold 6 denominator (a0..a5) and "
                         "4 numerator (b0..b3) values")
    return ct.tf(coefficients.num, coefficients.den,
                 inputs="u_c", outputs="v_y", name="G")


# --- Sec. III-B, eq. 8, Table 2: multiplicative uncertainty -----------------
UNCERTAINTY_SPREAD = 0.05   #: +-5 % on each of a0 ... a5
UNCERTAINTY_LEVELS = 3      #: nominal and the two extremes -> 3**6 = 729 models


@dataclass(frozen=True)
class UncertaintyWeightParameters:
    """Table 2: parameters of H_m(s), eq. 8 (frequencies in rad/s).

    Examples
    --------
    >>> UNCERTAINTY_WEIGHT.g, UNCERTAINTY_WEIGHT.omega1
    (0.02, 6300.0)
    >>> UncertaintyWeightParameters(g=0.05).g
    0.05
    """

    g: float = 0.02
    zeta1: float = 3.5
    zeta2: float = 0.05
    zeta3: float = 0.7
    zeta4: float = 0.08
    omega1: float = 6.3e3
    omega2: float = 1.4e4
    omega3: float = 1.0e4
    M: float = 1.0
    epsilon: float = 1e-8


UNCERTAINTY_WEIGHT = UncertaintyWeightParameters()


def uncertainty_weight(params=UNCERTAINTY_WEIGHT, **overrides):
    """Return the multiplicative uncertainty weight H_m(s) of eq. 8.

    Two inverse notch filters at omega1 and omega2 in series with a first-order
    low-pass (eps*s + omega3)/(s + omega3/M), scaled by g: the toolkit's
    :func:`~piezolib.uncertainty.weight.inverse_notch_weight` with Table 2's
    parameters.

    Parameters
    ----------
    params : UncertaintyWeightParameters, optional
        Defaults to Table 2.
    **overrides
        Any field of :class:`UncertaintyWeightParameters` (e.g. ``g=0.05``).

    Returns
    -------
    control.TransferFunction
        Fifth-order weight from ``u_c`` to ``y_Delta``, named ``H_m``.

    Examples
    --------
    >>> H_m = uncertainty_weight()
    >>> H_m.name, len(H_m.den[0][0]) - 1        # name, order
    ('H_m', 5)
    >>> float(abs(H_m(0))), float(abs(uncertainty_weight(g=0.05)(0)))
    (0.02, 0.05)
    """
    p = _with_overrides(params, UncertaintyWeightParameters, overrides)
    # checked under Table 2's names first: those are the names the caller passed
    for name in ("g", "omega1", "omega2", "omega3", "M", "zeta2", "zeta4"):
        check_positive(name, getattr(p, name))
    for name in ("zeta1", "zeta3", "epsilon"):
        check_nonnegative(name, getattr(p, name))
    return inverse_notch_weight(p.g, [(p.omega1, p.zeta1, p.zeta2), (p.omega2, p.zeta3, p.zeta4)],
                                p.omega3, p.M, p.epsilon,
                                inputs="u_c", outputs="y_Delta", name="H_m")


# --- Sec. III-C: Dahl hysteresis model --------------------------------------
@dataclass(frozen=True)
class DahlParameters:
    """Published Dahl model parameters (eq. 10-13), units not stated.

    With the equations as printed, ``g_a`` multiplies the actuator input
    voltage in x_a = g_a v_a - H (eq. 13).

    Examples
    --------
    >>> DAHL.g_a, DAHL.gamma_a
    (0.925, 30.0)
    """

    alpha1: float = 1.76e3
    alpha2: float = 3.46e7
    beta1: float = 0.0
    beta2: float = 3.11e7
    gamma_a: float = 30.0
    g_a: float = 0.925


DAHL = DahlParameters()


# --- Sec. IV-B, eq. 15: performance weights ----------------------------------
@dataclass(frozen=True)
class ErrorWeightParameters:
    """Eq. 15: H_e(s) = (s/M_e + omega_e) / (s + omega_e*eps_e), omega in rad/s.

    Examples
    --------
    >>> ERROR_WEIGHT
    ErrorWeightParameters(M_e=2.0, eps_e=0.003, omega_e=1260.0)
    """

    M_e: float = 2.0
    eps_e: float = 0.003
    omega_e: float = 1.26e3


@dataclass(frozen=True)
class OutputWeightParameters:
    """Eq. 15: H_y(s) = ((s + omega_y/M_y) / (eps_y*s + omega_y))^2, rad/s.

    Examples
    --------
    >>> OUTPUT_WEIGHT.M_y, OUTPUT_WEIGHT.omega_y
    (1.5, 7500.0)
    """

    M_y: float = 1.5
    eps_y: float = 1e-4
    omega_y: float = 7.5e3


ERROR_WEIGHT = ErrorWeightParameters()
OUTPUT_WEIGHT = OutputWeightParameters()


def error_weight(params=ERROR_WEIGHT, **overrides):
    """Return the error weight H_e(s) of eq. 15.

    1/|H_e| is the template on S: it tends to eps_e at low frequency and to
    M_e at high frequency, crossing 1 near omega_e (the toolkit's
    :func:`~piezolib.robust.performance_weights.sensitivity_weight`).

    Parameters
    ----------
    params : ErrorWeightParameters, optional
        Defaults to the published values.
    **overrides
        ``M_e``, ``eps_e`` or ``omega_e`` [rad/s].

    Returns
    -------
    control.TransferFunction
        First-order weight from ``v_e`` to ``y1``, named ``H_e``.

    Examples
    --------
    >>> H_e = error_weight()
    >>> print(f"{1 / abs(H_e(0)):.4f}")      # template on S at DC: eps_e
    0.0030
    >>> print(f"{1 / abs(error_weight(M_e=3.0)(1e9j)):.2f}")   # ... M_e far above omega_e
    3.00
    """
    p = _with_overrides(params, ErrorWeightParameters, overrides)
    for name in ("M_e", "eps_e", "omega_e"):     # the names the caller passed
        check_positive(name, getattr(p, name))
    return sensitivity_weight(p.eps_e, p.M_e, p.omega_e, inputs="v_e", outputs="y1", name="H_e")


def output_weight(params=OUTPUT_WEIGHT, **overrides):
    """Return the output weight H_y(s) of eq. 15.

    1/|H_y| is the template on T: M_y^2 at low frequency, eps_y^2 at high
    frequency (the toolkit's
    :func:`~piezolib.robust.performance_weights.complementary_sensitivity_weight`
    of order 2).

    Parameters
    ----------
    params : OutputWeightParameters, optional
        Defaults to the published values.
    **overrides
        ``M_y``, ``eps_y`` or ``omega_y`` [rad/s].

    Returns
    -------
    control.TransferFunction
        Second-order weight from ``v_y`` to ``y2``, named ``H_y``.

    Examples
    --------
    >>> H_y = output_weight()
    >>> H_y.name, len(H_y.den[0][0]) - 1
    ('H_y', 2)
    >>> print(f"{1 / abs(H_y(0)):.4f}")      # template on T at DC: M_y**2
    2.2500
    """
    p = _with_overrides(params, OutputWeightParameters, overrides)
    for name in ("M_y", "eps_y", "omega_y"):     # the names the caller passed
        check_positive(name, getattr(p, name))
    return complementary_sensitivity_weight(p.M_y, p.eps_y, p.omega_y, order=2,
                                            inputs="v_y", outputs="y2", name="H_y")


# --- Sec. IV-B, eq. 24: reduced 6th-order controller -------------------------
@dataclass(frozen=True)
class ControllerCoefficients:
    """Coefficients of K(s) = n(s)/d(s), eq. 24, lowest power first.

    ``n`` holds n0 ... n5, ``d`` holds d0 ... d5 (leading s^6 coefficient 1).
    See :data:`CONTROLLER_NOTE` for d3, d4, d5.

    Examples
    --------
    >>> CONTROLLER.d[3:]                     # the three printed as 'd3', see CONTROLLER_NOTE
    (786000000000000.0, 32100000000.0, 469000.0)
    """

    n: tuple = (4.73e22, 1.51e22, 7.66e17, 1.04e15, 1.78e10, 5.29e6)
    d: tuple = (7.79e19, 4.71e19, 7.38e18, 7.86e14, 3.21e10, 4.69e5)

    @property
    def num(self):
        """Numerator coefficients, highest power first."""
        return np.asarray(self.n[::-1], dtype=float)

    @property
    def den(self):
        """Denominator coefficients, highest power first (monic)."""
        return np.r_[1.0, self.d[::-1]]


CONTROLLER = ControllerCoefficients()

CONTROLLER_NOTE = (
    "Eq. 24 prints 'd3' for the last three denominator coefficients "
    "(7.86e14, 3.21e10, 4.69e5). They are read in printed order as d3, d4, d5: "
    "the only reading in which the coefficients decrease with the power of s "
    "as in every other polynomial of the paper; it yields a stable K and a "
    "stable closed loop with G.")


def controller(coefficients=CONTROLLER):
    """Return the published reduced controller K(s) of eq. 24.

    Returns
    -------
    control.TransferFunction
        Sixth-order controller from ``v_e`` [V] to ``u_b`` [V], named ``K``.

    Examples
    --------
    >>> import control as ct
    >>> K = controller()
    >>> K.input_labels, K.output_labels, len(K.den[0][0]) - 1
    (['v_e'], ['u_b'], 6)
    >>> bool((ct.poles(ct.feedback(plant() * K)).real < 0).all())   # stable loop
    True
    """
    if not isinstance(coefficients, ControllerCoefficients):
        raise TypeError("coefficients must be a ControllerCoefficients instance, "
                        f"got {type(coefficients).__name__}")
    if len(coefficients.n) != 6 or len(coefficients.d) != 6:
        raise ValueError("coefficients must hold 6 numerator (n0..n5) and "
                         "6 denominator (d0..d5) values")
    return ct.tf(coefficients.num, coefficients.den,
                 inputs="v_e", outputs="u_b", name="K")


# --- Sec. IV-B/C: reported figures of merit ----------------------------------
FIGURES_OF_MERIT = {
    "norm_He_S": 0.81,         #: ||H_e S||_inf, nominal performance
    "norm_Hy_T": 0.92,         #: ||H_y T||_inf, nominal performance
    "mu_RS": 0.48,             #: peak mu of M11 = -H_m T, robust stability
    "mu_RP": 0.71,             #: peak mu of M, robust performance
    "mu_full_order": 0.71,     #: mu upper bound of the full-order controller
    "full_controller_order": 36,
    "reduced_controller_order": 6,
}

DESIGN_GOALS = {
    "peak_to_peak_error_pct_up_to_10Hz": 1.0,  #: Sec. IV-B, desired tracking
    "peak_to_peak_error_pct_at_50Hz": 5.0,
    "S_peak_dB_max": 6.0,                       #: ||S||_inf < 6 dB
    "T_peak_dB_max": 3.5,                       #: ||T||_inf < 3.5 dB
    "tracking_range_um": 12.0,
}

#: Table 4 experiment: triangles of these actuator voltage amplitudes at 10 Hz.
HYSTERESIS_TEST = {"actuator_amplitudes_V": (10.0, 20.0, 30.0, 40.0),
                   "frequency_Hz": 10.0}

#: Table 5 experiment: 12 um triangles at these frequencies.
TRACKING_TEST = {"amplitude_um": 12.0,
                 "frequencies_Hz": (1.0, 10.0, 20.0, 30.0, 40.0, 50.0)}

#: Sec. VI averages of the improvement rows, in %.
CONCLUSION_AVERAGES = {
    "hysteresis_III_vs_I": 95.93,
    "hysteresis_III_vs_II": 57.84,
    "tracking_III_vs_I": 80.5,
    "tracking_III_vs_II": 58.33,
}

#: Numbers printed differently in the text and in the tables.
TEXT_VARIANTS = {
    ("table5", "improvement_II_vs_I", 20.0): 52.31,
}

#: Row labels of Tables 4 and 5: the three cases, then the three improvement rows.
CASE_ROWS = ["case_I", "case_II", "case_III",
              "improvement_II_vs_I", "improvement_III_vs_I", "improvement_III_vs_II"]


def table1():
    """Table 1: properties of the P-752.21 stage, as a DataFrame.

    The table's text layer merges two rows ("30 20 N/um"); the load capacity
    of 30 N is confirmed by Sec. II, which leaves 20 N/um for the stiffness.

    Examples
    --------
    >>> table1().set_index("item").loc["resonant frequency", "quantity"]
    '2100'
    """
    return pd.DataFrame(
        [("driven voltage", "-20 to 120", "V"),
         ("resolution", "0.2", "nm"),
         ("resonant frequency", "2100", "Hz"),
         ("load capacity", "30", "N"),
         ("stiffness in motion direction", "20", "N/um"),
         ("electrical capacitance", "3.7", "uF"),
         ("stage mass", "0.55", "kg")],
        columns=["item", "quantity", "unit"])


def table2():
    """Table 2: parameters of H_m, as a one-row-per-parameter DataFrame.

    Examples
    --------
    >>> table2().set_index("parameter").loc[["g", "omega1"], "value"].tolist()
    [0.02, 6300.0]
    """
    return pd.DataFrame({"parameter": [f.name for f in fields(UNCERTAINTY_WEIGHT)],
                         "value": [getattr(UNCERTAINTY_WEIGHT, f.name)
                                   for f in fields(UNCERTAINTY_WEIGHT)]})


def case_rows_index():
    """The row index shared by Tables 4 and 5 (and the workbook's reproductions).

    Examples
    --------
    >>> list(case_rows_index())[:3]
    ['case_I', 'case_II', 'case_III']
    """
    return pd.Index(CASE_ROWS, name="row")


def table4():
    """Table 4: hysteresis % at 10 Hz versus actuator amplitude [V].

    Rows: ``case_I`` (open loop), ``case_II`` (Dahl feedforward),
    ``case_III`` (feedforward + mu controller) and the three improvement rows
    in %.  Columns: actuator voltage amplitude in V.

    Examples
    --------
    >>> t4 = table4()
    >>> t4.shape, list(t4.columns)
    ((6, 4), [10.0, 20.0, 30.0, 40.0])
    >>> t4.loc["case_III"].tolist()
    [0.31, 0.37, 0.41, 0.44]
    """
    data = [[6.19, 9.08, 11.16, 12.44],
            [0.45, 0.81, 1.23, 2.12],
            [0.31, 0.37, 0.41, 0.44],
            [92.73, 91.07, 88.98, 82.96],
            [94.99, 95.93, 96.33, 96.46],
            [31.11, 54.32, 66.67, 79.25]]
    columns = pd.Index(HYSTERESIS_TEST["actuator_amplitudes_V"], name="amplitude_V")
    return pd.DataFrame(data, index=case_rows_index(), columns=columns)


def table5():
    """Table 5: tracking error % of 12 um triangles versus frequency [Hz].

    Same rows as :func:`table4`; columns: triangle frequency in Hz.

    Examples
    --------
    >>> t5 = table5()
    >>> list(t5.columns)
    [1.0, 10.0, 20.0, 30.0, 40.0, 50.0]
    >>> t5.loc[["case_I", "case_III"], 50.0].tolist()
    [12.98, 4.58]
    """
    data = [[7.33, 9.47, 10.56, 11.72, 12.13, 12.98],
            [3.54, 4.29, 4.93, 5.28, 5.72, 6.19],
            [0.51, 0.94, 1.46, 2.39, 3.71, 4.58],
            [51.71, 54.69, 53.31, 54.95, 52.84, 52.31],
            [93.04, 90.07, 86.17, 79.61, 69.41, 64.71],
            [85.59, 78.09, 70.39, 54.73, 35.14, 26.01]]
    columns = pd.Index(TRACKING_TEST["frequencies_Hz"], name="frequency_Hz")
    return pd.DataFrame(data, index=case_rows_index(), columns=columns)


class DesignProblem(NamedTuple):
    """The paper's design problem: plant, weights and published controller.

    All five are SISO python-control models in ordinary time (seconds), with
    named signals; frequencies in rad/s.

    Attributes
    ----------
    G : control.TransferFunction
        Plant of eq. 4, ``u_c`` [V] -> ``v_y`` [V].
    H_m : control.TransferFunction
        Multiplicative uncertainty weight of eq. 8, ``u_c`` [V] -> ``y_Delta`` [V].
    H_e : control.TransferFunction
        Error weight of eq. 15, ``v_e`` [V] -> ``y1`` (dimensionless).
    H_y : control.TransferFunction
        Output weight of eq. 15, ``v_y`` [V] -> ``y2`` (dimensionless).
    K : control.TransferFunction
        Reduced controller of eq. 24, ``v_e`` [V] -> ``u_b`` [V].

    Examples
    --------
    >>> p = problem()
    >>> p._fields
    ('G', 'H_m', 'H_e', 'H_y', 'K')
    >>> p.H_e.name
    'H_e'
    """

    G: ct.TransferFunction
    H_m: ct.TransferFunction
    H_e: ct.TransferFunction
    H_y: ct.TransferFunction
    K: ct.TransferFunction


def problem():
    """Return the published design problem in one call.

    Returns
    -------
    DesignProblem
        ``(G, H_m, H_e, H_y, K)`` built from the published values
        (:func:`plant`, :func:`uncertainty_weight`, :func:`error_weight`,
        :func:`output_weight`, :func:`controller`); it unpacks as
        ``G, H_m, H_e, H_y, K = problem()``.

    Examples
    --------
    >>> G, H_m, H_e, H_y, K = problem()
    >>> G.input_labels, K.output_labels
    (['u_c'], ['u_b'])
    """
    return DesignProblem(G=plant(), H_m=uncertainty_weight(), H_e=error_weight(),
                         H_y=output_weight(), K=controller())


def _with_overrides(params, cls, overrides):
    if not isinstance(params, cls):
        raise TypeError(f"params must be a {cls.__name__}, got {type(params).__name__}")
    names = {f.name for f in fields(cls)}
    unknown = set(overrides) - names
    if unknown:
        raise TypeError(f"unknown parameter(s) {sorted(unknown)}; "
                        f"expected some of {sorted(names)}")
    return cls(**{**{n: getattr(params, n) for n in names}, **overrides})
