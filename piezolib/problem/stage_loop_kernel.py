"""The closed loop of a batch of virtual stages and a section controller, compiled.

:func:`closed_loop` runs the per-sample loop of
:class:`~piezolib.problem.stage_batch.StageBatchSimulation` fed by a
:class:`~piezolib.robust.export.SectionFilterBatch` (the loop every tracking
experiment runs) as one compiled function (numba).  Each operation is the one
the numpy path applies elementwise, in the same order and precision (float32
sections stay float32; no fused multiply-add, no reassociation), so the result
is identical, float for float, to the Python loop it replaces; the Python loop
costs about 0.5 ms per sample whatever the number of members, this one a few
nanoseconds per member and sample: each stage of a sample is a loop over the
members, which the compiler runs on vector registers (2.5x faster than one
member at a time on notebook 12's 200 members).

numba is imported on first use, and the compiled function is cached on disk
(``__pycache__``), so a process that never runs a closed loop does not pay for
it and the compilation (a few seconds) happens once per machine.
"""

import functools

import numpy as np

from piezolib._checks import check_bool, check_integer, check_mapping, check_positive, check_real

__all__ = ["closed_loop"]

#: The entries of ``stage`` (:meth:`StageBatchSimulation.run_sections_loop`).
_STAGE_KEYS = ("dac", "adc", "gain", "amp", "out_lo", "out_hi", "has_plays", "r", "w", "w0",
               "plays", "b0", "b1", "a1", "z", "noise", "log", "v_y")


@functools.cache
def _kernel():
    """The compiled loop (numba imported and the function compiled or loaded once)."""
    import numba

    # a module global, not a closure cell: numba keys a cached function on the pickled
    # contents of its closure, and a dispatcher pickles differently in every process, so a
    # closure over it missed the disk cache and recompiled the loop in every kernel (3-4 s)
    global _convert

    @numba.njit(cache=True, nogil=True)
    def _convert(v, lsb, code_lo, code_hi):
        # _Converter.convert_scalar: round half to even, limit the code, back to volts
        out = np.rint(v / lsb)
        out = max(out, code_lo)
        return min(out, code_hi) * lsb

    @numba.njit(cache=True, nogil=True)
    def loop(v_r, u_f, delay, dac, adc, gain, amp, out_lo, out_hi,
             has_plays, r, w, w0, plays, b0, b1, a1, z, noise, log, coef, s, v_y0,
             u_b, diverged_v):
        # each stage of the sample is one loop over the members (innermost, contiguous):
        # the compiler runs it on vector registers, each member's operations in the order
        # of the Python loop (no reassociation), so the result is the same float for float
        n, N = v_r.shape[0], v_y0.shape[0]
        order, n_plays, n_sec = z.shape[0], r.shape[0], coef.shape[0]
        v_y = v_y0.copy()
        v = np.empty(N, coef.dtype)         # the error in the sections' precision, then y
        y = np.empty(N, coef.dtype)
        v_a = np.empty(N)
        v_h = np.empty(N)
        y_k = np.empty(N)
        x_in = np.empty(N)
        z_new = np.empty(N)
        limit = diverged_v * diverged_v
        for k in range(n):
            # the controller: sections in their precision, one after the other
            for i in range(N):
                v[i] = v_r[k] - v_y[i]
            for q in range(n_sec):
                c0, c1, c2, c4, c5 = coef[q, 0], coef[q, 1], coef[q, 2], coef[q, 4], coef[q, 5]
                for i in range(N):
                    y[i] = c0 * v[i] + s[0, q, i]
                for i in range(N):
                    s1 = (c1 * v[i] - c4 * y[i]) + s[1, q, i]
                    s[1, q, i] = c2 * v[i] - c5 * y[i]
                    s[0, q, i] = s1
                    v[i] = y[i]
            total = 0.0
            for i in range(N):
                u_b[k, i] = np.float64(v[i])
                total += u_b[k, i] * u_b[k, i]
            if not total < limit:
                return k
            # the stage: u_c = u_f + u_b (delayed), DAC, amplifier, plays, plant, ADC
            for i in range(N):
                ub = u_b[k - delay, i] if k >= delay else 0.0
                u_c = u_f[k] + ub
                u_dac = _convert(u_c, dac[0], dac[1], dac[2])
                v_cmd = u_dac * gain
                log[0, k, i], log[1, k, i], log[2, k, i] = u_c, u_dac, v_cmd
                v_a[i] = v_cmd
                if amp:
                    v_a[i] = min(max(v_cmd, out_lo), out_hi)
                    log[3, k, i] = v_a[i]
            if has_plays:
                for i in range(N):
                    v_h[i] = w0[i] * v_a[i]
                for p in range(n_plays):
                    for i in range(N):
                        lo, hi = v_a[i] + (-r[p, i]), v_a[i] + r[p, i]
                        plays[p, i] = min(max(plays[p, i], lo), hi)
                        v_h[i] = v_h[i] + (plays[p, i] - r[p, i]) * w[p, i]
            else:
                for i in range(N):
                    v_h[i] = v_a[i]
            for i in range(N):
                x_in[i] = v_h[i] / gain
                y_k[i] = z[0, i] + b0[i] * x_in[i]
            # z_new[m] = x_in b1[m] + z[m + 1] - y_k a1[m], in place from m = 0 upwards
            # (z[m + 1] is read before it is overwritten)
            for m in range(order):
                for i in range(N):
                    z_new[i] = x_in[i] * b1[m, i]
                    if m < order - 1:
                        z_new[i] = z_new[i] + z[m + 1, i]
                    z[m, i] = z_new[i] - y_k[i] * a1[m, i]
            for i in range(N):
                analog = z[0, i] + noise[k + 1, i]
                log[4, k, i] = y_k[i]
                log[5, k + 1, i] = analog
                v_y[i] = _convert(analog, adc[0], adc[1], adc[2])
                log[6, k + 1, i] = v_y[i]
        return -1

    return loop


