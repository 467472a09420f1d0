"""Independent checks of the mu designs (piezolib.problem.verification), on small problems."""

from types import SimpleNamespace

import control as ct
import numpy as np
import pandas as pd
import pytest

from piezolib import robust
from piezolib.problem import analysis, genplant, verification

S = ct.tf("s")
FS = 10e3


@pytest.fixture(scope="module")
def small():
    """A 2nd-order plant with first-order weights and a lag controller that stabilises it."""
    G = ct.tf([4e6], [1, 400, 4e6])
    H_m = 0.2 * (S / 2e3 + 1) / (S / 2e4 + 1)
    H_e = 0.3 / (S / 50 + 1)
    H_y = 0.2 * (S / 1e3 + 1) / (S / 1e4 + 1)
    K = ct.ss(ct.tf([200.0], [1.0, 0.01]))
    return G, H_m, H_e, H_y, K


def _analysis(name, **values):
    """A RobustnessAnalysis with the given peaks (the curves are not used here)."""
    base = dict(name=name, nominal_stability=True, closed_loop_poles=np.array([-1.0]),
                norm_He_S=0.5, omega_He_S=1.0, norm_Hy_T=0.5, omega_Hy_T=1.0, mu_RS=0.2,
                omega_RS=1.0, mu_RP=0.8, mu_RP_lower=0.8, omega_RP=2000.0, omega=np.ones(2),
                mu_RS_curve=np.ones(2), mu_RP_upper=np.ones(2), mu_RP_lower_curve=np.ones(2))
    return analysis.RobustnessAnalysis(**{**base, **values})


def _table3(with_delay=(3.4, 1.1, 1.1, 0.9, 0.94), **published):
    names = ["published K (eq. 24)", "our full K (22)", "our reduced K (6)",
             "delay-aware full K (26)", "delay-aware fixed-order K (6)"]
    results = {names[0]: _analysis(names[0], **{**dict(norm_He_S=0.808, norm_Hy_T=0.982,
                                                       mu_RS=0.819, mu_RP=1.448), **published})}
    results.update({n: _analysis(n) for n in names[1:]})
    controllers = {n: ct.ss(ct.tf([1.0], [1.0, 1.0])) for n in names}
    return verification.Table3Study(controllers, results, pd.Series(dict(zip(names, with_delay))),
                                    1, 0.8)


def test_sampled_radii_are_the_sampled_loop_radii_of_the_tustin_controller(small):
    G, *_, K = small
    radii = verification.sampled_radii(G, K, FS, delays=(0, 1, 2))
    Kd = robust.discretize(K, FS).K
    assert radii.index.name == "delay [samples]" and list(radii.index) == [0, 1, 2]
    assert radii.tolist() == [robust.sampled_loop_radius(G, Kd, d) for d in (0, 1, 2)]


def test_sampled_radii_refuse_a_negative_delay(small):
    G, *_, K = small
    with pytest.raises(ValueError, match="delays"):
        verification.sampled_radii(G, K, FS, delays=(-1,))


def test_mu_on_a_small_grid_bounds_are_ordered(small):
    G, H_m, H_e, H_y, K = small
    P = genplant.delay_aware_plant(G, H_m, H_e, H_y, fs=FS)
    res = verification._mu_on(P, K, omega=np.logspace(1, 5, 12))
    assert res.upper.shape == (12,) and np.all(res.lower <= res.upper * (1 + 1e-9))


def test_delay_aware_problem_states_the_delay_and_the_rolloff(small):
    G, H_m, H_e, H_y, K = small
    row = verification.delay_aware_problem(G, H_m, H_e, H_y, K, K, fs=FS, delay_samples=1,
                                           omega=np.logspace(0, 6, 200))
    assert row.name == "delay-aware problem, 10 kHz, d = 1"
    assert row["effective delay tau [us]"] == pytest.approx(150.0)
    assert row["Pade accurate to 1e-4 up to [rad/s]"] == pytest.approx(0.5 / 150e-6)
    assert row["resonance [Hz]"] == pytest.approx(2e3 / (2 * np.pi), rel=1e-9)
    assert row["roll-off bound K_hf [V/V]"] == genplant.DESIGN_ROLLOFF.hf_gain
    # |G K| = 200 |G| / |s|: the first 0 dB crossing near 200 rad/s
    assert 150 < row["crossover of the deployed loop [rad/s]"] < 250


