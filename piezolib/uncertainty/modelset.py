"""The parametric model set: models of G with perturbed denominator coefficients.

A member has denominator a_i (1 + spread q_i), i < n, with normalised offsets
q_i in [-1, 1]; the leading coefficient and the numerator are those of G.
Responses and poles of all members are computed at once (see ``docs/uncertainty.md``).
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import numpy.polynomial.polynomial as npoly

from piezolib._checks import check_finite_array, check_integer
from piezolib.uncertainty.polynomials import (
    batched_roots, check_frequencies, check_plant, check_spread, coefficient_scale, jw_powers,
    loop_polynomials, plant_polynomials, scale_coefficients)

__all__ = [
    "MAX_MEMBERS", "ModelSet", "model_set", "level_offsets", "perturbed_plant", "set_response",
    "member_poles", "member_closed_loop_poles", "unstable_members", "check_model_set",
    "frequency_basis",
]

#: Largest number of models :func:`model_set` and :func:`level_offsets` build.
MAX_MEMBERS = 1_000_000


@dataclass(frozen=True, eq=False)
class ModelSet:
    """Models of G with perturbed denominator coefficients.

    Attributes
    ----------
    plant : control.TransferFunction
        The nominal model G (SISO, proper).
    spread : float
        Relative perturbation of each a_i (0.05 for +-5 %).
    levels : int
        Values per coefficient, equally spaced in [-spread, +spread].
    offsets : ndarray, shape (M, n)
        Normalised offsets q in [-1, 1]; column i perturbs a_i (s^i).

    Examples
    --------
    >>> G = ct.tf([1], [1, 0.2, 1])
    >>> mset = model_set(G, 0.05, levels=2)
    >>> mset.size, mset.order, mset.offsets.shape        # 2 levels ** 2 coefficients
    (4, 2, (4, 2))
    """

    plant: ct.TransferFunction
    spread: float
    levels: int
    offsets: np.ndarray

    @property
    def size(self):
        """Number of models M (``levels ** n`` for :func:`model_set`)."""
        return self.offsets.shape[0]

    @property
    def order(self):
        """Denominator degree n of the plant."""
        return self.offsets.shape[1]

    @property
    def coefficients(self):
        """(M, n+1) member denominators, lowest power first, monic."""
        a, _ = plant_polynomials(self.plant)
        return np.c_[a[:-1] * (1 + self.spread * self.offsets), np.ones(self.size)]

    @property
    def denominators(self):
        """(M, n+1) denominator coefficients, highest power first, seconds."""
        return self.coefficients[:, ::-1]

    @property
    def time_scale(self):
        """Frequency scale [rad/s] of the scaled evaluations (of the nominal denominator)."""
        a, _ = plant_polynomials(self.plant)
        return coefficient_scale(a)

    def scaled_coefficients(self, omega_s):
        """(M, n+1) member denominators in scaled frequency p = s/omega_s, lowest first."""
        return scale_coefficients(self.coefficients, omega_s, self.order)

    def member(self, k):
        """Member ``k`` as a transfer function named ``G_k`` (same signals as G)."""
        k = check_integer("k", k, minimum=0)
        if k >= self.size:
            raise ValueError(f"k must be < {self.size}, got {k}")
        return perturbed_plant(self.plant, self.spread, self.offsets[k], name=f"G_{k}")


def check_model_set(mset):
    """Raise TypeError unless ``mset`` is a :class:`ModelSet`."""
    if not isinstance(mset, ModelSet):
        raise TypeError(f"mset must be a ModelSet (see model_set()), got {type(mset).__name__}")
    return mset


def level_offsets(levels, n):
    """All ``levels**n`` combinations of ``levels`` values in [-1, 1].

    Parameters
    ----------
    levels : int
        Values per coefficient, >= 2.
    n : int
        Number of coefficients, >= 1.

    Returns
    -------
    ndarray, shape (levels**n, n)
        Row 0 is all -1; the rows run through the combinations in
        lexicographic order (the last column varies fastest).

    Raises
    ------
    ValueError
        When ``levels**n`` exceeds :data:`MAX_MEMBERS`.

    Examples
    --------
    >>> level_offsets(3, 2)[:4]                 # every combination of -1, 0, 1 for 2 coefficients
    array([[-1., -1.],
           [-1.,  0.],
           [-1.,  1.],
           [ 0., -1.]])
    """
    levels = check_integer("levels", levels, minimum=2)
    n = check_integer("n", n, minimum=1)
    size = levels ** n
    if size > MAX_MEMBERS:
        raise ValueError(f"levels = {levels} gives {levels}**{n} = {size:.3g} models, more than "
                         f"MAX_MEMBERS = {MAX_MEMBERS:,}; use fewer levels")
    values = np.linspace(-1.0, 1.0, levels)
    grids = np.meshgrid(*[values] * n, indexing="ij")
    return np.stack(grids, axis=-1).reshape(size, n)


def perturbed_plant(G, spread, offsets, name=None):
    """The member of G's box with normalised offsets q.

    Denominator a_i (1 + spread q_i), i < n, same numerator and signals as G
    (e.g. the critical member of
    :func:`~piezolib.uncertainty.margin.parametric_stability_margin`).

    Parameters
    ----------
    G : control.LTI
        Nominal SISO proper plant.
    spread : float
        Relative spread, 0 < spread < 1.
    offsets : array_like, shape (n,)
        q_i in [-1, 1], lowest power first.
    name : str, optional
        Name of the returned model.

    Returns
    -------
    control.TransferFunction

    Examples
    --------
    >>> G = ct.tf([1], [1, 0.2, 1])
    >>> Gp = perturbed_plant(G, 0.1, [1, -1])          # a0 up 10 %, a1 down 10 %
    >>> Gp.den[0][0]
    array([1.  , 0.18, 1.1 ])
    """
    G = check_plant(G)
    spread = check_spread(spread)
    a, b = plant_polynomials(G)
    q = check_finite_array("offsets", offsets, shape=(len(a) - 1,))
    if np.any(np.abs(q) > 1):
        raise ValueError("offsets must lie in [-1, 1]")
    den = np.r_[a[:-1] * (1 + spread * q), 1.0]
    return ct.tf(b[::-1], den[::-1], inputs=G.input_labels, outputs=G.output_labels,
                 name=name)


def model_set(G, spread, levels=3):
    """The parametric model set: every combination of ``levels`` values per coefficient.

    Parameters
    ----------
    G : control.LTI
        Nominal SISO proper model with at least one pole.
    spread : float
        Relative spread of every denominator coefficient, 0 < spread < 1
        (0.05 for +-5 %).
    levels : int, optional
        Values per coefficient, >= 2, equally spaced in [-spread, spread]
        (default 3: the nominal value and both extremes).

    Returns
    -------
    ModelSet
        ``levels ** n`` models, n = degree of G's denominator.

    Raises
    ------
    ValueError
        When ``levels ** n`` exceeds :data:`MAX_MEMBERS` (1e6 models).

    Examples
    --------
    >>> mset = model_set(ct.tf([1], [1, 2, 1]), 0.1)
    >>> mset.size, mset.order
    (9, 2)
    """
    G = check_plant(G)
    spread = check_spread(spread)
    a, _ = plant_polynomials(G)
    levels = check_integer("levels", levels, minimum=2)
    return ModelSet(plant=G, spread=spread, levels=levels,
                    offsets=level_offsets(levels, len(a) - 1))


def frequency_basis(mset, omega):
    """Check a model set and a frequency grid; the scaled basis of its frequency responses.

    Parameters
    ----------
    mset : ModelSet
    omega : array_like
        Frequencies [rad/s], positive.

    Returns
    -------
    a, b : ndarray
        Denominator and numerator of the nominal plant, lowest power first.
    ws : float
        Coefficient scale omega_s [rad/s].
    V : ndarray, shape (len(omega), max(len(a), len(b)))
        Powers (j omega / omega_s)^k.
    """
    check_model_set(mset)
    omega = check_frequencies(omega)
    a, b = plant_polynomials(mset.plant)
    ws = coefficient_scale(a)
    return a, b, ws, jw_powers(omega / ws, max(len(a), len(b)))


def set_response(mset, omega):
    """Frequency responses of every member, shape (M, len(omega)), complex.

    Evaluated as one matrix product of the (M, n+1) scaled coefficient array
    with the matrix of powers of j omega / omega_s (no loop over models).

    Parameters
    ----------
    mset : ModelSet
    omega : array_like
        Frequencies [rad/s], positive.

    Examples
    --------
    >>> G = ct.tf([1], [1, 0.2, 1])
    >>> mset = model_set(G, 0.1)
    >>> R = set_response(mset, [1e-4, 1.0])             # one row per member; 1 / a0 near DC
    >>> R.shape, round(float(np.abs(R[:, 0]).min()), 4), round(float(np.abs(R[:, 0]).max()), 4)
    ((9, 2), 0.9091, 1.1111)
    """
    a, b, ws, V = frequency_basis(mset, omega)
    num = scale_coefficients(b, ws, len(a) - 1) @ V[:, :len(b)].T
    return num[None, :] / (mset.scaled_coefficients(ws) @ V[:, :len(a)].T)


def member_poles(mset):
    """Poles [rad/s] of every member, shape (M, n).

    From stacked companion matrices in scaled time (one batched eigenvalue call).

    Examples
    --------
    >>> G = ct.tf([1], [1, 0.2, 1])
    >>> poles = member_poles(model_set(G, 0.1))
    >>> poles.shape, bool(np.all(poles.real < 0))
    ((9, 2), True)
    """
    check_model_set(mset)
    ws = mset.time_scale
    return batched_roots(mset.scaled_coefficients(ws)) * ws


def member_closed_loop_poles(mset, K):
    """Closed-loop poles [rad/s] of every member with controller K.

    The characteristic polynomials a_k d + b n of all members are formed as
    one (M, n + deg d + 1) array in scaled time and their roots found from
    stacked companion matrices.

    Parameters
    ----------
    mset : ModelSet
    K : control.LTI
        SISO proper controller (K = n/d).

    Returns
    -------
    ndarray, shape (M, n + deg d)
    """
    check_model_set(mset)
    polys = loop_polynomials(mset.plant, K)
    members = mset.scaled_coefficients(polys.ws)             # (M, n+1) low first
    c = np.zeros((mset.size, members.shape[1] + len(polys.d) - 1))
    for j, dj in enumerate(polys.d):
        c[:, j:j + members.shape[1]] += dj * members
    bn = npoly.polymul(polys.b, polys.n)
    c[:, :len(bn)] += bn
    return batched_roots(c) * polys.ws


def unstable_members(mset, K=None):
    """Indices of the members with a pole in Re s >= 0.

    Parameters
    ----------
    mset : ModelSet
    K : control.LTI, optional
        With a controller, the closed-loop poles of each member are tested
        instead (see :func:`member_closed_loop_poles`).

    Returns
    -------
    ndarray of int

    Examples
    --------
    >>> mset = model_set(ct.tf([1], [1, 2, 2, 1]), 0.5)   # +-50 % on a third-order denominator
    >>> bad = unstable_members(mset)
    >>> len(bad) > 0, mset.offsets[bad[0]]     # a0 up, a1 and a2 down: a2 a1 < a0
    (True, array([ 1., -1., -1.]))
    """
    poles = member_poles(mset) if K is None else member_closed_loop_poles(mset, K)
    return np.flatnonzero(poles.real.max(axis=1) >= 0)
