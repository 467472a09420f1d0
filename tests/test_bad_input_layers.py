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
import re

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

LAYERS = {
    "problem": ("paper", "genplant", "stage", "stage_batch", "stage_calibration", "stage_data",
                "design", "analysis", "hysteresis_fits", "stage_hysteresis", "paths",
                "fsm_benchmark"),
    "workbook": ("study", "pipeline", "loop", "experiments", "report", "style", "plotting",
                 "reproduce", "cli", "outputs", "session", "two_dof", "set_tracking", "sweep",
                 "tables", "document"),
}

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
                                     "G": PLANT, "fs": POSITIVE}),
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
    "fsm_benchmark.axis_loop_response": (
        dict(K=ct.tf([1.0], [1.0, 1.0]), G=AXIS_G, W_m=ct.tf([0.1], [1.0]),
             W_S=ct.tf([1.0], [1.0, 1.0]), W_T=ct.tf([0.1], [1.0]), W_u=ct.tf([0.01], [1.0]),
             omega=OMEGA, fs=6400.0),
        {"K": {"text": "x", "improper": ct.tf([1.0, 0.0], [1.0])},
         "omega": {"empty": [], "negative": -OMEGA, "nan": np.r_[OMEGA[:-1], np.nan]},
         "G": {"text": "x"}, "fs": POSITIVE, "delay_samples": {"negative": -1}}),
    "fsm_benchmark.noise_floor": (dict(level_mV=100),
                                  {"level_mV": {"other level": 150}, "split": {"other": "x"},
                                   "folder": {"number": 3}}),
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
    "document.execute_report": (None, {"study": STUDY_GIVEN, "timeout": POSITIVE}),
    "document.read_executed": (None, {"path": {"missing": "/nonexistent.ipynb", "number": 3}}),
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
}

#: Public functions without an argument a user could get wrong.
EXEMPT = {
    "paper.case_rows_index": "no arguments", "paper.table1": "no arguments",
    "paper.table2": "no arguments", "paper.table4": "no arguments",
    "paper.table5": "no arguments", "paper.problem": "no arguments",
    "hysteresis_fits.workbook_dahl_path": "no arguments",
    "hysteresis_fits.write_workbook_dahl": "no arguments (writes a committed artifact)",
    "hysteresis_fits.clear_cache": "no arguments",
    "paths.project_root": "no arguments", "paths.data_dir": "no arguments",
    "fsm_benchmark.data_folder": "no arguments",
    "fsm_benchmark.write_manifest": "writes the committed data's manifest; its folder is checked "
                                    "by paths.check_directory (a valid call needs the 21 MB data)",
    "study.list_studies": "no arguments", "study.study_files": "no arguments",
    "study.studies_dir": "no arguments", "study.section_fields": "no arguments",
    "sweep_spec.specs_dir": "no arguments",
    "pipeline.memory": "no arguments (its location comes from PIEZOLIB_CACHE)",
    "pipeline.library_fingerprint": "no arguments",
    "pipeline.reference_design_path": "no arguments",
    "pipeline.mixed_design_path": "no arguments",
    "pipeline.write_reference_design": "only cache, a flag (a whole design run)",
    "style.use_style": "no arguments",
    "reproduce.check_data": "no arguments", "cli.parser": "no arguments",
    "reproduce.default_jobs": "no arguments",
    "outputs.project_root": "no arguments", "outputs.data_dir": "no arguments",
    "outputs.runs_dir": "no arguments", "outputs.notebooks_dir": "no arguments",
    "outputs.report_dir": "no arguments",
    "document.report_notebook": "no arguments", "document.find_chromium": "no arguments",
    "tables.format_number": "any value is a cell: non-numbers are shown as they are",
    "reproduce.study_spec": "formats the study for inject_study, which loads (checks) it",
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
    assert not (set(CASES) | set(EXEMPT)) - public, "entries for names that are not public"
    missing = public - set(CASES) - set(EXEMPT)
    assert not missing, f"public functions with no bad-input cases: {sorted(missing)}"
    # every named argument exists: a renamed parameter must not leave a case testing nothing
    for qualname, (_, corrupt) in CASES.items():
        params = inspect.signature(function(qualname)).parameters
        if not any(p.kind is p.VAR_KEYWORD for p in params.values()):
            assert set(corrupt) <= set(params), (qualname, set(corrupt) - set(params))


@pytest.mark.parametrize("qualname", sorted(q for q, (v, _) in CASES.items() if v is not None))
def test_the_valid_call_works(qualname, tmp_path):
    call(qualname, resolve(CASES[qualname][0], tmp_path))


def _filled(qualname, valid, argument, value):
    """The bad call: the valid one with ``argument`` replaced, or, where the valid call is
    too costly to run, every required argument filled with a harmless valid value."""
    if valid is not None:
        return {**valid, argument: value}
    params = inspect.signature(function(qualname)).parameters
    kwargs = {}
    for name, p in params.items():
        if name == argument or p.default is not inspect.Parameter.empty \
                or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        kwargs[name] = FILLERS[name]
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


@pytest.mark.parametrize("qualname, valid, argument, value", list(bad_calls(CASES)))
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
