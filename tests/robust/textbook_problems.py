"""Textbook robust-control problems with published or closed-form answers (test data).

Shared by ``tests/robust/test_textbook.py``, ``test_dk.py``, ``test_hinf.py``,
``test_dgk_textbook.py``, ``benchmarks/bench_textbook.py`` and ``bench_mixed_musyn.py``; nothing
in ``piezolib`` imports it.  Every builder is written from the textbook definition of the
problem; every closed form is derived in the docstring or comment next to it.  Only
``numpy``, ``scipy`` and python-control are used here, so the references are independent
of ``piezolib.robust``.  Frequencies are in rad/s (rad/min for the distillation column,
as in the book), time in seconds (minutes).

Sources of the published numbers:

* [SP05] S. Skogestad and I. Postlethwaite, *Multivariable Feedback Control*, 2nd ed.,
  Wiley 2005: Sec. 2.8.3 (S/KS design of the disturbance process, gamma_min = 1.37),
  Sec. 3.7.1 (spinning satellite), Sec. 8.12 / Table 8.1 (distillation column with the
  inverse-based controller), Sec. 8.12.4 (DK-iteration).  The mu values of Table 8.1
  and of the DK-iteration are those printed by the book's own MATLAB programs
  (``Fig8_15.m``: mu_RP 5.7726, mu_RS 0.5242, mu_NP 0.500 on ``logspace(-3, 3, 61)``;
  ``Sec8_124.m``: mu 1.1798, 1.0275, 1.0207 for DK iterations 1-3 and 0.9740 with
  Lundstrom's optimal scaling ``D_OPT_NUM``/``D_OPT_DEN`` below).
* [Y94] P. M. Young, "The rank one mixed mu problem and 'Kharitonov-type' analysis",
  Automatica 30(12), 1994: mu of a rank-one matrix in closed form (re-derived in
  :func:`rank_one_mu`).
* [T80] A. Tannenbaum, "Feedback stabilization of linear dynamical plants with uncertainty
  in the gain factor", Int. J. Control 32(1), 1980; [KT85] P. P. Khargonekar and
  A. Tannenbaum, "Non-Euclidean metrics and the robust stabilization of systems with
  parameter uncertainty", IEEE Trans. Automat. Contr. 30(10), 1985; [DFT92] J. C. Doyle,
  B. A. Francis and A. R. Tannenbaum, *Feedback Control Theory*, Macmillan 1992, Ch. 11
  (gain-margin optimisation by a conformal map and Nevanlinna-Pick interpolation): the
  largest gain interval one controller can stabilise (re-derived in :func:`gain_margin`).
* [WB92] B. Wie and D. S. Bernstein, "Benchmark problems for robust control design",
  J. Guidance, Control, and Dynamics 15(5), 1992 (first posed at the 1990 ACC): two carts
  joined by a spring of unknown stiffness 0.5 <= k <= 2, force on cart 1, position of
  cart 2 measured; the benchmark's published designs stabilise the whole interval
  (:func:`acc_benchmark`).
"""

import warnings
from fractions import Fraction
from typing import NamedTuple

import control as ct
import numpy as np

__all__ = [
    "MixedSensitivity", "disturbance_process", "MIXSENS_GAMMA_BOOK",
    "Satellite", "spinning_satellite", "satellite_T", "satellite_mu_complex",
    "satellite_mu_real",
    "rank_one_mu",
    "TwoMass", "two_mass_spring",
    "Distillation", "distillation_column", "distillation_N", "distillation_mu",
    "G0", "BLK_RP", "SP_GRID", "SP_MU_RP", "SP_MU_RS", "SP_MU_NP", "SP_DK_MU", "SP_DOPT_MU",
    "lundstrom_scaling",
    "pointwise_lft", "exact_response",
    "GainMargin", "gain_margin", "gain_ratio_sup_real", "gain_ratio_sup_complex",
    "gain_margin_controller", "complex_mu_bound", "ratio_of_radius", "radius_of_ratio",
    "gain_T0", "gain_loop",
    "AccBenchmark", "acc_benchmark", "ACC_K_RANGE", "spring_loop",
    "real_stability_interval", "stable_on_grid",
]


# --- 1. S/KS mixed sensitivity of the disturbance process [SP05, Sec. 2.8.3] -------------

MIXSENS_GAMMA_BOOK = 1.37        # gamma_min printed in [SP05] (three significant digits)


class MixedSensitivity(NamedTuple):
    """The S/KS problem: plant G, weights W1 (on S) and Wu (on KS), generalized plant P."""
    G: ct.TransferFunction
    W1: ct.TransferFunction
    Wu: ct.TransferFunction
    P: ct.StateSpace


def disturbance_process(M=1.5, omega_b=10.0, A=1e-4):
    """G = 200/((10 s + 1)(0.05 s + 1)^2), W1 = (s/M + w_B)/(s + w_B A), Wu = 1.

    P (``control.augw``) has inputs [w, u] and outputs [z1 = W1 S w, z2 = Wu K S w, v],
    so ||F_l(P, K)||_inf = sup_w sqrt(|W1 S|^2 + |K S|^2).
    """
    s = ct.tf("s")
    G = 200 / ((10 * s + 1) * (0.05 * s + 1) ** 2)
    W1 = (s / M + omega_b) / (s + omega_b * A)
    Wu = ct.tf(1, 1)
    with warnings.catch_warnings():       # augw itself calls python-control's deprecated connect()
        warnings.simplefilter("ignore", FutureWarning)
        P = ct.ss(ct.augw(G, W1, Wu))
    return MixedSensitivity(G, W1, Wu, P)


# --- 2. Spinning satellite [SP05, Sec. 3.7.1] -------------------------------------------

class Satellite(NamedTuple):
    """Plant G, controller K = I and P for input uncertainty: F_l(P, K) = T_I."""
    a: float
    G: ct.StateSpace
    K: ct.StateSpace
    P: ct.StateSpace


