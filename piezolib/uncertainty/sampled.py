"""The members of a model set at a sampling rate: exact ZOH models and sampled loops.

:func:`member_zoh_coefficients` discretises every member of a
:class:`~piezolib.uncertainty.modelset.ModelSet` with a zero-order hold in
one batched matrix exponential (no loop over members), and
:func:`sampled_loop_poles` gives the poles of each member's sampled loop with
a discrete controller and a computation delay of whole samples: what a
real-time target runs, where :func:`~piezolib.uncertainty.member_closed_loop_poles`
is the continuous loop.  :func:`random_model_set` draws members from the
box uniformly, beside the grid of :func:`~piezolib.uncertainty.model_set`.
"""

import math

import control as ct
import numpy as np
import scipy.signal as sg

from piezolib._checks import check_count, check_integer, check_positive, check_proper, check_siso
from piezolib.robust.matrix_exponential import expm_stack
from piezolib.uncertainty.modelset import ModelSet, check_model_set
from piezolib.uncertainty.polynomials import (batched_roots, check_plant, check_spread,
                                              plant_polynomials, scale_coefficients)

__all__ = ["random_model_set", "member_zoh_coefficients", "sampled_loop_poles",
           "sampled_loop_unstable", "sampled_loop_spread", "MAX_MEMBERS", "MAX_DELAY_SAMPLES"]


#: Most members of a random model set (its offsets take 8 n bytes a member, and every
#: analysis of the set loops over the members).
MAX_MEMBERS = 1_000_000
#: Most samples of computation delay of a sampled loop: its matrix grows by a state per
#: sample and its eigenvalues cost the cube (1000 samples: 74 s for two members here,
#: ``benchmarks/bench_size_limits.py``).
MAX_DELAY_SAMPLES = 100


def random_model_set(G, spread, count, seed=0):
    """``count`` members of G's box drawn uniformly (offsets q_i ~ U[-1, 1]).

    Parameters
    ----------
    G : control.LTI
        Nominal SISO proper model with at least one pole.
    spread : float
        Relative spread of every denominator coefficient, 0 < spread < 1.
    count : int
        Number of members, 1 ... :data:`MAX_MEMBERS`.
    seed : int
        Seed of the draw (numpy's default generator).

    Returns
    -------
    ModelSet
        ``levels`` is 0: the members are a sample, not a grid.
    """
    G = check_plant(G)
    spread = check_spread(spread)
    count = check_count("count", count, maximum=MAX_MEMBERS,
                        why="every analysis of the set loops over its members")
    seed = check_integer("seed", seed, minimum=0)
    n = len(plant_polynomials(G)[0]) - 1
    offsets = np.random.default_rng(seed).uniform(-1.0, 1.0, (count, n))
    return ModelSet(plant=G, spread=spread, levels=0, offsets=offsets)


def member_zoh_coefficients(mset, dt):
    """Exact ZOH discretisation of every member, as direct-form filter rows.

    Each member is realised in controllable canonical form in scaled time
    (s = omega_s p, omega_s the set's :attr:`~ModelSet.time_scale`, so the
    coefficients are of order one) and held over one sample by the matrix
    exponential of [[A, B], [0, 0]] dt, all members in one batched call.
    The denominator is det(zI - A_d) and the numerator
    det(zI - A_d + B_d C) - det(zI - A_d) (+ D det(zI - A_d)).

    Parameters
    ----------
    mset : ModelSet
        Members of a strictly proper or biproper plant.
    dt : float
        Sample time [s].

    Returns
    -------
    b, a : ndarray, shape (M, n + 1)
        Numerators and denominators in powers of z^-1 (highest power of z
        first, a[:, 0] = 1), row k for member k, for ``scipy.signal.lfilter``;
        b[:, 0] = 0 exactly for a strictly proper plant.
    """
    check_model_set(mset)
    dt = check_positive("dt", dt)
    ws = mset.time_scale
    n = mset.order
    a_nom, b_nom = plant_polynomials(mset.plant)
    if len(b_nom) > n + 1:
        raise ValueError("mset.plant must be proper")
    den = mset.scaled_coefficients(ws)                        # (M, n+1) low first, monic
    num = np.zeros(n + 1)
    num[:len(b_nom)] = scale_coefficients(b_nom, ws, n)       # low first, same scaling
    d = num[n]                                                # direct feedthrough
    C = num[None, :n] - d * den[:, :n]                        # the strictly proper parts
    size = mset.size
    M = np.zeros((size, n + 1, n + 1))
    M[:, :n - 1, 1:n] = np.eye(n - 1)                         # x_i' = x_{i+1}
    M[:, n - 1, :n] = -den[:, :n]                             # x_n' = -sum a_i x_i + u
    M[:, n - 1, n] = 1.0
    E = expm_stack(M * (ws * dt))       # scipy's expm takes the stack one matrix at a time
    Ad, Bd = E[:, :n, :n], E[:, :n, n]
    a = _characteristic(Ad)
    b = _characteristic(Ad - Bd[:, :, None] * C[:, None, :]) - a
    if d:
        b = b + d * a
    else:
        b[:, 0] = 0.0                                         # exactly: no feedthrough
    return b, a


def _characteristic(A):
    """det(zI - A) of a stack of matrices: (M, n + 1) coefficients, highest power first."""
    roots = np.linalg.eigvals(A)
    p = np.ones((A.shape[0], 1), dtype=complex)
    for k in range(A.shape[1]):
        p = np.concatenate([p, np.zeros((A.shape[0], 1))], axis=1) \
            - roots[:, k:k + 1] * np.concatenate([np.zeros((A.shape[0], 1)), p], axis=1)
    return p.real


