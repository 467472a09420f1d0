"""The committed results follow from the committed reference controllers on this machine.

Reproducibility rule (README): tables keep 4 significant digits; every number downstream of
the committed reference controllers (data/controllers/reference_design.json) is deterministic up
to floating-point rounding, so recomputing it here must give the committed value within one unit
of the 4th digit (relative 1e-3).  Run before the notebooks rewrite data/results/ (pytest runs
tests/ before notebooks/).
"""

import pandas as pd
import pytest

from piezolib.problem import analysis
from piezolib.problem.hysteresis import workbook_dahl_fit
from piezolib.problem.stage import VirtualStage
from piezolib.robust import export
from piezolib.robust.discrete import discretize
from piezolib.workbook import experiments, pipeline
from piezolib.workbook.paths import data_dir

RTOL = 1e-3


def committed(table, quantity):
    frame = pd.read_csv(data_dir() / "results" / f"{table}.csv")
    return float(frame.set_index("quantity").loc[quantity, "ours"])


@pytest.fixture(scope="module")
def problem():
    return pipeline.study_problem("reference")


def test_table3_mu_of_the_committed_controllers(problem):
    G, H_m, H_e, H_y, K_pub = problem
    ours = pipeline.study_controllers("reference")
    for name, K in (("published K (eq. 24)", K_pub),
                    (f"our reduced K ({ours.K_nodelay_reduced.nstates})", ours.K_nodelay_reduced),
                    (f"delay-aware fixed-order K ({ours.K_fixed.nstates})", ours.K_fixed)):
        mu = analysis.analyze(K, G, H_m, H_e, H_y, name=name).mu_RP
        assert mu == pytest.approx(committed("mu_synthesis", f"mu_RP ({name})"), rel=RTOL), name


def test_table5_case_III_with_the_committed_controller(problem, tmp_path):
    G = problem.G
    ours = pipeline.study_controllers("reference")
    sections = export.export_controller(discretize(ours.K_deployed, 10_000.0, G=G).K, tmp_path,
                                        "K", meta={})
    result = experiments.tracking_test(VirtualStage(seed=0), workbook_dahl_fit().model, sections,
                                       (1.0, 50.0))
    for f in (1.0, 50.0):
        value = float(result.table.loc["case_III", f])
        assert value == pytest.approx(
            committed("tracking", f"tracking error case_III at {f:g} Hz"), rel=RTOL), f