def spinning_satellite(a=10.0):
    """G(s) = [[s - a^2, a (s + 1)], [-a (s + 1), s - a^2]] / (s^2 + a^2), K = I.

    Realisation (A, B, C) = ([[0, a], [-a, 0]], I, [[1, a], [-a, 1]]).  P has inputs
    [w1, w2, u1, u2] (w enters at the plant input) and outputs [z1, z2, e1, e2] with
    z = -u and e = -G (u + w), so that F_l(P, K) = K G (I + K G)^-1 = T_I, the map
    seen by a multiplicative input perturbation.
    """
    A = np.array([[0.0, a], [-a, 0.0]])
    C = np.array([[1.0, a], [-a, 1.0]])
    I2, Z2 = np.eye(2), np.zeros((2, 2))
    G = ct.ss(A, I2, C, Z2)
    P = ct.ss(A, np.hstack([I2, I2]), np.vstack([Z2, -C]), np.block([[Z2, -I2], [Z2, Z2]]))
    return Satellite(a, G, ct.ss([], [], [], I2), P)


def satellite_T(omega, a=10.0):
    """T_I(j omega) = (I + a J)/(1 + j omega), J = [[0, 1], [-1, 0]]: shape (nf, 2, 2).

    With K = I the closed-loop state matrix is A - B C = -I, so T = C/(s + 1).
    """
    R = np.array([[1.0, a], [-a, 1.0]])
    return R[None] / (1 + 1j * np.asarray(omega, float))[:, None, None]


def satellite_mu_complex(omega, a=10.0):
    """mu of T_I for diagonal, full or repeated-scalar complex Delta: sqrt(1 + a^2)/|1 + j w|.

    I + a J is normal with eigenvalues 1 +- j a, so rho(T_I) = sigma_max(T_I); rho is a
    lower bound (delta I is in each structure) and sigma_max an upper bound.
    """
    return np.sqrt(1 + a * a) / np.abs(1 + 1j * np.asarray(omega, float))


def satellite_mu_real(omega, a=10.0):
    """mu of T_I for two independent real input-gain errors (diagonal real Delta).

    det(I - T_I diag(d1, d2)) = 0 with c = 1/(1 + j w) reads
    1 - c (d1 + d2) + c^2 (1 + a^2) d1 d2 = 0; times (1 + j w)^2 its imaginary part is
    w (2 - d1 - d2) and its real part 1 - w^2 - (d1 + d2) + (1 + a^2) d1 d2.  For w > 0:
    d1 + d2 = 2 and d1 d2 = q = (1 + w^2)/(1 + a^2), so real d exist only for w <= a,
    the smaller max |d| is 1 + sqrt(1 - q) and mu = 1/(1 + sqrt(1 - q)); mu = 0 for
    w > a.  At w = 0 the imaginary condition is void, d1 = -d2 = 1/sqrt(1 + a^2) is the
    smallest solution and mu = sqrt(1 + a^2) (mu jumps at w = 0).
    """
    omega = np.asarray(omega, float)
    q = (1 + omega ** 2) / (1 + a * a)
    mu = np.where(q <= 1, 1 / (1 + np.sqrt(np.clip(1 - q, 0, None))), 0.0)
    return np.where(omega == 0, np.sqrt(1 + a * a), mu)


# --- 3. Rank-one matrices [Y94] ----------------------------------------------------------

def _block_slices(blk):
    """(output slice, input slice, kind) of each MATLAB blk row; kind: real/scalar/full."""
    rows, p, q = [], 0, 0
    for r, c in blk:
        if c == 0:
            k = abs(int(r))
            kind, nr, nc = ("real" if r < 0 else "scalar"), k, k
        else:
            kind, nr, nc = "full", int(r), int(c)
        rows.append((slice(p, p + nc), slice(q, q + nr), kind))
        p, q = p + nc, q + nr
    return rows


def rank_one_mu(a, b, blk):
    """Exact mu of the rank-one matrix M = a b^H for the structure ``blk``.

    det(I - M Delta) = 1 - sum_i b_i^H Delta_i a_i (a_i: the entries of a on block i's
    outputs, b_i on its inputs).  With |Delta_i| <= 1 a complex full block makes
    b_i^H Delta_i a_i fill the disc of radius |a_i| |b_i|, a complex repeated scalar the
    disc of radius z_i = |b_i^H a_i|, a real repeated scalar the segment [-z_i, z_i] with
    z_i = b_i^H a_i.  mu = the largest t on the positive real axis inside this convex
    Minkowski sum, i.e. min over directions of the support function divided by
    cos(theta); with x = tan(theta):

        mu = min_x  sum_real |Re z_i + x Im z_i| + sqrt(1 + x^2) sum_complex r_i.

    The function is convex; between the kinks x_i = -Re z_i / Im z_i it is
    alpha + beta x + C sqrt(1 + x^2), stationary at x = -beta / sqrt(C^2 - beta^2) when
    |beta| < C, so the minimum is found exactly among the kinks and these points.
    """
    a = np.asarray(a, complex).ravel()
    b = np.asarray(b, complex).ravel()
    z_real, radius = [], 0.0
    for out, inp, kind in _block_slices(blk):
        if kind == "full":
            radius += np.linalg.norm(a[out]) * np.linalg.norm(b[inp])
        elif kind == "scalar":
            radius += abs(np.vdot(b[inp], a[out]))
        else:
            z_real.append(np.vdot(b[inp], a[out]))
    z = np.array(z_real, complex)

    def f(x):
        return np.sum(np.abs(z.real + x * z.imag)) + np.sqrt(1 + x * x) * radius

    slopes = z.imag[z.imag != 0]
    kinks = np.sort(-z.real[z.imag != 0] / slopes)
    candidates = [f(x) for x in kinks] or [f(0.0)]
    edges = np.concatenate([[-np.inf], kinks, [np.inf]])
    for lo, hi in zip(edges[:-1], edges[1:]):
        # any interior point: the signs of the real terms are constant between kinks
        if np.isfinite(lo) and np.isfinite(hi):
            inside = (lo + hi) / 2
        else:
            inside = hi - 1 if np.isfinite(hi) else lo + 1 if np.isfinite(lo) else 0.0
        beta = np.sum(np.sign(z.real + inside * z.imag) * z.imag)   # slope of the linear part
        if radius > abs(beta):
            x = -beta / np.sqrt(radius ** 2 - beta ** 2)
            if lo <= x <= hi:
                candidates.append(f(x))
    return float(min(candidates))


