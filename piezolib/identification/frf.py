"""Nonparametric MIMO frequency response (best linear approximation) from periodic multisines.

The robust method for periodic excitations: the records hold ``R``
realisations of a random-phase multisine, each measured over ``P`` steady-state
periods of ``N`` samples.  With ``n_u`` inputs the realisations come in groups
of ``n_u`` whose input spectra, as an ``n_u x n_u`` matrix U(k) per excited
line k (column = realisation), are invertible (orthogonal multisines make them
optimally conditioned).  Per group the frequency response matrix (FRM) is
G_m(k) = Y_m(k) U_m(k)^-1 from the period-averaged spectra; the best linear
approximation (BLA) is the mean of the groups' FRMs.  Two variances come with
it, per input-output entry and line:

* the noise variance, from the spread of the FRMs computed period by period
  (what changes from one period to the next of one realisation is noise);
* the total variance, from the spread of the FRMs over the groups (which also
  changes with the random phases, through the nonlinear distortions).

Their difference estimates the variance of the stochastic nonlinear
distortions; with a linear system it is zero up to estimation error.  Every
variance is that of the *averaged* BLA (already divided by the number of
periods or groups).  Only the excited lines are used: :func:`excited_lines`
finds them in the input spectrum.

Frequencies are in Hz (``frequency_Hz``); ``G`` has the unit of the output
over the unit of the input (e.g. m/V).

Examples
--------
Two orthogonal multisines on a static 2 x 2 gain give it back exactly:

>>> import numpy as np
>>> N, lines = 64, np.arange(1, 10)
>>> rng = np.random.default_rng(1)
>>> X = np.zeros((N, 2), complex)
>>> X[lines] = np.exp(2j * np.pi * rng.random((lines.size, 2)))
>>> x = np.fft.irfft(X[:N // 2 + 1], n=N, axis=0)                   # (N, 2): one multisine each
>>> T = np.array([[1.0, 1.0], [1.0, -1.0]])                          # orthogonal mixing
>>> u = np.einsum("nc,cr->ncr", x, T)                                # (N, 2 inputs, 2 realisations)
>>> u = np.concatenate([u, -u], axis=2)[..., None].repeat(2, axis=3)  # 2 groups, 2 periods
>>> gain = np.array([[2.0, 0.5], [0.0, -1.0]])
>>> y = np.einsum("ij,njrp->nirp", gain, u) + 1e-9 * rng.standard_normal(u.shape)
>>> bla = bla_periodic(u, y, fs=100.0)
>>> bla.G.shape, bool(np.allclose(bla.G, gain[:, :, None], atol=1e-6))
((2, 2, 9), True)
"""

from dataclasses import dataclass

import control as ct
import numpy as np

from piezolib._checks import check_finite_array, check_positive

__all__ = ["BLA", "excited_lines", "bla_periodic"]

#: Largest condition number of a group's input matrix U_m(k) accepted by
#: :func:`bla_periodic` (orthogonal multisines give 1).
MAX_CONDITION = 1e8


@dataclass(frozen=True)
class BLA:
    """Best linear approximation of a MIMO system on the excited lines.

    Attributes
    ----------
    frequency_Hz : ndarray, shape (F,)
        Frequencies of the excited lines [Hz].
    lines : ndarray of int, shape (F,)
        Their DFT line numbers (frequency = line * fs / N).
    fs : float
        Sampling frequency [Hz].
    G : ndarray of complex, shape (n_y, n_u, F)
        The BLA [output unit / input unit].
    G_groups : ndarray of complex, shape (M, n_y, n_u, F)
        The FRM of each group of realisations.
    var_noise : ndarray, shape (n_y, n_u, F)
        Variance of ``G`` due to the measurement noise (periods' spread).
    var_total : ndarray, shape (n_y, n_u, F)
        Variance of ``G`` due to noise and nonlinear distortion (groups' spread).
    n_periods, n_groups : int
        Periods P and groups M the estimates come from.

    Examples
    --------
    >>> N, lines = 64, np.arange(1, 11)                # 10 lines of a 64-sample period
    >>> rng = np.random.default_rng(0)
    >>> u = np.zeros((N, 1, 2, 2))                      # N, n_u, R = 2 realisations, P = 2 periods
    >>> for r in range(2):
    ...     phases = rng.uniform(0, 2 * np.pi, lines.size)
    ...     u[:, 0, r, :] = np.cos(2 * np.pi * np.outer(np.arange(N), lines) / N + phases).sum(1)[:, None]
    >>> y = 0.5 * u + 0.5 * np.roll(u, 1, axis=0)       # y[k] = (u[k] + u[k-1]) / 2, periodic
    >>> b = bla_periodic(u, y, fs=64.0)
    >>> b.frequency_Hz[:3], b.lines[:3]
    (array([1., 2., 3.]), array([1, 2, 3]))
    >>> bool(b.std_total.max() < 1e-12), b.frd().ninputs        # linear, noise free
    (True, 1)
    """

    frequency_Hz: np.ndarray
    lines: np.ndarray
    fs: float
    G: np.ndarray
    G_groups: np.ndarray
    var_noise: np.ndarray
    var_total: np.ndarray
    n_periods: int
    n_groups: int

    @property
    def var_distortion(self):
        """Variance of ``G`` due to the nonlinear distortions: total - noise, clipped at 0."""
        return np.maximum(self.var_total - self.var_noise, 0.0)

    @property
    def std_noise(self):
        """Standard deviation of ``G`` due to noise, shape (n_y, n_u, F)."""
        return np.sqrt(self.var_noise)

    @property
    def std_total(self):
        """Standard deviation of ``G`` due to noise and distortion, shape (n_y, n_u, F)."""
        return np.sqrt(self.var_total)

    @property
    def std_distortion(self):
        """Standard deviation of ``G`` due to the nonlinear distortions, shape (n_y, n_u, F)."""
        return np.sqrt(self.var_distortion)

    def frd(self, input_labels=None, output_labels=None):
        """The BLA as a :class:`control.FrequencyResponseData` (frequencies in rad/s).

        Parameters
        ----------
        input_labels, output_labels : list of str, optional
            Signal names (default ``u[i]``, ``y[i]``).
        """
        n_y, n_u, _ = self.G.shape
        return ct.frd(self.G, 2 * np.pi * self.frequency_Hz,
                      inputs=_labels("input_labels", input_labels, n_u, "u"),
                      outputs=_labels("output_labels", output_labels, n_y, "y"))


