"""Notebook 08's stages from the records to the plant model (piezolib.workbook.your_stage) on
small records of known plants.

The full-size pipeline (the example records, the Dahl fit, the DK design, the experiments)
is run by the notebook itself; here each stage's own logic: what it computes from a record
whose plant is known, what it checks, what it refuses, and how a stage that needs the
plant passes on when there is no identification record.
"""

import control as ct
import numpy as np
import pytest

from piezolib import identification as ident
from piezolib.records import Record
from piezolib.workbook import your_stage as own
from piezolib.workbook.outputs import notebooks_dir

FS = 5000.0
PLANT = ct.tf([800.0], [1.0, 1000.0])           # first order, DC gain 0.8, 159 Hz


def chirp_record(n=1500, seed=0):
    """A run from rest: rest, a step to 1 V, then broadband excitation; output in um (3 um/V)."""
    rng = np.random.default_rng(seed)
    u = np.concatenate([np.zeros(200), np.ones(300), 1 + 0.3 * rng.standard_normal(n - 500)])
    y = ident.zoh_simulate(PLANT, u, FS)
    return Record(u, 3.0 * y, FS, "V", "um", "u_c", "x")


def write_csv(path, rec):
    np.savetxt(path, np.column_stack([rec.time, rec.input, rec.output]), delimiter=",",
               fmt="%.9g")


# -- the study and the notebook's parameters ---------------------------------------------------

def test_ones_own_records_get_a_study_of_their_own_never_the_reference(tmp_path):
    # notebook 08 on a folder of one's own records with the default study rewrote the
    # reference study's data/results/own_stage.csv and two committed figures
    own_study = own.records_study(None, tmp_path / "stage 7 runs")
    assert own_study.name == "own_stage_7_runs" and not own_study.is_reference
    assert own.records_study(None, None) == "reference"        # the example records
    assert own.records_study("wide_error_weight", tmp_path) == "wide_error_weight"
    with pytest.raises(ValueError, match="need a study of their own"):
        own.records_study("reference", tmp_path)


def test_papermill_knows_every_parameter_of_notebook_08():
    # "unknown parameter" warnings for INPUT_*/OUTPUT_* (assigned as tuples), and the weights
    # written as dict(...) calls, which papermill cannot read, although all were applied
    import ast
    import json

    papermill = pytest.importorskip("papermill")
    path = notebooks_dir() / "08_your_own_stage.ipynb"
    cell = next(c for c in json.loads(path.read_text())["cells"]
                if "parameters" in c.get("metadata", {}).get("tags", []))
    assigned = {node.targets[0].id for node in ast.parse("".join(cell["source"])).body
                if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name)}
    assert len(assigned) == len(ast.parse("".join(cell["source"])).body)   # one name each
    assert set(papermill.inspect_notebook(str(path))) == assigned


# -- records -----------------------------------------------------------------------------------

def test_load_records_reads_each_file_with_one_mapping(tmp_path):
    rec = chirp_record()
    write_csv(tmp_path / "chirp.csv", rec)
    write_csv(tmp_path / "loop.csv", rec)
    loaded = own.load_records(tmp_path, "chirp.csv", {"loop": "loop.csv"},
                              columns={"time": 0, "input": 1, "output": 2}, fs=FS,
                              input=("u_c", "V", 1.0), output=("x", "um", 2.0))
    assert loaded.have_plant and list(loaded.all) == ["chirp", "loop"]
    np.testing.assert_allclose(loaded.loops["loop"].output, 2.0 * rec.output, rtol=1e-8)
    assert loaded.checks == {"every record is sampled at the stated rate (0.1 %)": True}
    assert str(loaded).splitlines()[0].startswith("chirp ")


def test_load_records_without_a_chirp_says_what_is_skipped(tmp_path):
    write_csv(tmp_path / "loop.csv", chirp_record())
    loaded = own.load_records(tmp_path, None, {"loop": "loop.csv"},
                              columns={"time": 0, "input": 1, "output": 2}, fs=FS)
    assert not loaded.have_plant
    assert "identification is skipped" in str(loaded)
    data = own.prepare_identification(loaded, (0.05, 0.09), 3.0, 0.2, (5.0, 2000.0))
    assert isinstance(data, own.Skipped) and data.checks == {}
    assert own.identify(data, 1, 0, nb=1, nk=1, floor_percent=70.0) is data


