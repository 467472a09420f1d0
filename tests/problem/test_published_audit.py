"""The published-design audit (notebook 00): pole tables, the nominal loop, Tables 4-5."""

import control as ct
import numpy as np
import pandas as pd
import pytest

from piezolib.problem import published_audit as audit


def test_units_table_names_every_signal_of_fig1():
    table = audit.units_table()
    assert list(table.columns) == ["symbol", "meaning", "unit", "range / relation"]
    units = table.set_index("symbol").unit
    assert units["u_c"] == units["v_y"] == "V" and units["omega"] == "rad/s"


def test_pole_table_of_a_second_order_system_is_exact():
    # wn = 10 rad/s, zeta = 0.1, and a real pole at -3 rad/s (damping 1)
    sys = ct.tf([300.0], np.polymul([1.0, 2.0, 100.0], [1.0, 3.0]))
    table = audit.pole_table(sys)
    assert table["omega_n [rad/s]"].tolist() == pytest.approx([3.0, 10.0])
    assert table["damping"].tolist() == pytest.approx([1.0, 0.1])
    assert table["f_n [Hz]"].iloc[1] == pytest.approx(10 / (2 * np.pi))


@pytest.mark.parametrize("bad", [ct.tf([1.0], [1.0, -0.5], 0.1), np.ones((2, 2))])
def test_pole_table_refuses_what_is_not_a_continuous_siso_model(bad):
    with pytest.raises((TypeError, ValueError), match="sys"):
        audit.pole_table(bad)


def test_nominal_audit_of_a_first_order_loop():
    # G = 1/(s + 1), K = 10: S = (s + 1)/(s + 11), T = 10/(s + 11)
    G, K = ct.tf([1.0], [1.0, 1.0]), ct.tf([10.0], [1.0])
    H_e, H_y, H_m = ct.tf([0.5], [1.0, 1.0]), ct.tf([1.0, 1.0], [1.0, 100.0]), \
        ct.tf([0.1, 0.1], [1.0, 10.0])
    nominal = audit.audit_nominal_loop(G, K, H_m, H_e, H_y, omega=np.logspace(-2, 4, 32))
    assert nominal.stable
    assert nominal.slowest_pole.real == pytest.approx(-11.0)
    assert nominal.steady_state_error == pytest.approx(1 / 11)
    assert nominal.dc_T == pytest.approx(10 / 11)
    assert nominal.norm_T == pytest.approx(10 / 11) and nominal.norm_S == pytest.approx(1.0)
    # |T| = 10/sqrt(w^2 + 121) falls to -3 dB at w = sqrt((10/10^(-3/20))^2 - 121)
    w3 = np.sqrt((10 / 10 ** (-3 / 20)) ** 2 - 121)
    assert nominal.bandwidth_Hz == pytest.approx(w3 / (2 * np.pi), rel=1e-2)
    table = nominal.performance_table()
    assert table.shape == (6, 4) and table.paper.notna().sum() == 3


def test_the_printed_improvements_follow_from_the_case_rows():
    consistency = audit.table_consistency()
    assert len(consistency.improvements) == 3 * (4 + 6)
    assert all(consistency.checks.values())
    assert max(consistency.worst.values()) < audit.IMPROVEMENT_ATOL_PERCENT
    claims = consistency.claims()
    assert len(claims) == 30 + 4 + 1
    text = claims[-1]
    assert (text["paper"], round(text["ours"], 2), text["reason"]) == (52.31, 53.31, "typo")
    assert text["quantity"] == "Case II improvement at 20 Hz (text)"


def test_a_misprinted_improvement_fails_the_check():
    good = audit.table_consistency()
    wrong = good.improvements.copy()
    wrong.loc[0, "printed"] += 1.0
    bad = audit.TableConsistency(wrong, good.averages, good.text_variants)
    assert not any(bad.checks.values())
    assert isinstance(bad.averages, pd.Series)
