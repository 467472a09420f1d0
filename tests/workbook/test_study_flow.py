"""A changed study flows from notebook 04 through 05, 06 and 07, headless, into runs/<study>/."""

import pandas as pd
import pytest

from piezolib.workbook import pipeline, reproduce, study
from piezolib.workbook.outputs import notebooks_dir, runs_dir


def ours(table, quantity):
    return float(table.set_index("quantity").loc[quantity, "ours"])


@pytest.mark.slow
def test_changed_weights_reach_the_controller_numbers_of_05_06_07(tmp_path):
    # a small study: wider error weight, a short DK-iteration with low-order D-fits
    small = study.load("reference").replace(
        name="test_small_flow", description="test: 04-07 with other weights",
        weights={"omega_e": 1600.0}, design={"max_iter": 2, "d_order": 2})
    path = small.save(tmp_path / "test_small_flow.toml")
    out = runs_dir() / small.name
    root = notebooks_dir().parent
    committed = sorted([*(root / "data" / "results").glob("*.csv"), *(root / "figures").glob("*.png"),
                        *(root / "data" / "controllers").glob("*")])
    before = {p: p.stat().st_mtime_ns for p in committed}
    for prefix in ("04", "05", "06", "07"):
        notebook, = reproduce.list_notebooks([prefix])
        reproduce.run_notebook(notebook, study=path, save_to=out / "notebooks")
    assert (out / "notebooks" / "05_mu_synthesis.ipynb").is_file()
    controllers = pipeline.derive_controllers(small)            # the cached design 05 made
    assert controllers.source == "disk cache"
    reference = pipeline.study_controllers("reference")
    assert abs(controllers.mu["no-delay DK"] - reference.mu["no-delay DK"]) > 1e-3

    results = out / "results"
    mu = pd.read_csv(results / "mu_synthesis.csv")
    # 05 reports the new design's mu (rounded to 4 significant digits), not the reference's
    assert ours(mu, "mu upper bound of the full-order controller") == float(
        f"{controllers.mu['no-delay DK']:.4g}")
    assert ours(mu, "order of the full-order controller") == controllers.K_nodelay_full.nstates
    # 06 ran the new deployed controller: its Case III row differs from the reference's
    track = pd.read_csv(results / "tracking.csv")
    ref_track = pd.read_csv(notebooks_dir().parent / "data" / "results" / "tracking.csv")
    q = "tracking error case_III at 50 Hz"
    assert ours(track, q) != ours(ref_track, q)
    # 07 gathered this study's tables for 04-06 and the reference's for the others
    report = pd.read_csv(results / "reproduction.csv")
    by_source = report.groupby("source").study.first()
    assert by_source["05_mu_synthesis"] == by_source["06_tracking_experiments"] == small.name
    assert by_source["01_identification"] == "reference"
    # and nothing was written to the reference study's folders
    assert {p: p.stat().st_mtime_ns for p in committed} == before
    exported = pipeline.read_controllers(out / "artifacts" / "controllers.json")
    assert exported.digest == pipeline.design_digest(small)
    assert (out / "controllers" / "K_ours.json").is_file()