# --- 4. Two-mass spring (ACC benchmark plant) --------------------------------------------

class TwoMass(NamedTuple):
    """Plant G (u -> x2) and the H-infinity generalized plant P."""
    G: ct.StateSpace
    P: ct.StateSpace


def two_mass_spring(m1=1.0, m2=1.0, k=1.0, rho=0.1, sigma=0.1):
    """Two masses on a spring; force u on m1, disturbance force w on m2, x2 measured.

    G(s) = k / (s^2 (m1 m2 s^2 + k (m1 + m2))) from u to x2 (a rigid-body double
    integrator and the undamped mode sqrt(k (m1 + m2) / (m1 m2)) rad/s).  P has inputs
    [w, n, u] and outputs [z1 = x2, z2 = rho u, y = x2 + sigma n] with states
    [x1, x2, v1, v2].  D12 = [0; rho] and D21 = [0, sigma] have full rank and the
    imaginary-axis modes are controllable from u and w and observable in x2, so the
    standard H-infinity assumptions hold.
    """
    A = np.array([[0, 0, 1, 0], [0, 0, 0, 1],
                  [-k / m1, k / m1, 0, 0], [k / m2, -k / m2, 0, 0]], float)
    b_u = np.array([[0], [0], [1 / m1], [0]])
    b_w = np.array([[0], [0], [0], [1 / m2]])
    c_x2 = np.array([[0.0, 1, 0, 0]])
    B = np.hstack([b_w, np.zeros((4, 1)), b_u])
    C = np.vstack([c_x2, np.zeros((1, 4)), c_x2])
    D = np.array([[0, 0, 0], [0, 0, rho], [0, sigma, 0]], float)
    return TwoMass(ct.ss(A, b_u, c_x2, 0), ct.ss(A, B, C, D))


# --- 5. Distillation column, LV configuration [SP05, Sec. 8.12] -------------------------

G0 = np.array([[87.8, -86.4], [108.2, -109.6]])   # steady-state gains, G = G0/(75 s + 1)
SP_GRID = np.logspace(-3, 3, 61)                   # the book's frequency grid [rad/min]
SP_MU_RP, SP_MU_RS, SP_MU_NP = 5.7726, 0.5242, 0.500   # Table 8.1 / Fig8_15.m, on SP_GRID
SP_DK_MU = (1.1798, 1.0275, 1.0207)                # Sec8_124.m: DK iterations 1-3, on SP_GRID
SP_DOPT_MU = 0.9740                                # Sec8_124.m: K-step with Lundstrom's d_opt
D_OPT_NUM = ((0.001, 1.0), (1.0, 0.25), (1.0, 0.054))   # 2 (0.001 s + 1)(s + 0.25)(s + 0.054)
D_OPT_DEN = ((1.0, 2 * 0.67, 0.67 ** 2 + 0.56 ** 2), (1.0, 0.013))  # ((s+0.67)^2+0.56^2)(s+0.013)


class Distillation(NamedTuple):
    """Plant, inverse-based controller and the generalized plant of the RP problem.

    P: inputs [d_I1, d_I2 (from Delta_I), w1, w2 (disturbance on y), u1, u2], outputs
    [z_I1, z_I2 (W_I u), z_P1, z_P2 (W_P (y + w)), v1, v2 (-(y + w))]; the structure
    is ``BLK_RP`` = two 1 x 1 input-uncertainty blocks and a 2 x 2 performance block.
    """
    G: ct.StateSpace
    K: ct.StateSpace
    P: ct.StateSpace
    c: float
    eps_k: float
    eps_p: float


BLK_RP = [(1, 1), (1, 1), (2, 2)]


def distillation_column(c=0.7, eps_k=1e-5, eps_p=1e-6):
    """G = G0/(75 s + 1), K = c (75 s + 1)/(s + eps_k) G0^-1, W_I = (s + 0.2)/(0.5 s + 1) I,
    W_P = (s/2 + 0.05)/(s + eps_p) I (the book's programs move the integrators of K and
    W_P to -eps_k and -eps_p).  Time in minutes.
    """
    s = ct.tf("s")
    G = ct.ss(1 / (75 * s + 1)) * ct.ss([], [], [], G0)
    K = ct.ss(c * (75 * s + 1) / (s + eps_k)) * ct.ss([], [], [], np.linalg.inv(G0))
    w_P = (s / 2 + 0.05) / (s + eps_p)
    w_I = (s + 0.2) / (0.5 * s + 1)

    def diag2(h, inputs, outputs, name):
        return ct.ss(ct.append(ct.ss(h), ct.ss(h)), inputs=inputs, outputs=outputs, name=name)

    parts = [
        ct.ss(G, inputs=["up1", "up2"], outputs=["y1", "y2"], name="G"),
        diag2(w_P, ["yw1", "yw2"], ["z_P1", "z_P2"], "W_P"),
        diag2(w_I, ["u1", "u2"], ["z_I1", "z_I2"], "W_I"),
        ct.summing_junction(["u1", "d_I1"], "up1"), ct.summing_junction(["u2", "d_I2"], "up2"),
        ct.summing_junction(["y1", "w1"], "yw1"), ct.summing_junction(["y2", "w2"], "yw2"),
        ct.summing_junction(["-yw1"], "v1"), ct.summing_junction(["-yw2"], "v2"),
    ]
    P = ct.interconnect(parts, inputs=["d_I1", "d_I2", "w1", "w2", "u1", "u2"],
                        outputs=["z_I1", "z_I2", "z_P1", "z_P2", "v1", "v2"])
    return Distillation(G, K, ct.ss(P), c, eps_k, eps_p)


