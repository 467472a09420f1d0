"""Export of discrete controllers as second-order sections, checked with the reference filter."""

import json
import shutil
import subprocess

import control as ct
import numpy as np
import pytest

from piezolib.robust.discrete import discretize
from piezolib.robust.export import (SectionFilter, SOSController, controller_sos,
                                    export_controller, read_json, sos_filter, write_c_header,
                                    write_json)
from piezolib.robust.margins import delay_tolerance

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
