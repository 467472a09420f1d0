"""Export of discrete controllers as second-order sections, checked with the reference filter."""

import functools
import json
import pathlib
import re
import shutil
import subprocess
import warnings

import control as ct
import numpy as np
import pytest

from piezolib.robust.discrete import discretize
from piezolib.robust.export import (ExportError, ExportWarning, SectionFilter, SOSController,
                                    controller_sos, export_controller, read_json, sos_filter,
                                    write_c_header, write_json)
from piezolib.robust.margins import delay_tolerance

ROOT = pathlib.Path(__file__).resolve().parents[2]
FS = 10e3
s = ct.tf("s")
# a 6th-order lead/lag controller with a lightly damped notch and an integrator-like pole
K = (300 * (s / 2e3 + 1) / (s / 2e4 + 1) * (s ** 2 + 600 * s + 6e3 ** 2) / (s ** 2 + 6e3 * s + 6e3 ** 2)
     * (s + 30) / (s + 1) / (s / 4e4 + 1) / (s / 6e4 + 1))
G = 2e8 / ((s + 1e3) * (s ** 2 + 2e3 * s + 1e8))


@pytest.fixture(scope="module")
def exported():
    d = discretize(K, FS, G=G)
    return d.K, controller_sos(d.K, "K_test")


def test_sections_reproduce_controller(exported):
    Kd, sos = exported
    w = np.logspace(0, np.log10(np.pi * FS * 0.99), 400)
    ref = np.ravel(Kd(np.exp(1j * w / FS)))
    assert np.max(np.abs(sos.frequency_response(w) / ref - 1)) < 1e-8
    # float32 coefficients: within 1e-3 above 10 Hz, 2 % from 1 Hz (pole near z = 1)
    err32 = np.abs(sos.frequency_response(w, "float32") / ref - 1)
    assert np.max(err32[w >= 2 * np.pi * 10]) < 1e-3
    assert np.max(err32[w >= 2 * np.pi * 1]) < 2e-2


def test_reference_filter_step_response(exported, tmp_path):
    Kd, sos = exported
    path = write_json(sos, tmp_path / "k.json", meta={"units": "V/V"})
    x = np.ones(3000)
    _, y_ref = ct.forced_response(Kd, U=x)
    y64 = sos_filter(read_json(path, "float64"), x)
    y32 = sos_filter(read_json(path, "float32"), x, "float32")
    scale = np.max(np.abs(y_ref))
    assert np.max(np.abs(y64 - y_ref)) < 1e-9 * scale
    assert np.max(np.abs(y32 - y_ref)) < 2e-3 * scale        # stated float32 tolerance
    doc = json.loads(path.read_text())
    assert doc["fs_Hz"] == FS and len(doc["sos_float32"]) == sos.n_sections


def test_float32_sections_keep_sampled_loop_stable(exported):
    Kd, sos = exported
    ref = delay_tolerance(G, Kd, delays=range(3))
    f32 = delay_tolerance(G, sos.to_statespace("float32"), delays=range(3))
    assert np.array_equal(ref.stable, f32.stable) and f32.stable[0]
    assert np.allclose(ref.spectral_radius, f32.spectral_radius, rtol=1e-4)


def test_c_header_runs_like_reference(exported, tmp_path):
    _, sos = exported
    header = write_c_header(sos, tmp_path / "k_test.h").read_text()
    assert "K_TEST_SOS_F32" in header and "K_TEST_SOS_F64" in header
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    (tmp_path / "main.c").write_text(
        '#include <stdio.h>\n#include "k_test.h"\nint main(void){float st[K_TEST_N_SECTIONS][2]'
        '={{0}};for(int k=0;k<200;++k){printf("%.9g\\n",(double)k_test_step_f32(st,'
        '(float)((k%7)-3)));}return 0;}\n')
    subprocess.run([cc, "-std=c99", "-O0", "-ffp-contract=off", "-o", str(tmp_path / "main"),
                    str(tmp_path / "main.c")], check=True, cwd=tmp_path)
    out = subprocess.run([str(tmp_path / "main")], check=True, capture_output=True, text=True)
    c_y = np.array(out.stdout.split(), float)
    x = np.array([(k % 7) - 3 for k in range(200)], float)
    # %.9g round-trips float32: the C float sections and the reference agree bit for bit
    assert np.array_equal(c_y.astype(np.float32), sos_filter(sos, x, "float32").astype(np.float32))


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_sos_filter_is_section_filter_step_by_step(exported, dtype):
    # sos_filter runs compiled; SectionFilter.step is the reference it must equal bit for bit
    _, sos = exported
    x = np.random.default_rng(3).standard_normal(3000)
    f = SectionFilter(sos, dtype)
    assert np.array_equal(sos_filter(sos, x, dtype), [f.step(v) for v in x])


