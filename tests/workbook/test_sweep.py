"""Design sweeps: runs on local workers and on a dask cluster, resuming from the per-point
records, the Pareto front, what a run shows (the specs: test_sweep_spec.py)."""

import io
import json
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from piezolib.workbook import cli, sweep, sweep_spec
from piezolib.workbook import study as studies

REPOSITORY = Path(__file__).resolve().parents[2]

#: What the fake evaluation does: ``calls`` counts them, ``stop_after`` interrupts the
#: sweep like Ctrl-C after that many calls, ``fail`` makes those omega_e values fail.
FAKE = {"calls": 0, "stop_after": None, "fail": (), "nan": ()}


def fake_evaluate(study, controller="fixed_order"):
    """Cheap, deterministic numbers of a point (module level: workers import it)."""
    FAKE["calls"] += 1
    if FAKE["stop_after"] is not None and FAKE["calls"] > FAKE["stop_after"]:
        raise KeyboardInterrupt
    omega_e = study.weights.omega_e
    if omega_e in FAKE["fail"]:
        raise RuntimeError(f"no design for omega_e {omega_e}")
    order = study.design.order if controller == "fixed_order" else 20
    if omega_e in FAKE["nan"]:
        return {"mu_RP": float("nan"), "controller_states": order}
    return {"mu_RP": omega_e / 1000 + 0.01 * order, "controller_states": order,
            "tracking_error_50Hz_percent": 5000 / omega_e + 0.1 * study.uncertainty.spread,
            "tracking_error_50Hz_low_percent": 5000 / omega_e - 0.01,
            "tracking_error_50Hz_high_percent": 5000 / omega_e + 0.01}


@pytest.fixture(autouse=True)
def checkout(tmp_path, monkeypatch):
    """Outputs under tmp_path (never the repository), a fresh fake evaluation."""
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    monkeypatch.setitem(FAKE, "calls", 0)
    monkeypatch.setitem(FAKE, "stop_after", None)
    monkeypatch.setitem(FAKE, "fail", ())
    monkeypatch.setitem(FAKE, "nan", ())
    return tmp_path


def grid_spec(name="small", **changes):
    data = {"name": name, "study": "reference", "set": {"design": {"max_iter": 2}},
            "grid": {"weights": {"omega_e": [1000.0, 1260.0, 1600.0]}, "design.order": [4, 6]}}
    return sweep_spec.spec_from_dict({**data, **changes})


def write(path, text):
    path.write_text(text, encoding="utf-8")
    return path


# --------------------------------------------------------------------------- runs
def run(spec, **options):
    stream = io.StringIO()
    result = sweep.run_sweep(spec, evaluate=fake_evaluate, stream=stream, **options)
    return result, stream.getvalue()


def test_a_grid_run_writes_one_row_per_point_a_record_each_and_the_figure(checkout):
    result, said = run(grid_spec(), jobs=1)
    table = result.table
    assert (result.evaluated, result.reused, result.failed) == (6, 0, 0)
    assert list(table["point"]) == list(range(1, 7))
    assert list(table.columns[:4]) == ["point", "weights.omega_e", "design.order", "controller"]
    assert np.allclose(table["mu_RP"], table["weights.omega_e"] / 1000 + 0.01 * table["design.order"])
    # the front: lower omega_e lowers mu_RP and raises the error; order 6 is dominated by 4
    assert list(table.loc[table.pareto, "point"]) == [1, 3, 5]
    out = checkout / "runs" / "sweeps" / "small"
    assert result.paths["table"] == out / "results.csv" and result.paths["figure"].is_file()
    assert pd.read_csv(out / "results.csv")["mu_RP"].tolist() == table["mu_RP"].tolist()
    assert len(list((out / "points").glob("*.json"))) == 6
    lines = said.splitlines()
    assert "[1/6] omega_e=1000 order=4  mu_RP 1.04  e(50 Hz) 5.005 %" in said
    assert sum(line.startswith("[") for line in lines) == 6
    assert lines[-1].startswith("sweep small: 6 evaluated, 0 reused, 0 failed in")
    # nothing outside runs/sweeps/<name>/
    assert sorted(p.name for p in checkout.iterdir()) == ["runs"]


