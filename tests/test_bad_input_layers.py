"""Bad input to the problem and workbook layers: a specific exception naming what is wrong.

The toolkit's sweep (``tests/test_bad_input.py``) extended upwards.  Each entry of ``CASES``
holds a valid call of one public function of ``piezolib.problem`` or ``piezolib.workbook`` (or
None where the valid call is a whole design or notebook run, exercised elsewhere) and bad
values per argument; each bad call must raise ValueError or TypeError (StudyError,
RecordError and ArtifactError are ValueErrors) whose message names the argument, or, for a
study, says "study" or names the file.  ``EXEMPT`` lists, with a reason, the public functions
that take no argument a user could get wrong.  ``test_every_public_function_is_covered``
keeps the two complete as the API grows; ``test_cli_*`` does the same for every option of
every subcommand of ``python -m piezolib``.
"""

import argparse
import importlib
import inspect
import pkgutil
import re
import types

import control as ct
import matplotlib.figure
import nbformat
import numpy as np
import pandas as pd
import pytest

from sweep import bad_calls
from piezolib.hysteresis import DahlModel
from piezolib.problem import paper
from piezolib.problem.stage import VirtualStage
from piezolib.problem.stage_batch import StageBatch
from piezolib.workbook import cli

#: Subpackages of the workbook left out of this sweep, with the reason.
SKIPPED_SUBPACKAGES = {
    "workbook.figures": "draws the figures of results the other layers compute and check; its "
                        "functions take those results, and tests/workbook/figures checks them "
                        "(its own bad-input sweep is still to be written)",
    "workbook.interactive": "the notebook widgets' panels, built from the same checked functions; "
                            "tests/workbook/interactive checks them",
}


def _public_modules(layer):
    """Every public module (name not starting with ``_``) of ``piezolib.<layer>``, found on
    disk: a module added tomorrow is swept without editing this file."""
    package = importlib.import_module(f"piezolib.{layer}")
    names = []
    for info in pkgutil.iter_modules(package.__path__):
        if info.name.startswith("_"):
            continue
        if info.ispkg:
            assert f"{layer}.{info.name}" in SKIPPED_SUBPACKAGES, \
                f"piezolib.{layer}.{info.name} is a subpackage this sweep does not cover"
            continue
        names.append(info.name)
    return tuple(sorted(names))


LAYERS = {layer: _public_modules(layer) for layer in ("problem", "workbook")}

G, H_M, H_E, H_Y, K = paper.problem()
S = ct.tf("s")
FS = paper.SAMPLING_FREQUENCY_HZ
STAGE = VirtualStage(seed=0)
STAGE_BATCH = StageBatch.of_seeds(STAGE, [0, 1])
DAHL = DahlModel(alpha1=236.0, alpha2=335.4, beta1=0.0, beta2=2.56, gamma_a=30.0, g_a=1.28,
                 form="bliman_sorine", x0=-0.15, start="rest")
V_R = np.zeros(200)
CLAIMS = importlib.import_module("piezolib.workbook.report").ClaimTable("campaign", "reference")
NOTEBOOK = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(
    "study = 'reference'", metadata={"tags": ["parameters"]})])
FIRST_NOTEBOOK = importlib.import_module("piezolib.workbook.reproduce").list_notebooks()[0]
FIG = matplotlib.figure.Figure()
FIG.set_label("fig99_campaign")
AXES = FIG.add_subplot()
OMEGA = np.logspace(2, 5, 20)
MEMBERS = importlib.import_module("piezolib.uncertainty").random_model_set(G, 0.05, 2)
AXIS_G = ct.tf([2e7], [1.0, 400.0, 4e7])             # a mirror-like resonance, V -> um
SECTIONS_10K = importlib.import_module("piezolib.robust").controller_sos(
    ct.tf([1.0, -0.5], [1.0, -0.2], 1 / FS), name="other")


def bare(cls):
    """An instance of ``cls`` with none of its fields: passes a type check, holds nothing.

    The filler of a result argument where the bad value of another argument must be refused
    before the result is read."""
    if issubclass(cls, tuple):                          # a namedtuple
        return cls(*[None] * len(cls._fields))
    return object.__new__(cls)


class Fill(dict):
    """The valid call is not run (a design or notebook-size run); these values fill its
    required arguments beside ``FILLERS`` in the bad calls."""


def _mod(name):
    return importlib.import_module(f"piezolib.{name}")


_CS, _CB, _HC = _mod("problem.coefficient_set"), _mod("problem.coefficient_box"), \
    _mod("problem.hysteresis_choice")
_VER, _WEI, _SI = _mod("problem.verification"), _mod("problem.weighting"), \
    _mod("problem.stage_identification")
_FM, _FC = _mod("problem.fsm_models"), _mod("problem.fsm_control")
_FF, _FF_FIND = _mod("workbook.feedforward_cases"), _mod("workbook.fsm_findings")
_TSET, _TSTUDY, _OWN = _mod("workbook.tracking_setup"), _mod("workbook.tracking_study"), \
    _mod("workbook.your_stage")
_OWN_H, _OWN_C = _mod("workbook.your_stage_hysteresis"), _mod("workbook.your_stage_control")
P_DESIGN = importlib.import_module("piezolib.problem.genplant").generalized_plant(G, H_M, H_E, H_Y)
M_CLOSED = importlib.import_module("piezolib.problem.genplant").closed_loop_matrix(
    K, G, H_M, H_E, H_Y)
P_ROLLOFF = importlib.import_module("piezolib.problem.genplant").design_plant(G, H_M, H_E, H_Y)
SURVEY = _CS.survey_model_set(G, 0.05, 2)
DISCRETE = ct.tf([1.0], [1.0, -0.5], 1 / FS)
K_DISCRETE = ct.tf([1.0, -0.5], [1.0, -0.2], 1 / FS)
FSM_MODEL = ct.ss(np.zeros((1, 1)), np.ones((1, 3)), np.ones((3, 1)), np.zeros((3, 3)), 1 / 6400)
_MM = _mod("problem.fsm_mimo")
MIRROR_G = ct.ss(0.5 * np.eye(3), np.eye(3), np.eye(3), np.zeros((3, 3)), 1 / 6400)
MIRROR_G_W = ct.ss(-np.eye(3), np.eye(3), np.eye(3), np.zeros((3, 3)))
MIRROR_K = ct.ss([], [], [], 0.1 * np.eye(3), 1 / 6400)
CONTROLLER_SET = types.SimpleNamespace(mu={"a": 1.0}, K_full=K, K_fixed=K)
RESULT = {"text": "abc", "number": 3}            # where a result of an earlier step belongs
CHIRP = bare(importlib.import_module("piezolib.problem.stage_data").ChirpExperiment)
CHIRPS = {"text": "abc", "empty": {}, "not chirps": {"a": 1}}
ORDERS = {"empty": [], "zero": [0], "text": "x"}
PAIR = {"out of range": (3, 0), "negative": (-1, 0), "text": "x"}
BAND = {"reversed": (50.0, 5.0), "negative": (-5.0, 50.0), "text": "x"}
_DRUN = _mod("workbook.design_run")
DESIGN_RUN = _DRUN.read_design_run(_DRUN.design_run_path())       # the committed record
RAW_FOREIGN = _mod("problem.foreign_hysteresis").foreign_raw_record("bouc_wen", fs=2000.0,
                                                                   periods=1.2)
# a stage and sections of one member that pass closed_loop's checks (the loop is not run)
KERNEL_STAGE = dict(dac=np.array([1e-3, -1e4, 1e4]), adc=np.array([1e-3, -1e4, 1e4]),
                    gain=15.0, amp=False, out_lo=-30.0, out_hi=150.0, has_plays=False,
                    r=np.zeros((0, 1)), w=np.zeros((0, 1)), w0=np.zeros(1),
                    plays=np.zeros((0, 1)), b0=np.zeros(1), b1=np.zeros((2, 1)),
                    a1=np.zeros((2, 1)), z=np.zeros((2, 1)), noise=np.zeros((5, 1)),
                    log=np.zeros((7, 5, 1)), v_y=np.zeros(1))
KERNEL_SECTIONS = (np.zeros((1, 6)), np.zeros((2, 1, 1)))


class InTmp(str):
    """A file name inside the test's temporary directory, written with the given text."""

    def __new__(cls, name, text=""):
        obj = super().__new__(cls, name)
        obj.text = text
        return obj


def resolve(kwargs, tmp_path):
    out = {}
    for key, value in kwargs.items():
        if isinstance(value, InTmp):
            path = tmp_path / value
            if value.text is not None:
                path.write_text(value.text)
            value = path
        out[key] = value
    return out


# bad values by kind of argument
STUDY = {"unknown name": "no_such_study", "missing file": "/nonexistent/x.toml",
         "number": 3.5, "none": None, "empty": "",
         "broken file": InTmp("broken.toml", 'name = "broken"\n[weights\n'),
         "name unlike its file": InTmp("other.toml", 'name = "reference"\n')}
STUDY_GIVEN = {k: v for k, v in STUDY.items() if k != "none"}    # where None means the reference
POSITIVE = {"zero": 0.0, "negative": -1.0, "nan": np.nan, "inf": np.inf, "text": "x"}
POSITIVE_INT = {"zero": 0, "negative": -1, "fraction": 1.5, "text": "x"}
SIGNAL = {"nan": np.r_[V_R[:-1], np.nan], "empty": np.array([]), "2-D": np.c_[V_R, V_R],
          "complex": V_R + 1j, "text": "abc"}
LTI = {"nan coefficient": ct.ss([[np.nan]], [[1.0]], [[1.0]], [[0.0]]),
       "discrete": ct.ss(ct.tf([1.0], [1.0, -0.5], 1e-4)), "not a model": np.ones((2, 2)),
       "two inputs": ct.ss(np.eye(1) * -1.0, np.ones((1, 2)), np.ones((1, 1)), np.zeros((1, 2)))}
#: a discrete model at the loop's rate is a valid controller
LTI_CONTINUOUS_OR_LOOP_RATE = {k: v for k, v in LTI.items() if k != "discrete"}
LTI_PROPER = {**LTI, "improper": ct.tf([1.0, 0.0, 0.0], [1.0, 1.0])}
PLANT = {**LTI_PROPER, "improper": G * S ** 4}
GRID = {"nan": np.r_[OMEGA[:-1], np.nan], "negative": -OMEGA, "empty": np.array([]),
        "complex": OMEGA + 1j, "text": "abc"}
MODEL = {"not a model": object(), "text": "dahl", "parameters": {"alpha1": 1.0}}
STAGE_BAD = {"not a stage": object(), "text": "stage", "model": DAHL}
DIRECTORY = {"a file": InTmp("plain.txt", "x"), "number": 3}
PATH_MISSING = {"missing": "/nonexistent/file.json", "number": 3,
                "not json": InTmp("bad.json", "{not json"), "empty": InTmp("empty.json", ""),
                "a directory": InTmp(".", None)}
FIGURE_BAD = {"none": None, "text": "fig", "axes array": np.zeros(2)}
FRAME_BAD = {"not a frame": [1, 2, 3], "none": None}
NAME = {"empty": "", "with a slash": "a/b", "with dots": "..", "number": 3}
SEEDS = {"empty": [], "negative": [-1], "fraction": [1.5], "text": ["a"], "repeated": [1, 1]}
TEXT_BAD = {"number": 3, "none": None}