def _distillation_ab(omega, c, eps_k, eps_p):
    """a = w_I tau and b = w_P eps of the decoupled loop L = c/(s + eps_k) I."""
    s = 1j * np.asarray(omega, float)
    tau = c / (s + eps_k + c)
    eps = (s + eps_k) / (s + eps_k + c)
    return (s + 0.2) / (0.5 * s + 1) * tau, (s / 2 + 0.05) / (s + eps_p) * eps


def distillation_N(omega, c=0.7, eps_k=1e-5, eps_p=1e-6):
    """Closed form of F_l(P, K) for the inverse-based controller, shape (nf, 4, 4).

    K G = G K = c/(s + eps_k) I, so T_I = tau I, K S = tau G^-1, S G = eps G, S = eps I
    and N = [[-a I, -a G^-1], [b G, b I]] with a = w_I tau, b = w_P eps.
    """
    a, b = _distillation_ab(omega, c, eps_k, eps_p)
    g = 1 / (75j * np.asarray(omega, float) + 1)
    G0inv = np.linalg.inv(G0)
    N = np.zeros((len(a), 4, 4), complex)
    N[:, :2, :2] = -a[:, None, None] * np.eye(2)
    N[:, :2, 2:] = -(a / g)[:, None, None] * G0inv
    N[:, 2:, :2] = (b * g)[:, None, None] * G0
    N[:, 2:, 2:] = b[:, None, None] * np.eye(2)
    return N


def distillation_mu(omega, structure="diagonal", c=0.7, eps_k=1e-5, eps_p=1e-6):
    """Closed-form mu of :func:`distillation_N`: 'diagonal' or 'full' RP, 'RS', 'NP'.

    With G = U Sigma V^H, diag(V, U)^H N diag(V, U) splits into 2 x 2 rank-one blocks
    [[a, a x], [b / x, b]] (x = d / sigma_i), so with a scaling d on the performance
    block sigma_max^2 = |a|^2 + |b|^2 + |a|^2 x^2 + |b|^2 / x^2; balancing the two
    singular values gives mu^2 = |a|^2 + |b|^2 + |a||b| (k + 1/k), k = cond(G), for a
    full 2 x 2 input block (2 full blocks: the D-bound is exact).  Diagonal input
    uncertainty adds a diagonal input scaling D_I (three blocks, 2S + F = 3: exact
    again), replacing k + 1/k by its minimum over D_I.  For 2 x 2 matrices
    k + 1/k = ||G||_F^2 / |det G|, minimised over D_I = diag(1, d) at
    2 ||g_1|| ||g_2|| / |det G| (g_j the columns of G0).  RS: mu = |a|; NP: |b|.
    """
    a, b = (np.abs(x) for x in _distillation_ab(omega, c, eps_k, eps_p))
    det = abs(np.linalg.det(G0))
    if structure == "RS":
        return a
    if structure == "NP":
        return b
    if structure == "full":
        k = np.sum(G0 ** 2) / det
    elif structure == "diagonal":
        k = 2 * np.linalg.norm(G0[:, 0]) * np.linalg.norm(G0[:, 1]) / det
    else:
        raise ValueError(f"structure must be 'diagonal', 'full', 'RS' or 'NP', not {structure!r}")
    return np.sqrt(a ** 2 + b ** 2 + a * b * k)


def lundstrom_scaling():
    """d_opt(s) of [SP05, Sec. 8.12.4] (Lundstrom's mu-optimal D-scaling) as a tf."""
    num = np.polymul(np.polymul(*D_OPT_NUM[:2]), D_OPT_NUM[2]) * 2
    den = np.polymul(*D_OPT_DEN)
    return ct.tf(num, den)


# --- 6. Gain-margin optimisation: real versus complex gain [T80, KT85, DFT92 Ch. 11] -----

class GainMargin(NamedTuple):
    """Plant P0, gain interval [k_lo, k_hi] as k = k0 (1 + r delta), generalized plant P.

    P has inputs [w_delta, n, u] and outputs [z_delta, e, y]; the structure is
    ``blk_mixed`` (delta real) or ``blk_complex`` (delta a complex disc), the second
    block a small 1 x 1 performance block (noise n -> plant output e).
    """
    P0: ct.StateSpace
    P: ct.StateSpace
    p: float
    z: float
    k_lo: float
    k_hi: float
    k0: float
    r: float
    eps: float
    blk_mixed: list
    blk_complex: list


def gain_ratio_sup_real(p, z):
    """sup k_hi / k_lo over all controllers for real gains: (z/p)^2 (z > p > 0).

    One controller C stabilises k P0 for every k in [1, K] iff T = P0 C / (1 + P0 C) is
    stable and 1 + (k - 1) T has no zero in the closed right half plane for those k
    (1 + k P0 C = (1 + (k - 1) T) / (1 - T) and 1/(1 - T) = 1 + P0 C):  T must map the
    right half plane into the slit plane C minus (-inf, -c], c = 1/(K - 1).  Interpolation
    (internal stability): T(p) = 1, T(z) = 0.  w = sqrt(1 + T/c) maps the slit plane
    onto the open right half plane, with w(z) = 1 and w(p) = sqrt(1 + 1/c) = sqrt(K),
    and phi(w) = (w - 1)/(w + 1) maps that onto the unit disc, phi(w(z)) = 0.  By
    Schwarz-Pick a function from the right half plane into the disc with a zero at z
    satisfies |f(p)| <= |(p - z)/(p + z)|, so feasibility needs
    (sqrt K - 1)/(sqrt K + 1) < (z - p)/(z + p), i.e. sqrt K < z/p; every K below is
    reached by a rational T (:func:`gain_margin_controller`, order 3).  The bound is a
    supremum, not a maximum: the constraint T(inf) = 0 (P0 strictly proper) makes the
    controllers' bandwidth grow without bound as K -> (z/p)^2.  The gain interval may sit
    anywhere on the positive axis: only the ratio counts (k -> k/k_lo rescales C).
    """
    return (z / p) ** 2


