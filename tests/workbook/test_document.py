"""The report document: ``python -m piezolib report`` executes notebook 07 and exports it
without code, with whole notes, one number format and the summary last."""

import html
import io
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import nbformat
import pandas as pd
import pytest

from piezolib.workbook import cli, document, outputs, report
from piezolib.workbook.style import unit_text

ROOT = outputs.project_root()          # read before any test points PIEZOLIB_ROOT elsewhere
#: Classes nbconvert gives a code cell's input and the prompts.
CODE_CLASSES = {"jp-InputPrompt", "jp-OutputPrompt", "jp-CodeMirrorEditor", "hl-ipython3",
                "input_area", "prompt"}


class _Page(HTMLParser):
    """The element classes, the tables (rows of cell texts) and the text of an HTML page."""

    def __init__(self):
        super().__init__()
        self.classes, self.tables, self.text, self._cell = set(), [], [], None
        self._skip = 0

    def handle_starttag(self, tag, attrs):
        self.classes.update((dict(attrs).get("class") or "").split())
        if tag in ("style", "script"):
            self._skip += 1
        elif tag == "table":
            self.tables.append([])
        elif tag == "tr" and self.tables:
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("style", "script"):
            self._skip -= 1
        elif tag in ("td", "th") and self._cell is not None and self.tables:
            self.tables[-1][-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._skip:
            return
        self.text.append(data)
        if self._cell is not None:
            self._cell.append(data)


@pytest.fixture(scope="module")
def checkout(tmp_path_factory):
    """A checkout with notebook 07, the committed result tables and the studies."""
    root = tmp_path_factory.mktemp("checkout")
    (root / "notebooks").mkdir()
    for path in ROOT.glob("notebooks/07_*.ipynb"):
        shutil.copy(path, root / "notebooks")
    shutil.copytree(ROOT / "data" / "results", root / "data" / "results")
    shutil.copytree(ROOT / "studies", root / "studies")
    return root


@pytest.fixture(scope="module")
def built(checkout):
    """``python -m piezolib report`` run once: (printed text, the HTML page, its parse)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PIEZOLIB_ROOT", str(checkout))
        out = io.StringIO()
        assert cli.main(["report"], stream=out) == 0
    page = (checkout / "runs" / "report" / "reference.html").read_text(encoding="utf-8")
    parsed = _Page()
    parsed.feed(page)
    return out.getvalue(), page, parsed


def test_the_document_goes_to_runs_report_and_its_path_is_printed(checkout, built):
    printed, page, _ = built
    assert printed.strip() == str(checkout / "runs" / "report" / "reference.html")
    assert "<title>07 · Reproduction report" in page
    assert re.search(r'<img[^>]+src="data:image/png;base64,', page)    # the scorecard, inline


def test_the_document_shows_no_code(built):
    _, page, parsed = built
    assert not parsed.classes & CODE_CLASSES
    nb = nbformat.read(next((ROOT / "notebooks").glob("07_*.ipynb")), as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            for line in cell.source.splitlines():
                if len(line.strip()) > 12:     # a line of code is nowhere in the page
                    assert html.escape(line.strip(), quote=False) not in page, line


def test_the_document_ends_on_the_summary(checkout, built):
    _, page, parsed = built
    table = pd.read_csv(checkout / "data" / "results" / "reproduction.csv", dtype=str,
                        keep_default_na=False)
    last_line = report.summary(table).splitlines()[-1].lstrip("- ")
    assert " ".join("".join(parsed.text).split()).endswith(last_line)
    summary = page.rindex(">Summary<")
    assert page.rfind("<table", summary) == -1 and page.rfind("<img", summary) == -1
    assert "published numbers recomputed" in page[summary:]
    assert "Every difference has a reason" in page[summary:]


def test_notes_are_whole(checkout, built):
    _, page, parsed = built
    table = pd.read_csv(checkout / "data" / "results" / "reproduction.csv", dtype=str,
                        keep_default_na=False)
    notes = {unit_text(n) for n in table.loc[table.verdict == "differs", "note"] if n}
    cells = {cell for t in parsed.tables for row in t for cell in row}
    assert any(len(n) > 80 for n in notes)             # notes the old display cut
    assert notes <= cells
    assert not [c for c in cells if c.endswith(("...", "…"))]


def test_numbers_have_one_format(built):
    _, _, parsed = built
    claims = next(t for t in parsed.tables if t[0][:6] == ["source", "section", "quantity",
                                                           "unit", "paper", "ours"])
    table4 = [row for row in claims[1:] if row[1] == "Table 4"]
    assert len(table4) > 20
    for row in table4:
        for cell in row[4:6]:                           # paper, ours
            assert re.fullmatch(r"-?\d+(\.\d+)?", cell), row
    cells = [cell for t in parsed.tables for row in t for cell in row]
    assert not [c for c in cells if re.search(r"\de[+-]\d", c)]    # no 9.15e+00 anywhere


def _executed_notebook(path):
    """A small notebook with outputs, as if executed: a heading, a printed line, a table."""
    code = nbformat.v4.new_code_cell("secret_code_line = 42\nprint('hello')")
    code.outputs = [nbformat.v4.new_output("stream", name="stdout", text="hello\n")]
    code.execution_count = 1
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell("# A small report"),
                                         code])
    nbformat.write(nb, path)
    return path


def test_an_executed_copy_is_exported_to_the_given_path(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    source = _executed_notebook(tmp_path / "done.ipynb")
    target = tmp_path / "elsewhere" / "mine.html"
    out = io.StringIO()
    assert cli.main(["report", "--executed", str(source), "--output", str(target)],
                    stream=out) == 0
    assert out.getvalue().strip() == str(target)
    page = target.read_text(encoding="utf-8")
    assert "hello" in page and "secret_code_line" not in page
    assert "<title>A small report</title>" in page
    assert not (tmp_path / "runs").exists()


def test_an_unexecuted_notebook_or_a_bad_study_is_a_usage_error(tmp_path, capsys):
    blank = tmp_path / "blank.ipynb"
    nbformat.write(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("x = 1")]), blank)
    assert cli.main(["report", "--executed", str(blank)]) == 2
    assert "has no outputs" in capsys.readouterr().err
    assert cli.main(["report", "--study", "no_such_study"]) == 2
    assert "no_such_study" in capsys.readouterr().err


def test_pdf_without_chromium_says_what_it_needs(tmp_path, monkeypatch):
    monkeypatch.setattr(document, "CHROMIUM_NAMES", ("no-such-browser-here",))
    page = tmp_path / "a.html"
    page.write_text("<html><body>a</body></html>")
    with pytest.raises(FileNotFoundError, match="apt-get install chromium"):
        document.print_pdf(page, tmp_path / "a.pdf")


@pytest.mark.skipif(document.find_chromium() is None, reason="no Chromium on the PATH")
def test_pdf_is_printed_with_chromium(tmp_path):
    page = tmp_path / "a.html"
    page.write_text("<html><body><h1>A report</h1></body></html>")
    pdf = document.print_pdf(page, tmp_path / "out" / "a.pdf")
    assert pdf == tmp_path / "out" / "a.pdf" and pdf.read_bytes().startswith(b"%PDF")