# name -> (valid call or None, {argument: bad values})
CASES = {
    # problem.paper
    "paper.plant": (dict(), {"coefficients": {"text": "abc", "negative": -1.0, "none": 3}}),
    "paper.uncertainty_weight": (dict(), {"params": {"text": "abc", "number": 3}}),
    "paper.error_weight": (dict(M_e=2.0), {"M_e": POSITIVE, "omega_e": POSITIVE,
                                           "params": {"text": "abc"}}),
    "paper.output_weight": (dict(), {"omega_y": POSITIVE, "params": {"text": "abc"}}),
    "paper.controller": (dict(), {"coefficients": {"text": "abc", "number": 3}}),
    # problem.genplant
    "genplant.check_models": (dict(G=G, H_m=H_M, H_e=H_E, H_y=H_Y),
                              {"G": PLANT, "H_m": LTI_PROPER, "H_e": LTI_PROPER, "H_y": LTI}),
    "genplant.generalized_plant": (dict(G=G, H_m=H_M, H_e=H_E, H_y=H_Y),
                                   {"G": PLANT, "H_e": LTI_PROPER,
                                    "effort_weight": {"negative": -1.0, "nan": np.nan},
                                    "omega_s": POSITIVE}),
    "genplant.design_plant": (dict(G=G, H_m=H_M, H_e=H_E, H_y=H_Y),
                              {"G": PLANT, "effort_weight": {"negative": -1.0, "text": "x"}}),
    "genplant.closed_loop_matrix": (dict(K=K, G=G, H_m=H_M, H_e=H_E, H_y=H_Y),
                                    {"K": LTI, "G": PLANT, "omega_s": POSITIVE}),
    "genplant.effective_delay": (dict(fs=FS, delay_samples=1),
                                 {"fs": POSITIVE, "delay_samples": {"negative": -1,
                                                                    "fraction": 0.5}}),
    "genplant.rolloff_weight": (dict(), {"params": {"text": "abc", "number": 3}}),
    "genplant.parametric_block_structure": (dict(n_coefficients=6),
                                            {"n_coefficients": {"zero": 0, "text": "x"}}),
    "genplant.parametric_design_plant": (dict(G=G, H_e=H_E, H_y=H_Y, spread=0.05, fs=FS),
                                         {"G": LTI_PROPER, "spread": POSITIVE, "fs": POSITIVE,
                                          "delay_samples": {"negative": -1, "text": "x"},
                                          "pade_order": {"zero": 0}}),
    "genplant.delayed_parametric_loop_response": (
        dict(K=K, G=G, H_e=H_E, H_y=H_Y, spread=0.05, omega=OMEGA, fs=FS, delay_samples=1),
        {"K": LTI, "omega": GRID, "spread": POSITIVE, "fs": POSITIVE,
         "delay_samples": {"negative": -1, "fraction": 0.5}}),
    "analysis.exact_margins_with_delay": (dict(G=G, K=K, fs=FS, delays=(1,)),
                                        {"G": PLANT, "K": LTI, "fs": POSITIVE,
                                         "delays": {"empty": [], "negative": [-1], "text": "x"}}),
    "design.design_mixed_controller": (None, {"G": PLANT, "K0": LTI, "fs": POSITIVE,
                                              "performance_scale": POSITIVE, "spread": POSITIVE,
                                              "dg_steps": POSITIVE_INT}),
    "design.mixed_tradeoff": (None, {"scales": {"empty": [], "negative": [-1.0], "text": "x"},
                                     "n_jobs": POSITIVE_INT}),
    "design.tradeoff_table": (None, {"designs": {"text": "abc", "not designs": [1, 2]},
                                     "G": PLANT, "fs": POSITIVE,
                                     "bounds": {"text": "abc", "list": [0.5]}}),
    # problem.mixed_end_points
    "mixed_end_points.read_end_points": (dict(), {"path": {"number": 3, "empty": ""}}),
    "mixed_end_points.bound_key": (
        dict(G=G, H_e=H_E, H_y=H_Y, performance_scale=0.5, spread=0.05, fs=FS),
        {"G": PLANT, "H_e": {"text": "x"}, "performance_scale": POSITIVE, "spread": POSITIVE,
         "fs": POSITIVE}),
    "mixed_end_points.margin_key": (
        dict(G=G, Kd=K_DISCRETE, delay_samples=1, samples=10),
        {"G": PLANT, "Kd": {"text": "x"}, "delay_samples": {"negative": -1, "fraction": 0.5},
         "samples": {"negative": -1}, "seed": {"negative": -1}, "spread_max": POSITIVE,
         "rtol": POSITIVE, "float32": {"text": "x"}}),
    "mixed_end_points.committed_bounds": (
        dict(designs=[], G=G, H_e=H_E, H_y=H_Y, fs=FS),
        {"designs": {"text": "abc", "not designs": [1, 2]}, "fs": POSITIVE,
         "path": {"number": 3}}),
    "mixed_end_points.committed_bracket": (
        dict(G=G, Kd=K_DISCRETE, delay_samples=1, samples=10),
        {"G": PLANT, "Kd": {"text": "x"}, "delay_samples": {"negative": -1},
         "samples": {"negative": -1}, "path": {"number": 3}}),
    "mixed_end_points.write_end_points": (
        Fill(bounds={}, margins={}),
        {"bounds": {"text": "abc", "negative": {"k": -1.0}},
         "margins": {"text": "abc", "not margins": {"k": 3.0}},
         "path": {"number": 3, "empty": ""}}),
    "design.choose_mixed_design": (dict(designs=[]), {"designs": {"text": "abc",
                                                                  "not designs": [1, 2]},
                                                      "spread": POSITIVE}),
    "genplant.delay_aware_plant": (dict(G=G, H_m=H_M, H_e=H_E, H_y=H_Y, fs=FS),
                                   {"G": PLANT, "fs": POSITIVE,
                                    "delay_samples": {"negative": -1, "fraction": 0.5},
                                    "pade_order": {"negative": -1, "fraction": 1.5}}),
    "genplant.delayed_closed_loop_response": (
        dict(K=K, G=G, H_m=H_M, H_e=H_E, H_y=H_Y, omega=OMEGA, fs=FS, delay_samples=1),
        {"K": LTI, "omega": GRID, "fs": POSITIVE, "delay_samples": {"negative": -1}}),
    # problem.stage_batch, stage_calibration
    "stage_batch.check_seeds": (dict(seeds=[1, 2]), {"seeds": SEEDS}),
    "stage_calibration.case_I_input": (dict(amplitude_V=5.0), {"amplitude_V": POSITIVE,
                                                               "periods": POSITIVE_INT,
                                                               "frequency_Hz": POSITIVE}),
    "stage_calibration.run_case_I": (None, {"stage": STAGE_BAD,
                                            "amplitudes_V": {"empty": [], "negative": [-5.0],
                                                             "text": ["a"]},
                                            "periods": POSITIVE_INT}),
    "stage_calibration.case_I_hysteresis": (None, {"records": {"empty": {}, "text": "abc",
                                                               "not records": {5.0: 1.0}}}),
    "stage_calibration.calibrate_hysteresis": (None, {"targets": {"negative": {5.0: -1.0},
                                                                  "not a dict": [1.0],
                                                                  "empty": {}},
                                                      "law": {"text": "abc"}}),
    # problem.stage_data
    # the valid call is cheap, and the settings FILLER (None) would fail before fs
    "stage_data.chirp_input": (
        dict(settings=importlib.import_module("piezolib.problem.stage_data").VALIDATION_CHIRP),
        {"settings": {"text": "abc", "none": None}, "fs": POSITIVE}),
    "stage_data.experiment_paths": (dict(), {"directory": DIRECTORY}),
    "stage_data.write_experiment_files": (None, {"directory": DIRECTORY}),
    # a file that is no record: its RecordError names the file and line, not "path"
    # (tests/problem/test_stage_data.py)
    "stage_data.load_record": (None, {"path": {"missing": "/nonexistent.csv", "number": 3}}),
    "stage_data.load_chirp": (dict(), {"which": {"unknown": "nope", "number": 3},
                                       "directory": DIRECTORY}),
    "stage_data.load_hysteresis_loops": (None, {"directory": DIRECTORY}),
    "stage_data.manifest_path": (dict(), {"directory": DIRECTORY}),
    "stage_data.read_manifest": (dict(), {"directory": DIRECTORY}),
    "stage_data.check_experiment_files": (None, {"directory": DIRECTORY}),
    "stage_data.write_foreign_records": (None, {"directory": DIRECTORY}),
    "stage_data.foreign_record_paths": (dict(), {"directory": DIRECTORY}),
    "stage_data.raw_hysteresis_record": (
        dict(amplitudes_V=(0.5,), periods=1, rest_s=0.05),
        {"seed": {"negative": -1, "text": "x"}, "sample_rate_Hz": POSITIVE,
         "amplitudes_V": {"empty": [], "negative": [-1.0], "nan": [np.nan], "text": "ab",
                          "too large": [5.0]},
         "top_V": POSITIVE, "rest_s": POSITIVE, "periods": {"zero": 0, "text": "x"},
         "frequency_Hz": POSITIVE, "noise_factor": {"negative": -1.0, "nan": np.nan, "text": "x"}}),
    # problem.design, analysis, hysteresis_fits
    "design.design_controller": (None, {"G": PLANT, "order": POSITIVE_INT,
                                        "d_order": {"negative": -1, "fraction": 1.5},
                                        "max_iter": POSITIVE_INT, "fs": POSITIVE,
                                        "delay_samples": {"negative": -2, "fraction": 0.5}}),
    "analysis.analyze": (None, {"K": LTI, "G": PLANT, "omega": GRID}),
    "analysis.table3": (None, {"analyses": {"text": "abc", "number": 3}}),
    "analysis.table3_peaks": (None, {"analyses": {"text": "abc", "number": 3}}),
    "analysis.robust_performance_peak": (dict(K=K, G=G, H_m=H_M, H_e=H_E, H_y=H_Y),
                                         {"K": LTI, "G": PLANT, "omega": GRID}),
    "analysis.box_stability_table": (None, {"controllers": {"empty": {}, "not a mapping": [K],
                                                            "not a pair": {"K": ct.ss(K)},
                                                            "nan K": {"K": (LTI["nan coefficient"], K)}},
                                            "G": PLANT, "spread": POSITIVE, "fs": POSITIVE,
                                            "delays": {"empty": [], "negative": [-1],
                                                       "text": "x"}}),
    "analysis.margins_table": (None, {"controllers": {"empty": {}, "not a mapping": [K],
                                                      "not a model": {"K": 3.0}},
                                      "G": PLANT, "fs": POSITIVE,
                                      "delays": {"negative": (-1,), "empty": (),
                                                 "fraction": (0.5,)}}),
    "analysis.achievable_mu_lower_bound": (None, {"G": PLANT}),
    "hysteresis_fits.published_dahl": (dict(), {"form": {"unknown": "nope", "number": 3},
                                                "params": {"text": "abc"}}),
    "hysteresis_fits.fit_case_I_loops": (None, {"form": {"unknown": "nope"},
                                                "start": {"unknown": "nope"},
                                                "stride": POSITIVE_INT,
                                                "directory": DIRECTORY}),
    "hysteresis_fits.workbook_dahl_fit": (None, {"directory": DIRECTORY}),
    "hysteresis_fits.share_stored_model_check": (None, {"call": {"text": "cache", "number": 3}}),
    # a file that is no model ("not json", "empty"): its error names the file, not "path"
    # (tests/problem/test_hysteresis_fits.py)
    "hysteresis_fits.read_dahl_model": (None, {"path": {k: v for k, v in PATH_MISSING.items()
                                                        if k not in ("not json", "empty")}}),
    "hysteresis_fits.write_dahl_model": (dict(model=DAHL, path=InTmp("dahl.json", None)),
                                         {"model": MODEL, "about": TEXT_BAD}),
    "hysteresis_fits.workbook_pi_fit": (None, {"directory": DIRECTORY,
                                               "n_plays": POSITIVE_INT}),
    "hysteresis_fits.validation_loops": (None, {"stage": STAGE_BAD}),
    "paths.check_directory": (dict(directory=InTmp(".", None)), {"directory": DIRECTORY}),
    "fsm_benchmark.file_name": (dict(signal="u", level_mV=100, split="test"),
                                {"signal": {"other": "x", "number": 3},
                                 "level_mV": {"other level": 150, "text": "100", "bool": True},
                                 "split": {"other": "validation", "number": 1}}),
    "fsm_benchmark.load": (dict(level_mV=300, split="test"),
                           {"level_mV": {"other level": 150, "text": "100"},
                            "split": {"other": "validation", "number": 1},
                            "folder": {"number": 3, "no manifest": InTmp(".", None)}}),
    "fsm_benchmark.check_files": (dict(), {"folder": {"number": 3,
                                                      "no manifest": InTmp(".", None)}}),
    "fsm_benchmark.score": (dict(model=ct.ss(np.zeros((1, 1)), np.ones((1, 3)), np.ones((3, 1)),
                                             np.zeros((3, 3)), 1 / 6400), level_mV=100),
                            {"model": {"continuous": ct.ss(-np.eye(1), np.ones((1, 3)),
                                                           np.ones((3, 1)), np.zeros((3, 3))),
                                       "2 inputs": ct.ss(np.zeros((1, 1)), np.ones((1, 2)),
                                                         np.ones((3, 1)), np.zeros((3, 2)),
                                                         1 / 6400),
                                       "other rate": ct.ss(np.zeros((1, 1)), np.ones((1, 3)),
                                                           np.ones((3, 1)), np.zeros((3, 3)),
                                                           1e-3),
                                       "not a model": np.ones((3, 3))},
                             "level_mV": {"other level": 150}, "split": {"other": "x"}}),
    "fsm_benchmark.score_simulation": (dict(simulate=lambda u: np.zeros_like(u) + 1e-9 * u,
                                            level_mV=100),
                                       {"simulate": {"not callable": 3,
                                                     "wrong shape": lambda u: u[:, :2]},
                                        "level_mV": {"other level": 150},
                                        "split": {"other": "x"}}),
    "fsm_benchmark.axis_design_plant": (
        dict(G=AXIS_G, W_m=ct.tf([0.1], [1.0]), W_S=ct.tf([1.0], [1.0, 1.0]),
             W_T=ct.tf([0.1], [1.0]), W_u=ct.tf([0.01], [1.0]), fs=6400.0),
        {"G": {"discrete": ct.tf([1.0], [1.0, -0.5], 1 / 6400), "text": "x",
               "improper": ct.tf([1.0, 0.0, 0.0], [1.0, 1.0])},
         "W_m": {"text": "x"}, "W_S": {"discrete": ct.tf([1.0], [1.0, -0.5], 1 / 6400)},
         "W_T": {"number": 3}, "W_u": {"text": "x"}, "fs": POSITIVE,
         "delay_samples": {"negative": -1, "fraction": 0.5}, "pade_order": {"zero": 0}}),
    "fsm_benchmark.noise_floor": (dict(level_mV=100),
                                  {"level_mV": {"other level": 150}, "split": {"other": "x"},
                                   "folder": {"number": 3},
                                   "without_drift": {"text": "yes", "number": 1}}),
    # workbook.study
    "study.load": (dict(spec="reference"), {"spec": STUDY}),
    "study.from_dict": (dict(data={"name": "from_dict_test"}),
                        {"data": {"not a mapping": [1, 2], "no name": {},
                                  "unknown section": {"name": "x", "nope": {}},
                                  "bool number": {"name": "x", "experiments":
                                                  {"amplitudes_V": [True]}}}}),
    "study.choices_digest": (dict(choices={"a": 1}), {"choices": {"not a mapping": [1],
                                                                  "unserialisable":
                                                                      {"a": object()}}}),
    # workbook.pipeline
    "pipeline.study_problem": (dict(study="reference"), {"study": STUDY}),
    "pipeline.study_uncertainty_weight": (dict(study="reference"), {"study": STUDY}),
    "pipeline.study_controllers": (None, {"study": STUDY}),
    "pipeline.derive_controllers": (None, {"study": STUDY}),
    "pipeline.design_choices": (dict(study="reference"), {"study": STUDY}),
    "pipeline.design_digest": (dict(study="reference"), {"study": STUDY}),
    "pipeline.write_controllers": (None, {"controllers": {"text": "abc", "none": None},
                                          "study": STUDY}),
    "pipeline.read_controllers": (None, {"path": PATH_MISSING}),
    "pipeline.case_III_controllers": (None, {"study": STUDY,
                                             "controllers": {"text": "abc", "number": 3}}),
    "pipeline.discretized_controllers": (None, {"study": STUDY,
                                                "controllers": {"text": "abc"}}),
    "pipeline.export_sections": (None, {"study": STUDY, "directory": DIRECTORY}),
    "pipeline.study_sections": (None, {"study": STUDY}),
    "pipeline.derive_mixed_designs": (None, {"study": STUDY, "controllers": {"text": "abc"},
                                             "n_jobs": POSITIVE_INT}),
    "pipeline.write_mixed_designs": (None, {"designs": {"text": "abc", "none": None}}),
    "pipeline.read_mixed_designs": (None, {"path": PATH_MISSING}),
    "pipeline.study_mixed_designs": (dict(study="reference"), {"study": STUDY}),
    "pipeline.study_mixed_sections": (dict(study="reference"), {"study": STUDY}),
    "pipeline.write_reference_mixed_designs": (None, {"controllers": {"text": "abc",
                                                                      "number": 3}}),
    # workbook.loop
    "loop.discrete_controller": (dict(K=K),
                                 {"K": {**LTI_CONTINUOUS_OR_LOOP_RATE,
                                        "other sample time": ct.ss(ct.tf([1.0], [1.0, -0.5], 1e-3))},
                                  "fs": POSITIVE}),
    "loop.run_loop": (dict(stage=STAGE, v_r=V_R),
                      {"stage": STAGE_BAD, "v_r": SIGNAL,
                       "delay_samples": {"negative": -1, "fraction": 0.5},
                       "sections_dtype": {"unknown": "float16", "number": 3},
                       "seeds": SEEDS, "controller": {"text": "abc", "array": np.ones(2)},
                       "feedforward": {"text": "abc", "negative gain": -2.0}}),
    "loop.batch_tracking_errors": (dict(batch=STAGE_BATCH, v_r=V_R, frequency_Hz=1000.0,
                                        range_um=12.0),
                                   {"batch": {**STAGE_BAD, "a stage": STAGE}, "v_r": SIGNAL,
                                    "frequency_Hz": POSITIVE,
                                    "discard_periods": {"negative": -1, "all": 100},
                                    "sections_dtype": {"unknown": "float16"},
                                    "range_um": POSITIVE}),
    # workbook.experiments
    "experiments.table4_reference": (dict(amplitude_V=5.0),
                                     {"amplitude_V": POSITIVE, "periods": POSITIVE_INT,
                                      "frequency_Hz": POSITIVE, "fs": POSITIVE,
                                      "amplifier_gain": POSITIVE}),
    "experiments.table4_measure": (None, {"reference_V": SIGNAL, "v_y_V": SIGNAL,
                                          "fs": POSITIVE, "um_per_volt": POSITIVE}),
    "experiments.run_case": (None, {"case": {"unknown": "IV", "number": 1},
                                    "stage": STAGE_BAD, "v_r": SIGNAL, "model": MODEL,
                                    "delay_samples": {"negative": -1}}),
    "experiments.case_table": (None, {"case_values": {"text": "abc", "number": 3},
                                      "columns": {"number": 3}}),
    "experiments.hysteresis_test": (None, {"stage": STAGE_BAD, "model": MODEL,
                                           "amplitudes_V": {"empty": [], "negative": [-5.0]},
                                           "periods": POSITIVE_INT, "seeds": SEEDS}),
    "experiments.tracking_periods": (dict(frequency_Hz=10.0),
                                     {"frequency_Hz": POSITIVE,
                                      "discard_periods": {"negative": -1, "fraction": 0.5},
                                      "min_measured_s": POSITIVE}),
    "experiments.tracking_reference": (dict(frequency_Hz=10.0, periods=3),
                                       {"frequency_Hz": POSITIVE, "periods": POSITIVE_INT,
                                        "amplitude_um": POSITIVE, "fs": POSITIVE}),
    "experiments.tracking_test": (None, {"stage": STAGE_BAD, "model": MODEL,
                                         "frequencies_Hz": {"empty": [], "negative": [-1.0]},
                                         "amplitude_um": POSITIVE, "seeds": SEEDS}),
    "experiments.add_table_claims": (None, {"claims": {"text": "abc", "none": None},
                                            "published": FRAME_BAD}),
    "experiments.design_goal_table": (None, {"results": {"text": "abc", "number": 3}}),
    # workbook.report
    "report.verdict": (dict(paper=1.0, ours=1.0), {"rtol": {"negative": -1.0, "nan": np.nan},
                                                   "atol": {"negative": -1.0},
                                                   "interval": {"reversed": (2.0, 1.0),
                                                                "text": "ab"}}),
    "report.goal_verdict": (dict(low=0.5, high=0.7, goal=1.0),   # a NaN interval: undecided
                            {"low": {"text": "x", "none": None}, "high": {"below low": 0.1},
                             "goal": {"nan": np.nan, "text": "x"}}),
    "report.side_by_side": (None, {"published": FRAME_BAD, "ours": FRAME_BAD}),
    "report.save_results": (None, {"frame": FRAME_BAD, "name": NAME,
                                   "study": {"with a slash": "a/b", "with dots": "..",
                                             "number": 3, "reserved": "cache"}}),
    "report.load_claims": (dict(), {"study": STUDY, "names": {"number": 3}}),
    "report.compare_studies": (None, {"first": STUDY, "second": STUDY}),
    "report.same_result": (dict(first=pd.Series({"ours": "1.0"}),
                                second=pd.Series({"ours": "1.0"})),
                           {"first": {"text": "abc", "number": 3}}),
    "report.reproduction_table": (None, {"claims": {"text": "abc", "number": 3}}),
    "report.inconsistent_verdicts": (None, {"table": FRAME_BAD}),
    "report.verdict_counts": (None, {"table": FRAME_BAD}),
    # workbook.style and plotting
    "style.new_figure": (dict(), {"nrows": POSITIVE_INT, "ncols": POSITIVE_INT}),
    "style.unit_text": (dict(text="u [V]"), {"text": TEXT_BAD}),
    "style.apply_unit_text": (None, {"fig": FIGURE_BAD}),
    "style.db": (dict(x=[1.0, 10.0]), {"x": {"text": "abc"}}),
    "style.plot_magnitude": (None, {"ax": FIGURE_BAD, "omega": GRID}),
    "plotting.name_figure": (None, {"fig": FIGURE_BAD, "number": {"text": "x", "negative": -1},
                                    "what": TEXT_BAD}),
    "plotting.figure_name": (dict(number=3, what="weights"),
                             {"number": {"negative": -1, "text": "x"},
                              "what": {**TEXT_BAD, "empty": ""}}),
    "plotting.save_figure": (None, {"fig": FIGURE_BAD, "directory": DIRECTORY}),
    "plotting.same_picture": (None, {"first": {"text": "abc", "not a png": b"xx", "number": 3},
                                     "tolerance": {"negative": -1.0, "nan": np.nan,
                                                   "inf": np.inf, "text": "x"}}),
    # workbook.reproduce, outputs, session
    "reproduce.list_notebooks": (dict(), {"selection": {"unknown prefix": ["99"],
                                                        "number": 3}}),
    "reproduce.notebook_waves": (None, {"paths": {"number": 3, "one path": "00_a.ipynb",
                                                  "not paths": [3]}}),
    "reproduce.inject_study": (None, {"nb": {"text": "abc", "none": None}, "study": STUDY}),
    "reproduce.run_notebook": (None, {"path": {"missing": "/nonexistent.ipynb", "number": 3},
                                      "timeout": POSITIVE, "study": STUDY_GIVEN}),
    "reproduce.run": (None, {"selection": {"unknown prefix": ["99"]}, "timeout": POSITIVE,
                             "study": STUDY_GIVEN, "jobs": POSITIVE_INT}),
    "outputs.study_output_dir": (dict(name="reference"), {"name": NAME}),
    "outputs.study_results_dir": (dict(name="reference"), {"name": NAME}),
    "outputs.study_figures_dir": (dict(name="reference"), {"name": NAME}),
    "outputs.study_controllers_dir": (dict(name="reference"), {"name": NAME}),
    "session.start": (None, {"study": STUDY, "claims": {"number": 3, "empty": ""}}),
    "outputs.sweep_output_dir": (dict(name="x"), {"name": NAME}),
    # workbook.sweep_spec
    "sweep_spec.load_spec": (dict(spec="omega_spread_order"), {"spec": STUDY}),
    "sweep_spec.spec_from_dict": (dict(data={"name": "x", "grid": {"design.order": [4]}}),
                                  {"data": {"not a mapping": [1, 2],
                                            "unknown parameter": {"name": "x",
                                                                  "grid": {"weights.nope": [1.0]}},
                                            "bad value": {"name": "x",
                                                          "grid": {"weights.omega_e": [-1.0]}},
                                            "unknown study": {"name": "x", "study": "no_such",
                                                              "grid": {"design.order": [4]}}},
                                   "relative_to": {"number": 3}}),
    # workbook.sweep
    "sweep.evaluate_point": (None, {"study": STUDY, "controller": {"unknown": "reduced",
                                                                   "number": 3}}),
    "sweep.run_sweep": (None, {"spec": {"unknown name": "no_such_sweep", "number": 3},
                               "jobs": POSITIVE_INT,
                               "scheduler": {"no protocol": "localhost:8786",
                                             "no port": "tcp://localhost", "number": 3},
                               "evaluate": {"not callable": 3}}),
    "sweep.read_record": (dict(path=InTmp("record.json", "{}")), {"path": {"number": 3,
                                                                           "none": None}}),
    "sweep.pareto_front": (dict(table=pd.DataFrame({"a": [1.0], "b": [2.0]}), x="a", y="b"),
                           {"table": FRAME_BAD, "x": {"missing": "nope"},
                            "y": {"missing": "nope"}}),
    "sweep.committed_points_dir": (dict(name="notebook11-reference"),
                                   {"name": {"path": "a/b", "number": 3}}),
    "sweep.seed_records": (None, {"spec": {"unknown name": "no_such_sweep", "number": 3},
                                  "folder": {"number": 3}}),
    "sweep.check_scheduler_address": (dict(address="tcp://127.0.0.1:8786"),
                                      {"address": {"no port": "tcp://localhost",
                                                   "text": "scheduler", "number": 3}}),
    "cli.main": (None, {}),                 # by argument below: test_cli_*
    "outputs.study_name_problem": (dict(name="a/b"), {}),    # returns the problem as text
    # workbook.two_dof, set_tracking
    "two_dof.dynamics_inverse": (dict(G=G, fs=FS),
                                 {"G": {"zero DC gain": S / (S + 1), "text": "x"},
                                  "fs": POSITIVE, "radius": {"above one": 2.0, "zero": 0.0}}),
    "pipeline.export_feedforward_sections": (None, {"study": STUDY, "directory": {"number": 3}}),
    "pipeline.study_feedforward_sections": (dict(study="reference"), {"study": STUDY}),
    "two_dof.two_dof_feedforward": (dict(G=G, model=DAHL, fs=FS),
                                    {"G": {"zero DC gain": S / (S + 1), "text": "x",
                                           "discrete": ct.tf([1.0], [1.0, -0.5], 1 / FS)},
                                     "model": {"text": "x", "number": 3}, "fs": POSITIVE,
                                     "radius": {**POSITIVE, "above one": 2.0},
                                     "sections": {"text": "x", "another filter": SECTIONS_10K}}),
    "set_tracking.tracking_over_set": (
        dict(stage=STAGE, mset=MEMBERS, model=DAHL, controller=K, frequencies_Hz=[50.0]),
        {"stage": {"text": "x", "a batch": STAGE_BATCH}, "mset": {"a plant": G},
         "model": {"text": "x"}, "controller": {"text": "x"},
         "case": {"unknown": "V", "number": 3}, "frequencies_Hz": {"empty": [], "negative": [-1.0],
                                                                   "text": "x"},
         "amplitude_um": POSITIVE, "delay_samples": {"negative": -1, "fraction": 0.5},
         "discard_periods": {"negative": -1}, "min_measured_s": POSITIVE}),
    "document.default_output": (dict(study="reference"), {"study": STUDY}),
    "document.export_html": (None, {"nb": {"text": "abc", "none": None},
                                    "path": {"number": 3, "empty": ""}}),
    "document.print_pdf": (None, {"html_path": {"number": 3}, "pdf_path": {"number": 3},
                                  "timeout": POSITIVE, "chromium": {"number": 3}}),
    "document.build": (None, {"study": STUDY_GIVEN, "output": {"number": 3},
                              "executed": {"missing": "/nonexistent.ipynb", "number": 3}}),
    "tables.readable": (None, {"frame": {"text": "x", "number": 3}}),
    "report.summary": (None, {"table": {"text": "x",
                                        "no verdicts": pd.DataFrame({"quantity": ["a"]})}}),
    "pipeline.checked_cache_call": (None, {"func": {"not callable": 3, "text": "abc"}}),
    "reproduce.remove_stale_temporaries": (None, {"study": STUDY,
                                                  "older_than_s": {"negative": -1.0,
                                                                   "nan": np.nan}}),
    # problem.published_audit
    "published_audit.pole_table": (dict(sys=G), {"sys": {"text": "x", "discrete": DISCRETE,
                                                         "two inputs": LTI["two inputs"]}}),
    "published_audit.audit_nominal_loop": (None, {"G": {"text": "x", "two inputs":
                                                        LTI["two inputs"]},
                                                  "K": {"text": "x", "two inputs":
                                                        LTI["two inputs"]},
                                                  "H_m": {"text": "x"}, "omega": GRID}),
    # problem.stage_identification
    "stage_identification.case_I_calibration": (Fill(loops={5.0: None}),
                                                {"stage": STAGE_BAD,
                                                 "loops": {"empty": {}, "text": "abc"}}),
    "stage_identification.chirp_settings_table": (None, {"chirps": CHIRPS}),
    "stage_identification.chirp_checks": (Fill(chirps={"a": CHIRP}),
                                          {"chirps": CHIRPS, "stage": STAGE_BAD}),
    "stage_identification.identify_chirp": (Fill(chirp=CHIRP), {"chirp": RESULT,
                                                                "stage": STAGE_BAD,
                                                                "fs": POSITIVE}),
    "stage_identification.coefficient_table": (dict(G=G), {"G": {"text": "x",
                                                                 "not a model": np.ones(2)}}),
    "stage_identification.validate_on_chirp": (Fill(chirp=CHIRP, model=G),
                                               {"model": {"text": "x", "not a model": np.ones(2)},
                                                "chirp": RESULT, "stage": STAGE_BAD,
                                                "fs": POSITIVE}),
    "stage_identification.compare_with_truth": (dict(model=G, truth=G),
                                                {"model": {"text": "x"}, "truth": {"text": "x"}}),
    "stage_identification.pole_pair_frequencies_Hz": (dict(sys=G), {"sys": {"text": "x"}}),
    # problem.coefficient_set
    "coefficient_set.envelope_grid": (dict(points=50), {"points": POSITIVE_INT}),
    "coefficient_set.covered_spreads": (None, {"H_m": {"text": "x"}, "G": {"text": "x"},
                                               "omega": GRID, "levels": POSITIVE_INT}),
    "coefficient_set.margin_gauges": (dict(G=G, K=K, omega=OMEGA),
                                      {"G": {"text": "x"}, "K": {"text": "x"}, "omega": GRID}),
    "coefficient_set.survey_model_set": (dict(G=G, spread=0.05, levels=2),
                                         {"G": {"text": "x"}, "spread": POSITIVE,
                                          "levels": POSITIVE_INT}),
    "coefficient_set.envelope_peaks": (Fill(survey=SURVEY),
                                       {"survey": RESULT, "omega": GRID,
                                        "grid_sizes": {"empty": [], "zero": [0], "text": "x"}}),
    "coefficient_set.cover_envelope": (Fill(survey=SURVEY),
                                       {"survey": RESULT, "omega": GRID, "H_m": {"text": "x"},
                                        "order": POSITIVE_INT}),
    "coefficient_set.compare_spreads": (
        Fill(survey=SURVEY, spreads=[0.05], cover=bare(_CS.EnvelopeCover),
             peaks=bare(_CS.EnvelopePeaks)),
        {"survey": RESULT, "cover": RESULT, "peaks": RESULT, "omega": GRID,
         "spreads": {"negative": [-0.1], "nan": [np.nan], "text": "x"}, "order": POSITIVE_INT}),
    "coefficient_set.loop_margins": (Fill(survey=SURVEY), {"survey": RESULT, "K": {"text": "x"},
                                                           "omega": GRID}),
    "coefficient_set.critical_offsets_kind": (dict(offsets=[1.0, -1.0, 1.0, -1.0, 1.0, -1.0]),
                                              {"offsets": {"empty": [], "nan": [np.nan],
                                                           "text": "ab", "2-D": np.ones((2, 2))}}),
    "coefficient_set.findings": (Fill(peaks=bare(_CS.EnvelopePeaks),
                                      cover=bare(_CS.EnvelopeCover),
                                      margins=bare(_CS.LoopMargins), mu_RS_paper=0.5),
                                 {"peaks": RESULT, "cover": RESULT, "margins": RESULT,
                                  "mu_RS_paper": {"text": "x", "nan": np.nan, "negative": -1.0}}),
    # problem.dahl_audit
    "dahl_audit.steady_state_table": (dict(models={"bliman_sorine": DAHL}),
                                      {"models": {"text": "abc", "empty": {},
                                                  "not models": {"a": 1}}}),
    "dahl_audit.audit_published": (None, {"models": {"text": "abc", "empty": {},
                                                     "not models": {"a": 1}}}),
    # problem.hysteresis_choice
    "hysteresis_choice.candidate_label": (dict(key=("bliman_sorine", False, "rest")),
                                          {"key": {"text": "x", "short": ("a", 1),
                                                   "number form": (3, False, "rest")}}),
    "hysteresis_choice.case_I_fits": (None, {"loops": {"text": "abc", "empty": {},
                                                       "not records": {5.0: 1.0}}}),
    "hysteresis_choice.lower_reversals": (None, {"case_I": RESULT}),
    "hysteresis_choice.start_effect": (None, {"case_I": RESULT}),
    "hysteresis_choice.implied_unit_scale": (None, {"case_I": RESULT}),
    "hysteresis_choice.per_amplitude_fits": (None, {"case_I": RESULT}),
    "hysteresis_choice.compare_models": (None, {"case_I": RESULT}),
    # problem.weighting
    "weighting.template_asymptotes": (dict(error_params=paper.ERROR_WEIGHT,
                                           output_params=paper.OUTPUT_WEIGHT),
                                      {"error_params": RESULT, "output_params": RESULT}),
    "weighting.eq16_entries": (dict(P=P_DESIGN, G=G, H_m=H_M, H_e=H_E, H_y=H_Y, omega=OMEGA),
                               {"P": {"text": "x", "not a model": np.ones((2, 2))},
                                "G": {"text": "x"}, "H_e": {"text": "x"}, "omega": GRID}),
    "weighting.eq18_error": (dict(M=M_CLOSED, K=K, G=G, H_m=H_M, H_e=H_E, H_y=H_Y, omega=OMEGA),
                             {"M": {"text": "x"}, "K": {"text": "x"}, "G": {"text": "x"},
                              "H_y": {"text": "x"}, "omega": GRID}),
    "weighting.templates_met": (None, {"controllers": {"text": "abc", "empty": {},
                                                       "not a model": {"K": 3.0}},
                                       "G": {"text": "x"}, "omega": GRID,
                                       "published": {"number": 3, "unknown": ["nope"]}}),
    # problem.verification
    "verification.regularisation_check": (None, {"G": PLANT, "omega": GRID}),
    "verification.sampled_radii": (dict(G=G, K=K, fs=FS, delays=(0, 1)),
                                   {"G": {"text": "x"}, "K": {"text": "x"}, "fs": POSITIVE,
                                    "delays": {"negative": [-1], "fraction": [0.5],
                                               "number": 3}}),
    "verification.delay_aware_problem": (
        dict(G=G, H_m=H_M, H_e=H_E, H_y=H_Y, K_nodelay=K, K_deployed=K, fs=FS, delay_samples=1,
             omega=OMEGA),
        {"G": PLANT, "K_nodelay": {"text": "x"}, "K_deployed": {"text": "x"}, "fs": POSITIVE,
         "delay_samples": {"negative": -1}, "omega": GRID}),
    "verification.dk_iteration_checks": (None, {"run": RESULT}),
    "verification.compare_rederived": (Fill(used=CONTROLLER_SET, rederived=CONTROLLER_SET),
                                       {"used": RESULT, "rederived": RESULT, "rtol": POSITIVE}),
    "verification.reduction_by_order": (Fill(P=P_DESIGN, orders=[4]),
                                        {"K": {"text": "x"}, "G": {"text": "x"},
                                         "P": {"text": "x"}, "orders": ORDERS, "omega": GRID}),
    "verification.verify_delay_aware": (
        Fill(K_full=K, K_reduced=K, K_fixed=K, plant=P_DESIGN, delay_samples=1),
        {"K_full": {"text": "x"}, "K_reduced": {"text": "x"}, "K_fixed": {"text": "x"},
         "plant": {"text": "x"}, "fs": POSITIVE, "delay_samples": {"negative": -1},
         "fixed_mu": {"text": "x", "negative": -1.0}, "omega": GRID,
         "lower": {"text": "x", "negative": -1.0, "zero": 0.0}}),
    "verification.delay_sweep": (Fill(d_order=1, grid=OMEGA),
                                 {"G": PLANT, "fs": POSITIVE,
                                  "d_order": {"negative": -1, "fraction": 0.5},
                                  "grid": GRID, "delays": {"negative": [-1], "number": 3},
                                  "known": {"text": "abc", "not pairs": {1: 3.0}}}),
    "verification.tustin_check": (dict(K=K, G=G, fs=FS), {"K": {"text": "x"}, "G": {"text": "x"},
                                                          "fs": POSITIVE}),
    "verification.table3_study": (
        Fill(published=K, nodelay_full=K, nodelay_reduced=K, delay_aware_full=K,
             delay_aware_fixed=K, delay_samples=1, nodelay_mu=0.9),
        {"published": {"text": "x"}, "nodelay_full": {"text": "x"},
         "delay_aware_fixed": {"text": "x"}, "fs": POSITIVE, "delay_samples": {"negative": -1},
         "nodelay_mu": {"text": "x", "nan": np.nan}, "omega": GRID}),
    "verification.loop_table": (dict(G=G, controllers={"K": K}),
                                {"G": {"text": "x"}, "controllers": {"text": "abc",
                                                                     "not a model": {"K": 3.0}}}),
    "verification.summary_lines": (
        Fill(nodelay_radii=pd.Series({0: 0.5}), designs=bare(_VER.DesignVerification),
             study=bare(_VER.Table3Study), paper_values={"mu_RP": 0.96}),
        {"nodelay_radii": {"text": "abc", "number": 3}, "designs": RESULT, "study": RESULT,
         "paper_values": {"text": "abc", "no mu_RP": {}}}),
    # problem.coefficient_box
    "coefficient_box.lft_exactness": (None, {"G": PLANT, "K": LTI_PROPER}),
    "coefficient_box.stability_margins": (
        Fill(controllers={"K": K}),
        {"G": PLANT, "H_m": {"text": "x"},
         "controllers": {"text": "abc", "empty": {}, "not a model": {"K": 3.0}},
         "grid": {"text": "x", "reversed": (1e5, 1e2, 10)},
         "certificate_grid": {"text": "x", "zero points": (1.0, 1e6, 0)},
         "exact": {"text": "abc"}}),
    "coefficient_box.spread_bounds": (
        Fill(spread=0.05, critical=bare(_mod("uncertainty").ParametricMargin)),
        {"G": PLANT, "K": LTI_PROPER, "spread": POSITIVE, "critical": RESULT,
         "grid": {"text": "x", "reversed": (1e5, 1e2, 10)}, "peak_points": {"negative": -1},
         "name": {"number": 3}}),
    "coefficient_box.recomputed_tradeoff": (None, {"designs": {"text": "abc",
                                                               "not designs": [1, 2]},
                                                   "G": PLANT, "fs": POSITIVE}),
    "coefficient_box.check_chosen_design": (
        Fill(design=None, deployed=K, sections={_CB.DEPLOYED: SECTIONS_10K}),
        {"design": {"text": "abc"}, "deployed": {"text": "x"},
         "sections": {"text": "abc", "no deployed": {}}, "G": PLANT, "H_e": {"text": "x"},
         "fs": POSITIVE, "grids": {"text": "x", "empty": [], "not triples": [(1.0, 2.0)]},
         "spread": POSITIVE, "delay_samples": {"negative": -1, "fraction": 0.5},
         "committed": {"text": "yes"}}),
    "coefficient_box.searched_end_points": (
        Fill(designs=[], deployed=K, sections={_CB.DEPLOYED: SECTIONS_10K}),
        {"designs": {"text": "abc", "not designs": [1, 2]}, "fs": POSITIVE}),
    "coefficient_box.mixed_claims": (Fill(chosen=bare(_CB.ChosenDesignCheck),
                                          tracking=pd.DataFrame()),
                                     {"chosen": RESULT, "tracking": RESULT}),
    "coefficient_box.summary_lines": (
        Fill(lft=bare(_CB.LFTExactness), margins=bare(_CB.BoxMargins),
             bounds=bare(_CB.SpreadBounds), chosen=bare(_CB.ChosenDesignCheck),
             tracking=pd.DataFrame()),
        {"lft": RESULT, "margins": RESULT, "bounds": RESULT, "chosen": RESULT,
         "tracking": RESULT, "published": {"number": 3}}),
    # problem.fsm_models, fsm_control
    "fsm_models.level_blas": (None, {"folder": {"number": 3, "no manifest": InTmp(".", None)}}),
    "fsm_models.fit_linear_models": (Fill(blas=bare(_FM.LevelBLAs), orders=[4],
                                          baseline_order=4),
                                     {"blas": RESULT, "orders": ORDERS,
                                      "baseline_order": POSITIVE_INT}),
    "fsm_models.score_linear_models": (None, {"linear": RESULT}),
    "fsm_models.level_change": (Fill(blas=bare(_FM.LevelBLAs)),
                                {"blas": RESULT, "bands_Hz": {"text": "x", "empty": (),
                                                              "reversed": ((600, 0),)}}),
    "fsm_models.fit_nonlinear_models": (Fill(blas=bare(_FM.LevelBLAs),
                                             linear=bare(_FM.LinearModels),
                                             play_thresholds_V=[0.1]),
                                        {"blas": RESULT, "linear": RESULT,
                                         "play_thresholds_V": {"empty": [], "negative": [-1.0],
                                                               "text": "x"}}),
    "fsm_models.level_spread_weight": (Fill(blas=bare(_FM.LevelBLAs),
                                            linear=bare(_FM.LinearModels)),
                                       {"blas": RESULT, "linear": RESULT, "pair": PAIR,
                                        "order": POSITIVE_INT}),
    # problem.fsm_causal
    "fsm_causal.derive_causal_model": (Fill(blas=bare(_FM.LevelBLAs), orders=[48, 48, 40]),
                                       {"blas": RESULT,
                                        "orders": {"two": [48, 48], "zero": [0, 48, 40],
                                                   "text": "x", "other levels": {1: 2}}}),
    "fsm_causal.fit_causal_model": (Fill(blas=bare(_FM.LevelBLAs), orders=[48, 48, 40],
                                         branches=[("u", 0)], window_samples=100.0),
                                    {"blas": RESULT, "orders": {"two": [48, 48], "text": "x"}}),
    "fsm_causal.write_causal_model": (None, {"fit": RESULT}),
    "fsm_causal.read_causal_model": (dict(), {"path": {"number": 3, "missing": "/nonexistent.npz"}}),
    "fsm_causal.score_causal_model": (None, {"fit": RESULT}),
    "fsm_models.derive_order_curve": (Fill(blas=bare(_FM.LevelBLAs)),
                                      {"blas": RESULT, "orders": ORDERS}),
    "fsm_models.write_order_curve": (None, {"curve": RESULT}),
    "fsm_models.read_order_curve": (dict(), {"path": {"number": 3, "missing": "/nonexistent.json"}}),
    "fsm_models.level_label": (dict(level_mV=100), {"level_mV": {"other level": 150,
                                                                 "text": "100"}}),
    "fsm_control.axis_entry": (dict(model=FSM_MODEL, pair=(0, 0)),
                               {"model": {"text": "x", "two inputs": LTI["two inputs"]},
                                "pair": PAIR}),
    "fsm_control.axis_nominal": (Fill(linear=bare(_FM.LinearModels), frequency_Hz=[10.0],
                                      nominal_order=8),
                                 {"linear": RESULT, "frequency_Hz": {"empty": [],
                                                                     "negative": [-1.0],
                                                                     "nan": [np.nan]},
                                  "nominal_order": POSITIVE_INT, "pair": PAIR,
                                  "orders": ORDERS}),
    "fsm_control.design_axis": (
        Fill(nominal=bare(_FC.AxisNominal), bandwidth_Hz=50.0, error_weight={},
             output_weight={}, output_corner=2.0, rolloff={}, dk_iterations=2),
        {"nominal": RESULT, "bandwidth_Hz": POSITIVE, "error_weight": {"text": "x"},
         "output_weight": {"text": "x"}, "output_corner": POSITIVE, "rolloff": {"text": "x"},
         "dk_iterations": POSITIVE_INT}),
    "fsm_control.verify_axis": (Fill(nominal=bare(_FC.AxisNominal), design=bare(_FC.AxisDesign)),
                                {"nominal": RESULT, "design": RESULT}),
    "fsm_control.axis_coupling": (Fill(blas=bare(_FM.LevelBLAs), linear=bare(_FM.LinearModels),
                                       design=bare(_FC.AxisDesign)),
                                  {"blas": RESULT, "linear": RESULT, "design": RESULT,
                                   "pair": PAIR, "band_Hz": BAND}),
    "fsm_control.hz_of_w_plane": (dict(nu_rad_s=100.0), {"nu_rad_s": {"negative": -1.0,
                                                                      "nan": np.nan,
                                                                      "text": "x"},
                                                         "fs": POSITIVE}),
    "fsm_control.significant": (dict(x=1.2345), {"x": {"text": "x", "none": None},
                                                 "digits": POSITIVE_INT}),
    "fsm_control.write_axis_design": (
        Fill(design=bare(_FC.AxisDesign), nominal=bare(_FC.AxisNominal), path="x.json"),
        {"design": RESULT, "nominal": RESULT, "path": {"number": 3, "empty": ""}}),
    "fsm_control.read_axis_design": (
        Fill(nominal=bare(_FC.AxisNominal), bandwidth_Hz=20.0, error_weight={}, output_weight={},
             output_corner=5.0, rolloff={}, dk_iterations=8),
        {"nominal": RESULT, "bandwidth_Hz": POSITIVE, "error_weight": {"text": "x"},
         "output_weight": {"text": "x"}, "output_corner": POSITIVE, "rolloff": {"text": "x"},
         "dk_iterations": POSITIVE_INT,
         "path": {"number": 3, "missing": "/nonexistent.json",
                  "not a record": InTmp("r.json", "{}")}}),
    # problem.fsm_mimo
    "fsm_mimo.mirror_model": (dict(model=MIRROR_G), {"model": {
        "text": "x", "two inputs": LTI["two inputs"],
        "continuous": ct.ss(-np.eye(3), np.eye(3), np.eye(3), np.zeros((3, 3)))}}),
    "fsm_mimo.relative_spread": (dict(level_responses=[np.ones((2, 2, 2)) * np.eye(2)],
                                      nominal_response=np.ones((2, 2, 2)) * np.eye(2)),
                                 {"level_responses": {"empty": [], "other shape": [np.ones(3)]},
                                  "nominal_response": {"nan": np.full((2, 2, 2), np.nan),
                                                       "not square": np.ones((2, 2, 3)),
                                                       "singular": np.ones((2, 2, 2))}}),
    "fsm_mimo.mirror_nominal": (Fill(linear=bare(_FM.LinearModels), frequency_Hz=[10.0],
                                     nominal_order=8),
                                {"linear": RESULT, "frequency_Hz": {"empty": [], "nan": [np.nan],
                                                                    "negative": [-1.0]},
                                 "nominal_order": POSITIVE_INT, "orders": ORDERS}),
    "fsm_mimo.mirror_weights": (Fill(params=_MM.DESIGN_PARAMETERS, nu=[1.0, 2.0],
                                     hull=[0.1, 0.2]),
                                {"params": {"text": "x", "empty": {}, "incomplete": {"a": 1}},
                                 "nu": {"empty": [], "negative": [-1.0, 2.0]},
                                 "hull": {"other length": [0.1], "negative": [-0.1, 0.2],
                                          "text": "x"}}),
    "fsm_mimo.mirror_design_plant": (
        dict(G=MIRROR_G_W, W_m=ct.tf(0.1, 1), W_S=ct.tf(1, [1, 1]), W_T=ct.tf(0.1, 1),
             W_u=ct.tf(0.1, 1)),
        {"G": {"text": "x", "discrete": MIRROR_G, "two inputs": LTI["two inputs"]},
         "W_m": {"unstable": ct.tf(1, [1, -1]), "text": "x", "3 x 3": MIRROR_G_W},
         "W_S": {"unstable": ct.tf(1, [1, -1])}, "W_T": {"text": "x"},
         "W_u": {"3 x 3": MIRROR_G_W}}),
    "fsm_mimo.delay_matrix": (dict(n=3), {"n": POSITIVE_INT}),
    "fsm_mimo.block_diagonal": (dict(controllers=[ct.ss([], [], [], [[1.0]])]),
                                {"controllers": {"empty": [], "text": "x",
                                                 "not SISO": [MIRROR_G]}}),
    "fsm_mimo.sampled_radius": (dict(G_d=MIRROR_G, K_d=MIRROR_K),
                                {"G_d": {"text": "x", "continuous": MIRROR_G_W},
                                 "K_d": {"text": "x",
                                         "2 x 2": ct.ss([], [], [], np.eye(2), 1 / 6400),
                                         "other rate": ct.ss([], [], [], np.eye(3), 1e-3)}}),
    "fsm_mimo.step_matrix": (dict(G_d=MIRROR_G, K_d=MIRROR_K, n_samples=20),
                             {"G_d": {"text": "x"}, "K_d": {"text": "x"},
                              "n_samples": POSITIVE_INT}),
    "fsm_mimo.step_crosstalk": (dict(G_d=MIRROR_G, K_d=MIRROR_K, n_samples=20),
                                {"G_d": {"text": "x"}, "K_d": {"text": "x"},
                                 "n_samples": POSITIVE_INT}),
    "fsm_mimo.mirror_margins": (Fill(models={"m": MIRROR_G}, controllers={"k": MIRROR_K}),
                                {"models": {"text": "x", "empty": {}},
                                 "controllers": {"text": "x", "empty": {}}}),
    "fsm_mimo.synthesis_plant": (Fill(nominal=bare(_MM.MirrorNominal), params={"a": 1}),
                                 {"nominal": RESULT, "params": {"text": "x", "empty": {}}}),
    "fsm_mimo.reduce_mirror_controller": (
        Fill(plant=None, K=MIRROR_K, mu=1.0, precision=0.01, orders=[2]),
        {"K": {"text": "x"}, "mu": POSITIVE, "precision": POSITIVE, "orders": ORDERS}),
    "fsm_mimo.derive_mirror_design": (Fill(linear=bare(_FM.LinearModels), frequency_Hz=[10.0]),
                                      {"linear": RESULT, "params": {"text": "x"},
                                       "frequency_Hz": {"empty": [], "nan": [np.nan]}}),
    "fsm_mimo.write_mirror_record": (Fill(record=bare(_MM.MirrorRecord), path="x.json"),
                                     {"record": RESULT, "path": {"number": 3, "empty": ""}}),
    "fsm_mimo.read_mirror_record": (dict(), {"path": {"number": 3,
                                                      "not json": InTmp("bad.json", "{no"),
                                                      "not a record": InTmp("r.json", "{}")}}),
    "fsm_mimo.export_mirror": (Fill(nominal=bare(_MM.MirrorNominal),
                                    record=bare(_MM.MirrorRecord)),
                               {"nominal": RESULT, "record": RESULT}),
    "fsm_mimo.nonlinear_loop": (Fill(causal_model=bare(_mod("identification").BasisModel),
                                     record=bare(_MM.MirrorRecord),
                                     nominal=bare(_MM.MirrorNominal)),
                                {"causal_model": RESULT, "record": RESULT, "nominal": RESULT,
                                 "n_samples": {"text": "x", "too few": 3}}),
    "fsm_mimo.verify_mirror": (Fill(nominal=bare(_MM.MirrorNominal),
                                    record=bare(_MM.MirrorRecord)),
                               {"nominal": RESULT, "record": RESULT,
                                "omega": {"text": "x", "short": [1.0, 2.0]}}),
    # workbook.case_comparison, feedforward_cases, weighting_findings, fsm_findings
    "case_comparison.case_III_comparison": (
        None, {"study": STUDY_GIVEN, "controllers": {"text": "abc", "empty": {},
                                                     "all None": {"K": None}},
               "model": {"text": "x", "number": 3}}),
    "feedforward_cases.feedforward_on_model": (Fill(paper_form=DAHL),
                                               {"model": MODEL, "paper_form": MODEL}),
    "feedforward_cases.case_II": (Fill(loops={5.0: None}, paper_form=DAHL),
                                  {"loops": {"text": "abc", "empty": {},
                                             "not records": {5.0: 1.0}},
                                   "model": MODEL, "paper_form": MODEL,
                                   "per_amplitude": {"text": "abc"}, "stage": STAGE_BAD}),
    "feedforward_cases.cross_check_on_stage": (Fill(comparison=bare(_HC.ModelComparison),
                                                    case=bare(_FF.CaseII)),
                                               {"comparison": RESULT, "case": RESULT}),
    "weighting_findings.findings": (
        Fill(entries=bare(_WEI.Eq16Entries), lft_error=1e-9, templates=bare(_WEI.Templates),
             error_params=paper.ERROR_WEIGHT, met=bare(_WEI.TemplatesMet)),
        {"entries": RESULT, "lft_error": {"text": "x", "nan": np.nan, "negative": -1.0},
         "templates": RESULT, "error_params": RESULT, "met": RESULT}),
    "fsm_findings.mimo_claim_rows": (Fill(mirror=bare(_MM.MirrorNominal),
                                          record=bare(_MM.MirrorRecord),
                                          checked=bare(_MM.MirrorVerification)),
                                     {"mirror": RESULT, "record": RESULT, "checked": RESULT,
                                      "exported": RESULT}),
    "fsm_findings.mimo_summary_lines": (Fill(mirror=bare(_MM.MirrorNominal),
                                             record=bare(_MM.MirrorRecord),
                                             checked=bare(_MM.MirrorVerification)),
                                        {"mirror": RESULT, "record": RESULT, "checked": RESULT}),
    "fsm_findings.claim_rows": (
        Fill(scores=bare(_FM.LinearScores), nonlinear=bare(_FM.NonlinearModels),
             weight=bare(_FM.LevelSpreadWeight), nominal=bare(_FC.AxisNominal),
             verified=bare(_FC.AxisVerification), design=bare(_FC.AxisDesign)),
        {name: RESULT for name in ("scores", "nonlinear", "weight", "nominal", "verified",
                                   "design")}),
    "fsm_findings.summary_lines": (
        Fill(blas=bare(_FM.LevelBLAs), scores=bare(_FM.LinearScores),
             change=bare(_FM.LevelChange), nonlinear=bare(_FM.NonlinearModels),
             weight=bare(_FM.LevelSpreadWeight), nominal=bare(_FC.AxisNominal),
             design=bare(_FC.AxisDesign), verified=bare(_FC.AxisVerification),
             coupling=bare(_FC.AxisCoupling)),
        {name: RESULT for name in ("blas", "scores", "change", "nonlinear", "weight", "nominal",
                                   "design", "verified", "coupling")}),
    "fsm_findings.causal_claim_rows": (None, {"causal": RESULT}),
    "fsm_findings.order_curve_claim_rows": (
        Fill(curve=bare(_FM.OrderCurve), scores=bare(_FM.LinearScores)),
        {"curve": RESULT, "scores": RESULT}),
    "fsm_findings.order_curve_summary_line": (
        Fill(curve=bare(_FM.OrderCurve), scores=bare(_FM.LinearScores)),
        {"curve": RESULT, "scores": RESULT}),
    "fsm_findings.nonlinear_loop_claim_rows": (None, {"loop": RESULT}),
    "fsm_findings.slashed": (dict(values=[1.0, 2.0]), {"values": {"text": "x", "number": 3,
                                                                  "not numbers": ["a"]}}),
    # workbook.tracking_setup, tracking_study
    "tracking_setup.ingredients": (None, {"study": STUDY_GIVEN}),
    "tracking_setup.sections_error": (dict(Kd=K_DISCRETE, sections=SECTIONS_10K, fs=FS),
                                      {"Kd": {"text": "x", "continuous": K},
                                       "sections": {"text": "x", "number": 3}, "fs": POSITIVE}),
    "tracking_setup.loop_margins": (None, {"ing": RESULT}),
    "tracking_setup.mu_certificate": (None, {"ing": RESULT}),
    "tracking_setup.error_definition_evidence": (None, {"ing": RESULT}),
    "tracking_study.run_experiments": (None, {"ing": RESULT}),
    "tracking_study.case_I_gain": (None, {"ing": RESULT}),
    "tracking_study.case_IV": (Fill(ing=bare(_TSET.Ingredients), runs=bare(_TSTUDY.Experiments)),
                               {"ing": RESULT, "runs": RESULT}),
    "tracking_study.saturation": (None, {"runs": RESULT}),
    "tracking_study.add_claims": (
        Fill(mu=bare(_TSET.MuCertificate), runs=bare(_TSTUDY.Experiments),
             case_iv=bare(_TSTUDY.CaseIV)),
        {"claims": RESULT, "mu": RESULT, "runs": RESULT, "case_iv": RESULT}),
    "tracking_study.summary": (
        Fill(reference=True, mu=bare(_TSET.MuCertificate), runs=bare(_TSTUDY.Experiments),
             case_iv=bare(_TSTUDY.CaseIV)),
        {"claims": RESULT, "reference": {"text": "yes", "number": 3}, "mu": RESULT,
         "runs": RESULT, "case_iv": RESULT}),
    # workbook.your_stage
    "your_stage.analysis_grid": (dict(low_rad_s=1.0, high_rad_s=1e3, points=10),
                                 {"low_rad_s": POSITIVE, "high_rad_s": {"below low": 0.5,
                                                                        "text": "x"},
                                  "points": POSITIVE_INT}),
    "your_stage.records_study": (dict(study=None, folder="my_records"),
                                 {"study": {**STUDY_GIVEN, "the reference": "reference"},
                                  "folder": {"number": 3, "empty": ""}}),
    "your_stage.load_records": (
        Fill(folder=InTmp(".", None), chirp_file="chirp.csv", loop_files={"a": "a.csv"},
             columns={"time": 0, "input": 1, "output": 2}, fs=1000.0),
        {"folder": {"number": 3, "a file": InTmp("plain.txt", "x")},
         "chirp_file": {"number": 3}, "loop_files": {"text": "abc", "empty": {}},
         "columns": {"text": "abc", "missing keys": {"time": 0}}, "fs": POSITIVE,
         "time_scale": POSITIVE, "delimiter": {"number": 3, "empty": ""},
         "input": {"text": "u", "short": ("u", "V")},
         "output": {"text": "y", "zero scale": ("y", "V", 0.0)}}),
    "your_stage.prepare_identification": (
        Fill(records=bare(_OWN.OwnRecords), window_s=(0.0, 1.0), um_per_volt=3.0, hold_out=0.3,
             band_Hz=(1.0, 100.0)),
        {"records": RESULT, "window_s": {"text": "x", "reversed": (1.0, 0.0)},
         "um_per_volt": POSITIVE, "hold_out": {"zero": 0.0, "one": 1.0, "text": "x"},
         "band_Hz": BAND}),
    "your_stage.identify": (
        Fill(data=bare(_OWN.IdentificationData), n_poles=2, n_zeros=0, nb=1, nk=1,
             floor_percent=1.0),
        {"data": RESULT, "n_poles": POSITIVE_INT, "n_zeros": {"negative": -1, "fraction": 0.5},
         "nb": POSITIVE_INT, "nk": {"negative": -1}, "floor_percent": POSITIVE,
         "coherence": {"above one": 2.0, "negative": -0.5, "text": "x"},
         "nperseg": POSITIVE_INT}),
    "your_stage.known_truth": (Fill(identification=bare(_OWN.Identification), omega=OMEGA),
                               {"identification": RESULT, "omega": GRID}),
    "your_stage.uncertainty_weight": (
        Fill(identification=bare(_OWN.Identification), spread=0.05, levels=3, order=4,
             omega=OMEGA),
        {"identification": RESULT, "spread": POSITIVE, "levels": POSITIVE_INT,
         "order": POSITIVE_INT, "omega": GRID, "truth": RESULT}),
    "your_stage_hysteresis.prepare_loops": (Fill(records=bare(_OWN.OwnRecords), um_per_volt=3.0,
                                      decimation=1),
                                 {"records": RESULT, "um_per_volt": POSITIVE,
                                  "decimation": POSITIVE_INT,
                                  "skip_transient": {"text": "yes", "number": 3}}),
    "your_stage_hysteresis.fit_hysteresis": (
        Fill(loops=bare(_OWN_H.HysteresisLoops), fit_loops=["a"], validation_loops=["a"],
             gamma_a=30.0, plays=4, ceiling_percent=5.0),
        {"loops": RESULT, "fit_loops": {"number": 3}, "validation_loops": {"number": 3},
         "gamma_a": POSITIVE, "plays": POSITIVE_INT, "ceiling_percent": POSITIVE}),
    "your_stage_control.design_for_loop": (
        Fill(identification=bare(_OWN.Identification), weight=bare(_OWN.UncertaintyWeight),
             error_weight={}, output_weight={}, rolloff={}, order=4, d_order=1, iterations=2,
             delay_samples=1),
        {"identification": RESULT, "weight": RESULT, "error_weight": {"text": "x"},
         "output_weight": {"text": "x"}, "rolloff": {"text": "x"}, "order": POSITIVE_INT,
         "d_order": {"negative": -1, "fraction": 0.5}, "iterations": POSITIVE_INT,
         "fs": POSITIVE, "delay_samples": {"negative": -1, "fraction": 0.5}}),
    "your_stage_control.verify_design": (
        Fill(loop=bare(_OWN_C.LoopDesign), identification=bare(_OWN.Identification),
             weight=bare(_OWN.UncertaintyWeight)),
        {"loop": RESULT, "identification": RESULT, "weight": RESULT, "truth": RESULT}),
    "your_stage_hysteresis.feedforward_cross_check": (None, {"choice": RESULT}),
    "your_stage_control.run_experiments": (
        Fill(loop=bare(_OWN_C.LoopDesign), choice=bare(_OWN_H.HysteresisChoice), seed=0,
             noise_rms_V=1e-3, amplitudes_V=[1.0], periods=2, frequencies_Hz=[10.0],
             amplitude_um=5.0, delay_samples=1, loop_rate_Hz=FS),
        {"loop": RESULT, "choice": RESULT, "seed": {"negative": -1, "text": "x"},
         "noise_rms_V": {"negative": -1.0, "nan": np.nan}, "amplitudes_V": {"empty": [],
                                                                            "negative": [-1.0]},
         "periods": POSITIVE_INT, "frequencies_Hz": {"empty": [], "negative": [-1.0]},
         "amplitude_um": POSITIVE, "delay_samples": {"negative": -1},
         "loop_rate_Hz": {**POSITIVE, "other rate": 5000.0},
         "noise_seeds": {"one": 1, "fraction": 2.5, "text": "x"}}),
    "your_stage_claims.record_claims": (
        Fill(records=bare(_OWN.OwnRecords), identification=None, weight=None, choice=None,
             loop=None, verification=None, experiments=None),
        {"claims": RESULT, "records": RESULT, "identification": RESULT, "weight": RESULT,
         "choice": RESULT, "loop": RESULT, "verification": RESULT, "experiments": RESULT,
         "truth": RESULT}),
    "your_stage_claims.written_tables": (
        Fill(experiments=bare(_OWN_C.Experiments)),
        {"experiments": RESULT, "path": {"missing": InTmp("missing.csv", None),
                                         "not a claim table": InTmp("t.csv", "a,b\n1,2\n")}}),
    "your_stage_claims.stage_checks": (dict(results=None), {"results": {"text": "abc",
                                                                 "number": 3}}),
    "your_stage_claims.known_truth_checks": (
        Fill(truth=None, identification=None, weight=None, choice=bare(_OWN_H.HysteresisChoice),
             verification=None, experiments=None),
        {"truth": RESULT, "choice": RESULT, "identification": RESULT, "weight": RESULT,
         "verification": RESULT, "experiments": RESULT}),
    "your_stage_claims.summary_lines": (Fill(records=bare(_OWN.OwnRecords), seconds=1.0),
                                 {"records": RESULT, "seconds": {"negative": -1.0,
                                                                 "nan": np.nan, "text": "x"}}),
    # workbook.design_run, problem.foreign_hysteresis, stage_loop_kernel
    "design_run.study_design_run": (dict(study="reference"), {"study": STUDY}),
    "design_run.derive_design_run": (None, {"study": STUDY,
                                            "cache": {"text": "yes", "number": 1},
                                            "derived": {"text": "abc", "a record": DESIGN_RUN}}),
    "design_run.write_design_run": (
        dict(run=DESIGN_RUN, path=InTmp("run.json", None)),
        {"run": {"text": "abc", "none": None, "controllers": bare(_mod("workbook.pipeline")
                                                                  .StudyControllers)},
         "path": {"number": 3, "empty": "", "a directory": InTmp(".", None)}}),
    "design_run.write_reference_record": (None, {"derived": {"text": "abc", "none": None,
                                                             "a record": DESIGN_RUN}}),
    "design_run.read_design_run": (dict(path=_DRUN.design_run_path()), {"path": PATH_MISSING}),
    "foreign_hysteresis.foreign_operator": (dict(family="duhem"),
                                            {"family": {"unknown": "nope", "number": 3,
                                                        "list": ["duhem"], "none": None}}),
    "foreign_hysteresis.foreign_raw_record": (
        dict(family="bouc_wen", fs=2000.0, periods=1.2),
        {"family": {"unknown": "nope", "list": ["duhem"]},
         "fs": {**POSITIVE, "too few samples": 10.0, "too many samples": 1e7},
         "seed": {"negative": -1, "text": "x"}, "rest_s": POSITIVE, "periods": POSITIVE,
         "noise_percent": POSITIVE, "x_offset": {"nan": np.nan, "inf": np.inf, "text": "x"}}),
    # the fit takes a minute: the valid call is not run
    "foreign_hysteresis.best_achievable": (Fill(raw=RAW_FOREIGN),
                                           {"raw": {"text": "abc", "a record": RAW_FOREIGN.record},
                                            "levels": {**POSITIVE_INT, "too many": 400},
                                            "rows": POSITIVE_INT}),
    "stage_loop_kernel.closed_loop": (
        Fill(v_r=np.zeros(4), u_f=np.zeros(4), delay=1, stage=KERNEL_STAGE,
             sections=KERNEL_SECTIONS, u_b=np.zeros((4, 1)), diverged_v=1e3),
        {"v_r": {"list": [0.0] * 4, "2-D": np.zeros((4, 1)), "integers": np.zeros(4, int),
                 "text": "abc"},
         "u_f": {"shorter": np.zeros(3), "float32": np.zeros(4, np.float32)},
         "delay": {"negative": -1, "fraction": 0.5},
         "stage": {"text": "abc", "empty": {},
                   "no log": {k: v for k, v in KERNEL_STAGE.items() if k != "log"},
                   "other members": {**KERNEL_STAGE, "z": np.zeros((2, 2))},
                   "short noise": {**KERNEL_STAGE, "noise": np.zeros((4, 1))},
                   "short log": {**KERNEL_STAGE, "log": np.zeros((7, 4, 1))},
                   "text gain": {**KERNEL_STAGE, "gain": "15"}},
         "sections": {"text": "abc", "one array": np.zeros((1, 6)),
                      "other members": (np.zeros((1, 6)), np.zeros((2, 1, 2))),
                      "mixed precision": (np.zeros((1, 6), np.float32), np.zeros((2, 1, 1)))},
         "u_b": {"other shape": np.zeros((3, 1)), "none": None},
         "diverged_v": POSITIVE}),
    "cli.error_line": (dict(exc=OSError(2, "No such file or directory", "x.csv")),
                       {"exc": {"text": "abc", "none": None, "a class": OSError}}),
    # workbook.report, document, session
    "report.findings": (Fill(name="mixed_mu"), {"name": {"unknown": "nope", "number": 3},
                                                 "study": STUDY}),
    "report.figure_path": (None, {"name": {"number": 3, "with a slash": "../x.png",
                                           "empty": ""}, "study": STUDY}),
    "document.print_css": (dict(), {"paper": {"unknown": "B7", "number": 3}}),
    "session.claim_lines": (dict(rows=[]), {"rows": {"text": "abc", "number": 3,
                                                     "not rows": [1, 2]}}),
}

