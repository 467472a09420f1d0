"""Experiment files of the virtual stage: byte-identical regeneration, loaders, chirps."""

import numpy as np
import pytest

from piezolib import paper
from piezolib.problem import stage_data as D
from piezolib.problem.stage import VirtualStage
from piezolib.problem.stage_calibration import case_I_input
from piezolib.workbook.outputs import data_dir


def test_experiment_files_are_reproducible_and_current(tmp_path):
    first = D.write_experiment_files(tmp_path / "a")
    second = D.write_experiment_files(tmp_path / "b")
    for p, q in zip(first, second):
        assert p.read_bytes() == q.read_bytes()
    committed = {**D.experiment_paths(), "manifest": D.manifest_path()}
    assert first[-1].name == D.MANIFEST_NAME               # the manifest too, byte-identical
    for p in first:
        stored = [c for c in committed.values() if c.name == p.name][0]
        assert stored.exists(), f"{stored} missing: run python -m piezolib data"
        assert stored.read_bytes() == p.read_bytes(), f"{stored} is out of date"


def test_default_directory_is_the_workbook_data_folder():
    paths = D.experiment_paths()
    assert {p.parent for p in paths.values()} == {data_dir()}
    assert sorted(k for k in paths if isinstance(k, float)) == sorted(D.EXPERIMENT_SEEDS)


def test_loaders_round_trip():
    loops = D.load_hysteresis_loops()
    assert sorted(loops) == [10.0, 20.0, 30.0, 40.0]
    rec = loops[20.0]
    assert len(rec) == 3001 and rec.v_a_V.max() == pytest.approx(20.0, abs=1e-3)
    fresh = VirtualStage(seed=D.EXPERIMENT_SEEDS[20.0]).run(case_I_input(20.0))
    assert np.allclose(rec.v_y_V, fresh.v_y_V, atol=1e-7)
    chirp = D.load_chirp("validation")
    u_op, y_op = chirp.operating_point
    assert u_op == pytest.approx(D.VALIDATION_CHIRP.top_V, abs=1e-3)
    assert chirp.sweep.u_c_V.max() <= u_op + 1e-7
    assert chirp.metadata["seed"] == D.VALIDATION_CHIRP.seed
    with pytest.raises(ValueError, match="which"):
        D.load_chirp("other")


def test_missing_file_names_the_regeneration_command(tmp_path):
    with pytest.raises(FileNotFoundError, match="python -m piezolib data"):
        D.load_record(tmp_path / "nothing.csv")
    with pytest.raises(FileNotFoundError, match="python -m piezolib data"):
        D.load_hysteresis_loops(tmp_path)


def test_chirp_deviations_start_at_rest_on_the_operating_point():
    chirp = D.load_chirp("identification")
    u, y, k = chirp.deviations()
    assert len(u) == len(y) == len(chirp.record) - chirp.hold_start
    assert k == chirp.start - chirp.hold_start
    assert np.all(u[:k] == 0.0) and abs(np.mean(y[:k])) < 1e-12   # the hold: at rest
    assert np.array_equal(u[k:], chirp.sweep.u_c_V - chirp.operating_point[0])


@pytest.mark.parametrize("settings", [D.IDENTIFICATION_CHIRP, D.VALIDATION_CHIRP],
                         ids=lambda s: s.name)
def test_chirp_input_ramps_holds_and_stays_below_its_top(settings):
    fs = paper.SAMPLING_FREQUENCY_HZ
    u, start = D.chirp_input(settings, fs)
    n_ramp = int(round(settings.ramp_s * fs))
    assert start == n_ramp + int(round(settings.hold_s * fs))
    assert len(u) == start + int(round(settings.duration_s * fs))
    assert u[0] == 0.0 and np.all(np.diff(u[:n_ramp]) > 0)
    assert np.all(u[n_ramp:start] == settings.top_V) and u[start] == settings.top_V
    assert u.max() <= settings.top_V
    assert np.ptp(u[start:]) == pytest.approx(2 * settings.amplitude_V, rel=1e-3)


def test_manifest_is_current_and_every_committed_file_passes():
    assert D.manifest_path().exists(), "data/manifest.json missing: run python -m piezolib data"
    assert D.check_experiment_files() == {}
    entries = D.read_manifest()
    assert sorted(entries) == sorted(p.name for p in D.experiment_paths().values())
    assert entries["hysteresis_loop_20V.csv"]["rows"] == 3001


