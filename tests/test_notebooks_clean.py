"""Notebooks are committed without outputs and with the expected name scheme."""

import json
import re

import pytest

from piezolib.workbook.outputs import notebooks_dir

NOTEBOOKS = sorted(notebooks_dir().glob("*.ipynb"))


def test_there_are_numbered_notebooks():
    assert NOTEBOOKS, "no notebooks found"
    for path in NOTEBOOKS:
        assert re.match(r"^\d\d_[a-z0-9_]+\.ipynb$", path.name), path.name


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_has_no_outputs(path):
    nb = json.loads(path.read_text())
    for index, cell in enumerate(nb["cells"]):
        if cell["cell_type"] == "code":
            assert cell.get("outputs", []) == [], f"cell {index} has outputs"
            assert cell.get("execution_count") is None, f"cell {index} has a count"


# -- a notebook reads as the paper: the static shape of its code cells -------------------------

#: The largest code cell (non-blank lines) outside the ``parameters`` cell.
MAX_CELL_LINES = 15
#: ``piezolib`` import statements of a notebook's one import cell.
MAX_PIEZOLIB_IMPORTS = 3
#: Non-blank code lines of all notebooks together (the narrative, not the algorithms).
MAX_TOTAL_LINES = 1300
#: Work items of the project's tracker named in a narrative ("issue 12", "#15's fix").
WORK_ITEM = re.compile(r"\b[Ii]ssues?\s*#?\d|(?<![\w&])#\d+\b|\bmoonshot\b")
_IMPORT = re.compile(r"^\s*(import|from)\s+\S+", re.M)
_PIEZOLIB_IMPORT = re.compile(r"^\s*(from\s+piezolib\b|import\s+piezolib\b)", re.M)


def _code_cells(path):
    """(index, source, is_parameters) of each code cell of a notebook."""
    cells = json.loads(path.read_text())["cells"]
    return [(i, "".join(c["source"]), "parameters" in c.get("metadata", {}).get("tags", []))
            for i, c in enumerate(cells) if c["cell_type"] == "code"]


def _lines(source):
    return sum(1 for line in source.splitlines() if line.strip())


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_every_code_cell_shows_one_thing(path):
    long = [(i, _lines(src)) for i, src, parameters in _code_cells(path)
            if not parameters and _lines(src) > MAX_CELL_LINES]
    assert not long, f"code cells over {MAX_CELL_LINES} lines (cell, lines): {long}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_a_notebook_defines_nothing_and_imports_once(path):
    cells = [(i, src) for i, src, parameters in _code_cells(path) if not parameters]
    defining = [i for i, src in cells if re.search(r"^\s*(def|class)\s", src, re.M)
                or re.search(r"\blambda\b", src)]
    assert not defining, f"cells that define functions or classes: {defining}"
    importing = [i for i, src in cells if _IMPORT.search(src)]
    assert len(importing) <= 1, f"imports in more than one cell: {importing}"
    count = sum(len(_PIEZOLIB_IMPORT.findall(src)) for _, src in cells)
    assert count <= MAX_PIEZOLIB_IMPORTS, f"{count} piezolib import statements"
    flags = [i for i, src in cells if re.search(r"^if [A-Z_]+:", src, re.M)]
    assert not flags, f"cells switched by a feature flag: {flags}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_the_narrative_names_no_work_item(path):
    cells = json.loads(path.read_text())["cells"]
    named = [i for i, c in enumerate(cells) if WORK_ITEM.search("".join(c["source"]))]
    assert not named, f"cells naming a work item of the tracker: {named}"


def test_the_notebooks_hold_narrative_not_algorithms():
    total = sum(_lines(src) for path in NOTEBOOKS for _, src, _ in _code_cells(path))
    assert total <= MAX_TOTAL_LINES, f"{total} non-blank code lines in the notebooks"