#: Public functions without an argument a user could get wrong.
EXEMPT = {
    "paper.case_rows_index": "no arguments", "paper.table1": "no arguments",
    "paper.table2": "no arguments", "paper.table4": "no arguments",
    "paper.table5": "no arguments", "paper.problem": "no arguments",
    "hysteresis_fits.workbook_dahl_path": "no arguments",
    "mixed_end_points.end_points_path": "no arguments",
    "hysteresis_fits.write_workbook_dahl": "no arguments (writes a committed artifact)",
    "paths.project_root": "no arguments", "paths.data_dir": "no arguments",
    "warm_kernels.available": "no arguments",
    "fsm_benchmark.data_folder": "no arguments",
    "fsm_mimo.record_path": "no arguments",
    "fsm_control.axis_record_path": "no arguments",
    "fsm_causal.causal_model_path": "no arguments",
    "fsm_benchmark.write_manifest": "writes the committed data's manifest; its folder is checked "
                                    "by paths.check_directory (a valid call needs the 21 MB data)",
    "study.study_files": "no arguments",
    "study.studies_dir": "no arguments", "study.section_fields": "no arguments",
    "sweep_spec.specs_dir": "no arguments",
    "pipeline.memory": "no arguments (its location comes from PIEZOLIB_CACHE)",
    "pipeline.library_fingerprint": "no arguments",
    "pipeline.reference_design_path": "no arguments",
    "pipeline.mixed_design_path": "no arguments",
    "design_run.design_run_path": "no arguments",
    "pipeline.write_reference_design": "only cache, a flag (a whole design run)",
    "style.use_style": "no arguments",
    "cli.parser": "no arguments",
    "reproduce.default_jobs": "no arguments",
    "outputs.project_root": "no arguments", "outputs.data_dir": "no arguments",
    "outputs.runs_dir": "no arguments", "outputs.notebooks_dir": "no arguments",
    "outputs.report_dir": "no arguments",
    "document.report_notebook": "no arguments", "document.find_chromium": "no arguments",
    "tables.format_number": "any value is a cell: non-numbers are shown as they are",
    "reproduce.study_spec": "formats the study for inject_study, which loads (checks) it",
    "published_audit.units_table": "no arguments",
    "published_audit.table_consistency": "no arguments",
    "dahl_audit.unit_conventions": "no arguments", "dahl_audit.published_models": "no arguments",
    "hysteresis_choice.case_I_loops": "no arguments",
    "your_stage.ran": "any value: it says whether the value is a result (not None or Skipped)",
}


