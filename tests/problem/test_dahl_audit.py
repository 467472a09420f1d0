"""The audit of the published Dahl parameters (notebook 03, sections 1-2)."""

import numpy as np
import pytest

from piezolib import hysteresis as hy
from piezolib.problem import dahl_audit, paper


def test_unit_conventions_single_out_amplifier_input_and_sensor_volts():
    table = dahl_audit.unit_conventions()
    dc_gain = paper.PLANT.b[0] / paper.PLANT.a[0]
    assert table.iloc[1, 2] == pytest.approx(dc_gain)
    ratio = table["published g_a / static gain"]
    np.testing.assert_allclose(ratio * table.iloc[:, 2], paper.DAHL.g_a)
    near = table[ratio.between(0.9, 1.1)]
    assert near[["v", "x"]].values.tolist() == [["u_c (amplifier input) [V]",
                                                 "v_y (sensor) [V]"]]


def test_steady_state_of_the_printed_form_is_the_same_both_ways():
    table = dahl_audit.steady_state_table(dahl_audit.published_models())
    expected = paper.DAHL.beta2 * paper.DAHL.gamma_a / paper.DAHL.alpha2
    rising, falling = table.loc["H after a long rising stroke"], table.loc[
        "H after a long falling stroke"]
    assert rising["printed"] == pytest.approx(expected) == falling["printed"]
    assert rising["bliman_sorine"] == pytest.approx(-falling["bliman_sorine"])
    assert table.loc["transient length 2/alpha1 [x-unit]", "printed"] == pytest.approx(
        2 / paper.DAHL.alpha1)


def test_the_published_parameters_give_no_loop_like_fig7():
    audit = dahl_audit.audit_published()
    assert set(audit.table["x unit"]) == set(audit.x_ranges)
    assert len(audit.table) == len(audit.x_ranges) * len(hy.FORMS)
    assert all(audit.checks.values()) and all(audit.simulation_checks.values())
    assert not audit.fig7_like
    assert "26.97" in audit.note


def test_a_well_damped_model_makes_the_checks_fail():
    """A model that has loops and can be simulated: the audit's statements do not hold."""
    damped = hy.DahlModel(alpha1=20.0, alpha2=10.0, beta1=0.0, beta2=2.0, gamma_a=1.0,
                          g_a=1.0, form="printed")
    audit = dahl_audit.audit_published({"printed": damped})
    assert not audit.simulation_checks[next(iter(audit.simulation_checks))]
    assert audit.not_invertible == ""
    assert not all(audit.checks.values())


def test_bad_models_are_named():
    with pytest.raises(TypeError, match="models"):
        dahl_audit.steady_state_table([1, 2])
    with pytest.raises(TypeError, match=r"models\['printed'\]"):
        dahl_audit.audit_published({"printed": 3.0})
    with pytest.raises(ValueError, match="models"):
        dahl_audit.audit_published({})