@pytest.fixture
def data_copy(tmp_path):
    import shutil
    for p in [*D.experiment_paths().values(), D.manifest_path()]:
        shutil.copy(p, tmp_path / p.name)
    return tmp_path


def test_truncated_or_corrupted_file_names_the_file_and_line(data_copy):
    path = data_copy / "hysteresis_loop_20V.csv"
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[:2000]))                     # cut at a line boundary
    with pytest.raises(ValueError, match=r"hysteresis_loop_20V.csv, line 2001: truncated"):
        D.load_hysteresis_loops(data_copy)
    problems = D.check_experiment_files(data_copy)
    assert list(problems) == [path] and "line 2001" in problems[path]
    bad = lines[:118] + ["0.0098,abc,0.1,0.1,0.1\n"] + lines[119:]
    path.write_text("".join(bad))
    with pytest.raises(ValueError, match=r"line 119: column 'u_c_V': 'abc' is not a number"):
        D.load_record(path)
    path.write_text("".join(lines[:22]))                       # header only
    with pytest.raises(ValueError, match="line 23: truncated"):
        D.load_record(path)


def test_a_file_that_is_no_record_names_the_file(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("a,b\nx,y\n")
    with pytest.raises(ValueError, match=r"r\.csv, line 1: missing column 't_s'"):
        D.load_record(path)
    with pytest.raises(NotADirectoryError, match="directory must be a folder"):
        D.load_hysteresis_loops(path)


def test_foreign_records_are_reproducible_and_current(tmp_path):
    written = D.write_foreign_records(tmp_path)
    committed = D.foreign_record_paths()
    for p in written:
        assert committed[p.name].exists(), f"{committed[p.name]} missing"
        assert committed[p.name].read_bytes() == p.read_bytes(), f"{p.name} is out of date"


def test_foreign_records_have_the_foreign_form():
    from piezolib import records
    path = D.foreign_record_paths()["loop_sine.csv"]
    assert not path.read_text().startswith("#")                 # no header, no comments
    rec = records.load_csv(path, time=0, input=1, output=2, input_unit="V", output_unit="um")
    assert rec.fs == pytest.approx(D.FOREIGN_FORM["sample_rate_Hz"])
    rest = int(D.FOREIGN_FORM["rest_s"] * rec.fs)
    assert np.all(rec.input[:rest] == 0) and rec.input[rest] > 1.0      # at rest, then a step
    # 5x the stage's noise: 3 um/V x 2.5 mV = 7.5 nm rms (plus 0.9 nm ADC steps) at rest
    assert 0.005 < np.std(rec.output[:rest]) < 0.011


def test_raw_record_starts_at_rest_steps_rings_and_has_a_noise_free_twin():
    """The raw record: the step sample is the input's first turning point, it rings
    the stage's resonances, and the noisy record differs from its twin by the noise only."""
    from piezolib import records
    from piezolib.problem.stage_data import RAW_RECORD, raw_hysteresis_record
    raw = raw_hysteresis_record()
    rec, twin, k = raw.record, raw.noise_free, raw.step_index
    assert rec.fs == RAW_RECORD["sample_rate_Hz"] and len(rec) >= 50_000
    np.testing.assert_array_equal(rec.input, twin.input)
    assert np.all(rec.input[:k] == 0) and rec.input[k] == pytest.approx(RAW_RECORD["top_V"], abs=1e-3)
    points = records.turning_points(rec.input)
    assert np.all(rec.input[k:points[0] + 1] == rec.input[k])    # first turning point: the step
    top = twin.output[k:k + 50]
    assert top.max() > 1.2 * twin.output[points[0] + 200]          # the overshoot rings
    noise = rec.output - twin.output
    assert np.std(noise) == pytest.approx(raw.noise_rms_V, rel=0.05)
    start_up = records.find_start_up(rec)
    assert start_up.step == k and k < start_up.settled < k + 250   # tens of ms of ringing
    with pytest.raises(ValueError, match="DAC range"):
        raw_hysteresis_record(amplitudes_V=(5.0,))