def test_section_filter_bad_input():
    with pytest.raises(ValueError, match="controller"):
        SectionFilter(np.ones((2, 5)))
    with pytest.raises(ValueError, match="dtype"):
        SectionFilter(np.array([[1.0, 0, 0, 1, 0, 0]]), "float16")
    with pytest.raises(ValueError, match="Kd"):
        controller_sos(K)
    with pytest.raises(ValueError, match="name"):
        controller_sos(ct.tf([1], [1, -0.5], 1e-4), "1bad")
    assert isinstance(controller_sos(ct.tf([1], [1, -0.5], 1e-4)), SOSController)


def test_export_controller_writes_both_files_and_returns_what_is_deployed(exported, tmp_path):
    Kd, sos = exported
    deployed = export_controller(Kd, tmp_path / "out", "K_test", meta={"note": "test"})
    assert (tmp_path / "out" / "K_test.json").exists() and (tmp_path / "out" / "K_test.h").exists()
    assert json.loads((tmp_path / "out" / "K_test.json").read_text())["meta"]["note"] == "test"
    np.testing.assert_array_equal(deployed.sos, read_json(tmp_path / "out" / "K_test.json",
                                                          "float32").sos)
    np.testing.assert_allclose(deployed.sos, sos.sos, rtol=1e-6, atol=1e-7)   # float32 rounding


# --- repeated poles and zeros, relative degree above one per section -----------------------
DT = 1e-4
Z_GRID = np.exp(1j * np.linspace(0.01, 0.99, 200) * np.pi)


def assert_reproduces(Kd, sos, rtol=1e-9):
    ref = np.ravel(Kd(Z_GRID))
    assert np.max(np.abs(sos.frequency_response(np.angle(Z_GRID) / DT) / ref - 1)) < rtol


def section_poles(sos):
    return np.concatenate([np.roots(row[3:]) for row in sos.sos])


def assert_roots_close(computed, expected, atol):
    """Each expected root matched by its own computed root within atol."""
    computed = list(computed)
    assert len(computed) == len(expected)
    for r in expected:
        j = int(np.argmin(np.abs(np.array(computed) - r)))
        assert abs(computed.pop(j) - r) < atol, (r, computed)


@pytest.mark.parametrize("poles, zeros", [
    ([0.5, 0.5], []),                                        # the bare StopIteration
    ([0.5, 0.5, 0.5], []),                                   # triple pole, relative degree 3
    ([0.5, 0.5, 0.5], [0.2]),
    ([0.9 * np.exp(0.3j), 0.9 * np.exp(-0.3j)] * 2, [0.3, 0.3]),   # a repeated complex pair
    ([0.9 * np.exp(0.3j), 0.9 * np.exp(-0.3j)] * 2, []),
    ([0.7, 0.7, -0.4, -0.4], [0.1, 0.1, 0.1]),               # repeated zeros too
])
def test_repeated_poles_and_zeros_are_paired_into_sections(poles, zeros):
    Kd = ct.tf(np.poly(zeros).real, np.poly(poles).real, DT)
    sos = controller_sos(Kd)
    assert_reproduces(Kd, sos)
    # every pole in a section (first-order sections carry a pole at 0): a multiple root is
    # fixed only to eps^(1/m), their product (the denominator) to rounding
    p = section_poles(sos)
    assert_roots_close(p[np.abs(p) > 0], poles, atol=1e-5)
    den = functools.reduce(np.polymul, [row[3:] for row in sos.sos])
    np.testing.assert_allclose(den[:len(poles) + 1], np.poly(poles).real, rtol=0, atol=1e-12)
    assert not np.any(den[len(poles) + 1:])
    # the relative degree as z^-1 factors: the impulse response starts when K_d's does
    pulse = np.r_[1.0, np.zeros(30)]
    _, ref = ct.forced_response(Kd, U=pulse)
    np.testing.assert_allclose(sos_filter(sos, pulse), np.ravel(ref), rtol=0,
                               atol=1e-12 * np.max(np.abs(ref)))


# --- a zero controller, a notch on the grid, a badly scaled 20th-order controller -----------
def test_zero_controller_is_refused_by_name():
    with pytest.raises(ValueError, match=r"Kd is identically zero .* 97 frequencies"):
        controller_sos(ct.tf(0, [1, -0.5], DT))
    with pytest.raises(ValueError, match="Kd is identically zero"):
        controller_sos(ct.ss([], [], [], [[0.0]], DT))


def test_zero_on_the_unit_circle_at_a_check_frequency_is_no_mismatch():
    # zeros at z = +-j (a notch at fs / 4, a point of the check grid): K_d(e^{j pi/2}) = 0
    Kd = ct.tf([1.0, 0.0, 1.0], [1.0, -0.5, 0.3], DT)
    sos = controller_sos(Kd)
    w = np.array([0.25, 0.3]) * 2 * np.pi / DT
    assert abs(sos.frequency_response(w)[0]) < 1e-15
    assert_reproduces(Kd, sos)