def test_dk_iteration_checks_state_the_bounds_and_the_gamma_tolerance():
    history = pd.DataFrame({"mu_upper": [1.3, 0.95], "gamma": [1.3001, 0.951]})
    good = verification.dk_iteration_checks(SimpleNamespace(history=history, mu_peak=0.95,
                                                            mu_lower_peak=0.9499))
    assert all(good.checks.values()) and all(good.reference_checks.values())
    assert good.text.startswith("largest mu / gamma - 1")
    bad = verification.dk_iteration_checks(SimpleNamespace(
        history=history.assign(gamma=[1.2, 0.95]), mu_peak=1.05, mu_lower_peak=0.9))
    assert not any(bad.checks.values())
    assert list(bad.reference_checks.values()) == [True, False]


def test_compare_rederived_fails_on_a_moved_mu_or_another_order():
    K2, K3 = ct.ss(ct.tf([1.0], [1.0, 1.0, 1.0])), ct.ss(ct.tf([1.0], [1.0, 2.0, 1.0, 1.0]))
    used = SimpleNamespace(mu={"fixed order": 0.94, "no-delay DK": 0.80}, K_full=K3, K_fixed=K2)
    same = verification.compare_rederived(used, SimpleNamespace(
        mu={"fixed order": 0.945, "no-delay DK": 0.80}, K_full=K3, K_fixed=K2))
    assert all(same.checks.values())
    assert same.table["relative difference"].iloc[0] == pytest.approx(0.945 / 0.94 - 1)
    moved = verification.compare_rederived(used, SimpleNamespace(
        mu={"fixed order": 0.97, "no-delay DK": 0.80}, K_full=K2, K_fixed=K2))
    assert not any(moved.checks.values())


@pytest.mark.slow
def test_reduction_by_order_gives_mu_and_errors_per_order(small):
    G, H_m, H_e, H_y, _ = small
    P = genplant.delay_aware_plant(G, H_m, H_e, H_y, fs=FS)
    K = ct.ss(ct.tf([200.0], [1.0, 0.01]) * ct.tf([1.0, 1e3], [1.0, 2e3])
              * ct.tf([1.0, 3e3], [1.0, 5e3]))
    result = verification.reduction_by_order(K, G, P, orders=(2, 3), omega=np.logspace(1, 5, 12))
    assert list(result.table.index) == [2, 3] and result.hsv.size == 3
    assert np.all(np.isfinite(result.table["mu_RP, G S-weighted residualisation"]))
    assert result.table["||(K - K_r) G S||"].iloc[1] < 1e-6          # order 3: K itself
    with pytest.raises(ValueError, match="orders"):
        verification.reduction_by_order(K, G, P, orders=())


def test_delay_sweep_reuses_known_delays_and_checks_the_bound(small):
    # every delay known: nothing is designed (the models are only checked)
    G, H_m, H_e, H_y, _ = small
    known = {0: (0.80, 0.70), 1: (0.90, 0.85), 2: (0.95, np.nan)}
    sweep = verification.delay_sweep(G, H_m, H_e, H_y, fs=FS, d_order=4, grid=np.logspace(1, 5, 20),
                                     delays=(0, 2), known=known)
    assert list(sweep.table.index) == [0, 1, 2] and sweep.table.index.name == "delay [samples]"
    assert sweep.table["tau [us]"].tolist() == pytest.approx([50.0, 150.0, 250.0])
    assert not sweep.checks["lower bound computed at the design delays"]   # d = 2 has none
    assert sweep.checks["lower bound <= DK mu_RP"]
    assert sweep.reference_checks == {"more delay, larger mu_RP": True}
    above = verification.delay_sweep(G, H_m, H_e, H_y, fs=FS, d_order=4, grid=np.logspace(1, 5, 20),
                                     delays=(), known={0: (0.9, 0.95), 1: (0.8, 0.7)})
    assert not above.checks["lower bound <= DK mu_RP"]
    assert not above.reference_checks["more delay, larger mu_RP"]


def test_tustin_check_of_a_slow_controller_matches(small):
    G, *_, K = small
    result = verification.tustin_check(K, G, FS)
    assert result.checks == {"sampled loop (no delay) stable": True}
    assert list(result.reference_checks.values()) == [True] and "NOTE" not in result.text


def test_table3_study_checks_and_claims():
    study = _table3()
    assert all(study.checks.values()) and all(study.reference_checks.values())
    claims = study.claims(paper_values={"norm_He_S": 0.81, "norm_Hy_T": 0.92, "mu_RS": 0.48,
                                        "mu_RP": 0.71})
    # 4 NS/NP/RS rows for each of our four controllers, mu_RP for all five, RP of the reduced
    assert len(claims) == 4 * 4 + 5 + 1
    assert claims[0]["quantity"] == "mu_RP (published K (eq. 24))"
    assert claims[0]["expect"] == "differs" and claims[0]["reason"] == "inconsistent parameters"
    assert "with 1 sample(s) of delay 3.400" in claims[0]["note"]
    assert claims[-1]["quantity"] == "robust performance met by the 1th-order controller " \
                                     "(mu_RP < 1)"
    assert sum("expect" in c for c in claims) == 1
    table = study.table(paper_values={"norm_He_S": 0.81, "norm_Hy_T": 0.92, "mu_RS": 0.48,
                                      "mu_RP": 0.71})
    assert list(table.columns)[:2] == ["paper", "published K (eq. 24)"]


