"""Speed of the Dahl model, its fit and the feedforward (prints numbers; no assertions).

    python benchmarks/bench_hysteresis.py

Goals: one feedforward step well under the 100 us sample period of the 10 kHz
loop; a voltage-driven simulation of a 3000-sample loop in a few ms; the joint
fit of the four Table 4 loops (with or without the offset x0) under a second.
Fit time of each model (Dahl, Prandtl-Ishlinskii) on a raw 10 s record of the
virtual stage (5x its sensor noise, from rest) at 5 kHz and 10 kHz, full rate.

    python benchmarks/bench_hysteresis.py --fits     # only the 10 s record fits
    python benchmarks/bench_hysteresis.py --raw      # only the raw-record fits

Raw record: the virtual stage's 51 000-sample record that starts at rest and steps
(``raw_hysteresis_record``): CPU time of fit_dahl (default stride: at most MAX_FIT_SAMPLES
samples), fit_pi and fit_hammerstein on the whole record and on the record cut after its
start-up, with the whole-record RMS error; goal for fit_dahl: <= 2 s of CPU.
"""

import sys
import warnings

import time

import numpy as np

from piezolib import hysteresis as hy
from piezolib.problem import hysteresis_fits as ph
from piezolib.workbook.experiments import table4_reference

from bench_stage import best_of      # scripts run from benchmarks/ see each other

MODEL = hy.DahlModel(alpha1=3.0, alpha2=4.0, beta1=0.0, beta2=0.2 * 4 / 30, gamma_a=30.0,
                     g_a=0.95, form="bliman_sorine")


def main():
    t, v = table4_reference(40.0)                        # 3 periods at 10 kHz: 3001 samples
    ff = hy.DahlFeedforward(MODEL)
    n = 100_000
    refs = 2.0 + 2.0 * np.sin(np.linspace(0, 200 * np.pi, n))
    refs = refs.tolist()

    def steps():
        ff.reset()
        step = ff.step
        for r in refs:
            step(r)

    print(f"DahlFeedforward.step: {best_of(steps, 3) / n * 1e6:.2f} us per sample")
    print(f"feedforward (array, {v.size} samples): "
          f"{best_of(lambda: hy.feedforward(MODEL, v)) * 1e3:.2f} ms")
    print(f"dahl_hysteresis (array, {v.size} samples): "
          f"{best_of(lambda: hy.dahl_hysteresis(MODEL, v)) * 1e3:.2f} ms")
    for form in hy.FORMS:
        m = MODEL.with_form(form)
        print(f"simulate_dahl {form} ({v.size} samples): "
              f"{best_of(lambda: hy.simulate_dahl(m, v)) * 1e3:.2f} ms")
    loops = []
    for amplitude in (10.0, 20.0, 30.0, 40.0):
        t, u = table4_reference(amplitude)
        x = hy.simulate_dahl(MODEL.with_offset(-0.15), u).x
        loops.append((u, x + np.random.default_rng(0).normal(0, 5e-4, x.size)))
    for form in hy.FORMS:
        for offset in (False, True):
            start = time.perf_counter()
            fit = hy.fit_dahl(loops, gamma_a=MODEL.gamma_a, form=form, offset=offset,
                              discard=1000, stride=10)
            print(f"fit_dahl {form}, offset={offset}, 4 synthetic loops, stride 10: "
                  f"{time.perf_counter() - start:.2f} s ({fit.result.nfev} evaluations, "
                  f"worst RMS {fit.rms_percent.max():.3f} %)")
    # the virtual stage's Case I loops: every candidate of notebook 03 (uncached: one fit each)
    total = time.perf_counter()
    for key in ph.CASE_I_CANDIDATES:
        start = time.perf_counter()
        fit = ph.fit_case_I_loops(*key)
        print(f"fit_case_I_loops{key}: {time.perf_counter() - start:.2f} s "
              f"(pooled RMS {fit.pooled_rms_percent:.2f} %)")
    print(f"all {len(ph.CASE_I_CANDIDATES)} candidates: {time.perf_counter() - total:.2f} s; "
          f"workbook_dahl_fit() afterwards (cached): "
          f"{best_of(ph.workbook_dahl_fit) * 1e6:.1f} us")


def fit_times():
    """Fit time of each model on a raw, noisy 10 s record at 5 and 10 kHz (one run each)."""
    from piezolib.problem.stage import VirtualStage
    for fs in (5_000.0, 10_000.0):
        stage = VirtualStage(seed=3, sample_rate_Hz=fs, noise_rms_V=5 * 0.5e-3)
        t = np.arange(int(10 * fs)) / fs
        u = 1.5 - 1.5 * np.cos(2 * np.pi * 2 * t) * (0.6 + 0.4 * np.cos(2 * np.pi * 0.1 * t))
        rec = stage.run(u - u[0])
        loop = (rec.u_c_V, rec.v_y_V)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", hy.FitWarning)
            start = time.perf_counter()
            dahl = hy.fit_dahl([loop], gamma_a=30.0, offset=True, start="rest", discard=int(fs))
            t_dahl = time.perf_counter() - start
        start = time.perf_counter()
        pi = hy.fit_pi([loop], n_plays=10, discard=int(fs))
        t_pi = time.perf_counter() - start
        print(f"10 s record at {fs / 1e3:g} kHz ({t.size} samples): fit_dahl (Bliman-Sorine, "
              f"offset, rest) {t_dahl:.2f} s, RMS {dahl.rms_percent[0]:.3f} %; fit_pi (10 plays) "
              f"{t_pi:.2f} s, RMS {pi.rms_percent[0]:.3f} %")


def raw_fit_times():
    """CPU time and error of each fit on the raw record (rest, step, ringing, 1 Hz cosines)."""
    from piezolib import records
    from piezolib.problem.stage_data import raw_hysteresis_record
    raw = raw_hysteresis_record()
    whole = raw.record
    cut = records.cut_at_turning_points(whole, skip_transient=True)
    print(f"raw record: {len(whole)} samples at {whole.fs:g} Hz; {cut.metadata['dropped']}")
    fits = {
        "fit_dahl (rest)": lambda r: hy.fit_dahl((r.input, r.output), 30.0, offset=True,
                                                 start="rest"),
        "fit_dahl (virgin)": lambda r: hy.fit_dahl((r.input, r.output), 30.0, offset=True,
                                                   start="virgin"),
        "fit_pi (auto start)": lambda r: hy.fit_pi((r.input, r.output)),
        "fit_hammerstein (4, 4)": lambda r: hy.fit_hammerstein((r.input, r.output), r.fs),
    }
    for label, rec in (("whole", whole), ("cut", cut)):
        for name, fit in fits.items():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", hy.FitWarning)
                start = time.process_time()
                result = fit(rec)
                cpu = time.process_time() - start
            print(f"  {label:5s} ({len(rec)} samples) {name:24s}: CPU {cpu:5.2f} s, RMS "
                  f"{result.rms_percent[0]:.3f} %, max {result.max_percent[0]:.2f} % of stroke")


if __name__ == "__main__":
    if "--raw" in sys.argv:
        raw_fit_times()
    else:
        if "--fits" not in sys.argv:
            main()
        fit_times()
        raw_fit_times()
