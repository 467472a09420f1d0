"""The three layers: toolkit <- problem <- workbook, checked on the source and at import."""

import ast
import json
import pathlib
import subprocess
import sys

import pytest

import piezolib

PACKAGE = pathlib.Path(piezolib.__file__).parent

TOOLKIT = ("robust", "hysteresis", "uncertainty", "identification", "signals", "metrics",
           "records", "_checks", "progress")
PROBLEM = ("paper", "problem")
WORKBOOK = ("workbook", "__main__")
# what each layer may not import (at any depth of the module)
FORBIDDEN = {
    "toolkit": ("piezolib.paper", "piezolib.problem", "piezolib.workbook"),
    "problem": ("piezolib.workbook",),
    "workbook": (),
}
# third-party imports the toolkit may not make at module level
TOOLKIT_HEAVY = ("matplotlib", "pandas")


def layer_of(path):
    top = path.relative_to(PACKAGE).parts[0].removesuffix(".py")
    for name, members in (("toolkit", TOOLKIT), ("problem", PROBLEM), ("workbook", WORKBOOK)):
        if top in members:
            return name
    return None


def imports_of(path):
    """(module name, at module level?) for every import statement of a source file."""
    tree = ast.parse(path.read_text(), filename=str(path))
    module_level = {id(node) for node in tree.body}
    package = ".".join(("piezolib",) + path.relative_to(PACKAGE).with_suffix("").parts[:-1])
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, id(node) in module_level) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{parent}.{base}" if base else parent
            names = [f"{base}.{alias.name}" for alias in node.names] if base == "piezolib" else [base]
            found += [(name, id(node) in module_level) for name in names]
    return found


SOURCES = sorted(PACKAGE.rglob("*.py"))


def test_every_module_belongs_to_a_layer():
    orphans = [str(p.relative_to(PACKAGE)) for p in SOURCES
               if p.name != "__init__.py" or p.parent != PACKAGE
               if layer_of(p) is None]
    assert not orphans, f"modules outside toolkit/problem/workbook: {orphans}"


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_imports_point_down_only(path):
    layer = layer_of(path)
    if layer is None:       # piezolib/__init__.py: lazy loader, imports nothing
        return
    bad = [name for name, _ in imports_of(path)
           if any(name == f or name.startswith(f + ".") for f in FORBIDDEN[layer])]
    assert not bad, f"{layer} module imports a higher layer: {bad}"
    if layer == "toolkit":
        heavy = [name for name, top in imports_of(path)
                 if top and name.split(".")[0] in TOOLKIT_HEAVY]
        assert not heavy, f"toolkit module imports {heavy} at module level"


def test_package_init_imports_nothing_eagerly():
    names = [name for name, _ in imports_of(PACKAGE / "__init__.py")]
    assert all(not n.startswith("piezolib") for n in names), names


def _loaded_after(code):
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys, json\n"
                          "print(json.dumps(sorted(sys.modules)))"],
                         capture_output=True, text=True, check=True)
    return set(json.loads(out.stdout.strip().splitlines()[-1]))


def test_robust_imports_no_paper_pandas_or_plotting():
    loaded = _loaded_after("import piezolib.robust")
    assert "piezolib.robust.mu" in loaded          # the import did load the toolkit
    assert "pandas" not in loaded
    assert not {m for m in loaded if m.startswith(("piezolib.paper", "piezolib.problem",
                                                   "piezolib.workbook"))}
    # python-control 0.10 imports matplotlib itself; piezolib.robust must add nothing to it
    by_control = _loaded_after("import control")
    assert {m for m in loaded if m.startswith("matplotlib")} <= by_control


@pytest.mark.parametrize("module", ["piezolib.hysteresis", "piezolib.uncertainty",
                                    "piezolib.identification", "piezolib.signals"])
def test_toolkit_packages_import_without_the_paper(module):
    loaded = _loaded_after(f"import {module}")
    assert module in loaded
    assert "piezolib.paper" not in loaded and "piezolib.workbook.plotting" not in loaded
    assert "pandas" not in loaded


def test_lazy_subpackages_resolve():
    assert piezolib.robust.mussv is not None
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        piezolib.nonexistent
