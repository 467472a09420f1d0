"""Float32 export of MIMO controllers: the realisation, the float32 checks and a C header that
gcc compiles and runs against the float64 simulation."""

import shutil
import subprocess
import warnings

import control as ct
import numpy as np
import pytest
import scipy.linalg as la
import scipy.signal as sig

from piezolib.robust.float32_check import ExportError, ExportWarning
from piezolib.robust.mimo_export import c_header, export_mimo

FS = 6400.0                     # [Hz], the mirror loop's rate


def lightly_damped(n_pairs, n_out, n_in, seed, zeta=0.02):
    """A stable continuous controller with pole pairs from 20 Hz to 1.5 kHz (damping zeta),
    in a random dense basis, Tustin-discretised at FS."""
    rng = np.random.default_rng(seed)
    blocks = []
    for f in np.geomspace(20.0, 1500.0, n_pairs):
        w = 2 * np.pi * f
        wd = w * np.sqrt(1 - zeta ** 2)
        blocks.append(np.array([[-zeta * w, wd], [-wd, -zeta * w]]))
    A = la.block_diag(*blocks)
    V = rng.standard_normal(A.shape) + 2 * np.eye(A.shape[0])
    A = V @ A @ np.linalg.inv(V)
    K = ct.ss(A, rng.standard_normal((A.shape[0], n_in)), rng.standard_normal((n_out, A.shape[0])),
              rng.standard_normal((n_out, n_in)))
    return ct.c2d(K, 1 / FS, "tustin")


@pytest.fixture(scope="module")
def k3():
    return lightly_damped(5, 3, 3, seed=1)


@pytest.fixture(scope="module")
def exported(k3):
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExportWarning)      # no warning on this controller
        return export_mimo(k3, name="K3")


def test_modal_form_keeps_the_poles_in_its_blocks(k3, exported):
    x = exported
    assert x.form == "modal" and x.n_states == 10
    # block-diagonal: nothing outside the 2 x 2 blocks, the blocks [[s, w], [-w, s]]
    mask = la.block_diag(*[np.ones((2, 2))] * 5).astype(bool)
    assert np.all(x.A[~mask] == 0)
    for i in range(0, 10, 2):
        blk = x.A[i:i + 2, i:i + 2]
        assert blk[0, 0] == blk[1, 1] and blk[0, 1] == -blk[1, 0]
    poles = np.sort_complex(np.linalg.eigvals(k3.A))
    assert np.allclose(np.sort_complex(np.linalg.eigvals(x.A)), poles, rtol=1e-12, atol=0)
    assert x.realisation_error < 1e-12 * x.basis_condition


def test_float32_checks_hold_within_their_bounds(exported):
    x = exported
    finite = np.isfinite(x.error)
    assert np.all(x.error[finite] <= x.bound[finite])
    assert x.max_error < 1e-3                          # a 3 x 3, 10-state lightly damped K
    assert x.radius32 < 1 and abs(x.radius32 - x.radius64) < 1e-6
    assert x.time_error <= x.time_bound and x.time_error_total <= x.time_bound_total


def test_float64_simulation_matches_python_control(k3, exported):
    e = np.random.default_rng(4).uniform(-1, 1, (400, 3))
    u = exported.simulate(e, dtype="float64")
    ref = ct.forced_response(k3, U=e.T).outputs.T
    assert np.max(np.abs(u - ref)) <= 1e-9 * np.max(np.abs(ref))


def test_well_conditioned_forms_beat_the_companion_form():
    # one channel, 8 states: the companion form's last row holds the characteristic polynomial,
    # whose float32 rounding moves the lightly damped poles far more than one ulp
    Kd = lightly_damped(4, 1, 1, seed=0)
    num, den = sig.ss2tf(Kd.A, Kd.B, Kd.C, Kd.D)
    companion = ct.ss(*sig.tf2ss(num, den), 1 / FS)
    with pytest.raises(ExportError, match="unstable"):
        export_mimo(companion, form="given")
    # the companion's modal basis is a Vandermonde matrix, too ill conditioned: Schur instead
    auto = export_mimo(companion)
    assert auto.form == "schur" and auto.radius32 < 1
    assert export_mimo(companion, form="modal").basis_condition > 1e6
    assert auto.max_error <= np.nanmax(auto.bound)
    # from a random dense basis, the modal form beats that basis itself
    modal, dense = export_mimo(Kd), export_mimo(Kd, form="given")
    assert modal.form == "modal"
    assert modal.max_error < dense.max_error / 3
    assert abs(modal.radius32 - modal.radius64) < abs(dense.radius32 - dense.radius64)


def test_defective_poles_fall_back_to_schur():
    A = np.array([[0.9, 1.0, 0.0], [0.0, 0.9, 0.0], [0.0, 0.0, 0.5]])   # a Jordan block
    Kd = ct.ss(A, np.ones((3, 2)), np.ones((2, 3)), np.zeros((2, 2)), 1 / FS)
    x = export_mimo(Kd)
    assert x.form == "schur"
    with pytest.raises(ValueError, match="defective"):
        export_mimo(Kd, form="modal")
    assert x.max_error <= np.nanmax(x.bound)


def test_tight_rtol_warns_with_the_numbers(k3):
    with pytest.warns(ExportWarning, match="rtol"):
        export_mimo(k3, rtol=1e-12)