def gain_ratio_sup_complex(p, z):
    """sup k_hi / k_lo certified by a complex disc: z/p (z > p > 0).

    The disc k = k0 (1 + r delta), |delta| <= 1 complex, is stabilised iff
    ||r T0||_inf < 1 (T0 = k0 P0 C / (1 + k0 P0 C)), small-gain on a 1 x 1 block.  T0 is
    stable with T0(p) = 1, T0(z) = 0, so by Nevanlinna-Pick min ||T0||_inf =
    (z + p)/(z - p) (:func:`complex_mu_bound`): r < (z - p)/(z + p), and the real segment
    inside that disc has ratio (1 + r)/(1 - r) < z/p (:func:`ratio_of_radius`).  The
    complex bound is the square root of the real one.
    """
    return z / p


def gain_margin_controller(p, z, a, ratio, alpha):
    """A controller C (negative feedback) stabilising k P0 for every k in [1, ratio].

    The construction behind :func:`gain_ratio_sup_real`, made rational: take
    g(s) = q alpha (s - z)/((s + z)(s + alpha)), |q| < 1, which maps the closed right half
    plane (and infinity) into the open unit disc; w = (1 + g)/(1 - g) then lies in the
    open right half plane, w^2 off (-inf, 0], and T = c (w^2 - 1), c = 1/(ratio - 1),
    off the slit (-inf, -c]: 1 + (k - 1) T has no zero in the closed right half plane for
    1 <= k <= ratio.  g(z) = 0 gives T(z) = 0; T(p) = 1 needs w(p) = sqrt(ratio), i.e.
    g(p) = (sqrt(ratio) - 1)/(sqrt(ratio) + 1), which fixes
    q = g(p) (p + z)/(p - z) (p + alpha)/alpha; |q| < 1 holds for alpha large enough
    exactly when sqrt(ratio) < z/p.  g(inf) = 0 makes T strictly proper, so C is proper.

    With g = n_g/d_g, T = 4 c n_g d_g/(d_g - n_g)^2, and
    C = T/(P0 (1 - T)) = 4 c q alpha (s + z)(s + alpha)(s + a)/R(s),
    R = ((d_g - n_g)^2 - 4 c n_g d_g)/(s - p) (T(p) = 1 makes s - p a factor; the
    factor s - z of n_g cancels P0's zero).  So the supremum (z/p)^2 is approached by
    controllers of fixed order 3 whose bandwidth alpha grows without bound, not by
    controllers of growing order.

    Returns
    -------
    control.TransferFunction
        C(s), for the loop 1 + k P0 C (python-control's and hinfsyn's u = K y: K = -C).
    """
    if not 1 < ratio < (z / p) ** 2:
        raise ValueError(f"need 1 < ratio < (z/p)^2 = {(z / p) ** 2:g}, got {ratio!r}")
    c = 1 / (ratio - 1)
    g_p = (np.sqrt(ratio) - 1) / (np.sqrt(ratio) + 1)
    q = g_p * (p + z) / (p - z) * (p + alpha) / alpha
    if abs(q) >= 1:
        raise ValueError(f"alpha = {alpha!r} is too small for ratio {ratio!r} (|q| = {abs(q):.3g})")
    n_g = q * alpha * np.array([1.0, -z])
    d_g = np.polymul([1.0, z], [1.0, alpha])
    margin = np.polysub(d_g, n_g)
    R, _ = np.polydiv(np.polysub(np.polymul(margin, margin), 4 * c * np.polymul(n_g, d_g)),
                      [1.0, -p])
    num = 4 * c * q * alpha * np.polymul(np.polymul([1.0, z], [1.0, alpha]), [1.0, a])
    return ct.tf(num, R)


def complex_mu_bound(p, z, r):
    """Lower bound r (z + p)/(z - p) of complex mu for every stabilising controller.

    mu of the closed loop over [delta (complex), performance] is at least mu of its
    1 x 1 delta channel, r |T0|, whose peak is at least r (z + p)/(z - p)
    (Nevanlinna-Pick, :func:`gain_ratio_sup_complex`).
    """
    return r * (z + p) / (z - p)


def ratio_of_radius(rho):
    """k_hi / k_lo = (1 + rho)/(1 - rho) of the segment k0 (1 + rho delta), delta in [-1, 1]."""
    return (1 + rho) / (1 - rho)


def radius_of_ratio(ratio):
    """Relative radius r = (K - 1)/(K + 1) of an interval of ratio K = k_hi / k_lo."""
    return (ratio - 1) / (ratio + 1)


def gain_margin(p=1.0, z=2.0, a=1.0, k_lo=0.5, k_hi=1.5, eps=0.05):
    """P0(s) = (s - z)/((s - p)(s + a)) with an uncertain gain k in [k_lo, k_hi].

    The gain problem of [T80, KT85], [DFT92, Ch. 11]: one unstable pole p, one
    non-minimum-phase zero z > p.  No controller stabilises a gain ratio
    k_hi / k_lo >= (z/p)^2 (:func:`gain_ratio_sup_real`); treating the gain as a complex
    disc certifies at most z/p (:func:`gain_ratio_sup_complex`).  The defaults (p = 1,
    z = 2: bounds 4 and 2) ask for the ratio 3, between the two, so a real-mu design can
    certify it and a complex one cannot (its mu is at least 1.5, :func:`complex_mu_bound`).
    The stable pole -a only makes P0 strictly proper; it plays no role in either bound.

    k = k0 (1 + r delta) with k0 = (k_lo + k_hi)/2 and r = (k_hi - k_lo)/(k_hi + k_lo)
    acts at the plant input: u_p = k0 (u + w_delta), z_delta = r u, w_delta = delta
    z_delta.  hinfsyn needs D12 of full column rank (z_delta = r u gives it) and D21 of
    full row rank: the sensor noise eps n on y, seen by the performance output
    e = eps y_p (y_p the noise-free plant output).  With u = K y and S = 1/(1 - k0 P0 K)
    the closed loop is M = [[r T0, eps r K S], [eps k0 P0 S, eps^2 T0]] (T0 = k0 P0 K S):
    both regularising channels carry eps (default 0.05), so mu is dominated by the gain
    channel r T0 unless K S or P0 S is large.

    Realisation of P0 (controller form): A = [[0, 1], [a p, p - a]], B = [0; 1],
    C = [-z, 1]: C (sI - A)^-1 B = (s - z)/(s^2 + (a - p) s - a p).
    """
    if not z > p > 0 or a <= 0 or not 0 < k_lo < k_hi:
        raise ValueError("need z > p > 0, a > 0 and 0 < k_lo < k_hi")
    A = np.array([[0.0, 1.0], [a * p, p - a]])
    B = np.array([[0.0], [1.0]])
    C = np.array([[-z, 1.0]])
    k0 = (k_lo + k_hi) / 2
    r = (k_hi - k_lo) / (k_hi + k_lo)
    zero = np.zeros((1, 2))
    P = ct.ss(A, np.hstack([k0 * B, np.zeros((2, 1)), k0 * B]),
              np.vstack([zero, eps * C, C]),
              np.array([[0.0, 0.0, r], [0.0, 0.0, 0.0], [0.0, eps, 0.0]]),
              inputs=["w_delta", "n", "u"], outputs=["z_delta", "e", "y"])
    return GainMargin(ct.ss(A, B, C, 0), P, p, z, k_lo, k_hi, k0, r, eps,
                      [(-1, 0), (1, 1)], [(1, 1), (1, 1)])


