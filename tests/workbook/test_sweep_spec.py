"""Sweep specs: the grid and the random sample over a base study, spec files by name and by
path, and every refused spec naming its key and value."""

from pathlib import Path

import numpy as np
import pytest

from piezolib.workbook import study as studies
from piezolib.workbook import sweep_spec

REPOSITORY = Path(__file__).resolve().parents[2]


@pytest.fixture(autouse=True)
def checkout(tmp_path, monkeypatch):
    """Outputs and studies/sweeps/ under tmp_path (never the repository's)."""
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path


def grid_spec(name="small", **changes):
    data = {"name": name, "study": "reference", "set": {"design": {"max_iter": 2}},
            "grid": {"weights": {"omega_e": [1000.0, 1260.0, 1600.0]}, "design.order": [4, 6]}}
    return sweep_spec.spec_from_dict({**data, **changes})


def write(path, text):
    path.write_text(text, encoding="utf-8")
    return path


def test_a_grid_is_the_cartesian_product_of_the_values_over_the_base_study():
    spec = grid_spec()
    points = spec.points()
    assert spec.parameters == ("weights.omega_e", "design.order")
    assert [(p.params["weights.omega_e"], p.params["design.order"]) for p in points] == [
        (1000.0, 4), (1000.0, 6), (1260.0, 4), (1260.0, 6), (1600.0, 4), (1600.0, 6)]
    assert [p.index for p in points] == list(range(1, 7))
    third = points[2].study
    assert (third.weights.omega_e, third.design.order, third.design.max_iter) == (1260.0, 4, 2)
    assert third.weights.M_e == studies.Study().weights.M_e           # the rest: the base's
    assert third.name == "small-0003" and points[2].options == {"controller": "fixed_order"}
    assert len({p.key("e") for p in points}) == 6                     # one record each


def test_the_shipped_spec_has_twelve_points(checkout):
    shipped = REPOSITORY / "studies" / "sweeps" / "omega_spread_order.toml"
    path = write(checkout / shipped.name, shipped.read_text(encoding="utf-8"))
    spec = sweep_spec.load_spec(path)
    points = spec.points()
    assert spec.name == "omega_spread_order" and len(points) == 12
    assert {p.study.uncertainty.weight for p in points} == {"fitted"}
    assert {p.study.uncertainty.spread for p in points} == {0.02, 0.03}
    assert spec.directory == checkout / "runs" / "sweeps" / "omega_spread_order"


def test_a_spec_file_names_its_sweep_and_reads_a_relative_base_study(checkout):
    mine = studies.Study().replace(name="mine", weights={"omega_e": 1500.0})
    mine.save(checkout / "mine.toml")
    path = write(checkout / "near.toml", 'study = "mine.toml"\n[grid]\ndesign.order = [4, 6]\n')
    spec = sweep_spec.load_spec(path)
    assert spec.name == "near"
    assert {p.study.weights.omega_e for p in spec.points()} == {1500.0}
    (checkout / "studies" / "sweeps").mkdir(parents=True)
    write(checkout / "studies" / "sweeps" / "by_name.toml", '[grid]\ndesign.order = [5]\n')
    assert sweep_spec.load_spec("by_name").points()[0].study.design.order == 5


@pytest.mark.parametrize("changes, said", [
    ({"grid": {"weights.omega_x": [1.0]}}, "'weights.omega_x'"),
    ({"grid": {"nowhere.omega_e": [1.0]}}, "'nowhere.omega_e'"),
    ({"grid": {"omega_e": [1.0]}}, "'omega_e'"),
    ({"grid": {"weights.omega_e": []}}, "weights.omega_e must be a non-empty list"),
    ({"grid": {"weights.omega_e": 1260.0}}, "weights.omega_e must be a non-empty list"),
    ({"grid": {"weights.omega_e": [1260, 1260.0]}}, "1260"),
    ({"grid": {"weights.omega_e": [1000.0, -5.0]}}, "weights.omega_e = -5.0"),
    ({"grid": {"design.order": [6, 2.5]}}, "design.order = 2.5"),
    ({"grid": {"controller": ["reduced"]}}, "controller = 'reduced'"),
    ({"grid": {}}, "[grid] names no parameter"),
    ({"random": {"samples": 2, "seed": 0, "design.order": [4, 6]}}, "either a [grid] or"),
    ({"set": {"weights.omega_e": -1.0}}, "[set]"),
    ({"set": {"controller": "full_order"}}, "[set] controller"),
    ({"study": "no_such_study"}, "no_such_study"),
    ({"nope": 1}, "unknown key(s) ['nope']"),
    ({"name": "a/b"}, "sweep name"),
    ({"name": "cache"}, "reserved"),
    # a combination the study refuses although each value passes: named by its point
    ({"grid": {"experiments.stage_seed": [0, 2 ** 32 - 20], "experiments.noise_seeds": [2, 30]}},
     "point 4 (experiments.stage_seed = 4294967276, experiments.noise_seeds = 30)"),
])
def test_a_bad_spec_names_the_key_and_the_value(changes, said):
    with pytest.raises(sweep_spec.SweepError) as info:
        grid_spec(**changes)
    assert said in str(info.value)