def test_c_header_needs_an_export():
    with pytest.raises(TypeError, match="controller"):
        c_header(np.eye(2))


MAIN = r"""
#include <stdio.h>
#include "{header}"
#include "input.h"
int main(void) {{
    float x[{nn}] = {{0}};
    float u[{p}];
    for (int k = 0; k < N_SAMPLES; ++k) {{
        {low}_step(x, E[k], u);
        for (int i = 0; i < {p}; ++i) printf(i ? " %.9g" : "%.9g", (double)u[i]);
        printf("\n");
    }}
    return 0;
}}
"""


def run_c(x, e, folder):
    """Compile x's header with a driver feeding e (float32 values) and return its u (N x p)."""
    gcc = shutil.which("gcc") or shutil.which("cc")
    if gcc is None:
        pytest.skip("no C compiler (gcc or cc) on PATH")
    header = folder / f"{x.name}.h"
    header.write_text(c_header(x))
    rows = ",\n".join("{" + ", ".join(np.format_float_scientific(np.float32(v), unique=True) + "f"
                                      for v in row) + "}" for row in e)
    (folder / "input.h").write_text(f"#define N_SAMPLES {len(e)}\n"
                                    f"static const float E[{len(e)}][{e.shape[1]}] = {{\n{rows}\n}};\n")
    main = folder / "main.c"
    main.write_text(MAIN.format(header=header.name, nn=max(x.n_states, 1), p=x.C.shape[0],
                                low=x.name.lower()))
    exe = folder / "main"
    # -ffp-contract=off: no fused multiply-adds, every product and sum rounded to float
    # as the bound assumes (an FMA rounds once instead of twice, which the bound covers too)
    subprocess.run([gcc, "-std=c99", "-O2", "-Wall", "-Werror", "-ffp-contract=off",
                    str(main), "-o", str(exe)], check=True, capture_output=True, text=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    return np.array([[float(v) for v in line.split()] for line in out.splitlines()])


def test_c_header_compiles_and_runs_against_float64(exported, k3, tmp_path):
    x = exported
    e = np.random.default_rng(7).uniform(-1, 1, (1500, 3)).astype(np.float32).astype(float)
    u_c = run_c(x, e, tmp_path)
    assert u_c.shape == (1500, 3)
    # against float64 arithmetic on the same float32 matrices: the arithmetic's rounding only,
    # bounded a posteriori (gamma_{n+m} |M| |v| per dot product, propagated by sum ||C A^j||)
    u64 = x.to_statespace("float32")
    ref32 = ct.forced_response(u64, U=e.T).outputs.T
    n, m = x.n_states, 3
    gamma = (n + m) * 2.0 ** -24 / (1 - (n + m) * 2.0 ** -24)
    u_py32 = x.simulate(e, "float32")                   # numpy's float32 run of the same recursion
    assert np.max(np.abs(u_py32 - u_c)) <= 1e-4 * np.max(np.abs(u_c))
    states = ct.forced_response(u64, U=e.T, return_x=True).states.T
    A32, B32, C32, D32 = (np.abs(M.astype(float)) for M in (x.A32, x.B32, x.C32, x.D32))
    d_state = gamma * (np.abs(states) @ A32.T + np.abs(e) @ B32.T)
    d_out = gamma * (np.abs(states) @ C32.T + np.abs(e) @ D32.T)
    gain, CAj = 0.0, x.C32.astype(float)
    for _ in range(len(e)):
        gain += np.max(np.sum(np.abs(CAj), axis=1))
        CAj = CAj @ x.A32.astype(float)
    # first order in the state error: 1.01 covers x32 - x64 in the |x| of the bound
    bound = 1.01 * (gain * d_state.max() + d_out.max())
    assert np.max(np.abs(u_c - ref32)) <= bound
    # against the float64 controller given: plus the coefficient rounding, ||Delta h||_l1 max|e|
    ref = ct.forced_response(k3, U=e.T).outputs.T
    imp = ct.impulse_response(u64 - k3, T=np.arange(len(e)) / FS).outputs     # (p, m, N)
    dh_l1 = np.max(np.sum(np.abs(imp), axis=-1).sum(axis=1))
    assert np.max(np.abs(u_c - ref)) <= bound + dh_l1 * np.max(np.abs(e))
    assert np.max(np.abs(u_c - ref)) <= 1e-3 * np.max(np.abs(ref))


def test_c_header_of_a_static_and_of_a_siso_controller(tmp_path):
    static = ct.ss([], [], [], [[1.0, -2.0], [0.5, 1.0]], 1 / FS)
    x = export_mimo(static, name="Kstatic")
    assert x.n_states == 0 and x.max_error == 0.0
    e = np.random.default_rng(8).uniform(-1, 1, (20, 2)).astype(np.float32).astype(float)
    (tmp_path / "a").mkdir()
    u_c = run_c(x, e, tmp_path / "a")
    assert np.allclose(u_c, e @ x.D32.astype(float).T, rtol=1e-6, atol=1e-7)
    siso = export_mimo(ct.c2d(ct.ss(ct.tf([100.0], [1.0, 100.0])), 1 / FS, "tustin"), name="K1")
    (tmp_path / "b").mkdir()
    e1 = e[:, :1]
    u1 = run_c(siso, e1, tmp_path / "b")
    ref = siso.simulate(e1, "float64")
    assert np.max(np.abs(u1 - ref)) <= 1e-5 * np.max(np.abs(ref))