def function(qualname):
    module, name = qualname.split(".")
    layer = next(k for k, mods in LAYERS.items() if module in mods)
    return getattr(importlib.import_module(f"piezolib.{layer}.{module}"), name)


def public_functions():
    names = set()
    for layer, modules in LAYERS.items():
        for module in modules:
            mod = importlib.import_module(f"piezolib.{layer}.{module}")
            assert hasattr(mod, "__all__"), f"{mod.__name__} has no __all__ to list its API"
            names |= {f"{module}.{n}" for n in getattr(mod, "__all__", ())
                      if callable(getattr(mod, n)) and not inspect.isclass(getattr(mod, n))}
    return names


def call(qualname, kwargs):
    f = function(qualname)
    star = [p for p in inspect.signature(f).parameters.values()
            if p.kind is inspect.Parameter.VAR_POSITIONAL]
    if star and star[0].name in kwargs:                 # table3(*analyses)
        kwargs = dict(kwargs)
        value = kwargs.pop(star[0].name)
        return f(value, **kwargs)
    return f(**kwargs)


def test_every_public_function_is_covered():
    public = public_functions()
    stale = (set(CASES) | set(EXEMPT)) - public
    assert not stale, f"entries for names that are not public: {sorted(stale)}"
    missing = public - set(CASES) - set(EXEMPT)
    assert not missing, f"public functions with no bad-input cases: {sorted(missing)}"
    # every named argument exists: a renamed parameter must not leave a case testing nothing
    for qualname, (_, corrupt) in CASES.items():
        params = inspect.signature(function(qualname)).parameters
        if not any(p.kind is p.VAR_KEYWORD for p in params.values()):
            assert set(corrupt) <= set(params), (qualname, set(corrupt) - set(params))