def test_a_local_dask_cluster_gives_the_same_table_as_local_workers():
    distributed = pytest.importorskip("distributed")
    local, _ = run(grid_spec("on_joblib"), jobs=1)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        remote, said = run(grid_spec("on_dask"), scheduler=cluster.scheduler_address)
    assert "on tcp://" in said or "on inproc://" in said
    assert remote.evaluated == 6
    pd.testing.assert_frame_equal(local.table, remote.table)


def test_a_sweep_killed_halfway_runs_only_the_missing_points_again(checkout):
    FAKE["stop_after"] = 4
    with pytest.raises(KeyboardInterrupt):
        run(grid_spec(), jobs=1)
    records = checkout / "runs" / "sweeps" / "small" / "points"
    assert len(list(records.glob("*.json"))) == 4           # each stored as it finished
    FAKE.update(calls=0, stop_after=None)
    result, said = run(grid_spec(), jobs=1)
    assert FAKE["calls"] == 2 and (result.evaluated, result.reused) == (2, 4)
    assert "6 points, 4 stored (reused), 2 to run" in said
    assert said.splitlines()[1].startswith("[5/6]")
    fresh, _ = run(grid_spec("fresh"), jobs=1)
    pd.testing.assert_frame_equal(result.table.drop(columns="key"),
                                  fresh.table.drop(columns="key"))
    # a third run reuses everything
    FAKE["calls"] = 0
    again, _ = run(grid_spec(), jobs=1)
    assert FAKE["calls"] == 0 and again.reused == 6


def test_a_corrupted_or_foreign_record_is_computed_again(checkout):
    run(grid_spec(), jobs=1)
    records = sorted((checkout / "runs" / "sweeps" / "small" / "points").glob("*.json"))
    doc = json.loads(records[0].read_text())
    doc["metrics"]["mu_RP"] = 0.1                          # edited by hand: fails its seal
    records[0].write_text(json.dumps(doc))
    records[1].write_text("{not json")
    assert sweep.read_record(records[0]) is None and sweep.read_record(records[1]) is None
    assert sweep.read_record(records[2], key="0" * 16) is None      # another point's key
    FAKE["calls"] = 0
    result, _ = run(grid_spec(), jobs=1)
    assert FAKE["calls"] == 2 and result.reused == 4
    assert 0.1 not in result.table["mu_RP"].tolist()


def test_a_failing_point_is_reported_not_stored_and_retried(checkout):
    FAKE["fail"] = (1260.0,)
    result, said = run(grid_spec(), jobs=1)
    assert (result.evaluated, result.failed) == (4, 2)
    failed = result.table[result.table.error != ""]
    assert list(failed.point) == [3, 4] and failed.mu_RP.isna().all()
    assert "FAILED: RuntimeError: no design for omega_e 1260.0" in said
    assert not failed.pareto.any()
    FAKE.update(calls=0, fail=())
    again, _ = run(grid_spec(), jobs=1)
    assert FAKE["calls"] == 2 and again.failed == 0


def test_a_point_with_a_non_finite_metric_is_a_failure_not_a_stored_success(checkout):
    # stored as sealed successes before, and reused on every rerun
    FAKE["nan"] = (1600.0,)
    result, said = run(grid_spec(), jobs=1)
    assert result.failed == 2 and "non-finite metrics: {'mu_RP': nan}" in said
    assert len(list((checkout / "runs" / "sweeps" / "small" / "points").glob("*.json"))) == 4
    FAKE.update(calls=0, nan=())
    again, _ = run(grid_spec(), jobs=1)
    assert FAKE["calls"] == 2 and again.failed == 0


def test_a_dry_run_lists_the_points_and_runs_nothing(checkout):
    run(grid_spec(), jobs=1)
    FAKE["calls"] = 0
    result, said = run(grid_spec(name="small", grid={"design.order": [4, 5]}), dry_run=True)
    assert FAKE["calls"] == 0
    # order 4 at the base's omega_e is point 3 of the first run: the same study, its record
    assert list(result.table["stored"]) == [True, False]
    assert "[1/2] order=4  (stored, key" in said and "[2/2] order=5  (to run, key" in said


def test_the_command_line_runs_and_lists_a_spec(checkout, capsys):
    path = write(checkout / "cli_sweep.toml",
                 '[set]\ndesign.max_iter = 1\n[grid]\nweights.omega_e = [1000.0, 2000.0]\n')
    stream = io.StringIO()
    assert cli.main(["sweep", str(path), "--dry-run"], stream=stream) == 0
    out = stream.getvalue()
    assert "[2/2] omega_e=2000  (to run" in out and "2 points, 0 stored, 2 to run" in out
    assert cli.main(["sweep", str(checkout / "missing.toml")]) == 2
    assert "missing.toml" in capsys.readouterr().err


