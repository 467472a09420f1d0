"""The reference study's design searches re-run from scratch land on the committed record
and the committed controllers (slow: the DK-iterations, the fixed-order search and the delay
sweep take minutes). Notebook 05 shows the committed record instead of re-running them."""

import numpy as np
import pytest

from piezolib.problem import verification
from piezolib.workbook import design_run, pipeline

pytestmark = pytest.mark.slow


def test_the_searches_rerun_from_scratch_land_on_the_committed_record():
    committed = design_run.read_design_run(design_run.design_run_path())
    controllers = pipeline.read_controllers(pipeline.reference_design_path())
    fresh = design_run.derive_design_run("reference", cache=False)
    rtol = verification.RE_DERIVATION_RTOL
    for used in (committed, controllers):
        assert all(verification.compare_rederived(used, fresh, rtol).checks.values())
    for d, (mu, lower) in committed.delay_sweep.items():
        assert fresh.delay_sweep[d][0] == pytest.approx(mu, rel=rtol), d
        assert np.isnan(lower) == np.isnan(fresh.delay_sweep[d][1])
        if not np.isnan(lower):
            assert fresh.delay_sweep[d][1] == pytest.approx(lower, rel=rtol), d
    assert fresh.dk.stop_reason.split(":")[0] == committed.dk.stop_reason.split(":")[0]