@pytest.mark.parametrize("qualname", sorted(q for q, (v, _) in CASES.items()
                                      if v is not None and not isinstance(v, Fill)))
def test_the_valid_call_works(qualname, tmp_path):
    call(qualname, resolve(CASES[qualname][0], tmp_path))


def _filled(qualname, valid, argument, value):
    """The bad call: the valid one with ``argument`` replaced, or, where the valid call is
    too costly to run, every required argument filled with a harmless valid value (the case's
    ``Fill``, else ``FILLERS``)."""
    if valid is not None and not isinstance(valid, Fill):
        return {**valid, argument: value}
    fillers = {**FILLERS, **(valid or {})}
    params = inspect.signature(function(qualname)).parameters
    kwargs = {}
    for name, p in params.items():
        if name == argument or p.default is not inspect.Parameter.empty \
                or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        kwargs[name] = fillers[name]
    return {**kwargs, argument: value}


# valid values for required arguments of the calls whose valid call is not run
FILLERS = {"G": G, "H_m": H_M, "H_e": H_E, "H_y": H_Y, "K": K, "stage": STAGE, "v_r": V_R,
           "model": DAHL, "controller": K, "study": "reference", "fs": FS, "K0": K,
           "designs": [], "spread": 0.05, "path": "/nonexistent/file.json",
           "controllers": {"K": ct.ss(K)}, "records": {}, "settings": None,
           "reference_V": np.sin(np.linspace(0, 60, 3000)),
           "v_y_V": np.sin(np.linspace(0, 60, 3000)),
           "case": "II", "case_values": {"I": [1.0], "II": [1.0], "III": [1.0]},
           "columns": ["a"], "claims": CLAIMS, "section": "x",
           "published": pd.DataFrame(), "result": None, "quantity": "q", "results": {},
           "ours": pd.DataFrame(), "frame": pd.DataFrame({"a": [1.0]}), "name": "x",
           "first": "reference", "second": "reference", "table": pd.DataFrame(),
           "fig": FIG, "ax": AXES, "omega": OMEGA, "response": np.ones(20), "number": 1,
           "what": "x", "directory": None, "tolerance": 0.25, "paths": [], "nb": NOTEBOOK, "func": len,
           "path": FIRST_NOTEBOOK, "form": "printed", "offset": True, "start": "rest", "analyses": None,
           "x": [1.0], "text": "x", "spec": "omega_spread_order",
           "html_path": "report.html", "pdf_path": "report.pdf"}