def closed_loop(v_r, u_f, delay, stage, sections, u_b, diverged_v):
    """Run the loop of :func:`piezolib.workbook.loop.run_loop` over all samples.

    Parameters
    ----------
    v_r, u_f : ndarray, shape (n,)
        Reference and feedforward [V], float64.
    delay : int
        Samples between the controller output and the stage input.
    stage : dict
        The batch simulation's coefficients and states (arrays updated in place;
        :meth:`StageBatchSimulation._compiled_state`).
    sections : tuple
        ``(coef, s)``: the (n_sections, 6) coefficients and the (2, n_sections, N)
        states of a :class:`~piezolib.robust.export.SectionFilterBatch`, in its
        precision (``s`` updated in place).
    u_b : ndarray, shape (n, N)
        Filled with the controller outputs [V].
    diverged_v : float
        The loop stops when the root sum of squares of the members' outputs
        reaches this [V].

    Returns
    -------
    int
        -1, or the sample at which the outputs diverged (u_b filled up to it).

    Raises
    ------
    TypeError, ValueError
        Naming the argument (or the entry of ``stage``): an array of another type,
        precision or shape than the loop indexes (it checks no bounds).
    """
    _check_arguments(v_r, u_f, delay, stage, sections, u_b, diverged_v)
    coef, s = sections
    return _kernel()(v_r, u_f, delay, stage["dac"], stage["adc"], stage["gain"],
                     stage["amp"], stage["out_lo"], stage["out_hi"], stage["has_plays"],
                     stage["r"], stage["w"], stage["w0"], stage["plays"], stage["b0"],
                     stage["b1"], stage["a1"], stage["z"], stage["noise"], stage["log"],
                     coef, s, stage["v_y"], u_b, float(diverged_v))


def _check_array(name, x, shape, dtypes=(np.float64,), min_rows=None):
    """``x`` as the compiled loop indexes it (it checks no bounds): an ndarray of one of
    ``dtypes`` and ``shape`` (None: any size), with at least ``min_rows`` rows."""
    if not isinstance(x, np.ndarray) or x.dtype not in dtypes:
        got = f"dtype {x.dtype}" if isinstance(x, np.ndarray) else type(x).__name__
        want = " or ".join(np.dtype(d).name for d in dtypes)
        raise TypeError(f"{name} must be a {want} ndarray, got {got}")
    if x.ndim != len(shape) or any(w is not None and w != g for w, g in zip(shape, x.shape)) \
            or (min_rows is not None and x.shape[0] < min_rows):
        want = tuple("any" if w is None else w for w in shape)
        rows = f" with at least {min_rows} rows" if min_rows is not None else ""
        raise ValueError(f"{name} must have shape {want}{rows}, got {x.shape}")
    return x


def _check_arguments(v_r, u_f, delay, stage, sections, u_b, diverged_v):
    """Types and shapes of :func:`closed_loop`'s arguments, naming the one that is wrong."""
    n = _check_array("v_r", v_r, (None,)).shape[0]
    _check_array("u_f", u_f, (n,))
    check_integer("delay", delay, minimum=0)
    check_mapping("stage", stage)
    missing = [key for key in _STAGE_KEYS if key not in stage]
    if missing:
        raise ValueError(f"stage lacks {missing} (StageBatchSimulation.run_sections_loop)")
    N = _check_array("stage['v_y']", stage["v_y"], (None,)).shape[0]
    order = _check_array("stage['z']", stage["z"], (None, N)).shape[0]
    n_plays = _check_array("stage['r']", stage["r"], (None, N)).shape[0]
    shapes = {"dac": (3,), "adc": (3,), "w": (n_plays, N), "plays": (n_plays, N),
              "w0": (N,), "b0": (N,), "b1": (order, N), "a1": (order, N)}
    for key, shape in shapes.items():
        _check_array(f"stage[{key!r}]", stage[key], shape)
    _check_array("stage['noise']", stage["noise"], (None, N), min_rows=n + 1)
    _check_array("stage['log']", stage["log"], (7, None, N))
    if stage["log"].shape[1] < n + 1:
        raise ValueError(f"stage['log'] must hold at least {n + 1} samples, got "
                         f"{stage['log'].shape[1]}")
    for key in ("amp", "has_plays"):
        check_bool(f"stage[{key!r}]", stage[key])
    for key in ("gain", "out_lo", "out_hi"):
        check_real(f"stage[{key!r}]", stage[key])
    if not isinstance(sections, tuple) or len(sections) != 2:
        raise TypeError("sections must be the pair (coefficients, states) of "
                        f"SectionFilterBatch.arrays, got {type(sections).__name__}")
    coef = _check_array("sections[0]", sections[0], (None, 6), (np.float32, np.float64))
    _check_array("sections[1]", sections[1], (2, coef.shape[0], N), (coef.dtype,))
    _check_array("u_b", u_b, (n, N))
    check_positive("diverged_v", diverged_v)