def _labels(name, labels, count, stem):
    """``count`` distinct signal names (default ``stem[i]``)."""
    if labels is None:
        return [f"{stem}[{i}]" for i in range(count)]
    if isinstance(labels, str) or not all(isinstance(x, str) for x in labels):
        raise TypeError(f"{name} must be a list of {count} signal names (str), got {labels!r}")
    labels = list(labels)
    if len(labels) != count or len(set(labels)) != count:
        raise ValueError(f"{name} must name each of the {count} signals once, got {labels}")
    return labels


def _as_periodic(name, x, ndim_min=2):
    """``x`` as an array (N, channels, R, P) of real samples."""
    x = check_finite_array(name, x, real=True)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim == 2:
        x = x[:, :, None]
    if x.ndim == 3:
        x = x[:, :, :, None]
    if x.ndim != 4:
        raise ValueError(f"{name} must have shape (N, channels, realisations, periods), "
                         f"got {x.ndim} dimensions")
    if x.shape[0] < 4 or min(x.shape) < 1:
        raise ValueError(f"{name} must have at least 4 samples per period, got shape {x.shape}")
    return x


def excited_lines(u, relative_threshold=1e-3):
    """DFT lines excited by a periodic input, found in its spectrum.

    Parameters
    ----------
    u : array_like, shape (N, ...)
        One period (or, along further axes, several periods, channels and
        realisations) of the input; axis 0 is time.
    relative_threshold : float, optional
        A line is excited when its power (summed over channels, realisations
        and periods) exceeds this fraction of the largest line's power.
        Measured inputs carry noise on every line: the default, -30 dB, sits
        well above such noise and well below a flat multisine's lines.

    Returns
    -------
    ndarray of int
        Line numbers 1 .. N//2 (DC excluded), ascending.

    Examples
    --------
    >>> import numpy as np
    >>> n = np.arange(64)
    >>> excited_lines(np.cos(2 * np.pi * 3 * n / 64) + 0.5 * np.sin(2 * np.pi * 7 * n / 64))
    array([3, 7])
    """
    u = check_finite_array("u", u, real=True)
    if u.ndim < 1 or u.shape[0] < 4:
        raise ValueError(f"u must have at least 4 samples along axis 0, got shape {u.shape}")
    relative_threshold = check_positive("relative_threshold", relative_threshold)
    if relative_threshold >= 1:
        raise ValueError(f"relative_threshold must be below 1, got {relative_threshold}")
    spectrum = np.fft.rfft(u, axis=0)
    power = np.sum(np.abs(spectrum.reshape(spectrum.shape[0], -1)) ** 2, axis=1)
    power[0] = 0.0
    if power.max() <= 0:
        raise ValueError("u excites no line: it is constant")
    return np.flatnonzero(power > relative_threshold * power.max())


