"""Notebook 08's figures drawn from the stages' results: the same figure names, and for a stage
that did not run (no identification record) a figure of that name saying why."""

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from piezolib.hysteresis import PIModel
from piezolib.records import Record
from piezolib.workbook import your_stage as own
from piezolib.workbook import your_stage_hysteresis as own_hysteresis
from piezolib.workbook.figures import own_stage as F

SKIPPED = own.Skipped(own.NO_PLANT_NOTE)


def _record(n=400, fs=1000.0):
    t = np.arange(n) / fs
    return Record(np.sin(2 * np.pi * 5 * t), 3 * np.sin(2 * np.pi * 5 * t - 0.2), fs,
                  input_unit="V", output_unit="um", input_name="u_c", output_name="x")


@pytest.mark.parametrize("draw, name", [
    (lambda: F.own_stage_identification(SKIPPED, np.ones(3)), "identification"),
    (lambda: F.own_stage_uncertainty(SKIPPED), "uncertainty"),
    (lambda: F.own_stage_mu(SKIPPED, np.ones(3)), "mu"),
    (lambda: F.own_stage_experiments(SKIPPED), "experiments")])
def test_a_stage_not_run_draws_a_note_under_the_figures_name(draw, name):
    fig = draw()
    assert fig.get_label() == f"extra_own_stage_{name}"
    assert [t.get_text() for t in fig.axes[0].texts] == [own.NO_PLANT_NOTE]
    plt.close(fig)


def test_the_records_without_an_identification_run_are_the_loops_alone():
    records = own.OwnRecords(None, {"sine": _record(), "triangle": _record(200)}, 1000.0)
    fig = F.own_stage_records(records, SKIPPED)
    assert [ax.get_title().split(":")[0] for ax in fig.axes if ax.get_title()] == [
        "sine", "triangle"]
    plt.close(fig)


def test_the_hysteresis_figure_shows_the_first_validation_record():
    model = PIModel((0.0, 0.3), (0.8, 0.2))
    v = 1 - np.cos(np.linspace(0, 4 * np.pi, 200))
    scores = pd.DataFrame({"RMS %": [0.5]},
                          index=pd.MultiIndex.from_tuples([("PI", "b")], names=["model", "record"]))
    fit = type("Fit", (), {"model": model})()
    choice = own_hysteresis.HysteresisChoice({"PI": fit}, scores, "PI", [(v, model.simulate(v))],
                                             ["b"], False, ("a",), (), {}, 5.0)
    fig = F.own_stage_hysteresis(choice, 10.0, 3.0, "actuator voltage [V]", "x [um]")
    assert fig.get_label() == "extra_own_stage_hysteresis"
    assert fig.axes[0].get_xlabel() == "actuator voltage [V]"
    assert "PI: RMS 0.50 % of stroke" in [t.get_text() for t in fig.axes[0].get_legend().texts]
    plt.close(fig)