@pytest.mark.parametrize("argument, value, error", [
    ("loop_files", {}, ValueError), ("loop_files", ["a.csv"], TypeError),
    ("columns", {"time": 0, "input": 1}, ValueError), ("input", ("u", "V"), TypeError),
    ("fs", -1.0, ValueError)])
def test_load_records_refuses_bad_arguments(tmp_path, argument, value, error):
    kwargs = dict(folder=tmp_path, chirp_file=None, loop_files={"loop": "loop.csv"},
                  columns={"time": 0, "input": 1, "output": 2}, fs=FS)
    kwargs[argument] = value
    with pytest.raises(error, match=argument):
        own.load_records(**kwargs)


# -- operating point, identification, known truth --------------------------------------------

def prepared(rec=None, hold_out=0.2):
    records = own.OwnRecords(chirp_record() if rec is None else rec, {}, FS, "chirp.csv")
    return own.prepare_identification(records, (0.05, 0.09), 3.0, hold_out, (5.0, 2000.0))


def test_prepare_identification_finds_the_operating_point_and_holds_out_the_end():
    data = prepared()
    assert data.u_op == pytest.approx(1.0) and data.x_op == pytest.approx(3.0 * 0.8, rel=1e-4)
    assert data.input_wobble == 0.0 and all(data.checks.values())
    assert data.record.output_unit == "V" and data.record.output_name == "v_y"
    assert len(data.estimation) + len(data.held_out) == len(data.record)
    assert len(data.held_out) == pytest.approx(0.2 * len(data.record), abs=1)


def test_prepare_identification_refuses_a_record_without_broadband_excitation():
    t = np.arange(1500) / FS
    slow = Record(1 + np.sin(2 * np.pi * 2 * t), np.sin(2 * np.pi * 2 * t), FS)
    with pytest.raises(ValueError, match="chirp.csv: 99 % of the input's power"):
        prepared(slow)
    with pytest.raises(ValueError, match="hold_out"):
        prepared(hold_out=1.5)


def test_identify_recovers_a_noise_free_first_order_plant():
    model = own.identify(prepared(), 1, 0, nb=1, nk=1, floor_percent=70.0, nperseg=256)
    assert model.fit_held_out > 99.9
    assert ct.dcgain(model.model) == pytest.approx(0.8, rel=1e-4)
    assert model.pole_pairs.empty                       # a first-order model has no pair
    assert model.checks == {"held-out fit above 70 %": True, "identified model stable": True}


def an_identification(model):
    """An Identification whose model is given (no estimation run)."""
    data = prepared()
    y = ident.zoh_simulate(model, data.record.input, FS)
    return own.Identification(data, None, model, y, 100.0, 100.0, 70.0, 0.0,
                              (np.array([1.0]), np.array([1.0 + 0j])))


def test_known_truth_of_the_true_plant_itself_has_no_error():
    from piezolib.problem.stage import VirtualStage
    G = VirtualStage().small_signal_model()
    omega = own.analysis_grid(1.0, 1e5, 50)
    model = an_identification(G)
    truth = own.known_truth(model, omega)
    assert truth.error_below_top < 1e-9 and truth.dc_identified == truth.dc_true
    np.testing.assert_array_equal(truth.y_true, model.y_sim)
    assert truth.fit_truth == ident.fit_percent(model.data.held_out.output,
                                                model.y_sim[model.n_estimation:])


def test_the_uncertainty_weight_covers_its_set_and_the_truth_where_it_can():
    omega = own.analysis_grid(1.0, 1e5, 100)
    model = an_identification(ct.tf([0.8e6], [1.0, 600.0, 1e6]))
    weight = own.uncertainty_weight(model, 0.01, 2, 2, omega)
    assert weight.model_set.size == 4 and weight.covered_rad_s is None
    assert all(weight.checks.values())
    assert "covers E_m: True" in str(weight)


# -- without a plant ----------------------------------------------------------------------------

def test_the_stages_that_need_the_plant_pass_a_skip_on():
    skipped = own.Skipped(own.NO_PLANT_NOTE)
    assert own.known_truth(skipped, np.ones(3)) is skipped
    assert own.uncertainty_weight(skipped, 0.01, 2, 2, np.ones(3)) is skipped
    assert not own.ran(skipped) and not own.ran(None)
