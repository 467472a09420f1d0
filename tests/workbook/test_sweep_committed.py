"""Notebook 11's committed sweep points: current for the notebook's grid, and re-derived from
scratch (slow) within their precision."""

import json
import math

import pytest

from piezolib.workbook import outputs, sweep, sweep_spec
from piezolib.workbook import study as studies

#: Relative precision of a committed point's numbers: a point is one DK step, a reduction and
#: a fixed-order SLSQP search, whose end point moves with rounding; the tracking errors
#: are means over the study's noise seeds of runs with that controller.
PRECISION = {"mu_RP": 0.01, "mu_RP_full_order": 0.01, "gain_margin_dB": 0.02,
             "phase_margin_deg": 0.02, "delay_margin_samples": 0.02,
             "tracking_error_10Hz_percent": 0.02, "tracking_error_50Hz_percent": 0.02,
             "tracking_error_50Hz_low_percent": 0.02, "tracking_error_50Hz_high_percent": 0.02}


def _notebook_spec():
    """The spec notebook 11 builds from its parameters cell, for the reference study."""
    cells = json.loads((outputs.notebooks_dir() / "11_sweeps.ipynb").read_text())["cells"]
    params = {}
    exec("".join(next(c for c in cells if "parameters" in c["metadata"].get("tags", []))
                 ["source"]), params)
    study = studies.load("reference")
    return sweep_spec.spec_from_dict({
        "name": f"notebook11-{study.name}", "study": study,
        "description": "notebook 11: omega_e x controller order",
        "set": {"design.max_iter": params["MAX_ITER"]},
        "grid": {"weights.omega_e": params["OMEGA_E"], "design.order": params["ORDERS"]}})


def _committed(spec):
    evaluation = f"{sweep.evaluate_point.__module__}.{sweep.evaluate_point.__qualname__}"
    folder = sweep.committed_points_dir(spec.name)
    return {p.index: sweep.read_record(folder / f"{p.key(evaluation)}.json", p.key(evaluation))
            for p in spec.points()}


def test_every_point_of_the_notebooks_sweep_has_an_intact_committed_record():
    records = _committed(_notebook_spec())
    missing = [index for index, doc in records.items() if doc is None]
    assert not missing, (f"points {missing} of notebook 11 have no committed record: run them "
                         "again (see the slow test below) and commit data/sweeps/")


@pytest.mark.slow
def test_the_committed_points_are_re_derived_from_scratch(monkeypatch):
    monkeypatch.setenv("PIEZOLIB_CACHE", "off")          # fresh designs, not the cached ones
    spec = _notebook_spec()
    records = _committed(spec)
    for point in spec.points():
        found, stored = sweep.evaluate_point(point.study, **point.options), \
            records[point.index]["metrics"]
        assert set(found) == set(stored)
        for name, value in stored.items():
            if name in PRECISION:
                assert math.isclose(found[name], value, rel_tol=PRECISION[name]), \
                    (point.params, name, found[name], value)
            else:                                       # states, stability, saturated samples
                assert found[name] == value, (point.params, name, found[name], value)


def test_seeding_copies_the_records_of_the_specs_points_only(tmp_path, monkeypatch):
    spec = _notebook_spec()
    folder = sweep.committed_points_dir(spec.name)
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))      # the sweep's outputs go here
    assert sweep.seed_records(spec, folder) == len(spec.points())
    assert sorted(p.read_bytes() for p in (spec.directory / "points").iterdir()) == \
        sorted(p.read_bytes() for p in folder.glob("*.json"))
    other = sweep_spec.spec_from_dict({"name": spec.name, "study": spec.base,
                                       "grid": {"weights.omega_e": [1100.0]}})
    assert sweep.seed_records(other, folder) == 0           # another grid: its points run
    with pytest.raises(ValueError, match="name"):
        sweep.committed_points_dir("../x")