def gain_T0(prob, K, omega):
    """T0(j omega) = k0 P0 K / (1 - k0 P0 K) at the nominal gain (u = K y), shape (nf,).

    The closed-loop map w_delta -> u of P is T0, so its uncertainty channel is r T0;
    |T0| is the usual complementary sensitivity's (the sign is the feedback convention's),
    T0(p) = -1 and T0(z) = 0 for every internally stabilising K.
    """
    L = prob.k0 * response(prob.P0, omega)[:, 0, 0] * response(K, omega)[:, 0, 0]
    return L / (1 - L)


def gain_loop(prob, K):
    """(A0, b, c, k0) with A(k) = A0 + (k - k0) b c the closed loop of k P0 and u = K y.

    Built from P0 and K alone (not from the LFT P): plant x' = A x + B k u, y = C x,
    controller x_K' = A_K x_K + B_K y, u = C_K x_K + D_K y (python-control's and
    hinfsyn's u = K y convention), so A(k) = [[A + k B D_K C, k B C_K], [B_K C, A_K]],
    affine in k with the rank-one slope [B; 0] [D_K C, C_K].
    """
    G, K = prob.P0, ct.ss(K)
    A, B, C = (np.asarray(m, float) for m in (G.A, G.B, G.C))
    Ak, Bk, Ck, Dk = (np.asarray(m, float) for m in (K.A, K.B, K.C, K.D))
    b = np.vstack([B, np.zeros((Ak.shape[0], 1))])
    c = np.hstack([Dk @ C, Ck])
    A_open = np.block([[A, np.zeros((A.shape[0], Ak.shape[0]))], [Bk @ C, Ak]])
    return A_open + prob.k0 * b @ c, b, c, prob.k0


# --- 7. ACC benchmark: two carts, uncertain spring [WB92] ---------------------------------

ACC_K_RANGE = (0.5, 2.0)     # the spring stiffness interval of [WB92] (m1 = m2 = 1)


class AccBenchmark(NamedTuple):
    """Generalized plant P of the two-cart benchmark with the spring as an LFT block.

    Inputs [w_delta, w, n, u], outputs [z_delta, z_x, z_u, y]; k = k0 + r delta.
    """
    P: ct.StateSpace
    k0: float
    r: float
    m1: float
    m2: float
    blk_mixed: list
    blk_complex: list


def acc_benchmark(k_range=ACC_K_RANGE, m1=1.0, m2=1.0, w_x=0.1, rho=0.1, sigma=0.1):
    """Two carts joined by a spring k in ``k_range`` [N/m], force u on cart 1, x2 measured.

    [WB92], problem 1: m1 = m2 = 1 kg, 0.5 <= k <= 2 N/m, noncollocated (actuator on
    cart 1, sensor on cart 2); the published answer is that controllers stabilising the
    whole interval exist (every design in the benchmark's special issue does; they are
    compared on effort and settling time, which [WB92] specifies for k = 1 only).  That
    is a yes/no statement, so a test can check it exactly (:func:`spring_loop`,
    :func:`real_stability_interval`) whatever digits a design has.

    States [x1, x2, v1, v2]; m1 v1' = k (x2 - x1) + u, m2 v2' = -k (x2 - x1) + w.  The
    spring k = k0 + r delta (k0 the midpoint, r the half width) is an LFT: z_delta =
    x2 - x1, and the force r w_delta (w_delta = delta z_delta) pushes cart 1 and pulls
    cart 2.  Performance block (last, 2 x 2): inputs [w (force on cart 2), n (sensor
    noise)], outputs [z_x = w_x x2, z_u = rho u]; y = x2 + sigma n.  D12 = [0; 0; rho]
    and D21 = [0, 0, sigma] have full rank; the rigid-body double integrator is
    stabilisable from u and detectable from x2.  The weights (0.1) are small so that mu
    is dominated by the spring: the test is about the stiffness range.  No controller's
    interval reaches below k = 0: there cart 2 (a free double integrator) is no longer
    driven by u, and its two poles at 0 stay in every closed loop.
    """
    k_lo, k_hi = k_range
    k0, r = (k_lo + k_hi) / 2, (k_hi - k_lo) / 2
    A = np.array([[0, 0, 1, 0], [0, 0, 0, 1],
                  [-k0 / m1, k0 / m1, 0, 0], [k0 / m2, -k0 / m2, 0, 0]], float)
    b_delta = np.array([[0], [0], [r / m1], [-r / m2]])
    b_w = np.array([[0], [0], [0], [1 / m2]])
    b_u = np.array([[0], [0], [1 / m1], [0]])
    c_delta = np.array([[-1.0, 1, 0, 0]])
    c_x2 = np.array([[0.0, 1, 0, 0]])
    B = np.hstack([b_delta, b_w, np.zeros((4, 1)), b_u])
    C = np.vstack([c_delta, w_x * c_x2, np.zeros((1, 4)), c_x2])
    D = np.zeros((4, 4))
    D[2, 3] = rho
    D[3, 2] = sigma
    P = ct.ss(A, B, C, D, inputs=["w_delta", "w", "n", "u"],
              outputs=["z_delta", "z_x", "z_u", "y"])
    return AccBenchmark(P, k0, r, m1, m2, [(-1, 0), (2, 2)], [(1, 1), (2, 2)])


