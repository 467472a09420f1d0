"""The library shows how it is called: runnable Examples in the public docstrings.

``pytest --doctest-modules`` (the project's default) runs every ``Examples`` section; this file
keeps their coverage: at least 30 % of the public functions and classes (names in a module's
``__all__`` defined there), and every entry point the README and the notebooks call first.
"""

import importlib
import inspect
import pkgutil

import pytest

import piezolib

#: Share of the public functions and classes with a runnable Examples section.
MIN_SHARE = 0.30

#: Entry points a user calls first (README, notebooks): each shows a call.
ENTRY_POINTS = [
    "robust.mu.ssv.mussv", "robust.dk.musyn", "robust.hinf.hinfsyn",
    "robust.fixed_order.fixed_order_musyn", "robust.lft.lft_response", "robust.discrete.discretize",
    "robust.margins.loop_margins", "robust.export.export_controller", "robust.preview.zpetc",
    "hysteresis.pi.fit_pi", "hysteresis.hammerstein.fit_hammerstein", "hysteresis.fit.fit_dahl",
    "records.reader.load_csv", "records.preparation.split",
    "records.preparation.cut_at_turning_points", "uncertainty.modelset.model_set",
    "uncertainty.margin.parametric_stability_margin", "uncertainty.weight.fit_covering_weight",
    "identification.continuous.identify", "identification.freqfit.fit_frf",
    "problem.paper.problem", "problem.genplant.generalized_plant", "workbook.session.start",
    "workbook.study.load",
]


def _public():
    """{qualified name: object} of every public function and class of the package."""
    found = {}
    for info in pkgutil.walk_packages(piezolib.__path__, "piezolib."):
        if info.name.endswith("__main__") or info.ispkg:
            continue
        module = importlib.import_module(info.name)
        for name in getattr(module, "__all__", []):
            obj = getattr(module, name, None)
            if (inspect.isfunction(obj) or inspect.isclass(obj)) \
                    and getattr(obj, "__module__", None) == module.__name__:
                found[f"{info.name}.{name}"] = obj
    return found


def _has_example(obj):
    doc = inspect.getdoc(obj) or ""
    return "Examples" in doc and ">>>" in doc


def test_a_share_of_the_public_api_shows_a_call():
    public = _public()
    shown = [name for name, obj in public.items() if _has_example(obj)]
    assert len(shown) >= MIN_SHARE * len(public), \
        f"{len(shown)} of {len(public)} public functions and classes have Examples"


@pytest.mark.parametrize("name", ENTRY_POINTS)
def test_every_entry_point_shows_a_call(name):
    module, _, attr = f"piezolib.{name}".rpartition(".")
    assert _has_example(getattr(importlib.import_module(module), attr)), name