def _controller_polynomials(Kd, dt):
    """(numerator, denominator) of a discrete SISO controller, highest power of z first."""
    if not isinstance(Kd, ct.LTI):
        raise TypeError(f"Kd must be a discrete control.StateSpace or TransferFunction, got "
                        f"{type(Kd).__name__}")
    check_siso("Kd", Kd)
    check_proper("Kd", Kd)
    if Kd.isctime(strict=False) or Kd.dt is True or not math.isclose(float(Kd.dt), dt,
                                                                      rel_tol=1e-9):
        raise ValueError(f"Kd must be a discrete model with sample time dt = {dt:g} s, got "
                         f"dt = {Kd.dt!r}")
    tf = ct.tf(Kd)
    num = np.atleast_1d(np.asarray(tf.num[0][0], dtype=float))
    den = np.atleast_1d(np.asarray(tf.den[0][0], dtype=float))
    if not (np.all(np.isfinite(num)) and np.all(np.isfinite(den))):
        raise ValueError("Kd has non-finite coefficients")
    return num / den[0], den / den[0]


def sampled_loop_poles(mset, Kd, dt, delay_samples=1):
    """Poles of every member's sampled loop: ZOH plant, discrete K, whole-sample delay.

    The loop u[k] = K_d(z) e[k - d], e = r - y, y = G_d(z) u, with G_d the
    exact ZOH model of the member (:func:`member_zoh_coefficients`); its
    characteristic polynomial a_G(z) a_K(z) z^d + b_G(z) b_K(z) for all
    members is one (M, degree + 1) array whose roots come from one batched
    eigenvalue call.

    Parameters
    ----------
    mset : ModelSet
    Kd : control.LTI
        Discrete SISO proper controller e -> u at sample time ``dt``.
    dt : float
        Sample time [s].
    delay_samples : int
        Computation delay d [samples], 0 ... :data:`MAX_DELAY_SAMPLES`.

    Returns
    -------
    ndarray, shape (M, n + deg a_K + d), complex
        Poles in the z-plane; a member's loop is stable when all lie inside
        the unit circle.
    """
    dt = check_positive("dt", dt)
    d = check_count("delay_samples", delay_samples, maximum=MAX_DELAY_SAMPLES, minimum=0,
                    why="each sample of delay adds a state to every member's loop matrix")
    bK, aK = _controller_polynomials(Kd, dt)
    b, a = member_zoh_coefficients(mset, dt)
    # highest power first: z^d a_G a_K + b_G b_K (b_G padded to a_G's length)
    # row-wise polynomial products: a 2-D convolution with a one-row kernel
    loop_a = sg.convolve(a, np.r_[aK, np.zeros(d)][None, :])
    loop_b = sg.convolve(b, bK[None, :])
    char = loop_a.copy()
    char[:, char.shape[1] - loop_b.shape[1]:] += loop_b
    return batched_roots(char[:, ::-1])


def sampled_loop_unstable(mset, Kd, dt, delay_samples=1):
    """Indices of the members whose sampled loop (see :func:`sampled_loop_poles`) has a
    pole on or outside the unit circle.

    Returns
    -------
    ndarray of int
    """
    poles = sampled_loop_poles(mset, Kd, dt, delay_samples)
    return np.flatnonzero(np.abs(poles).max(axis=1) >= 1.0)


def sampled_loop_spread(G, Kd, dt, delay_samples=1, levels=3, spread_max=0.5, rtol=1e-3):
    """Largest spread at which every member of a grid has a stable sampled loop (bisection).

    The members' ZOH models depend on the coefficients through a matrix
    exponential, so the exact zero-exclusion margin of the continuous loop
    (:func:`~piezolib.uncertainty.margin.parametric_stability_margin`) has no
    sampled counterpart here: the box is probed on the ``levels**n`` grid of
    :func:`~piezolib.uncertainty.model_set` (vertices included for any
    ``levels``).  The result is an upper bound on the sampled loop's true
    margin: a point of the box between the grid points may fail earlier.

    Parameters
    ----------
    G : control.LTI
        Nominal continuous SISO plant.
    Kd : control.LTI
        Discrete controller at sample time ``dt``.
    dt : float
        Sample time [s].
    delay_samples : int
    levels : int
        Values per coefficient of the grid (>= 2).
    spread_max : float
        Upper end of the search (< 1).
    rtol : float
        Relative width of the final bracket.

    Returns
    -------
    float
        The spread (0 when the nominal loop is unstable, ``spread_max`` when
        every grid member is stable there).
    """
    from piezolib.uncertainty.modelset import model_set

    spread_max = check_spread(spread_max, "spread_max")
    rtol = check_positive("rtol", rtol)

    def stable(spread):
        return sampled_loop_unstable(model_set(G, spread, levels), Kd, dt, delay_samples).size == 0

    nominal = ModelSet(check_plant(G), spread_max, 1, np.zeros((1, len(plant_polynomials(G)[0]) - 1)))
    if sampled_loop_unstable(nominal, Kd, dt, delay_samples).size:
        return 0.0
    if stable(spread_max):
        return spread_max
    low, high = 0.0, spread_max
    while high - low > rtol * high:
        mid = 0.5 * (low + high)
        low, high = (mid, high) if stable(mid) else (low, mid)
    return low
