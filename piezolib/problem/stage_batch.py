"""N virtual stages run at once: one state array of shape (N,) per state.

A loop over noise seeds (the 95 % intervals of Tables 4-5) or over the
members of a model set runs N stages through the same arithmetic; side by
side, a step of 32 members costs about three times one member's step
(``benchmarks/bench_loop_seeds.py``).  Running members at once is this
module's one concern: :class:`StageBatch` (the members, their
whole-record run), :class:`StageBatchSimulation` (their sample-by-sample run)
and :func:`check_seeds` (the seeds that name the members).  Member i of a batch
gives, float for float, the record that :class:`~piezolib.problem.stage.VirtualStage`
i gives alone: the single stage, :mod:`piezolib.problem.stage`, is what this
module builds on, and it knows nothing of batches.  So a batch is made here,
from a stage: :meth:`StageBatch.of_seeds` (one stage, N noise seeds) and
:meth:`StageBatch.over_model_set` (one stage per member of a model set); as
methods of the stage they would make the two modules import each other.
"""

import numbers
import warnings
from collections.abc import Iterable
from dataclasses import replace

import numpy as np

from piezolib._checks import check_finite_array, check_integer, check_type
from piezolib.problem import paper
from piezolib.problem.stage import (Saturation, StageRecord, StageSaturationWarning,
                                    StageSimulation, VirtualStage)

__all__ = ["StageBatch", "StageBatchSimulation", "check_seeds"]


def check_seeds(seeds, min_count=1, name="seeds", why=None):
    """Return ``seeds`` as a tuple of distinct non-negative ints.

    Parameters
    ----------
    seeds : sequence of int
        Noise seeds (Python or numpy integers; not bool).
    min_count : int
        Fewest seeds accepted.
    name : str
        Argument name used in the error messages.
    why : str, optional
        Reason for ``min_count``, appended to its error message.

    Returns
    -------
    tuple of int

    Raises
    ------
    ValueError
        ``seeds`` is not a sequence, holds fewer than ``min_count`` seeds, a
        non-integer, a negative or a repeated seed.
    """
    if isinstance(seeds, (str, bytes)) or not isinstance(seeds, Iterable):
        raise ValueError(f"{name} must be a sequence of non-negative integers, got {seeds!r}")
    seeds = list(seeds)
    if len(seeds) < min_count:
        raise ValueError(f"{name} must hold at least {min_count} seed(s), got {len(seeds)}"
                         + (f": {why}" if why else ""))
    out = []
    for s in seeds:
        if isinstance(s, bool) or not isinstance(s, numbers.Integral):
            raise ValueError(f"{name} must be integers, got {s!r}")
        if s < 0:
            raise ValueError(f"{name} must be non-negative, got {int(s)}")
        out.append(int(s))
    repeated = sorted({s for s in out if out.count(s) > 1})
    if repeated:
        raise ValueError(f"{name} must be distinct, got {repeated} more than once")
    return tuple(out)


