"""Lower bounds on the peak mu any stabilising controller can achieve.

For a generalized plant P and a block structure Delta = diag(Delta_1, ...,
Delta_N), every controller K gives M = F_l(P, K) and

    mu_Delta(M(jw)) >= sigma_max(M_ii(jw))    for every complex full block i,

because restricting Delta to the single block Delta_i (the others zero) can
only lower mu, and mu of one full complex block is the largest singular
value.  Hence

    sup_w mu_Delta(M(jw)) >= ||F_l(P_i, K)||_inf >= inf_K ||F_l(P_i, K)||_inf,

with P_i the plant keeping only block i's channels (and the measurements and
controls).  The right-hand side is an ordinary H-infinity problem.  Two
numbers bound it from below:

``pointwise``
    At each frequency the closed-loop value F_l(P_i, K)(jw) =
    P11 + P12 X P21 with X = K (I - P22 K)^-1 ranging over all complex
    matrices, so sigma_max >= min_X sigma_max(P11 + P12 X P21), which by
    Parrott's theorem equals max(sigma_max(U_perp^H P11), sigma_max(P11
    V_perp)) (U_perp spans the complement of the range of P12, V_perp that
    of the row space of P21).  Valid for every K, stabilising or not; the
    maximum over a finite grid is still a valid lower bound.
``hinf``
    The optimum of the H-infinity problem by gamma-iteration
    (:func:`piezolib.robust.hinf.hinfsyn`): the bracket (gamma_infeasible,
    gamma] around inf_K.  When P_i is singular (D12 or D21 rank deficient)
    the problem is solved with a vanishing regularisation; the lower end is
    then that of the regularised problem, which tends to the exact infimum
    from above as the regularisation goes to zero, so the function repeats
    the search with smaller weights and reports the smallest lower end only
    when it has settled.

``value`` of :class:`LowerBound` is the H-infinity lower end when the
problem needed no regularisation or the regularised values settled, else
the pointwise bound; ``certified`` says which.
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.linalg as la

from piezolib._checks import (check_channels, check_finite_array, check_integer, check_lti,
                              check_positive)
from piezolib.robust.blocks import block_slices, parse_blk
from piezolib.robust.hinf import HinfSynthesisError, hinfsyn
from piezolib.robust.lti import frequency_grid

__all__ = ["LowerBound", "performance_lower_bound", "pointwise_lower_bound",
           "structured_lower_bound", "achievable_range"]

#: Effort / noise weights tried, largest first, when the sub-problem is singular.
REGULARIZATION_SEQUENCE = (1e-4, 1e-5, 1e-6)
_SETTLED_RTOL = 2e-3


@dataclass(frozen=True)
class LowerBound:
    """A lower bound on inf_K sup_w mu(F_l(P, K)(jw)) and how it was obtained.

    Attributes
    ----------
    value : float
        The lower bound reported (dimensionless): ``hinf_lower`` when
        ``method == 'hinf'``, else ``pointwise``.
    method : {'hinf', 'pointwise'}
        Which bound ``value`` is.
    pointwise : float
        max over ``omega`` of Parrott's frequency-wise bound (valid for any K).
    omega_pointwise : float
        Frequency of that maximum [rad/s].
    hinf_lower : float
        Lower end of the final gamma bracket of the H-infinity problem
        (nan when the synthesis failed).
    hinf_upper : float
        ||F_l(P_i, K)||_inf of the returned controller on the sub-plant as
        given (no regularisation): the infimum lies in
        [hinf_lower, hinf_upper] up to the bracket tolerance.
    K : control.StateSpace or None
        The (near-)optimal controller of the H-infinity problem.
    hinf : HinfResult or None
        The last synthesis result.
    regularization : tuple
        (weight, gamma_infeasible, gamma) of every regularised search, in order.
    outputs, inputs : tuple of int
        Indices of P's exogenous outputs / inputs the bound uses.
    """

    value: float
    method: str
    pointwise: float
    omega_pointwise: float
    hinf_lower: float
    hinf_upper: float
    K: object
    hinf: object
    regularization: tuple
    outputs: tuple
    inputs: tuple

    def __str__(self):
        return (f"lower bound {self.value:.4f} ({self.method}; pointwise {self.pointwise:.4f}"
                f" at {self.omega_pointwise:.4g} rad/s, H-inf bracket "
                f"[{self.hinf_lower:.4f}, {self.hinf_upper:.4f}])")


def _indices(name, selection, labels, n):
    """Indices into the first ``n`` of ``labels`` from names or integers, checked."""
    if isinstance(selection, (str, int, np.integer)):
        selection = [selection]
    try:
        items = list(selection)
    except TypeError:
        raise TypeError(f"{name} must be a sequence of signal names or indices, "
                        f"got {selection!r}") from None
    if not items:
        raise ValueError(f"{name} must select at least one signal")
    out = []
    for item in items:
        if isinstance(item, str):
            if item not in labels[:n]:
                raise ValueError(f"{name}: {item!r} is not one of the exogenous signals "
                                 f"{list(labels[:n])}")
            out.append(labels.index(item))
        else:
            i = check_integer(name, item, minimum=0)
            if i >= n:
                raise ValueError(f"{name}: index {i} out of range (P has {n} exogenous signals)")
            out.append(i)
    if len(set(out)) != len(out):
        raise ValueError(f"{name} selects a signal twice: {items}")
    return tuple(out)


def _check_plant(P, nmeas, ncon):
    check_lti("P", P)
    if not P.isctime():
        raise ValueError("P must be a continuous-time model")
    nmeas, ncon = check_channels(P, nmeas, ncon)
    return ct.ss(P), nmeas, ncon


def _sub_plant(P, nmeas, ncon, outputs, inputs):
    """P keeping exogenous outputs ``outputs`` and inputs ``inputs`` (plus the loop signals)."""
    p1, m1 = P.noutputs - nmeas, P.ninputs - ncon
    rows = list(outputs) + list(range(p1, P.noutputs))
    cols = list(inputs) + list(range(m1, P.ninputs))
    A, B, C, D = (np.asarray(x, float) for x in (P.A, P.B, P.C, P.D))
    return ct.ss(A, B[:, cols], C[rows], D[np.ix_(rows, cols)])


def _parrott(P11, P12, P21):
    """min over complex X of sigma_max(P11 + P12 X P21) (Parrott's theorem)."""
    values = []
    for M, side in ((P12, "left"), (P21.conj().T, "right")):
        U, s, _ = la.svd(M)
        rank = int(np.sum(s > 1e-12 * max(1.0, s[0] if s.size else 0.0)))
        Uperp = U[:, rank:]
        if Uperp.shape[1] == 0:
            values.append(0.0)
            continue
        R = Uperp.conj().T @ P11 if side == "left" else P11 @ Uperp
        values.append(float(la.svdvals(R)[0]))
    return max(values)


def pointwise_lower_bound(P, nmeas, ncon, omega, *, outputs=None, inputs=None):
    """Frequency-wise lower bound on ||F_l(P, K)||_inf valid for every controller K.

    Parameters
    ----------
    P : control.LTI
        Continuous-time generalized plant; the last ``nmeas`` outputs are
        measurements, the last ``ncon`` inputs controls.
    nmeas, ncon : int
        Number of measurements and controls.
    omega : array_like
        Frequencies [rad/s] (positive).
    outputs, inputs : sequence of str or int, optional
        Exogenous outputs / inputs kept (names or indices); default all.

    Returns
    -------
    bound : ndarray
        min_X sigma_max(P11 + P12 X P21) at each frequency (dimensionless
        when P is), shape ``(len(omega),)``.

    Raises
    ------
    ValueError, TypeError
        Bad P, sizes, selections or frequencies.
    """
    P, nmeas, ncon = _check_plant(P, nmeas, ncon)
    omega = check_finite_array("omega", omega, ndim=1, min_length=1, real=True)
    if np.any(omega <= 0):
        raise ValueError("omega must hold positive frequencies [rad/s]")
    p1, m1 = P.noutputs - nmeas, P.ninputs - ncon
    outs = tuple(range(p1)) if outputs is None else _indices("outputs", outputs,
                                                             list(P.output_labels), p1)
    ins = tuple(range(m1)) if inputs is None else _indices("inputs", inputs,
                                                           list(P.input_labels), m1)
    Ps = _sub_plant(P, nmeas, ncon, outs, ins)
    q1, r1 = len(outs), len(ins)
    resp = np.moveaxis(np.atleast_3d(Ps.frequency_response(omega).complex), -1, 0)
    resp = resp.reshape(len(omega), Ps.noutputs, Ps.ninputs)
    return np.array([_parrott(H[:q1, :r1], H[:q1, r1:], H[q1:, :r1]) for H in resp])


def performance_lower_bound(P, nmeas, ncon, perf_outputs, perf_inputs, *, omega=None,
                            rtol=1e-4, max_iter=60, regularization=REGULARIZATION_SEQUENCE):
    """Lower bound on the peak mu of any stabilising K: the optimal H-inf norm of one full block.

    mu_RP(F_l(P, K)) >= ||F_l(P_perf, K)||_inf >= inf_K ||F_l(P_perf, K)||_inf
    for every K when (``perf_outputs``, ``perf_inputs``) are the channels of a
    complex full block of the structure (the performance block, or a full
    uncertainty block).  See the module docstring for how the infimum is
    bracketed.

    Parameters
    ----------
    P : control.LTI
        Continuous-time generalized plant (the one mu is computed on, without
        any regularisation outputs).
    nmeas, ncon : int
        Number of measurements (last outputs) and controls (last inputs).
    perf_outputs, perf_inputs : sequence of str or int
        The block's channels: P's exogenous outputs it reads and inputs it
        drives (signal names or indices).
    omega : array_like, optional
        Grid [rad/s] of the pointwise bound; default 2000 points spanning the
        poles of P by four decades either side.
    rtol : float
        Relative width of the gamma bracket.
    max_iter : int
        Maximum number of gamma trials of each H-infinity search (at least
        2; :func:`~piezolib.robust.hinf.hinfsyn`).  The bound depends on
        counts only, never on wall time.
    regularization : sequence of float
        Decreasing effort/noise weights tried when the sub-plant is singular.

    Returns
    -------
    LowerBound

    Raises
    ------
    ValueError, TypeError
        Bad P, sizes or channel selections.

    Examples
    --------
    >>> import control as ct
    >>> s = ct.tf('s')
    >>> W = 0.5 * (s + 10) / (s + 0.01)          # performance weight on S
    >>> G = 1 / (s + 1)
    >>> P = ct.ss(ct.tf([[W.num[0][0], (-W * G).num[0][0]], [[1], (-G).num[0][0]]],
    ...                 [[W.den[0][0], (W * G).den[0][0]], [[1], G.den[0][0]]]))
    >>> lb = performance_lower_bound(P, 1, 1, [0], [0])
    >>> round(lb.value, 3)                       # S(inf) = 1 forces ||W S|| >= |W(inf)|
    0.5
    """
    P, nmeas, ncon = _check_plant(P, nmeas, ncon)
    p1, m1 = P.noutputs - nmeas, P.ninputs - ncon
    outs = _indices("perf_outputs", perf_outputs, list(P.output_labels), p1)
    ins = _indices("perf_inputs", perf_inputs, list(P.input_labels), m1)
    rtol = check_positive("rtol", rtol)
    max_iter = check_integer("max_iter", max_iter, minimum=2)
    weights = tuple(check_positive("regularization", w) for w in regularization)
    if omega is None:
        mags = np.abs(ct.poles(P)) if P.nstates else np.ones(1)
        mags = mags[mags > 0] if np.any(mags > 0) else np.ones(1)
        omega = frequency_grid(mags.min() / 1e4, mags.max() * 1e4, 2000)
    pw = pointwise_lower_bound(P, nmeas, ncon, omega, outputs=outs, inputs=ins)
    k = int(np.argmax(pw))
    Ps = _sub_plant(P, nmeas, ncon, outs, ins)
    reg, res, lower, upper = [], None, np.nan, np.nan
    try:
        res = hinfsyn(Ps, nmeas, ncon, rtol=rtol, max_iter=max_iter,
                      effort_weight=None, noise_weight=None)
        lower, upper, method = res.gamma_infeasible, res.norm, "hinf"
    except HinfSynthesisError as err:
        if "rank deficient" not in str(err):
            raise
        method = "pointwise"
        for w in weights:
            try:
                r = hinfsyn(Ps, nmeas, ncon, rtol=rtol, max_iter=max_iter,
                            effort_weight=w, noise_weight=w)
            except HinfSynthesisError:
                break
            reg.append((w, r.gamma_infeasible, r.gamma))
            if res is None or r.norm <= res.norm:
                res = r
            if (len(reg) > 1 and abs(reg[-1][1] - reg[-2][1])
                    <= _SETTLED_RTOL * reg[-1][1]):
                method = "hinf"
                break
        if reg:
            lower, upper = min(x[1] for x in reg), res.norm
    value = max(lower, pw[k]) if method == "hinf" else float(pw[k])
    return LowerBound(value=float(value), method=method, pointwise=float(pw[k]),
                      omega_pointwise=float(omega[k]), hinf_lower=float(lower),
                      hinf_upper=float(upper), K=None if res is None else res.K, hinf=res,
                      regularization=tuple(reg), outputs=outs, inputs=ins)


def structured_lower_bound(P, blk, nmeas, ncon, **kwargs):
    """Largest :func:`performance_lower_bound` over the complex full blocks of ``blk``.

    Parameters
    ----------
    P : control.LTI
        Generalized plant whose exogenous channels match ``blk``.
    blk : sequence
        Block structure in MATLAB ``mussv`` convention (rows (r, c)).
    nmeas, ncon : int
        Number of measurements and controls.
    **kwargs
        Passed to :func:`performance_lower_bound`.

    Returns
    -------
    best : LowerBound
        The largest bound.
    per_block : tuple of (int, LowerBound)
        Block index and bound for every complex full block (real and
        repeated blocks are skipped: their mu is not an H-inf norm).
    """
    P, nmeas, ncon = _check_plant(P, nmeas, ncon)
    blocks = parse_blk(blk, P.noutputs - nmeas, P.ninputs - ncon)
    out = []
    for i, (b, (ins, outs)) in enumerate(zip(blocks, block_slices(blocks))):
        if not b.is_full:
            continue
        lb = performance_lower_bound(P, nmeas, ncon, range(outs.start, outs.stop),
                                     range(ins.start, ins.stop), **kwargs)
        out.append((i, lb))
    if not out:
        raise ValueError("blk has no complex full block to bound")
    return max(out, key=lambda x: x[1].value)[1], tuple(out)


def achievable_range(lower, achieved, what="mu_RP"):
    """The line printed beside a design: ``achievable mu_RP in [lower, ours]``.

    Parameters
    ----------
    lower : LowerBound or float
        Lower bound on the achievable peak.
    achieved : float
        Peak (upper bound) reached by the design.
    what : str
        Name of the quantity.

    Returns
    -------
    str
        The bracket; when ``lower`` exceeds ``achieved`` there is none, and
        the text says so instead of printing one.
    """
    lo = lower.value if isinstance(lower, LowerBound) else check_positive("lower", lower)
    achieved = check_positive("achieved", achieved)
    if not isinstance(what, str):
        raise TypeError(f"what must be a str (the quantity's name), got {what!r}")
    if lo > achieved:
        # no bracket: a peak read on a grid can miss the true one, or one of the two is wrong
        return (f"achievable {what} >= {lo:.3f}, but ours is {achieved:.3f}, below that bound: "
                "the design's peak was read on a grid that misses it, or a number is wrong")
    gap = achieved / lo - 1.0
    return f"achievable {what} in [{lo:.3f}, {achieved:.3f}] (ours within {100 * gap:.1f} % of the bound)"