def test_table3_study_reference_checks_fail_on_other_numbers():
    assert not _table3(mu_RP=1.3).reference_checks[
        "published K recomputed: mu_RS = 0.819, mu_RP = 1.448"]
    assert not _table3(with_delay=(3.4, 1.1, 0.9, 0.9, 0.94)).reference_checks[
        "with the delay: RP met by the deployed K, not by the reduced no-delay K"]


def test_loop_table_names_an_unstable_loop():
    G = ct.tf([1.0], [1.0, -1.0])                          # unstable plant
    table = verification.loop_table(G, {"weak": ct.tf([0.5], [1.0]), "strong": ct.tf([3.0], [1.0])})
    assert table["stable"].tolist() == [False, True]
    assert table.loc["strong", "slowest closed-loop pole [rad/s]"] == pytest.approx(2.0)
    assert table.loc["strong", "|K(inf)| [V/V]"] == pytest.approx(3.0)


def test_summary_lines_say_what_holds():
    names = ["DK full order (26)", "DK reduced (6)", "fixed-order mu (6)"]
    table = pd.DataFrame({n: {"mu_RP upper (Pade)": mu, **{f"radius, {d} delay": 0.9 + 0.05 * d
                                                            for d in range(4)}}
                          for n, mu in zip(names, (0.94, 0.97, 0.94))})
    designs = verification.DesignVerification(
        table, {n: ct.ss(ct.tf([1.0], [1.0, 1.0])) for n in names}, {},
        SimpleNamespace(value=0.855), None, {}, {}, "")
    lines = verification.summary_lines(pd.Series({0: 0.93, 1: 1.05}), designs, _table3(),
                                       paper_values={"mu_RP": 0.71, "mu_RS": 0.48})
    assert len(lines) == 4
    assert "**unstable** with 1 sample(s)" in lines[0]
    assert "stable with 0, 1 sample(s) of delay" in lines[1]            # radius 1.0 at d = 2
    assert "out of reach once the delay is modelled" in lines[2]       # 0.855 > 0.8
    assert "**not met**" in lines[3]
    with pytest.raises(TypeError, match="designs"):
        verification.summary_lines(pd.Series({0: 0.9}), None, _table3(), {})


@pytest.mark.slow
def test_regularisation_check_of_a_small_problem(small):
    G, H_m, H_e, H_y, _ = small
    result = verification.regularisation_check(G, H_m, H_e, H_y, omega=np.logspace(0, 6, 40))
    assert all(result.checks.values())
    assert result.table["max sigma on the grid"] <= result.table["gamma"] * (1 + 1e-3)


@pytest.mark.slow
def test_verify_delay_aware_of_a_small_problem(small):
    G, H_m, H_e, H_y, K = small
    P = genplant.delay_aware_plant(G, H_m, H_e, H_y, fs=FS)
    result = verification.verify_delay_aware(K, K, K, G, H_m, H_e, H_y, plant=P, fs=FS,
                                             delay_samples=1, omega=np.logspace(0, 6, 40))
    assert all(result.checks.values())
    assert result.fixed_mu == result.full_mu == result.reduced_mu
    assert not result.reference_checks["fixed-order synthesis beats reduction (by 0.02)"]
    assert result.lower.value <= result.fixed_mu and 0 < result.fixed_radius(1) < 1


def test_verify_delay_aware_takes_a_recorded_lower_bound(small):
    G, H_m, H_e, H_y, K = small
    P = genplant.delay_aware_plant(G, H_m, H_e, H_y, fs=FS)
    result = verification.verify_delay_aware(K, K, K, G, H_m, H_e, H_y, plant=P, fs=FS,
                                             delay_samples=1, omega=np.logspace(0, 6, 40),
                                             lower=0.5)
    assert isinstance(result.lower, verification.RecordedBound) and result.per_block == ()
    assert result.lower.value == 0.5 and "0.5000" in result.text
    # a recorded bound above every design fails the check that no design is below it
    high = verification.verify_delay_aware(K, K, K, G, H_m, H_e, H_y, plant=P, fs=FS,
                                           delay_samples=1, omega=np.logspace(0, 6, 40),
                                           lower=1e3)
    assert not high.checks["no design below the lower bound on achievable mu"]
