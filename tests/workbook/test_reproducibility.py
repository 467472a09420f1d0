"""The committed results follow from the committed reference artifacts on this machine.

Reproducibility rule (README): a table row states its precision (default one unit of the 4th
significant digit; a statistic over noise seeds: a quarter of its 95 % interval).  Every number
downstream of the committed artifacts (controllers, their float32 sections, the workbook Dahl
model) is deterministic up to floating-point rounding, so recomputing it here must give the
committed value within that precision.  Run before the notebooks rewrite data/results/ (pytest
runs tests/ before notebooks/).
"""

import pandas as pd
import pytest

from piezolib.problem import analysis
from piezolib.problem.hysteresis_fits import workbook_dahl_fit
from piezolib.problem.stage import VirtualStage
from piezolib.workbook import experiments, pipeline, report, study
from piezolib.workbook.outputs import data_dir

RTOL = 1e-3


def committed(table, quantity):
    frame = pd.read_csv(data_dir() / "results" / f"{table}.csv")
    return float(frame.set_index("quantity").loc[quantity, "ours"])


def committed_row(table, quantity):
    frame = pd.read_csv(data_dir() / "results" / f"{table}.csv", dtype=str, keep_default_na=False)
    return frame.set_index("quantity").loc[quantity]


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


def test_table5_case_III_with_the_committed_controller():
    reference = study.load("reference")
    sections = pipeline.study_sections(reference)["K_ours"]
    result = experiments.tracking_test(VirtualStage(seed=0), workbook_dahl_fit().model, sections,
                                       (1.0, 50.0), seeds=reference.experiments.seeds)
    for f in (1.0, 50.0):
        row = committed_row("tracking", f"tracking error case_III at {f:g} Hz")
        again = row.copy()
        again["ours"] = f"{result.table.loc['case_III', f]:.4g}"
        again["low"] = f"{result.low.loc['case_III', f]:.4g}"
        again["high"] = f"{result.high.loc['case_III', f]:.4g}"
        assert report.same_result(row, again), (f, row[["ours", "low", "high"]].tolist(),
                                                again[["ours", "low", "high"]].tolist())