class StageBatch:
    """N virtual stages run side by side: one state array of shape (N,) per state.

    Each member is a :class:`VirtualStage`; the batch runs them with the
    arithmetic of :meth:`VirtualStage.run` (:meth:`run`) and of
    :class:`StageSimulation` (:meth:`start`) applied elementwise, so member i
    of a batch gives, float for float, the record that ``stages[i]`` gives
    alone.  Typical use: one stage with N noise seeds
    (:meth:`of_seeds`), or those plus the noise-free stage.

    Parameters
    ----------
    stages : sequence of VirtualStage
        The members, N >= 1.  They may differ in the seed, the sensor noise,
        the plant (of one order) and the hysteresis (the same number of plays,
        or none in every member); they must share the sample rate, the
        amplifier (gain, output limits) and the converters.

    Attributes
    ----------
    stages : tuple of VirtualStage
    size : int
        N.
    seeds : tuple of int
        The members' noise seeds.
    fs, gain : float
        Sample rate [Hz] and amplifier gain [V/V] (shared).
    b, a : ndarray, shape (N, order + 1)
        The members' direct-form plant coefficients (rows, read-only).
    noise_rms_V : ndarray, shape (N,)
        The members' sensor noise [V rms].
    thresholds_V, weights : ndarray, shape (N, n_plays) or None
        The members' play thresholds [V] and weights (None: linear stages).
    linear_weight : ndarray, shape (N,) or None
        The members' w0.

    Examples
    --------
    >>> batch = StageBatch.of_seeds(VirtualStage(), [0, 1, 2])
    >>> records = batch.run(np.full(1000, 1.0))    # one StageRecord per member
    >>> sim = batch.start()
    >>> v_y = sim.v_y_V                            # shape (3,)
    >>> for k in range(1000):
    ...     v_y = sim.step(1.0 + 0.5 * (1.0 - v_y))
    >>> records = sim.records()
    >>> len(records), len(records[0].t_s)
    (3, 1000)
    """

    def __init__(self, stages):
        if isinstance(stages, VirtualStage) or not isinstance(stages, Iterable):
            raise TypeError("stages must be a sequence of VirtualStage, got "
                            f"{type(stages).__name__}")
        stages = tuple(stages)
        if not stages:
            raise ValueError("stages must hold at least one VirtualStage")
        for i, st in enumerate(stages):
            if not isinstance(st, VirtualStage):
                raise TypeError(f"stages[{i}] must be a VirtualStage, got {type(st).__name__}")
        first = stages[0]

        def shared(st):
            return (st.fs, st.gain, st.out_lo, st.out_hi, st.dac.lo, st.dac.hi, st.dac.lsb,
                    st.adc.lo, st.adc.hi, st.adc.lsb)

        for i, st in enumerate(stages[1:], 1):
            if shared(st) != shared(first):
                raise ValueError(f"stages must share the sample rate, the amplifier and the "
                                 f"converters; stages[{i}] differs from stages[0]")
            if len(st.a) != len(first.a):
                raise ValueError(f"stages must have plants of one order; stages[{i}] has "
                                 f"order {len(st.a) - 1}, stages[0] {len(first.a) - 1}")
            if (st.hysteresis is None) != (first.hysteresis is None) or (
                    st.hysteresis is not None
                    and len(st.hysteresis.thresholds_V) != len(first.hysteresis.thresholds_V)):
                raise ValueError(f"stages must all have hysteresis with the same number of "
                                 f"plays, or none; stages[{i}] differs from stages[0]")
        self.stages = stages
        self.size = len(stages)
        self.seeds = tuple(st.seed for st in stages)
        self.fs, self.gain = first.fs, first.gain
        self.dac, self.adc = first.dac, first.adc
        self.out_lo, self.out_hi = first.out_lo, first.out_hi
        self.b = _read_only(np.array([st.b for st in stages], dtype=float))
        self.a = _read_only(np.array([st.a for st in stages], dtype=float))
        self.noise_rms_V = _read_only(np.array([st.noise_rms for st in stages], dtype=float))
        if first.hysteresis is None:
            self.thresholds_V = self.weights = self.linear_weight = None
        else:
            hs = [st.hysteresis for st in stages]
            self.thresholds_V = _read_only(np.array([h.thresholds_V for h in hs]))
            self.weights = _read_only(np.array([h.weights for h in hs]))
            self.linear_weight = _read_only(np.array([h.linear_weight for h in hs]))

    def __len__(self):
        return self.size

    def __repr__(self):
        return f"StageBatch(size={self.size}, seeds={list(self.seeds)})"

    @classmethod
    def of_seeds(cls, stage, seeds):
        """N copies of ``stage`` that differ only in the noise seed.

        Parameters
        ----------
        stage : VirtualStage
        seeds : sequence of int
            Distinct non-negative noise seeds, one per member (N >= 1).

        Returns
        -------
        StageBatch
            Member i is ``stage.replace(seed=seeds[i])``.
        """
        check_type("stage", stage, VirtualStage, "a VirtualStage")
        return cls([stage.replace(seed=s) for s in check_seeds(seeds)])

    @classmethod
    def over_model_set(cls, stage, mset, seeds=None):
        """One copy of ``stage`` per member of a model set, as a batch.

        Member k has the exact ZOH model of ``mset``'s member k as its linear
        dynamics (:func:`piezolib.uncertainty.sampled.member_zoh_coefficients`,
        all members in one batched call) and everything else of ``stage``:
        hysteresis, amplifier, converters, noise level.  Members may be
        unstable on their own (``unstable_plant_ok``): run them in a loop
        that stabilises them.

        Parameters
        ----------
        stage : VirtualStage
        mset : piezolib.uncertainty.ModelSet
            Perturbations of the stage's plant (``mset.plant`` is normally
            ``stage.settings.plant``; any plant of the same order works).
        seeds : sequence of int, optional
            One noise seed per member; default: the stage's seed for every
            member (the same noise, so that members differ by their plant
            only).

        Returns
        -------
        StageBatch
        """
        from piezolib.uncertainty.modelset import check_model_set
        from piezolib.uncertainty.sampled import member_zoh_coefficients

        check_type("stage", stage, VirtualStage, "a VirtualStage")
        check_model_set(mset)
        if seeds is None:
            seeds = [stage.seed] * mset.size
        else:
            seeds = [check_integer("seeds[i]", s, minimum=0) for s in seeds]
            if len(seeds) != mset.size:
                raise ValueError(f"seeds must hold one seed per member ({mset.size}), got "
                                 f"{len(seeds)}")
        b, a = member_zoh_coefficients(mset, 1.0 / stage.fs)
        members = []
        for k, seed in enumerate(seeds):
            new = object.__new__(VirtualStage)
            new.__dict__.update(stage.__dict__)
            new.settings = replace(stage.settings, plant=mset.member(k), unstable_plant_ok=True)
            new.seed, new.b, new.a = seed, b[k], a[k]
            members.append(new)
        return cls(members)

    def run(self, u_c):
        """Apply one sampled control input to every member (open loop).

        The noise-free part (DAC, amplifier, hysteresis, G) is computed once
        for members that share the plant and the hysteresis; each member
        then adds its own noise and is converted by the ADC.

        Parameters
        ----------
        u_c : array_like
            Control input [V] at the sample rate, 1-D (the same for every
            member).

        Returns
        -------
        list of StageRecord
            Record i is identical, float for float, to ``stages[i].run(u_c)``.
            Limited samples give one :class:`StageSaturationWarning` per
            place of the chain, naming the members concerned.
        """
        u = check_finite_array("u_c", u_c, ndim=1, min_length=1, real=True)
        n = len(u)
        t = np.arange(n) / self.fs
        records, fronts, truths, draws = [], {}, {}, {}
        for st in self.stages:
            # the hysteresis is shared by members that differ only in the plant (a model set)
            front_key, plant_key = self._truth_key(st)
            if front_key not in fronts:
                fronts[front_key] = st._before_plant(u)
            u_dac, v_a, v_h, sat_in, sat_out = fronts[front_key]
            if (front_key, plant_key) not in truths:
                truths[front_key, plant_key] = st._plant_output(v_h)
            y = truths[front_key, plant_key]
            # the arithmetic of VirtualStage.run, member by member
            if st.seed not in draws:        # members of a model set share the stage's seed
                draws[st.seed] = np.random.default_rng(st.seed).standard_normal(n)
            noise = st.noise_rms * draws[st.seed]
            analog = y + noise
            v_y = st.adc.convert(analog)
            sat_adc = Saturation.of("ADC", st.adc.limits, analog)
            records.append(StageRecord(t, u_dac, v_a, paper.UM_PER_VOLT * y, v_y, sat_in,
                                       sat_out, sat_adc, st.seed))
        _warn_members(records, self.fs)
        return records

    @staticmethod
    def _truth_key(st):
        """(hysteresis key, plant key) of a member's noise-free output."""
        h = st.hysteresis
        return (None if h is None else (h.thresholds_V, h.weights, h.linear_weight),
                (st.b.tobytes(), st.a.tobytes()))


    def start(self):
        """Begin a sample-by-sample simulation of all members (for closed
        loops); see :class:`StageBatchSimulation`."""
        return StageBatchSimulation(self)