def bla_periodic(u, y, fs, lines=None, relative_threshold=1e-3):
    """Best linear approximation with noise and distortion variances (robust method).

    Parameters
    ----------
    u : array_like, shape (N, n_u, R, P)
        Input samples: N per period, n_u channels, R realisations, P
        steady-state periods (transients already removed).  R must be a
        multiple of n_u: realisations ``m*n_u .. (m+1)*n_u - 1`` form group m,
        whose input matrix must be invertible on every excited line
        (orthogonal multisines).
    y : array_like, shape (N, n_y, R, P)
        Output samples, same N, R and P.
    fs : float
        Sampling frequency [Hz].
    lines : array_like of int, optional
        DFT lines to use (1 .. N//2); default :func:`excited_lines` of ``u``.
    relative_threshold : float, optional
        Passed to :func:`excited_lines` when ``lines`` is not given.

    Returns
    -------
    BLA

    Raises
    ------
    ValueError
        Fewer than 2 periods or 2 groups (neither variance could be
        estimated), R not a multiple of n_u, shapes that do not match, or a
        group's input matrix singular on a line (condition number above
        :data:`MAX_CONDITION`).

    Examples
    --------
    >>> N, lines = 64, np.arange(1, 11)                # 10 lines of a 64-sample period
    >>> rng = np.random.default_rng(0)
    >>> u = np.zeros((N, 1, 2, 2))                      # N, n_u, R = 2 realisations, P = 2 periods
    >>> for r in range(2):
    ...     phases = rng.uniform(0, 2 * np.pi, lines.size)
    ...     u[:, 0, r, :] = np.cos(2 * np.pi * np.outer(np.arange(N), lines) / N + phases).sum(1)[:, None]
    >>> y = 0.5 * u + 0.5 * np.roll(u, 1, axis=0)       # y[k] = (u[k] + u[k-1]) / 2, periodic
    >>> b = bla_periodic(u, y, fs=64.0)
    >>> b.G.shape, b.n_periods, b.n_groups
    ((1, 1, 10), 2, 2)
    >>> bool(np.allclose(b.G[0, 0], 0.5 + 0.5 * np.exp(-2j * np.pi * lines / N)))
    True
    """
    u = _as_periodic("u", u)
    y = _as_periodic("y", y)
    fs = check_positive("fs", fs)
    N, n_u, R, P = u.shape
    if y.shape[0] != N or y.shape[2:] != (R, P):
        raise ValueError(f"y must have shape ({N}, n_y, {R}, {P}) like u, got {y.shape}")
    if P < 2:
        raise ValueError(f"u must hold at least 2 periods (last axis) for the noise variance, "
                         f"got {P}")
    if R % n_u or R // n_u < 2:
        raise ValueError(f"u must hold a multiple of n_u = {n_u} realisations, at least 2 groups "
                         f"(axis 2), got {R}")
    if lines is None:
        lines = excited_lines(u, relative_threshold)
    else:
        lines = check_finite_array("lines", lines, ndim=1, min_length=1, real=True)
        if np.any(lines != np.round(lines)) or lines.min() < 1 or lines.max() > N // 2:
            raise ValueError(f"lines must be integers in 1 .. {N // 2}")
        lines, counts = np.unique(lines.astype(int), return_counts=True)
        if np.any(counts > 1):          # a repeated line would count twice in every mean
            raise ValueError(f"lines must name each DFT line once, got "
                             f"{lines[counts > 1].tolist()} more than once")
    M = R // n_u
    U = np.fft.rfft(u, axis=0)[lines]                   # (F, n_u, R, P)
    Y = np.fft.rfft(y, axis=0)[lines]                   # (F, n_y, R, P)
    F, n_y = lines.size, y.shape[1]
    G_groups = np.empty((M, n_y, n_u, F), complex)
    var_noise = np.empty((M, n_y, n_u, F))
    for m in range(M):
        cols = slice(m * n_u, (m + 1) * n_u)
        Um, Ym = U[:, :, cols], Y[:, :, cols]           # (F, n_u, n_u, P), (F, n_y, n_u, P)
        Ubar, Ybar = Um.mean(axis=3), Ym.mean(axis=3)
        cond = np.linalg.cond(Ubar)
        if not np.all(cond < MAX_CONDITION):
            k = int(np.argmax(np.where(np.isfinite(cond), cond, np.inf)))
            raise ValueError(f"u: the input matrix of group {m} (realisations {m * n_u}.."
                             f"{(m + 1) * n_u - 1}) is singular at line {lines[k]} (condition "
                             f"{cond[k]:.3g}): the realisations are not orthogonal multisines")
        G_groups[m] = _frm(Ubar, Ybar)
        per_period = np.stack([_frm(Um[..., p], Ym[..., p]) for p in range(P)])
        dev = per_period - per_period.mean(axis=0)
        var_noise[m] = np.sum(np.abs(dev) ** 2, axis=0) / (P - 1) / P
    G = G_groups.mean(axis=0)
    var_total = np.sum(np.abs(G_groups - G) ** 2, axis=0) / (M - 1) / M
    return BLA(frequency_Hz=lines * fs / N, lines=lines, fs=fs, G=G, G_groups=G_groups,
               var_noise=var_noise.mean(axis=0) / M, var_total=var_total, n_periods=P,
               n_groups=M)


def _frm(U, Y):
    """G = Y U^-1 per line: U (F, n_u, n_u), Y (F, n_y, n_u) -> G (n_y, n_u, F)."""
    # G U = Y  <=>  U^T G^T = Y^T
    Gt = np.linalg.solve(np.swapaxes(U, 1, 2), np.swapaxes(Y, 1, 2))   # (F, n_u, n_y)
    return np.transpose(Gt, (2, 1, 0))