def test_a_malformed_scheduler_address_fails_before_anything_runs():
    with pytest.raises(ValueError, match="scheduler"):
        sweep.run_sweep(grid_spec(), scheduler="localhost:8786", evaluate=fake_evaluate)
    assert FAKE["calls"] == 0


# --------------------------------------------------------------------------- Pareto
def test_the_pareto_front_keeps_the_undominated_rows_and_skips_missing_values():
    table = pd.DataFrame({"a": [1.0, 2.0, np.nan, 0.5, 1.0], "b": [2.0, 1.0, 0.1, 3.0, 2.0]})
    assert sweep.pareto_front(table, "a", "b").tolist() == [True, True, False, True, True]
    with pytest.raises(ValueError, match="y"):
        sweep.pareto_front(table, "a", "c")


# --------------------------------------------------------------------------- the real one
@pytest.mark.slow
def test_a_real_point_gives_its_design_margins_and_tracking(checkout, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(REPOSITORY))       # the committed Dahl model and data
    monkeypatch.setenv("PIEZOLIB_CACHE", str(checkout / "cache"))     # a fresh design, written here
    point = studies.Study().replace(name="real_point", design={"max_iter": 1, "order": 4})
    metrics = sweep.evaluate_point(point)
    assert set(metrics) == set(sweep.METRICS)
    assert metrics["controller_states"] == 4
    assert 0.7176 < metrics["mu_RP"] < 3          # above the achievable bound (README)
    assert (metrics["tracking_error_50Hz_low_percent"] <= metrics["tracking_error_50Hz_percent"]
            <= metrics["tracking_error_50Hz_high_percent"])
    full = sweep.evaluate_point(point, controller="full_order")
    assert full["mu_RP"] == metrics["mu_RP_full_order"] and full["controller_states"] > 4


# --------------------------------------------------------------------------- what a run shows
def test_a_runs_checks_findings_and_its_rerun(checkout):
    spec = grid_spec()
    result, _ = run(spec, jobs=1)
    assert result.checks and all(result.checks.values())
    assert "the deployed controller has the swept order" in result.checks
    assert list(result.overview().columns) == [
        "point", "weights.omega_e", "design.order", "mu_RP", "controller_states",
        "tracking_error_50Hz_percent", "pareto"]
    lines = result.findings()
    assert lines[0].startswith("**6 designs** over ω_e ∈ {1000, 1260, 1600} × order ∈ {4, 6} "
                               "(2 DK iteration(s) each)")
    assert "1 local worker(s); 0 reused, 0 failed." in lines[0]
    assert lines[1] == "**Lowest μ_RP:** 1.040 at ω_e = 1000, order = 4 (50 Hz error 5.00 %)."
    assert lines[-1].startswith("**Pareto front:** points 1, 3, 5 of 6")
    again, _ = run(spec, jobs=1)
    assert all(again.resumed_checks(result).values())
    assert not all(result.resumed_checks(result).values())    # it computed its points
    assert spec.clear_records() == 6 and spec.clear_records() == 0
    fresh, _ = run(spec, jobs=1)
    assert fresh.evaluated == 6


def test_the_checks_of_a_run_can_fail(checkout):
    result, _ = run(grid_spec(), jobs=1)
    table = result.table
    broken = {
        "the front holds every undominated point": table.assign(pareto=False),
        "no point of the Pareto front is beaten in both numbers": table.assign(pareto=True),
        "the deployed controller has the swept order": table.assign(controller_states=20),
        "the 95 % interval of the 50 Hz error holds its mean":
            table.assign(tracking_error_50Hz_low_percent=99.0),
        "mu_RP > 0 at every point": table.assign(mu_RP=-1.0),
    }
    for name, bad in broken.items():
        assert not sweep.SweepResult(result.spec, bad, 6, 0, 0, 1.0, {}).checks[name], name
    assert not sweep.SweepResult(result.spec, table, 5, 0, 1, 1.0, {}).checks["every point ran"]


