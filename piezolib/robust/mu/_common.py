"""Helpers that several mu-bound modules share (private to :mod:`piezolib.robust.mu`).

The D-scaled and the D,G-scaled upper bounds take the same regularised
Newton steps; the lower bound and the symmetric-lift certificate start from
the D-balanced matrix; the D,G bound and its branch and bound certify with
the same rounding-safe eigenvalue.  Each helper lives here once, so that no
bound module imports another's private names.
"""

import numpy as np

__all__ = ["STEP_FRACTIONS", "absolute_hessian", "newton_direction",
           "central_difference_hessian", "scaled_matrix", "certified_lmi_top"]

#: fractions of a Newton step that a line search tries (all at once, batched)
STEP_FRACTIONS = np.array([1.0, 0.5, 0.25, 0.125, 1 / 16, 1 / 64, 1 / 256])


def absolute_hessian(H, free, rows=None):
    """H on the free parameters with its eigenvalues replaced by their magnitudes, floored above 0.

    Only ``rows`` (default: all) are transformed; the others are taken to be
    positive definite already.  Fixed parameters' rows and columns are zero.
    |lambda|: along negative curvature (the repeated scalars' triangular
    parametrisation is not convex) a step goes downhill, as far as the curvature says.
    """
    idx = np.nonzero(free)[0]
    Hf = H[:, idx[:, None], idx[None, :]]
    Hf = 0.5 * (Hf + np.swapaxes(Hf, 1, 2))
    rows = np.ones(len(H), bool) if rows is None else rows
    if np.any(rows) and not _above_floor(Hf[rows]):
        lam, Q = np.linalg.eigh(Hf[rows])
        floor = 1e-9 * np.maximum(np.abs(lam).max(1, keepdims=True), 1.0)
        Hf[rows] = (Q * np.maximum(np.abs(lam), floor)[:, None, :]) @ np.swapaxes(Q, 1, 2)
    out = np.zeros_like(H)
    out[:, idx[:, None], idx[None, :]] = Hf
    return out


def _above_floor(H):
    """Whether every matrix of the stack H has its eigenvalues above absolute_hessian's floor.

    By a Cholesky factorisation of H - 1e-9 max(|H|_F, 1) I (cheaper than the
    eigenvalues; the Frobenius norm bounds the largest |lambda|): where it
    succeeds, the floored |lambda| would return H unchanged.  The diagonal
    scalings' convex surrogate mostly passes.
    """
    shift = 1e-9 * np.maximum(np.linalg.norm(H, axis=(1, 2)), 1.0)
    try:
        np.linalg.cholesky(H - shift[:, None, None] * np.eye(H.shape[1]))
    except np.linalg.LinAlgError:
        return False
    return True


def newton_direction(H, g, free, max_step, positive=False):
    """Regularised Newton direction -H^-1 g on the free parameters, and its decrement.

    H is first made positive definite (:func:`absolute_hessian`) unless
    ``positive`` says it is.  The step's length is limited to ``max_step``.
    """
    H = H if positive else absolute_hessian(H, free)
    idx = np.nonzero(free)[0]
    step = np.zeros_like(g)
    step[:, idx] = -np.linalg.solve(H[:, idx[:, None], idx[None, :]], g[:, idx, None])[:, :, 0]
    norm = np.linalg.norm(step, axis=1, keepdims=True)
    step *= np.minimum(1.0, max_step / np.maximum(norm, 1e-300))
    decrement = -np.einsum("ni,ni->n", step, g)
    return step, decrement


def central_difference_hessian(value_and_gradient, x, h, cols):
    """Value, gradient and Hessian columns ``cols`` by central differences of gradients.

    ``value_and_gradient(points)`` maps the stacked points (2 len(cols) + 1
    copies of x (N, n), shifted by +-h along each of ``cols``) to their values
    and gradients; the other Hessian columns are zero.
    """
    N, n = x.shape
    k = cols.size
    shifts = np.zeros((2 * k + 1, n))
    shifts[1 + np.arange(k), cols] = h
    shifts[1 + k + np.arange(k), cols] = -h
    F, g = value_and_gradient((x[None] + shifts[:, None]).reshape(-1, n))
    g = g.reshape(len(shifts), N, n)
    H = np.zeros((N, n, n))
    H[:, :, cols] = np.moveaxis((g[1:1 + k] - g[1 + k:]) / (2 * h), 0, 2)
    return F[:N], g[0], H


def scaled_matrix(M, Dl, Dr):
    """Dl M Dr^-1 for stacks of matrices (nf, p, q), by a solve rather than an inverse."""
    return np.swapaxes(np.linalg.solve(np.swapaxes(Dr, 1, 2), np.swapaxes(Dl @ M, 1, 2)), 1, 2)


def certified_lmi_top(A, GA):
    """lambda_max of A^H A + j (GA - GA^H) plus a bound on its rounding errors.

    A = D M D^-1 and GA = D^-1 G M D^-1 (the D,G LMI after the congruence with
    D^-1).  Forming H and its eigenvalues in floating point errs by a few n eps
    times the size of its terms; added, so that sqrt of the result bounds mu
    also when G is large (the bound must not fall below mu by rounding).
    """
    H = np.swapaxes(A, 1, 2).conj() @ A + 1j * (GA - np.swapaxes(GA, 1, 2).conj())
    H = 0.5 * (H + np.swapaxes(H, 1, 2).conj())
    size = np.linalg.norm(A, axis=(1, 2)) ** 2 + 2 * np.linalg.norm(GA, axis=(1, 2))
    return np.linalg.eigvalsh(H)[:, -1] + 8 * A.shape[2] * np.finfo(float).eps * size
