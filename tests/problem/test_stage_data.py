"""Experiment files of the virtual stage: byte-identical regeneration, loaders, chirps."""

import numpy as np
import pytest

from piezolib import paper
from piezolib.problem import stage_data as D
from piezolib.problem.stage import VirtualStage, case_I_input
from piezolib.workbook.paths import data_dir


def test_experiment_files_are_reproducible_and_current(tmp_path):
    first = D.write_experiment_files(tmp_path / "a")
    second = D.write_experiment_files(tmp_path / "b")
    for p, q in zip(first, second):
        assert p.read_bytes() == q.read_bytes()
    committed = D.experiment_paths()
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