# --------------------------------------------------------------------------- faults
def test_a_second_run_of_a_running_sweep_is_refused_naming_the_first(checkout):
    from piezolib import files

    spec = grid_spec()
    with files.exclusive_lock(spec.directory / sweep.LOCK_NAME, "sweep small"):
        with pytest.raises(files.LockHeld) as info:
            run(spec, jobs=1)
    assert FAKE["calls"] == 0                             # computed every point twice before
    said = str(info.value)
    assert f"process {os.getpid()}" in said and "sweep.lock" in said
    assert "sweep small is already running" in said
    assert not (spec.directory / sweep.LOCK_NAME).exists()    # the first run's end removes it


def test_the_lock_file_of_a_killed_run_is_taken_over(checkout, caplog):
    spec = grid_spec()
    lock = spec.directory / sweep.LOCK_NAME
    lock.parent.mkdir(parents=True)
    lock.write_text(json.dumps({"pid": 999999999, "host": "h", "since": "then"}) + "\n")
    result, _ = run(spec, jobs=1)
    assert result.evaluated == 6 and not lock.exists()
    assert "process 999999999 on h, is no longer running" in caplog.text


def test_an_unwritable_output_folder_is_refused_before_the_first_evaluation(checkout):
    spec = grid_spec()
    spec.directory.parent.mkdir(parents=True)
    spec.directory.write_text("a file where the sweep's folder goes")  # writable by no one
    with pytest.raises(OSError, match="sweeps/small"):
        run(spec, jobs=1)
    assert FAKE["calls"] == 0                       # evaluated a point first, before


def test_a_failed_write_loses_no_computed_point(checkout, monkeypatch):
    from piezolib import files

    real = files.atomic_write
    refused = []

    def full_disk_after_two_records(path, data):      # the disk fills after two records
        if Path(path).parent.name == "points" and len(list(Path(path).parent.glob("*.json"))) >= 2:
            refused.append(Path(path).name)
            raise OSError(28, f"cannot write {path}: No space left on device", str(path))
        return real(path, data)

    monkeypatch.setattr(files, "atomic_write", full_disk_after_two_records)
    result, said = run(grid_spec(), jobs=1)           # stopped at the third point before
    assert (result.evaluated, result.failed) == (6, 0)
    assert result.table["mu_RP"].notna().all()        # every computed point is in the table
    assert len(result.problems) == 4 and "point 3: computed" in result.problems[0]
    assert "No space left on device" in result.problems[0]
    assert "point 3: its record was not written" in said and "NOT STORED: point 6" in said
    assert len(set(refused)) == 4                     # each tried again after later points
    monkeypatch.setattr(files, "atomic_write", real)
    FAKE["calls"] = 0
    again, _ = run(grid_spec(), jobs=1)
    assert FAKE["calls"] == 4 and again.reused == 2 and not again.problems


def test_a_record_refused_once_is_written_after_the_next_point(checkout, monkeypatch):
    from piezolib import files

    real = files.atomic_write
    refusals = {"left": 1}

    def one_refusal(path, data):
        if Path(path).parent.name == "points" and refusals["left"]:
            refusals["left"] -= 1
            raise OSError(5, f"cannot write {path}: Input/output error", str(path))
        return real(path, data)

    monkeypatch.setattr(files, "atomic_write", one_refusal)
    result, said = run(grid_spec(), jobs=1)
    assert not result.problems and "point 1: its record was not written" in said
    assert len(list((result.spec.directory / "points").glob("*.json"))) == 6


# --------------------------------------------------------------------------- progress
def test_each_point_line_says_what_is_done_running_and_left_with_an_estimate():
    _, said = run(grid_spec(), jobs=1)
    lines = [line for line in said.splitlines() if line.startswith("[")]
    assert "| 1 done, 1 running, 4 left; " in lines[0] and " s left" in lines[0]
    assert "| 5 done, 1 running, 0 left; " in lines[4]
    assert "| 6 done, 0 running, 0 left; " in lines[5] and "left" not in lines[5][-10:]


def test_on_a_terminal_the_status_is_a_line_redrawn_in_place():
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    stream = Terminal()
    sweep.run_sweep(grid_spec(), jobs=1, evaluate=fake_evaluate, stream=stream)
    text = stream.getvalue()
    assert "\r" in text and "\x1b[K" in text
    # the status is taken off before the summary, and not drawn again after it
    assert text.rpartition("\r\x1b[K")[2].startswith("sweep small: 6 evaluated")
    assert text.endswith(".png\n")
