"""The matrix exponential of a stack of matrices, in one batched computation.

``scipy.linalg.expm`` accepts a stack but computes each matrix in turn, about
a millisecond per small matrix; the members of a model set (hundreds of 7 x 7
matrices) then cost seconds.  :func:`expm_stack` runs the same algorithm
(scaling and squaring with the degree-13 Padé approximant, Higham 2005) on the
whole stack with numpy's batched products and solves: each matrix gets its own
scaling, so the accuracy is expm's (a relative error of a few units of
rounding per squaring).
"""

import numpy as np

from piezolib._checks import check_finite_array

__all__ = ["expm_stack"]

#: Coefficients of the degree-13 Padé approximant of exp (Higham 2005, Table 10.4).
_PADE13 = (64764752532480000.0, 32382376266240000.0, 7771770303897600.0,
           1187353796428800.0, 129060195264000.0, 10559470521600.0, 670442572800.0,
           33522128640.0, 1323241920.0, 40840800.0, 960960.0, 16380.0, 182.0, 1.0)
#: The largest 1-norm for which the degree-13 approximant is accurate to double precision.
_THETA13 = 5.371920351148152


def expm_stack(A):
    """exp(A_k) of every matrix of a stack.

    Parameters
    ----------
    A : array_like, shape (..., n, n)
        Real or complex, finite.

    Returns
    -------
    ndarray, shape (..., n, n)

    Examples
    --------
    >>> A = np.array([[[0.0, 1.0], [0.0, 0.0]], [[-1.0, 0.0], [0.0, -2.0]]])
    >>> np.round(expm_stack(A), 6)
    array([[[1.      , 1.      ],
            [0.      , 1.      ]],
    <BLANKLINE>
           [[0.367879, 0.      ],
            [0.      , 0.135335]]])
    """
    A = check_finite_array("A", A)
    if A.ndim < 2 or A.shape[-1] != A.shape[-2]:
        raise ValueError(f"A must be a stack of square matrices (..., n, n), got shape {A.shape}")
    shape = A.shape
    A = A.reshape((-1,) + shape[-2:])
    norm = np.abs(A).sum(axis=-2).max(axis=-1)               # 1-norm of each matrix
    with np.errstate(divide="ignore"):
        s = np.maximum(0, np.ceil(np.log2(norm / _THETA13))).astype(int)
    A = A / (2.0 ** s)[:, None, None]
    b = _PADE13
    eye = np.broadcast_to(np.eye(shape[-1]), A.shape)
    A2 = A @ A
    A4 = A2 @ A2
    A6 = A4 @ A2
    U = A @ (A6 @ (b[13] * A6 + b[11] * A4 + b[9] * A2)
             + b[7] * A6 + b[5] * A4 + b[3] * A2 + b[1] * eye)
    V = (A6 @ (b[12] * A6 + b[10] * A4 + b[8] * A2)
         + b[6] * A6 + b[4] * A4 + b[2] * A2 + b[0] * eye)
    R = np.linalg.solve(V - U, V + U)
    for k in range(int(s.max(initial=0))):
        more = s > k                                          # squarings still owed
        R[more] = R[more] @ R[more]
    return R.reshape(shape)
