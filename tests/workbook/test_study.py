"""Studies: a serialisable description of every choice, derived studies, output folders."""

import pytest

from piezolib import paper
from piezolib.workbook import outputs, study


@pytest.fixture
def checkout(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    (tmp_path / "studies").mkdir()
    return tmp_path


def test_reference_defaults_are_the_published_choices():
    ref = study.Study()
    assert ref.is_reference and ref.name == "reference"
    assert ref.uncertainty.spread == paper.UNCERTAINTY_SPREAD
    assert ref.weights.error == paper.ERROR_WEIGHT and ref.weights.output == paper.OUTPUT_WEIGHT
    assert ref.loop.fs_Hz == paper.SAMPLING_FREQUENCY_HZ
    assert ref.experiments.frequencies_Hz == paper.TRACKING_TEST["frequencies_Hz"]


def test_the_committed_reference_file_is_the_default_study():
    # studies/reference.toml of the checkout must say what the code's defaults say
    assert study.load("reference") == study.Study()


def test_toml_round_trip_and_replace(checkout):
    wide = study.Study().replace(name="wide", description="wider H_e",
                                 weights={"omega_e": 2500}, design={"max_iter": 3})
    path = wide.save(checkout / "studies" / "wide.toml")
    back = study.load("wide")
    assert back == study.load(path) == wide
    assert back.weights.omega_e == 2500 and back.design.max_iter == 3
    assert back.weights.M_e == paper.ERROR_WEIGHT.M_e                  # untouched
    assert [p.stem for p in study.study_files()] == ["wide"]
    # the digest depends only on the sections asked for, and not on int vs float
    ref = study.Study()
    assert wide.digest("uncertainty", "experiments") == ref.digest("uncertainty", "experiments")
    assert wide.digest("weights") != ref.digest("weights")
    assert wide.digest("weights") == study.Study().replace(
        name="x", weights={"omega_e": 2500.0}).digest("weights")


def test_bad_studies_name_the_field(checkout):
    ref = study.Study()
    with pytest.raises(study.StudyError, match="weights.omega_e"):
        ref.replace(name="bad", weights={"omega_e": -1.0})
    with pytest.raises(study.StudyError, match="unknown field.*omega_z"):
        ref.replace(name="bad", weights={"omega_z": 1.0})
    with pytest.raises(study.StudyError, match="unknown study section"):
        ref.replace(name="bad", plant={"a": 1})
    with pytest.raises(study.StudyError, match="own name"):
        ref.replace(uncertainty={"spread": 0.03})
    with pytest.raises(study.StudyError, match="design.order"):
        ref.replace(name="bad", design={"order": 2.5})
    with pytest.raises(study.StudyError, match="uncertainty.spread"):
        ref.replace(name="bad", uncertainty={"spread": float("nan")})
    with pytest.raises(study.StudyError, match="name"):
        ref.replace(name="has space")
    with pytest.raises(study.StudyError, match="no study named 'nope'"):
        study.load("nope")
    (checkout / "studies" / "broken.toml").write_text("name = 'broken'\n[weights\n")
    with pytest.raises(study.StudyError, match="broken.toml: not valid TOML"):
        study.load("broken")
    (checkout / "studies" / "typo.toml").write_text("name = 'typo'\n[loop]\nfs = 5000.0\n")
    with pytest.raises(study.StudyError, match=r"typo.toml: unknown field.*\[loop\]"):
        study.load("typo")
    # a unit suffix in its old lower case (before the _Hz convention): the new spelling is named
    (checkout / "studies" / "old.toml").write_text("name = 'old'\n[loop]\nfs_hz = 5000.0\n")
    with pytest.raises(study.StudyError, match=r"old.toml: \[loop\] 'fs_hz' is now spelled 'fs_Hz'"):
        study.load("old")


def test_the_uncertainty_weight_choice_is_checked(checkout):
    ref = study.load("reference")
    assert ref.uncertainty.weight == "published"
    for change, field in (({"weight": "exact"}, "uncertainty.weight"),
                          ({"weight_order": 0}, "uncertainty.weight_order"),
                          ({"weight_grid": [1e6, 1.0, 100]}, "uncertainty.weight_grid"),
                          ({"weight_grid": [1.0, 1e6]}, "uncertainty.weight_grid"),
                          ({"weight_grid": [1.0, 1e6, 10]}, r"uncertainty.weight_grid\[2\]")):
        with pytest.raises(study.StudyError, match=field):
            ref.replace(name="bad", uncertainty=change)
    fitted = ref.replace(name="fitted", uncertainty={"weight": "fitted", "weight_grid": [1, 1e5, 300]})
    assert fitted.uncertainty.weight_grid == (1, 1e5, 300)
    assert study.load(fitted.save(checkout / "studies" / "fitted.toml")) == fitted


def test_a_study_file_cannot_pose_as_another_study(checkout):
    studies = checkout / "studies"
    # a file named reference.toml with a changed spread would overwrite the committed results
    (studies / "reference.toml").write_text("name = 'reference'\n[uncertainty]\nspread = 0.03\n")
    with pytest.raises(study.StudyError, match="must keep the paper's choices"):
        study.load("reference")
    (studies / "reference.toml").write_text(study.Study().to_toml())
    assert study.load("reference") == study.Study()
    # a name that differs from its file's writes into another study's folder
    (studies / "mine.toml").write_text("name = 'theirs'\n")
    with pytest.raises(study.StudyError, match="named 'theirs' but its file 'mine.toml'"):
        study.load("mine")
    with pytest.raises(study.StudyError, match="reserved"):
        study.Study(name="cache")
    with pytest.raises(study.StudyError, match="report documents"):
        study.Study(name="report")                 # runs/report/ holds the report documents
    (studies / "cache.toml").write_text("name = 'cache'\n")
    with pytest.raises(study.StudyError, match="cache.toml: study name 'cache' is reserved"):
        study.load("cache")
    with pytest.raises(study.StudyError, match="letters, digits"):
        study.Study(name="caf\u00e9")


@pytest.mark.parametrize("values, shown", [("[10.0, true]", "True"), ('[10, "a"]', "'a'")])
def test_a_list_of_numbers_names_the_field_of_a_bad_entry(checkout, values, shown):
    (checkout / "studies" / "odd.toml").write_text(
        f"name = 'odd'\n[experiments]\namplitudes_V = {values}\n")
    with pytest.raises(study.StudyError, match=rf"odd.toml: experiments.amplitudes_V .*got {shown}"):
        study.load("odd")


def test_each_study_has_its_own_output_folders(checkout):
    reference = study.load("reference")
    assert reference.figures_dir == checkout / "figures"
    assert reference.results_dir == checkout / "data" / "results"
    assert outputs.study_controllers_dir("reference") == checkout / "data" / "controllers"
    s = study.Study().replace(name="explore", uncertainty={"spread": 0.03})
    assert s.figures_dir == checkout / "runs" / "explore" / "figures"
    assert s.results_dir == checkout / "runs" / "explore" / "results"
    assert outputs.study_controllers_dir("explore") == checkout / "runs" / "explore" / "controllers"
    with pytest.raises(ValueError, match="name"):
        outputs.study_results_dir("")
