"""Notebook 08's claim rows and closing checks (piezolib.workbook.your_stage_claims): the rows
of a run without a plant, the checks of stages not run, the known truth's checks."""

import numpy as np
import pandas as pd
import pytest

from piezolib import hysteresis as hy
from piezolib.records import Record
from piezolib.workbook import your_stage as own
from piezolib.workbook import your_stage_claims as own_claims
from piezolib.workbook import your_stage_control as own_control
from piezolib.workbook import your_stage_hysteresis as own_hysteresis
from piezolib.workbook.report import ClaimTable

FS = 5000.0
PI_TRUTH = hy.PIModel((0.0, 0.3, 0.6, 0.9), (0.8, 0.2, 0.15, 0.1), x0=0.1)


def loop_pair(n=400):
    v = 1.5 - 1.5 * np.cos(2 * np.pi * np.arange(n) / 100.0)
    return v, PI_TRUTH.simulate(v)


def test_without_a_plant_the_claims_are_the_rate_and_the_hysteresis_rows(monkeypatch):
    # fit_dahl replaced by a two-play PI fit: the rows without the slow Dahl fit
    monkeypatch.setattr(hy, "fit_dahl",
                        lambda data, gamma_a, **kw: hy.fit_pi(data, n_plays=2, offset=True))
    loops = own_hysteresis.HysteresisLoops({"raw": loop_pair()}, {}, 100.0)
    choice = own_hysteresis.fit_hysteresis(loops, ["raw"], [], gamma_a=30.0, plays=4,
                                           ceiling_percent=5.0)
    skipped = own.Skipped(own.NO_PLANT_NOTE)
    records = own.OwnRecords(None, {"raw": Record(*loop_pair(), FS)}, FS)
    claims = own_claims.record_claims(ClaimTable("own_stage", "test"), records, skipped,
                                      skipped, choice, skipped, skipped, skipped)
    frame = claims.frame()
    assert frame.quantity.tolist() == ["record sampling rate",
                                       "Dahl: validation RMS on raw (second half)",
                                       "PI: validation RMS on raw (second half)",
                                       "Hammerstein: validation RMS on raw (second half)",
                                       "hysteresis model chosen by validation"]
    assert frame.note.str.contains("held out in time").sum() == 3


def test_stages_not_run_have_no_checks_and_the_summary_says_why():
    skipped = own.Skipped(own.NO_PLANT_NOTE)
    assert own_claims.stage_checks(skipped, None) == {}
    assert own_claims.summary_lines(own.OwnRecords(None, {}, FS), 1.0)[0] == own.NO_PLANT_NOTE


def test_known_truth_checks_without_a_truth_state_the_pi_fit_only():
    fit = hy.fit_pi([loop_pair()], n_plays=4, offset=True)
    choice = own_hysteresis.HysteresisChoice({"PI": fit}, pd.DataFrame(), "Dahl", [], [], False,
                                             (), (), {}, 5.0)
    assert own_claims.known_truth_checks(None, None, None, choice, None, None) == {
        "PI fits its loops within 0.5 % of stroke (the stage's hysteresis is made of plays)":
        True}


class _Seeded:
    """Stands in for an ExperimentResult run with noise seeds (what record_claims reads)."""

    table = pd.DataFrame({10.0: [5.0, 1.0, 0.2]}, index=["case_I", "case_II", "case_III"])
    seeds = (7, 8, 9)

    def interval(self, row, column):
        value = self.table.loc[row, column]
        return 0.9 * value, 1.2 * value


@pytest.fixture
def seeded_claims(monkeypatch):
    """(experiments, claim frame) of a run without a plant whose experiments used seeds."""
    monkeypatch.setattr(hy, "fit_dahl",
                        lambda data, gamma_a, **kw: hy.fit_pi(data, n_plays=2, offset=True))
    loops = own_hysteresis.HysteresisLoops({"raw": loop_pair()}, {}, 100.0)
    choice = own_hysteresis.fit_hysteresis(loops, ["raw"], [], gamma_a=30.0, plays=4,
                                           ceiling_percent=5.0)
    skipped = own.Skipped(own.NO_PLANT_NOTE)
    records = own.OwnRecords(None, {"raw": Record(*loop_pair(), FS)}, FS)
    experiments = own_control.Experiments(_Seeded(), _Seeded(), None, "Dahl", 0, 0.0)
    return experiments, own_claims.record_claims(ClaimTable("own_stage", "test"), records,
                                                 skipped, skipped, choice, skipped, skipped,
                                                 experiments).frame()


def test_experiment_rows_run_with_noise_seeds_carry_their_interval(seeded_claims):
    _, frame = seeded_claims
    row = frame.set_index("quantity").loc["tracking error %, 10 Hz, case III"]
    assert (row.ours, row.low, row.high) == (0.2, 0.9 * 0.2, 1.2 * 0.2)
    # a rerun that moves the mean by less than a quarter of the interval keeps the file
    assert np.isclose(row.precision, (1.2 - 0.9) * 0.2 / 4) and "3 noise seeds" in row.note


def test_written_tables_hold_the_values_of_the_claim_table(seeded_claims, tmp_path):
    experiments, frame = seeded_claims
    frame.loc[frame.quantity == "tracking error %, 10 Hz, case III", "ours"] = 0.21  # kept
    frame.to_csv(tmp_path / "own_stage.csv", index=False)
    table4, table5 = own_claims.written_tables(experiments, tmp_path / "own_stage.csv")
    assert table5.loc["case_III", 10.0] == 0.21 and table4.loc["case_III", 10.0] == 0.2
    assert _Seeded.table.loc["case_III", 10.0] == 0.2               # the results untouched
    frame[frame.quantity != "hysteresis %, 10 V, case I"].to_csv(tmp_path / "short.csv")
    with pytest.raises(ValueError, match="hysteresis %, 10 V, case I"):
        own_claims.written_tables(experiments, tmp_path / "short.csv")
