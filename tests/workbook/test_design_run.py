"""The record of the design searches: written and read back exactly, refused when edited,
the committed one belonging to the committed controllers (the slow step re-runs the searches:
test_design_rederivation.py)."""

import json

import control as ct
import numpy as np
import pandas as pd
import pytest

from piezolib.problem import verification
from piezolib.workbook import design_run, pipeline


def small_run():
    history = pd.DataFrame({"iteration": [1, 2], "mu_upper": [1.3, 0.81],
                            "mu_lower": [np.nan, 0.8], "accepted": [True, False]})
    omega = np.logspace(0, 3, 5)
    dk = design_run.SearchRecord(history, "done", 0.81, 0.8, omega, 2.5,
                                 np.linspace(1, 2, 5) + 0.1j, np.linspace(1, 2, 5), 4)
    fixed = design_run.SearchRecord(history, "stalled", 0.79, 0.78, omega, 1.5)
    K = ct.ss([[-1.0]], [[1.0]], [[2.0]], [[0.5]], inputs=["v_e"], outputs=["u_b"], name="K")
    return design_run.DesignRun("reference", "abc", "test", dk, fixed, {"fixed order": 0.79},
                                {0: (0.7, 0.5), 1: (0.8, np.nan)}, K, K)


def test_a_record_reads_back_exactly(tmp_path):
    run = small_run()
    back = design_run.read_design_run(design_run.write_design_run(run, tmp_path / "r.json"))
    pd.testing.assert_frame_equal(back.dk.history, run.dk.history)
    assert np.array_equal(back.dk.optimal_d, run.dk.optimal_d)
    assert np.array_equal(back.dk.d_fit, run.dk.d_fit) and back.dk.d_fit_order == 4
    assert back.fixed_order.d_fit is None and back.fixed_order.elapsed == 1.5
    assert back.delay_sweep[0] == (0.7, 0.5) and np.isnan(back.delay_sweep[1][1])
    assert back.mu == run.mu and np.array_equal(back.K_full.A, run.K_full.A)


def test_a_failed_mu_value_reads_back_as_nan(tmp_path):
    # a search whose H-inf step failed has mu NaN: written as null, read back as NaN
    run = small_run()
    run = design_run.DesignRun(*[{"fixed order": np.nan} if f == "mu" else getattr(run, f)
                                 for f in design_run.DesignRun.__dataclass_fields__])
    back = design_run.read_design_run(design_run.write_design_run(run, tmp_path / "r.json"))
    assert np.isnan(back.mu["fixed order"])


def test_an_edited_record_is_refused_naming_the_file(tmp_path):
    path = design_run.write_design_run(small_run(), tmp_path / "r.json")
    doc = json.loads(path.read_text())
    doc["delay_sweep"]["0"][0] = 0.5
    path.write_text(json.dumps(doc))
    with pytest.raises(pipeline.ArtifactError, match="r.json"):
        design_run.read_design_run(path)
    path.write_text("[1, 2]")
    with pytest.raises(pipeline.ArtifactError, match="r.json.*not a JSON object"):
        design_run.read_design_run(path)


def test_the_committed_record_belongs_to_the_committed_controllers():
    run = design_run.study_design_run("reference")
    ours = pipeline.study_controllers("reference")
    assert run.digest == ours.digest == pipeline.design_digest("reference")
    assert all(verification.compare_rederived(ours, run).checks.values())
    assert set(run.delay_sweep) == set(design_run.SWEEP_DELAYS)
    assert run.dk.d_fit is not None and run.dk.d_fit.shape == run.dk.omega.shape