#: Arguments holding a study (a name, a file or its fields).
STUDY_ARGUMENTS = ("study", "spec", "first", "second", "data")
#: Where a function reports an argument under the name its users know it by.
ALIASES = {("loop.discrete_controller", "K"): r"\bcontroller\b|\bK\b"}


def _bad_calls():
    """``bad_calls(CASES)``, those listed in ``PENDING`` marked as expected to fail (strict:
    one that is fixed fails until its entry is removed)."""
    for param in bad_calls(CASES):
        qualname, _, argument, _ = param.values
        kind = param.id[len(f"{qualname}-{argument}-"):]
        if kind in PENDING.get(qualname, {}).get(argument, ()):
            param = pytest.param(*param.values, id=param.id, marks=pytest.mark.xfail(
                strict=True, reason="no clear error naming the argument yet: a fix is pending"))
        yield param


#: {name: {argument: bad kinds}} that do not yet raise a ValueError/TypeError naming the
#: argument (an AttributeError or KeyError from deep inside, or no error): each is a bug of
#: that function, listed here so that the sweep stays complete while the fixes are pending.
PENDING = {
}


@pytest.mark.parametrize("qualname, valid, argument, value", list(_bad_calls()))
def test_bad_input_raises_naming_the_argument(qualname, valid, argument, value, tmp_path):
    kwargs = resolve(_filled(qualname, valid, argument, value), tmp_path)
    with pytest.raises((ValueError, TypeError, OSError)) as info:
        call(qualname, kwargs)
    message = str(info.value)
    if isinstance(info.value, OSError):
        # a file that cannot be read or written: the error names it
        assert info.value.filename or re.search(r"/|\\", message), message
    elif argument in STUDY_ARGUMENTS:
        # a study is named by what the user gave: "study ...", the file, or the field
        assert re.search(rf"study|\.toml|\b{argument}\b|\b[a-z]+\.[a-z_A-Z]+\b", message,
                         re.I), message
    elif isinstance(value, InTmp):
        assert str(tmp_path / value) in message, message     # the file is named
    elif (qualname, argument) in ALIASES:
        assert re.search(ALIASES[qualname, argument], message, re.I), message
    else:
        assert re.search(rf"\b{re.escape(argument)}\b", message, re.I), message


