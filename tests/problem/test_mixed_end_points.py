"""Notebook 09's committed search end points: keys, reading, use, and the slow re-derivation."""

from unittest import mock

import control as ct
import numpy as np
import pytest

from piezolib.problem import coefficient_box as box
from piezolib.problem import design
from piezolib.problem import mixed_end_points as ep
from piezolib.uncertainty import sampled_parametric_margin
from piezolib.workbook import pipeline
from piezolib.workbook import study as studies

G1 = ct.tf([1.0], [1.0, 1.0])
KD = ct.tf([2.0], [1.0], 0.05)


@pytest.fixture(scope="module")
def reference():
    study = studies.load("reference")
    G, _, H_e, H_y, _ = pipeline.study_problem(study)
    return (pipeline.study_mixed_designs(study).designs, G, H_e, H_y, study.loop.fs_Hz,
            pipeline.study_controllers(study).K_deployed,
            {box.DEPLOYED: pipeline.study_sections(study)["K_ours"],
             box.MIXED: pipeline.study_mixed_sections(study)})


def test_keys_follow_every_input_and_ignore_rounding_noise():
    base = ep.margin_key(G1, KD, 1, 300)
    assert base == ep.margin_key(ct.tf([1.0 + 1e-15], [1.0, 1.0]), KD, 1, 300)
    others = [ep.margin_key(G1, KD, 2, 300), ep.margin_key(G1, KD, 1, 301),
              ep.margin_key(G1, 1.5 * KD, 1, 300), ep.margin_key(G1, KD, 1, 300, seed=1),
              ep.margin_key(G1, KD, 1, 300, float32=True), ep.margin_key(G1, KD, 1, 300, rtol=1e-4),
              ep.margin_key(ct.tf([1.0], [1.0, 1.001]), KD, 1, 300)]
    assert len({base, *others}) == 8
    assert ep.bound_key(G1, G1, G1, 0.5, 0.05, 1e4) != ep.bound_key(G1, G1, 2 * G1, 0.5, 0.05, 1e4)


def test_a_missing_file_holds_nothing_and_a_written_one_reads_back(tmp_path):
    assert ep.read_end_points(tmp_path / "none.json") == {"bounds": {}, "margins": {}}
    m = sampled_parametric_margin(ct.tf([1], [1, 3, 3, 1]), KD, 1, samples=20)
    path = ep.write_end_points({"b": 0.25}, {ep.margin_key(ct.tf([1], [1, 3, 3, 1]), KD, 1, 20): m},
                               tmp_path / "e.json")
    low, high, q = ep.committed_bracket(ct.tf([1], [1, 3, 3, 1]), KD, 1, 20, path=path)
    assert (low, high) == (m.spread, m.spread_unstable) and np.array_equal(q, m.offsets)
    assert ep.read_end_points(path)["bounds"] == {"b": 0.25}
    (tmp_path / "bad.json").write_text('{"format": 99}')
    with pytest.raises(ValueError, match="format"):
        ep.read_end_points(tmp_path / "bad.json")


def test_the_committed_file_covers_the_reference_study(reference):
    designs, G, H_e, H_y, fs, _, sections = reference
    bounds = ep.committed_bounds(designs, G, H_e, H_y, fs)
    assert sorted(bounds) == sorted(d.performance_scale for d in designs)
    # each design's bound lies below its own mu_RP upper bound (no controller is below it)
    assert all(0 < bounds[d.performance_scale] <= d.mu_peak for d in designs)
    for name in (box.DEPLOYED, box.MIXED):
        Kd = sections[name].to_statespace("float32")
        for d in (0, 1, 2, 3):
            assert ep.committed_bracket(G, Kd, d, box.SAMPLED_MARGIN_SAMPLES) is not None


def test_the_tradeoff_takes_known_bounds_without_searching(reference):
    designs, G, H_e, H_y, fs, *_ = reference
    known = {d.performance_scale: 0.5 for d in designs}
    with mock.patch("piezolib.robust.achievable.performance_lower_bound",
                    side_effect=AssertionError("searched")):
        table = design.tradeoff_table(designs, G, H_e, H_y, fs, bounds=known)
    assert (table["no controller below"] == 0.5).all()
    with pytest.raises(ValueError, match="bounds"):
        design.tradeoff_table(designs[:1], G, H_e, H_y, fs,
                              bounds={designs[0].performance_scale: -1.0})
    with pytest.raises(TypeError, match="bounds"):
        design.tradeoff_table(designs[:1], G, H_e, H_y, fs, bounds=[0.5])


@pytest.mark.slow
def test_the_committed_end_points_are_rederived_from_scratch(reference):
    designs, G, H_e, H_y, fs, deployed, sections = reference
    bounds, margins = box.searched_end_points(designs, deployed, sections, G, H_e, H_y, fs)
    stored = ep.read_end_points()
    assert sorted(bounds) == sorted(stored["bounds"])
    for key, value in bounds.items():     # the gamma bracket's relative width (rtol 1e-4)
        assert value == pytest.approx(stored["bounds"][key], rel=2e-4)
    assert sorted(margins) == sorted(stored["margins"])
    for key, m in margins.items():        # the bisection's relative width (rtol 1e-3)
        c = stored["margins"][key]
        assert m.spread == pytest.approx(c["spread"], rel=2e-3)
        assert m.spread_unstable == pytest.approx(c["spread_unstable"], rel=2e-3)
