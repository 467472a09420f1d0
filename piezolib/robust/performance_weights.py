"""Performance weights: templates on the sensitivity S and the complementary sensitivity T.

``sensitivity_weight`` is W_S(s) = ((s/M + omega_b) / (s + omega_b A))^n, so
that ||W_S S||_inf < 1 holds |S| below 1/|W_S|: A^n at low frequency, M^n at
high frequency, crossing 1 near omega_b (for n = 1 the textbook performance
weight w_P of Skogestad and Postlethwaite).  ``complementary_sensitivity_weight``
is W_T(s) = ((s + omega_b/M) / (eps s + omega_b))^n, holding |T| below M^n at
low and eps^n at high frequency.  Frequencies in rad/s; the weights are
dimensionless ratios of the signals they weight.

They sit in :mod:`piezolib.robust` because they weight loop functions of any
H-infinity or mu design; :mod:`piezolib.uncertainty` describes how a model
set departs from its nominal model, and its weight shapes (the inverse-notch
form, the covering fit) are in :mod:`piezolib.uncertainty.weight`.
"""

import control as ct
import numpy as np

from piezolib._checks import check_integer, check_positive

__all__ = ["sensitivity_weight", "complementary_sensitivity_weight"]


def sensitivity_weight(low_frequency_bound, high_frequency_bound, bandwidth_rad_s, order=1, *,
                       inputs="e", outputs="z_e", name="W_S"):
    """Weight W_S(s) = ((s/M + omega_b) / (s + omega_b A))^n on the sensitivity S.

    1/|W_S| is the template on |S|: A^n at low frequency, M^n at high
    frequency, about 1 near omega_b.

    Parameters
    ----------
    low_frequency_bound : float
        A > 0: the template's low-frequency level per section (the
        steady-state error allowed, e.g. 0.003).
    high_frequency_bound : float
        M > 0: the template's high-frequency level per section (the peak of
        |S| allowed, e.g. 2).
    bandwidth_rad_s : float
        omega_b > 0 [rad/s]: where the template crosses about 1.
    order : int, optional
        n >= 1, the number of identical first-order sections (slope of the
        template 20 n dB/decade).
    inputs, outputs, name : str, optional
        Signal and system names (default ``e -> z_e``, ``W_S``).

    Returns
    -------
    control.TransferFunction
        Stable, minimum-phase, biproper weight of order n.

    Raises
    ------
    ValueError, TypeError
        When a bound or the bandwidth is not a positive finite number, or
        ``order`` is not an integer >= 1 (the message names the argument).

    Examples
    --------
    >>> W = sensitivity_weight(0.01, 2.0, 10.0)          # |S| <= 1 % at DC, <= 2 at HF
    >>> W.num[0][0], W.den[0][0], W.input_labels
    (array([ 0.5, 10. ]), array([1. , 0.1]), ['e'])
    >>> round(float(abs(W(0))), 3), round(float(abs(W(1e6j))), 3)      # 1/A and 1/M
    (100.0, 0.5)
    """
    A, M, omega_b, order = _checked(low_frequency_bound, high_frequency_bound, bandwidth_rad_s,
                                    order)
    return _power([1 / M, omega_b], [1, omega_b * A], order, inputs, outputs, name)


def complementary_sensitivity_weight(low_frequency_bound, high_frequency_bound, bandwidth_rad_s,
                                     order=1, *, inputs="y", outputs="z_y", name="W_T"):
    """Weight W_T(s) = ((s + omega_b/M) / (eps s + omega_b))^n on the complementary sensitivity T.

    1/|W_T| is the template on |T|: M^n at low frequency, eps^n at high
    frequency, about 1 near omega_b.

    Parameters
    ----------
    low_frequency_bound : float
        M > 0: the template's low-frequency level per section (|T| is about
        1 there, so M > 1 leaves it free, e.g. 1.5).
    high_frequency_bound : float
        eps > 0: the template's high-frequency level per section (the
        roll-off demanded, e.g. 1e-4).
    bandwidth_rad_s : float
        omega_b > 0 [rad/s]: where the template crosses about 1.
    order : int, optional
        n >= 1, the number of identical first-order sections.
    inputs, outputs, name : str, optional
        Signal and system names (default ``y -> z_y``, ``W_T``).

    Returns
    -------
    control.TransferFunction
        Stable, minimum-phase, biproper weight of order n (its poles at
        -omega_b / eps).

    Raises
    ------
    ValueError, TypeError
        As :func:`sensitivity_weight`.

    Examples
    --------
    >>> W = complementary_sensitivity_weight(1.5, 1e-3, 100.0, order=2)
    >>> round(float(abs(W(0))), 4), np.sort(np.abs(W.poles())).round(-3)   # 1/M^2; poles at omega_b/eps
    (0.4444, array([100000., 100000.]))
    """
    M, eps, omega_b, order = _checked(low_frequency_bound, high_frequency_bound, bandwidth_rad_s,
                                      order)
    return _power([1, omega_b / M], [eps, omega_b], order, inputs, outputs, name)


def _checked(low_frequency_bound, high_frequency_bound, bandwidth_rad_s, order):
    """The arguments both weights share, checked under their public names."""
    return (check_positive("low_frequency_bound", low_frequency_bound),
            check_positive("high_frequency_bound", high_frequency_bound),
            check_positive("bandwidth_rad_s", bandwidth_rad_s),
            check_integer("order", order, minimum=1))


def _power(num, den, order, inputs, outputs, name):
    """(num/den)^order as a named transfer function."""
    num_n, den_n = np.ones(1), np.ones(1)
    for _ in range(order):
        num_n, den_n = np.polymul(num_n, num), np.polymul(den_n, den)
    return ct.tf(num_n, den_n, inputs=inputs, outputs=outputs, name=name)