FS20 = 1 / DT
# (pole Hz, pole damping, zero Hz, zero damping, gain) of ten sections, connected in this
# order: lightly damped resonances and notches (zero damping 0: on the unit circle)
SECTIONS20 = [(4100, 0.0015, 7700, 0.0, 3.0), (20, 0.03, 40, 0.03, 300.0),
              (115, 0.004, 220, 0.002, 60.0), (150, 0.0065, 140, 0.001, 270.0),
              (114, 0.034, 210, 0.0016, 14.0), (370, 0.009, 290, 0.0, 0.44),
              (1.2, 0.027, 2.1, 0.01, 19.0), (15, 0.005, 16, 0.0, 47.0),
              (20, 0.016, 37, 0.0, 16.0), (92, 0.043, 100, 0.0, 0.63)]


def z_root(f_Hz, zeta):
    w = 2 * np.pi * f_Hz
    return np.exp((-zeta * w + 1j * w * np.sqrt(1 - zeta ** 2)) / FS20)


def test_minimal_20th_order_controller_built_section_by_section():
    # each section realised on its own and connected in series: a minimal realisation
    # (no pole meets a zero), but scaled so badly (cond A ~ 1e24) that its plain frequency
    # response and SLICOT's zeros lose most digits; once called "not minimal"
    Kd, poles, zeros, gain = None, [], [], 1.0
    for fp, zp, fz, zz, k in SECTIONS20:
        p, z = z_root(fp, zp), z_root(fz, zz)
        sec = ct.ss(ct.tf(k * np.poly([z, np.conj(z)]).real, np.poly([p, np.conj(p)]).real, DT))
        Kd = sec if Kd is None else ct.series(Kd, sec)
        poles, zeros, gain = poles + [p, np.conj(p)], zeros + [z, np.conj(z)], gain * k
    assert Kd.nstates == 20
    sos = controller_sos(Kd)
    truth = gain * np.array([np.prod(x - np.array(zeros)) / np.prod(x - np.array(poles))
                             for x in Z_GRID])
    h = sos.frequency_response(np.angle(Z_GRID) / DT)
    floor = 1e-6 * np.max(np.abs(truth))        # the notches: an absolute error there
    assert np.max(np.abs(h - truth) / np.maximum(np.abs(truth), floor)) < 1e-6
    assert_roots_close(section_poles(sos), poles, atol=1e-8)
    assert_roots_close(np.concatenate([np.roots(row[:3]) for row in sos.sos]), zeros, atol=1e-8)
    # the same controller as one transfer function: its coefficients fix the poles only
    # to ~1e-3, and the message says so instead of "is Kd minimal?"
    Ktf = ct.tf(gain * np.poly(zeros).real, np.poly(poles).real, DT)
    with pytest.raises(ValueError, match="state-space model"):
        controller_sos(Ktf)


# --- float32: a pole rounded onto the unit circle is refused, a large error reported -------
def lag(distance):
    """A unit-DC-gain lag with its pole at z = 1 - distance."""
    return ct.tf([distance], [1.0, -(1.0 - distance)], DT)


def resonance(radius, theta=0.01):
    """A unit-DC-gain resonance with poles at radius e^{+-j theta}."""
    den = [1.0, -2 * radius * np.cos(theta), radius ** 2]
    return ct.tf([sum(den)], den, DT)


@pytest.mark.parametrize("Kd, r64", [(lag(1e-9), "0.999999999"),
                                     (resonance(1 - 1e-8), "0.99999999")])
def test_float32_export_refuses_a_pole_rounded_onto_the_unit_circle(Kd, r64, tmp_path):
    with pytest.raises(ExportError, match=rf"Kd: .*section 0 of K marginal .*radius {r64} .*"
                                           r"in float64, 1 .*in float32"):
        export_controller(Kd, tmp_path, "K")
    assert not list(tmp_path.iterdir())                     # nothing written
    sos = controller_sos(Kd)                                # float64 sections are fine
    for run in (lambda: SectionFilter(sos, "float32"), lambda: sos_filter(sos, [1.0], "float32"),
                lambda: SectionFilter(sos.sos, "float32"),
                lambda: write_json(sos, tmp_path / "k.json"),
                lambda: write_c_header(sos, tmp_path / "k.h")):
        with pytest.raises(ExportError, match="section 0"):
            run()
    assert not list(tmp_path.iterdir())
    assert isinstance(ExportError("x"), ValueError)
    # a float64 target: exported, the float32 coefficients written alongside flagged
    with pytest.warns(ExportWarning, match="marginal"):
        deployed = export_controller(Kd, tmp_path, "K", dtype="float64")
    np.testing.assert_array_equal(deployed.sos, sos.sos)
    SectionFilter(sos, "float64")                           # float64 arithmetic: no check