def test_neither_grid_nor_random_is_an_error():
    with pytest.raises(sweep_spec.SweepError, match="either a"):
        sweep_spec.spec_from_dict({"name": "x"})


@pytest.mark.parametrize("table, said", [
    ({"seed": 0, "weights.omega_e": [1.0, 2.0]}, "samples"),
    ({"samples": 3, "weights.omega_e": [1.0, 2.0]}, "seed"),
    ({"samples": 3, "seed": 0}, "names no parameter"),
    ({"samples": 3, "seed": 0, "weights.omega_e": [2.0, 1.0]}, "must rise"),
    ({"samples": 3, "seed": 0, "weights.omega_e": [-2.0, 1.0]}, "weights.omega_e = -2.0"),
    ({"samples": 3, "seed": 0, "weights.omega_e": [1.0, 2.0, 3.0]}, "[low, high]"),
    ({"samples": 3, "seed": 0, "weights.omega_e": {"low": 1.0, "high": 9.0, "scale": "ln"}},
     "scale"),
    ({"samples": 3, "seed": 0, "weights.omega_e": {"low": 0.0, "high": 9.0, "scale": "log"}},
     "log needs"),
    ({"samples": 3, "seed": 0, "design.order": [4, 6.5]}, "integers"),
    ({"samples": 3, "seed": 0, "uncertainty.weight": ["a", "b"]}, "choices"),
    ({"samples": 3, "seed": 0, "controller": {"choices": []}}, "non-empty"),
    ({"samples": 3, "seed": 0, "controller": {"choices": ["fixed_order", "x"]}},
     "controller = 'x'"),
])
def test_a_bad_random_table_names_what_is_wrong(table, said):
    with pytest.raises(sweep_spec.SweepError) as info:
        sweep_spec.spec_from_dict({"name": "r", "random": table})
    assert said in str(info.value)


def test_a_random_sample_is_reproducible_and_inside_its_ranges():
    table = {"samples": 40, "seed": 7, "weights.omega_e": {"low": 800.0, "high": 2500.0,
                                                           "scale": "log"},
             "design.order": [4, 8], "uncertainty.spread": [0.01, 0.05],
             "controller": {"choices": ["fixed_order", "full_order"]}}
    first = sweep_spec.spec_from_dict({"name": "r", "random": table}).points()
    again = sweep_spec.spec_from_dict({"name": "r", "random": table}).points()
    assert [p.params for p in first] == [p.params for p in again]
    assert len(first) == 40                 # continuous draws: no repeats
    omega = np.array([p.params["weights.omega_e"] for p in first])
    assert omega.min() >= 800.0 and omega.max() <= 2500.0
    orders = {p.params["design.order"] for p in first}
    assert orders <= {4, 5, 6, 7, 8} and all(isinstance(o, int) for o in orders)
    assert {p.options["controller"] for p in first} == {"fixed_order", "full_order"}
    other = sweep_spec.spec_from_dict({"name": "r", "random": {**table, "seed": 8}}).points()
    assert [p.params for p in other] != [p.params for p in first]


def test_repeated_random_draws_become_one_point():
    spec = sweep_spec.spec_from_dict({"name": "r", "random": {"samples": 30, "seed": 0,
                                                         "design.order": [4, 5]}})
    assert sorted(p.params["design.order"] for p in spec.points()) == [4, 5]


def test_a_spec_file_whose_name_differs_from_its_file_is_refused(checkout):
    path = write(checkout / "one.toml", 'name = "two"\n[grid]\ndesign.order = [4]\n')
    with pytest.raises(sweep_spec.SweepError, match="one.toml"):
        sweep_spec.load_spec(path)


# --------------------------------------------------------------------------- limits
def test_a_grid_of_more_points_than_the_limit_is_refused_before_any_study_is_built():
    # 73 x 137 = 10001 points: one more than MAX_POINTS (accepted before, after ~8 s of set-up)
    assert sweep_spec.MAX_POINTS == 10_000
    grid = {"weights.omega_e": [500.0 + k for k in range(73)],
            "weights.omega_y": [1e5 + k for k in range(137)]}
    with pytest.raises(sweep_spec.SweepError) as info:
        sweep_spec.spec_from_dict({"name": "big", "grid": grid})
    said = str(info.value)
    assert "[grid] gives 10001 points" in said and "at most 10000 points" in said
    assert "73 (weights.omega_e) x 137 (weights.omega_y)" in said


def test_a_random_sample_of_more_points_than_the_limit_is_refused():
    # 100000 was the documented maximum (and took minutes to set up)
    with pytest.raises(sweep_spec.SweepError, match=r"samples must be an integer in "
                                                    r"\[1, 10000\].*got 100000"):
        sweep_spec.spec_from_dict({"name": "big", "random": {
            "samples": 100_000, "seed": 0, "weights.omega_e": [800.0, 2500.0]}})


def test_a_spec_builds_its_points_once():
    spec = grid_spec()
    first, again = spec.points(), spec.points()
    assert first == again and first is not again            # a fresh list each call
    assert all(a is b for a, b in zip(first, again))        # of the same points