def spring_loop(prob, K):
    """(A0, b, c, k0) with A(k) = A0 + (k - k0) b c the closed loop of the carts and u = K y.

    Built from the physical model (not from P): the spring adds (k - k0) (x2 - x1) to
    m1 v1' and subtracts it from m2 v2', a rank-one change b c of the state matrix with
    b = [0, 0, 1/m1, -1/m2, 0...], c = [-1, 1, 0, 0, 0...]; y = x2 (noise-free),
    u = C_K x_K + D_K y.
    """
    K = ct.ss(K)
    m1, m2, k0 = prob.m1, prob.m2, prob.k0
    A = np.array([[0, 0, 1, 0], [0, 0, 0, 1],
                  [-k0 / m1, k0 / m1, 0, 0], [k0 / m2, -k0 / m2, 0, 0]], float)
    B = np.array([[0], [0], [1 / m1], [0]])
    C = np.array([[0.0, 1, 0, 0]])
    Ak, Bk, Ck, Dk = (np.asarray(m, float) for m in (K.A, K.B, K.C, K.D))
    A0 = np.block([[A + B @ Dk @ C, B @ Ck], [Bk @ C, Ak]])
    nk = Ak.shape[0]
    b = np.vstack([[[0], [0], [1 / m1], [-1 / m2]], np.zeros((nk, 1))])
    c = np.hstack([[[-1.0, 1, 0, 0]], np.zeros((1, nk))])
    return A0, b, c, k0


# --- exact stability interval of a real parameter entering with rank one ------------------

def real_stability_interval(A0, b, c, grid=None):
    """Largest open interval (t_lo, t_hi) around 0 on which A0 + t b c is Hurwitz.

    A0 (n x n) must be Hurwitz; b (n x 1), c (1 x n).  For s = j w not an eigenvalue of
    A0, det(j w I - A0 - t b c) = det(j w I - A0) (1 - t g(j w)) with
    g(s) = c (sI - A0)^-1 b (matrix determinant lemma), so an eigenvalue reaches the
    imaginary axis exactly at t = 1/g(j w) for the w >= 0 where g(j w) is real and
    nonzero; the eigenvalues move continuously in t, so the interval ends at the
    crossing gains of smallest modulus on each side (+-inf if there is none).

    The frequencies where g(j w) is real are the imaginary-axis zeros of the odd function
    h(s) = g(s) - g(-s) = c (sI - A0)^-1 b + c (sI + A0)^-1 b, the finite eigenvalues of
    its Rosenbrock pencil (backward stable, no grid).  A log grid of w (``grid``,
    default 1e-4 ... 1e4 scaled by the spectral radius of A0) is scanned for sign
    changes of Im g(j w) as a second route; the union of both candidate sets is used
    (a spurious candidate can only shorten the interval, a missed one would lengthen
    it).  The pencil's candidates are polished by Newton steps on Im g(j w), the grid's
    brackets solved by Brent's method; a candidate counts where |Im g| <= 1e-9 |g|.
    """
    A0, b, c = (np.asarray(m, float) for m in (A0, b, c))
    n = A0.shape[0]
    if np.linalg.eigvals(A0).real.max() >= 0:
        raise ValueError("A0 must be Hurwitz (the nominal closed loop is unstable)")
    from scipy import linalg, optimize

    def g(w):
        return (c @ np.linalg.solve(1j * w * np.eye(n) - A0, b))[0, 0]

    def dg(w):          # d g(j w) / d w = -j c (j w I - A0)^-2 b
        x = np.linalg.solve(1j * w * np.eye(n) - A0, b)
        return (-1j * c @ np.linalg.solve(1j * w * np.eye(n) - A0, x))[0, 0]

    # Rosenbrock pencil of h: [[A_h - s I, B_h], [C_h, 0]]
    A_h = linalg.block_diag(A0, -A0)
    pencil_a = np.block([[A_h, np.vstack([b, b])], [np.hstack([c, c]), np.zeros((1, 1))]])
    pencil_b = linalg.block_diag(np.eye(2 * n), np.zeros((1, 1)))
    lam = linalg.eigvals(pencil_a, pencil_b)
    lam = lam[np.isfinite(lam)]
    scale = max(1.0, np.abs(np.linalg.eigvals(A0)).max())
    cands = [abs(x.imag) for x in lam if abs(x.real) <= 1e-6 * max(scale, abs(x))]
    if grid is None:
        grid = scale * np.logspace(-4, 4, 20001)
    crossings = [0.0]
    for w in cands:
        for _ in range(8):              # Newton on Im g(j w) = 0
            step = g(w).imag / dg(w).imag if dg(w).imag != 0 else 0.0
            if not np.isfinite(step):
                break
            w = abs(w - step)
            if abs(step) <= 1e-15 * max(1.0, w):
                break
        crossings.append(w)
    im = np.array([g(w).imag for w in grid])
    for i in np.nonzero(np.sign(im[:-1]) * np.sign(im[1:]) < 0)[0]:
        # a bracket keeps its root (Brent), whatever Newton did with the pencil's candidates
        crossings.append(optimize.brentq(lambda w: g(w).imag, grid[i], grid[i + 1],
                                         xtol=1e-15, rtol=4 * np.finfo(float).eps))
    gains = []
    for w in crossings:
        value = g(w)
        if abs(value.imag) <= 1e-9 * max(abs(value), 1e-300) and value.real != 0:
            gains.append(1.0 / value.real)
    gains = np.array(gains)
    t_hi = gains[gains > 0].min() if np.any(gains > 0) else np.inf
    t_lo = gains[gains < 0].max() if np.any(gains < 0) else -np.inf
    return float(t_lo), float(t_hi)