# --- the command line ---------------------------------------------------------------------

def _options():
    """(subcommand, option) for every option and positional of every subcommand."""
    parser = cli.parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {(name, action.dest) for name, p in sub.choices.items() for action in p._actions
            if not isinstance(action, argparse._HelpAction)}


# (argv, exit status, what stderr must say): every one ends in a message, not a traceback
CLI_CASES = {
    ("reproduce", "notebooks"): [(["reproduce", "99"], 2, "99"),
                                 (["reproduce", "--no-data", "no_such"], 2, "no_such")],
    ("reproduce", "timeout"): [(["reproduce", "--timeout", "0"], 2, "timeout"),
                               (["reproduce", "--timeout", "nan"], 2, "timeout"),
                               (["reproduce", "--timeout", "x"], 2, "timeout")],
    ("reproduce", "jobs"): [(["reproduce", "--jobs", "0"], 2, "jobs"),
                            (["reproduce", "--jobs", "1.5"], 2, "jobs")],
    ("reproduce", "keep_going"): [(["reproduce", "--keep-going=yes"], 2, "keep-going")],
    ("reproduce", "no_data"): [(["reproduce", "--no-data=1"], 2, "no-data")],
    ("reproduce", "study"): [(["reproduce", "--study", "no_such_study"], 2, "no_such_study"),
                             (["reproduce", "--study"], 2, "study")],
    ("reproduce", "list"): [(["reproduce", "--list=x"], 2, "list")],
    ("controllers", "write_reference"): [(["controllers", "--write-reference=1"], 2,
                                          "write-reference")],
    ("controllers", "write_mixed"): [(["controllers", "--write-mixed=1"], 2, "write-mixed")],
    ("sweep", "spec"): [(["sweep"], 2, "spec"), (["sweep", "no_such_sweep"], 2, "no_such_sweep"),
                        (["sweep", "/nonexistent/s.toml"], 2, "s.toml")],
    ("sweep", "jobs"): [(["sweep", "omega_spread_order", "--jobs", "0"], 2, "jobs")],
    ("sweep", "scheduler"): [(["sweep", "omega_spread_order", "--scheduler", "localhost"], 2,
                              "scheduler"),
                             (["sweep", "omega_spread_order", "--scheduler"], 2, "scheduler")],
    ("sweep", "dry_run"): [(["sweep", "omega_spread_order", "--dry-run=1"], 2, "dry-run")],
    ("compare", "first"): [(["compare"], 2, "first"),
                           (["compare", "no_such", "reference"], 2, "no_such")],
    ("compare", "second"): [(["compare", "reference"], 2, "second"),
                            (["compare", "reference", "reference"], 2, "reference"),
                            (["compare", "reference", "no_such"], 2, "no_such")],
    ("report", "study"): [(["report", "--study", "no_such_study"], 2, "no_such_study"),
                          (["report", "--study"], 2, "study")],
    ("report", "timeout"): [(["report", "--timeout", "0"], 2, "timeout"),
                            (["report", "--timeout", "x"], 2, "timeout")],
    ("report", "executed"): [(["report", "--executed", "/nonexistent.ipynb"], 2, "executed")],
    ("report", "output"): [(["report", "--output"], 2, "output")],
    ("report", "pdf"): [(["report", "--pdf=1"], 2, "pdf")],
    ("report", "paper"): [(["report", "--paper", "B7"], 2, "paper"),
                          (["report", "--paper"], 2, "paper")],
}


def test_every_cli_option_has_bad_cases():
    missing = _options() - set(CLI_CASES)
    assert not missing, f"command-line options with no bad-input case: {sorted(missing)}"
    assert not set(CLI_CASES) - _options(), "cases for options that do not exist"


@pytest.mark.parametrize("argv, status, said",
                         [pytest.param(*case, id=" ".join(case[0]))
                          for cases in CLI_CASES.values() for case in cases])
def test_cli_bad_arguments_exit_with_a_message(argv, status, said, capsys):
    try:
        got = cli.main(argv)
    except SystemExit as exc:                       # argparse's usage errors
        got = exc.code
    err = capsys.readouterr().err
    assert got == status, err
    assert said in err and "Traceback" not in err, err