def test_float32_response_error_beyond_the_rounding_is_reported(tmp_path):
    # pole at 1 - 1.4 ulp: float32 puts it at 1 - 1 ulp, the DC gain grows by 40 %, more
    # than the first-order effect of the rounding (0.5 ulp / 1.4 ulp = 36 %)
    Kd = lag(1.4 * 2.0 ** -24)
    with pytest.warns(ExportWarning, match=r"by 0\.4 \(relative\) at DC, more than the "
                                           r"first-order effect of the rounding \(0\.357\).*"
                                           r"DC gain 1 in float64, 1\.4 in float32"):
        deployed = export_controller(Kd, tmp_path, "K")
    with pytest.warns(ExportWarning, match="at DC"):
        check = controller_sos(Kd).check_float32()
    assert check.max_error == pytest.approx(0.4, rel=1e-6) and check.omega_max_error == 0
    assert check.dc_gain == pytest.approx((1.0, 1.4), rel=1e-6)
    assert deployed.sos[0, 4] == np.float32(-(1 - 2.0 ** -24))
    assert issubclass(ExportWarning, UserWarning)


def test_float32_rtol_is_an_application_tolerance(tmp_path):
    # pole at 1 - 1e-7: float32 moves it to 1 - 2^-23 (away from the circle), the DC gain
    # drops by 16 %: within the rounding's own effect (19 %), not within rtol = 1 %
    Kd = lag(1e-7)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExportWarning)
        export_controller(Kd, tmp_path, "K")
    with pytest.warns(ExportWarning) as caught:
        export_controller(Kd, tmp_path, "K", rtol=0.01)
    text = " ".join(str(w.message) for w in caught)
    assert "pole 0 of section 0 (at DC): its distance to the unit circle changes by 0.192" in text
    assert re.search(r"by 0\.161 \(relative\) at DC, more than rtol \(0\.01\)", text)
    with pytest.raises(ValueError, match="rtol"):
        export_controller(Kd, tmp_path, "K", rtol=0.0)


def test_project_controllers_pass_the_float32_check_silently(exported, tmp_path):
    Kd, sos = exported
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExportWarning)
        export_controller(Kd, tmp_path, "K_test")
        for path in sorted((ROOT / "data" / "controllers").glob("K_*.json")):
            check = read_json(path, "float64").check_float32()
            assert np.all(check.stability32 == check.stability64), path
            SectionFilter(read_json(path, "float32"), "float32")
    # the float32 error stays within the first-order effect of the rounding (the tolerance);
    # it is large only next to the zeros at z = -1, where the response itself vanishes
    check = sos.check_float32()
    known = np.isfinite(check.error)
    assert np.all(check.error[known] <= check.bound[known])
    assert np.max(check.error[known & (check.omega < 0.9 * np.pi * FS)]) < 1e-3


# --- a written file carries its checksum ---------------------------------------------------
def test_an_edited_section_file_is_refused(exported, tmp_path):
    # write_json seals the file with a SHA-256 of its content; a changed coefficient (one
    # step to the next double) is an edited or corrupted file, not a controller to run
    _, sos = exported
    path = write_json(sos, tmp_path / "k.json")
    read_json(path, "float32")
    doc = json.loads(path.read_text())
    doc["sos_float64"][0][1] = float(np.nextafter(doc["sos_float64"][0][1], np.inf))
    path.write_text(json.dumps(doc, indent=1))
    with pytest.raises(ValueError, match=rf"path {re.escape(str(path))}: content differs"):
        read_json(path)


# --- sections must be normalised: a0 = 1 --------------------------------------------------
def test_sections_with_a0_other_than_one_are_refused(exported, tmp_path):
    _, sos = exported
    path = write_json(sos, tmp_path / "k.json")
    doc = json.loads(path.read_text())
    doc["sos_float32"][2][3] = 2.0
    del doc["content_sha256"]                 # as a hand-written file: no checksum
    path.write_text(json.dumps(doc))
    read_json(path, "float64")
    with pytest.raises(ValueError, match=rf"path {re.escape(str(path))}: section 2 of "
                                         r"sos_float32 has a0 = 2\.0"):
        read_json(path, "float32")
    with pytest.raises(ValueError, match=r"sos section 0 has a0 = 2\.0"):
        SOSController(np.array([[1.0, 0, 0, 2.0, -1.0, 0]]), FS)
    with pytest.raises(ValueError, match=r"controller section 0 has a0 = 0\.5"):
        SectionFilter(np.array([[1.0, 0, 0, 0.5, -0.25, 0]]))
    with pytest.raises(ValueError, match="fs"):
        SOSController(sos.sos, -1.0)