def stable_on_grid(A0, b, c, t):
    """Largest real part of the eigenvalues of A0 + t b c for every t in ``t`` (root locus)."""
    A0, b, c = (np.asarray(m, float) for m in (A0, b, c))
    return np.array([np.linalg.eigvals(A0 + ti * b @ c).real.max() for ti in np.atleast_1d(t)])


# --- independent evaluation of closed loops -----------------------------------------------

def pointwise_lft(P, K, omega):
    """F_l(P, K)(j omega) from P(j omega) and K(j omega), frequency by frequency.

    P11 + P12 K (I - P22 K)^-1 P21 needs no closed-loop realisation, so it is as
    accurate as the responses of P and K themselves, and those are evaluated by
    :func:`response` (componentwise accurate).  Shape (nf, p1, m1).
    """
    omega = np.asarray(omega, float)
    ny, nu = K.ninputs, K.noutputs
    Pw, Kw = response(P, omega), response(K, omega)
    P11, P12 = Pw[:, :-ny, :-nu], Pw[:, :-ny, -nu:]
    P21, P22 = Pw[:, -ny:, :-nu], Pw[:, -ny:, -nu:]
    closed = np.linalg.solve(np.eye(ny) - P22 @ Kw, P21)
    return P11 + P12 @ Kw @ closed


def response(sys, omega):
    """C (j omega I - A)^-1 B + D, shape (nf, p, m), with a componentwise small error.

    Gaussian elimination with one step of iterative refinement in working precision is
    componentwise backward stable (Skeel 1980), so the error is bounded by
    eps * :func:`response_condition`.  python-control's evaluation (after a Hessenberg
    reduction) is only normwise stable: on the distillation K-step's controller (two
    poles within rounding of each other) it was up to 1e-4 off, differently under every
    BLAS kernel, where this is 2e-11 to 6e-11 off.
    """
    sys = ct.ss(sys)
    A, B, C, D = (np.asarray(m, float) for m in (sys.A, sys.B, sys.C, sys.D))
    out = []
    for w in np.atleast_1d(np.asarray(omega, float)):
        M = 1j * w * np.eye(A.shape[0]) - A
        x = np.linalg.solve(M, B) if A.shape[0] else np.zeros((0, B.shape[1]))
        if A.shape[0]:
            x = x + np.linalg.solve(M, B - M @ x)
        out.append(C @ x + D)
    return np.array(out)


def response_condition(sys, omega):
    """Componentwise condition of C (j omega I - A)^-1 B + D against relative changes
    of the entries of A: max | |C R| |j omega I - A| |R B| | / max |response|,
    R = (j omega I - A)^-1 (first order)."""
    sys = ct.ss(sys)
    A, B, C, D = (np.asarray(m, float) for m in (sys.A, sys.B, sys.C, sys.D))
    M = 1j * float(omega) * np.eye(A.shape[0]) - A
    R = np.linalg.inv(M)
    value = C @ R @ B + D
    return float(np.abs(np.abs(C @ R) @ np.abs(M) @ np.abs(R @ B)).max() / np.abs(value).max())


def exact_response(sys, omega):
    """C (j omega I - A)^-1 B + D of a state-space model in exact rational arithmetic.

    The stored floating-point matrices are exact binary fractions, so this is the true
    response of the realisation as stored (rounded once at the end): a reference for
    closed loops whose floating-point evaluation is ill-conditioned.  Gaussian
    elimination on Gaussian rationals; fine for a few dozen states and a few frequencies.
    """
    A, B, C, D = (np.asarray(m, float) for m in (sys.A, sys.B, sys.C, sys.D))
    n, m = B.shape
    w = Fraction(float(omega))
    # complex numbers as (re, im) pairs of Fractions; rows of [j w I - A, B]
    rows = [[(Fraction(-A[i, j]), w if i == j else Fraction(0)) for j in range(n)]
            + [(Fraction(B[i, k]), Fraction(0)) for k in range(m)] for i in range(n)]

    def mul(x, y):
        return (x[0] * y[0] - x[1] * y[1], x[0] * y[1] + x[1] * y[0])

    def div(x, y):
        den = y[0] * y[0] + y[1] * y[1]
        return ((x[0] * y[0] + x[1] * y[1]) / den, (x[1] * y[0] - x[0] * y[1]) / den)

    for col in range(n):
        pivot = max(range(col, n), key=lambda r: abs(rows[r][col][0]) + abs(rows[r][col][1]))
        rows[col], rows[pivot] = rows[pivot], rows[col]
        for r in range(col + 1, n):
            if rows[r][col] == (0, 0):
                continue
            f = div(rows[r][col], rows[col][col])
            rows[r] = rows[r][:col] + [(x[0] - y[0], x[1] - y[1]) for x, y in
                                       zip(rows[r][col:], (mul(f, v) for v in rows[col][col:]))]
    X = [[None] * m for _ in range(n)]
    for k in range(m):
        for i in reversed(range(n)):
            acc = rows[i][n + k]
            for j in range(i + 1, n):
                t = mul(rows[i][j], X[j][k])
                acc = (acc[0] - t[0], acc[1] - t[1])
            X[i][k] = div(acc, rows[i][i])
    out = np.zeros((C.shape[0], m), complex)
    for i in range(C.shape[0]):
        for k in range(m):
            re = Fraction(D[i, k]) + sum(Fraction(C[i, j]) * X[j][k][0] for j in range(n))
            im = sum(Fraction(C[i, j]) * X[j][k][1] for j in range(n))
            out[i, k] = float(re) + 1j * float(im)
    return out


def with_effort_output(P, weight, nmeas, ncon):
    """P with ``weight`` * u appended to its performance outputs (hinfsyn's P_reg for D12)."""
    P = ct.ss(P)
    n, m = P.nstates, P.ninputs
    C = np.vstack([P.C[:-nmeas], np.zeros((ncon, n)), P.C[-nmeas:]])
    D = np.vstack([P.D[:-nmeas], np.hstack([np.zeros((ncon, m - ncon)), weight * np.eye(ncon)]),
                   P.D[-nmeas:]])
    return ct.ss(P.A, P.B, C, D)