def _clip(x, lo, hi, out):
    """min(max(x, lo), hi) elementwise into ``out`` (two ufunc calls: np.clip's Python
    wrapper costs more than both)."""
    np.maximum(x, lo, out=out)
    return np.minimum(out, hi, out=out)


def _read_only(arr):
    arr.setflags(write=False)
    return arr


def _warn_members(records, fs, stacklevel=4):
    """One StageSaturationWarning per place of the chain that limited any member."""
    for place in ("input_saturation", "output_saturation", "adc_saturation"):
        hit = [r for r in records if getattr(r, place).occurred]
        if not hit:
            continue
        seeds = ", ".join(str(r.seed) for r in hit[:8]) + (", ..." if len(hit) > 8 else "")
        prefix = (f"{len(hit)} of {len(records)} batch members (seeds {seeds}); seed "
                  f"{hit[0].seed}: ") if len(records) > 1 else ""
        warnings.warn(prefix + getattr(hit[0], place).message(fs), StageSaturationWarning,
                      stacklevel=stacklevel)


class StageBatchSimulation:
    """Sample-by-sample run of a :class:`StageBatch`, all members at once.

    The arithmetic of :meth:`StageSimulation.step` on arrays of shape (N,):
    the DAC and ADC quantisers (round half to even), the amplifier limits,
    the play operators, the direct-form II transposed plant filter and each
    member's noise stream (its own generator, drawn in the same blocks).
    Member i is therefore identical, float for float, to a
    :class:`StageSimulation` of ``batch.stages[i]`` driven by the same inputs.

    Causality as in :class:`StageSimulation`: :attr:`v_y_V` is v_y[k];
    :meth:`step` applies u_c[k] and returns v_y[k+1].

    Saturation is recorded per member; the warnings are issued by
    :meth:`records` (one per place of the chain, naming the members), not
    while stepping, which keeps a step cheap: about 20 us for N = 32
    (``benchmarks/bench_loop_seeds.py``), against 6 us for one
    :class:`StageSimulation` step.  The signals are kept in blocks of
    4096 samples: about 56 N bytes per sample.
    """

    _BLOCK = StageSimulation._BLOCK
    #: rows of a block of the signal log
    _SIGNALS = ("u", "u_dac", "v_cmd", "v_a", "y", "analog", "v_y")

    def __init__(self, batch):
        if not isinstance(batch, StageBatch):
            raise TypeError(f"batch must be a StageBatch, got {type(batch).__name__}")
        self._batch = bt = batch
        n = bt.size
        # one generator per distinct seed: members of a model set share the stage's seed,
        # and each of their streams is that seed's stream (drawn once, scaled per member)
        seeds = [st.seed for st in bt.stages]
        self._rngs = {seed: np.random.default_rng(seed) for seed in dict.fromkeys(seeds)}
        self._member_stream = [list(self._rngs).index(seed) for seed in seeds]
        self._noise_rms = np.array([st.noise_rms for st in bt.stages])
        # states and coefficients are held transposed, (order or n_plays, N): row j is
        # one state of every member.  Constants are 0-d arrays: a ufunc takes them
        # faster than Python floats, with the same values.
        order = bt.a.shape[1] - 1
        self._z, self._z_next = np.zeros((order, n)), np.empty((order, n))
        self._z_tmp = np.empty((order, n))
        self._b0, self._b1 = bt.b[:, 0].copy(), np.ascontiguousarray(bt.b[:, 1:].T)
        self._a1 = np.ascontiguousarray(bt.a[:, 1:].T)
        self._x = np.empty(n)
        self._gain = np.array(bt.gain)
        self._out = (np.array(bt.out_lo), np.array(bt.out_hi))
        # the amplifier limits cannot act when the DAC's extreme codes stay inside them
        # (gain * u_dac is monotone in u_dac): then v_a = v_cmd exactly, as in the
        # single run, and the limits are skipped
        dac, adc = bt.dac, bt.adc
        self._amp_limits = not (bt.out_lo <= bt.gain * (dac.code_lo * dac.lsb)
                                and bt.gain * (dac.code_hi * dac.lsb) <= bt.out_hi)
        self._dac = tuple(np.array(float(x)) for x in (dac.lsb, dac.code_lo, dac.code_hi))
        self._adc = tuple(np.array(float(x)) for x in (adc.lsb, adc.code_lo, adc.code_hi))
        if bt.thresholds_V is None:
            self._plays = None
        else:
            r = np.ascontiguousarray(bt.thresholds_V.T)
            self._r, self._w = r, np.ascontiguousarray(bt.weights.T)
            self._w0 = bt.linear_weight
            self._plays = 0.0 + r                   # initial_state(0.0): 0.0 + r
            self._pm_r = np.stack([-r, r])          # v_a + (-r) is v_a - r exactly
            self._bounds = np.empty_like(self._pm_r)
            self._h = np.empty((r.shape[0] + 1, n))
            self._h_sum = np.empty(n)
            self._h_rows = list(self._h[2:])
        self._blocks = []               # (7, BLOCK, N): the signals of _SIGNALS by sample
        self._whole_log = None          # (7, n, N) after run_sections_loop: the blocks' array
        self._k = 0
        self._j = 0                     # row of sample k in the last block
        self._new_block()
        self._measure(np.zeros(n))

    def _new_block(self):
        bt = self._batch
        draws = np.stack([rng.standard_normal(self._BLOCK) for rng in self._rngs.values()],
                         axis=1)
        # member i: noise_rms_i * its seed's draws, the product StageSimulation forms
        self._noise = self._noise_rms * draws[:, self._member_stream]
        self._log = np.empty((len(self._SIGNALS), self._BLOCK, bt.size))
        self._blocks.append(self._log)
        self._whole_log = None          # the log goes on in separate blocks

    @staticmethod
    def _convert(v, out, lsb, code_lo, code_hi):
        # _Converter.convert_scalar elementwise: round half to even, limit the code (its
        # limiting of v first only keeps round() from overflowing; the code is the same)
        np.divide(v, lsb, out)
        np.rint(out, out)
        _clip(out, code_lo, code_hi, out)
        return np.multiply(out, lsb, out)

    def _measure(self, y):
        """Measurement v_y[k] from the noise-free output y[k] (k = self._k)."""
        log, j = self._log, self._j
        analog = np.add(y, self._noise[j], log[5, j])
        self._v_y = self._convert(analog, log[6, j], *self._adc)

    @property
    def size(self):
        """Number of members N."""
        return self._batch.size

    @property
    def seeds(self):
        """The members' noise seeds."""
        return self._batch.seeds

    @property
    def k(self):
        """Number of samples applied so far (index of the current measurement)."""
        return self._k

    @property
    def v_y_V(self):
        """Measurements v_y[k] of the members at the current sample [V], shape (N,)."""
        return self._v_y.copy()

    @property
    def state(self):
        """Internal state after :attr:`k` samples (copies).

        Returns
        -------
        filter_state : ndarray, shape (N, order)
            Row i: ``StageSimulation.state[0]`` of member i.
        play_outputs_V : ndarray, shape (N, n_plays)
            Row i: ``StageSimulation.state[1]`` of member i ((N, 0) for
            linear stages).
        """
        plays = (np.empty((self.size, 0)) if self._plays is None else self._plays.T.copy())
        return self._z.T.copy(), plays

    def step(self, u_c):
        """Apply u_c[k] to every member for one period; return v_y[k+1].

        Parameters
        ----------
        u_c : float or array_like, shape (N,)
            Control input of each member [V] (a scalar is applied to all).

        Returns
        -------
        ndarray, shape (N,)
            The next measurement of each member [V] (a new array).
        """
        n = self._batch.size
        u = np.asarray(u_c, dtype=float)
        if u.shape != (n,):
            if u.ndim > 1 or (u.ndim == 1 and u.shape[0] != n):
                raise ValueError(f"u_c must be a scalar or of shape ({n},), got shape "
                                 f"{u.shape} at sample {self._k}")
            u = np.full(n, float(u))
        if not np.isfinite(u).all():
            raise ValueError(f"u_c must be finite, got {u!r} at sample {self._k}")
        return self._advance(u).copy()

    def _advance(self, u, u_b=None):
        """:meth:`step` with u_c = u (+ u_b) for finite arrays of shape (N,) (or u a
        float); returns v_y[k+1] as a view that later steps do not change."""
        log, j = self._log, self._j
        u_c = log[0, j]
        if u_b is None:
            u_c[...] = u
        else:
            np.add(u, u_b, u_c)
        u_dac = self._convert(u_c, log[1, j], *self._dac)
        v_a = v_cmd = np.multiply(u_dac, self._gain, log[2, j])
        if self._amp_limits:
            v_a = _clip(v_cmd, *self._out, log[3, j])
        if self._plays is not None:
            # the plays: y_i <- min(max(y_i, v_a - r_i), v_a + r_i)
            plays, bounds, h = self._plays, self._bounds, self._h
            np.add(v_a, self._pm_r, bounds)
            _clip(plays, bounds[0], bounds[1], plays)
            # v_h = w0 v_a, then + w_i (y_i - r_i) play by play, in that order as
            # StageSimulation.step adds them (row by row: cheaper than a cumulative sum
            # over axis 0 for N in the hundreds)
            np.multiply(self._w0, v_a, h[0])
            np.subtract(plays, self._r, h[1:])
            np.multiply(h[1:], self._w, h[1:])
            v_h = np.add(h[0], h[1], self._h_sum)
            for row in self._h_rows:
                np.add(v_h, row, v_h)
        else:
            v_h = v_a
        x_in = np.divide(v_h, self._gain, self._x)
        # direct form II transposed, StageSimulation.step's arithmetic per member:
        # y = z0 + b0 x;  z_i = (z_{i+1} + x b_{i+1}) - y a_{i+1};  z_last = x b - y a
        z, z_new = self._z, self._z_next
        y_k = np.multiply(self._b0, x_in, log[4, j])
        np.add(z[0], y_k, y_k)
        np.multiply(x_in, self._b1, z_new)
        np.add(z_new[:-1], z[1:], z_new[:-1])
        np.multiply(y_k, self._a1, self._z_tmp)
        np.subtract(z_new, self._z_tmp, z_new)
        self._z, self._z_next = z_new, z
        self._k += 1
        self._j = j + 1
        if self._j == self._BLOCK:
            self._new_block()
            self._j = 0
        self._measure(z_new[0])
        return self._v_y

    @classmethod
    def workspace_size(cls, n, N):
        """Length of a ``workspace`` that holds the signal log of an ``n``-sample
        :meth:`run_sections_loop` of ``N`` members (float64 entries).

        Examples
        --------
        >>> StageBatchSimulation.workspace_size(1000, 2) == 7 * 4096 * 2
        True
        """
        n = check_integer("n", n, minimum=0)
        N = check_integer("N", N, minimum=0)
        return len(cls._SIGNALS) * (n // cls._BLOCK + 1) * cls._BLOCK * N

    def run_sections_loop(self, v_r, u_f, sections, delay, diverged_v, workspace=None):
        """The whole closed loop with a section controller, compiled
        (:func:`piezolib.problem.stage_loop_kernel.closed_loop`): from sample 0, at each
        sample k ``u_b[k] = sections.step(v_r[k] - v_y[k])`` and u_c[k] = u_f[k] +
        u_b[k - delay] (0 before), with :meth:`step`'s arithmetic, so the records and
        outputs are identical, float for float, to that loop in Python.

        Parameters
        ----------
        v_r, u_f : ndarray, shape (n,)
            Reference and feedforward [V] (finite).
        sections : piezolib.robust.export.SectionFilterBatch
            The controller of every member (its states are advanced).
        delay : int
            Computation delay [samples].
        diverged_v : float
            Stop when the root sum of squares of the members' u_b reaches this [V].
        workspace : ndarray, optional
            A 1-D float64 array to keep the signal log in when it is large enough
            (:meth:`workspace_size`; else a new one is allocated): a caller that runs
            many loops one after the other passes the same array and saves the fresh
            memory each run would touch (hundreds of MB for hundreds of members over
            seconds, paid in page faults).  It is overwritten: the signals of a
            simulation (:meth:`samples`; :meth:`records` copies them) are valid until
            the next run that uses it.

        Returns
        -------
        u_b : ndarray, shape (n, N)
            Controller outputs [V] (up to the diverged sample).
        diverged : int
            -1, or the sample at which the outputs diverged (the simulation is then
            left unusable).
        """
        from piezolib.problem.stage_loop_kernel import closed_loop

        if self._k:
            raise RuntimeError("run_sections_loop starts at sample 0 of a new simulation")
        v_r, u_f = (np.ascontiguousarray(x, dtype=float) for x in (v_r, u_f))
        n, N, B = v_r.shape[0], self.size, self._BLOCK
        # the noise blocks the Python loop would draw, in the same order
        noises = [self._noise]
        for _ in range(n // B):
            self._new_block()
            noises.append(self._noise)
        noise = np.concatenate(noises)
        shape = (len(self._SIGNALS), noise.shape[0], N)
        if workspace is not None:
            if not (isinstance(workspace, np.ndarray) and workspace.dtype == np.float64
                    and workspace.ndim == 1 and workspace.flags.c_contiguous
                    and workspace.flags.writeable):
                raise TypeError("workspace must be a writeable 1-D float64 ndarray")
        size = self.workspace_size(n, N)              # = prod(shape)
        log = (workspace[:size].reshape(shape) if workspace is not None
               and workspace.size >= size else np.empty(shape))
        log[5:, 0] = self._blocks[0][5:, 0]            # the measurement at sample 0
        blocks = [log[:, b * B:(b + 1) * B] for b in range(len(noises))]
        plays = self._plays is not None
        empty = np.zeros((0, N))
        state = dict(dac=np.array([float(x) for x in self._dac]),
                     adc=np.array([float(x) for x in self._adc]),
                     gain=float(self._gain), amp=bool(self._amp_limits),
                     out_lo=float(self._out[0]), out_hi=float(self._out[1]), has_plays=plays,
                     r=self._r if plays else empty, w=self._w if plays else empty,
                     w0=np.asarray(self._w0, float) if plays else np.zeros(N),
                     plays=self._plays if plays else empty, b0=self._b0, b1=self._b1,
                     a1=self._a1, z=self._z, noise=noise, log=log, v_y=self._v_y)
        u_b = np.zeros((n, N))
        diverged = closed_loop(v_r, u_f, int(delay), state, sections.arrays, u_b, diverged_v)
        stop = n if diverged < 0 else diverged
        self._blocks, self._log, self._whole_log = blocks, blocks[-1], log
        self._k, self._j = stop, stop % B
        self._v_y = log[6, stop]
        return u_b[:stop + (diverged >= 0)], diverged

    def record(self, i):
        """The samples applied so far to member ``i`` as a :class:`StageRecord`
        (no warning; see :meth:`records`)."""
        i = check_integer("i", i, minimum=0)
        if i >= self.size:
            raise ValueError(f"i must be below the batch size {self.size}, got {i}")
        return self._records([i])[0]

    def records(self):
        """The samples applied so far, one :class:`StageRecord` per member.

        Issues one :class:`StageSaturationWarning` per place of the chain
        (DAC/amplifier input, amplifier output, ADC) where any member was
        limited, naming the members.

        Returns
        -------
        list of StageRecord
            Record i is identical, float for float, to
            ``StageSimulation.record()`` of member i.
        """
        records = self._records(range(self.size))
        _warn_members(records, self._batch.fs, stacklevel=3)
        return records

    def samples(self, name):
        """One signal of every member over the samples applied so far, by sample.

        Parameters
        ----------
        name : str
            One of ``"u"`` (u_c requested [V]), ``"u_dac"``, ``"v_cmd"``, ``"v_a"``,
            ``"y"`` (noise-free output [V]), ``"analog"`` (before the ADC [V]) or
            ``"v_y"`` (measured [V]).

        Returns
        -------
        ndarray, shape (k, N)
            Row k: sample k of every member (read-only; a view of the log after
            :meth:`run_sections_loop`).  Column i is the signal of
            :meth:`records`' record i (``v_y`` is its ``v_y_V``).

        Examples
        --------
        >>> sim = StageBatch.of_seeds(VirtualStage(), [0, 1]).start()
        >>> for k in range(5):
        ...     _ = sim.step(1.0)
        >>> sim.samples("v_y").shape
        (5, 2)
        """
        if name not in self._SIGNALS:
            raise ValueError(f"name must be one of {self._SIGNALS}, got {name!r}")
        row, n = self._SIGNALS.index(name), self._k
        if self._whole_log is not None:          # the compiled loop's: one array
            out = self._whole_log[row, :n]
        else:
            out = np.concatenate([blk[row][:min(self._BLOCK, n - start)]
                                  for start, blk in zip(range(0, n, self._BLOCK),
                                                        self._blocks)])
        out = out.view()
        out.setflags(write=False)
        return out

    def saturation_counts(self):
        """Samples limited anywhere in the chain, per member: the sum of the counts of
        :meth:`records`' three :class:`~piezolib.problem.stage.Saturation` (DAC/amplifier
        input, amplifier output, ADC), without building the records.

        Returns
        -------
        ndarray of int, shape (N,)
        """
        bt = self._batch
        return sum(np.count_nonzero((x < lo) | (x > hi), axis=0)
                   for (lo, hi), x in ((bt.dac.limits, self.samples("u")),
                                       ((bt.out_lo, bt.out_hi), self.samples("v_cmd")),
                                       (bt.adc.limits, self.samples("analog"))))

    def _records(self, members):
        bt = self._batch
        n = self._k
        members = list(members)

        def signal(name):
            # (n, N) by sample -> (len(members), n): a row per member
            return np.ascontiguousarray(self.samples(name)[:, members].T)

        u_dac, v_cmd, y, v_y = (signal(name) for name in ("u_dac", "v_cmd", "y", "v_y"))
        v_a = signal("v_a") if self._amp_limits else v_cmd
        sat_in = _saturations("DAC/amplifier input", bt.dac.limits, signal("u"))
        sat_out = _saturations("amplifier output", (bt.out_lo, bt.out_hi), v_cmd)
        sat_adc = _saturations("ADC", bt.adc.limits, signal("analog"))
        t = np.arange(n) / bt.fs
        return [StageRecord(t, u_dac[m], v_a[m], paper.UM_PER_VOLT * y[m], v_y[m], sat_in[m],
                            sat_out[m], sat_adc[m], bt.stages[i].seed)
                for m, i in enumerate(members)]


def _saturations(where, limits, requested):
    """:meth:`Saturation.of` of each row of ``requested``, shape (M, n)."""
    outside = ((requested < limits[0]) | (requested > limits[1])).any(axis=1)
    return [Saturation.of(where, limits, row) if out else Saturation(where, tuple(limits))
            for row, out in zip(requested, outside)]
