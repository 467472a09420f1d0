"""The report document: ``python -m piezolib report`` executes notebook 07 and exports it
without code, with whole notes, one number format and the summary last."""

import html
import io
import re
import shutil
import subprocess
from html.parser import HTMLParser

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
    shutil.copytree(ROOT / "figures", root / "figures")           # the sections' figures
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


def test_the_document_opens_on_the_summary(checkout, built):
    _, page, parsed = built
    table = pd.read_csv(checkout / "data" / "results" / "reproduction.csv", dtype=str,
                        keep_default_na=False)
    text = " ".join("".join(parsed.text).split())
    last_line = report.summary(table).splitlines()[-1].lstrip("- ")
    summary = text.index("Summary")
    assert text.index(last_line) > summary
    assert text.index(last_line) < text.index("Where the reproduction differs")
    assert "published numbers recomputed" in text[summary:summary + 300]
    assert "Every difference has a reason" in text[summary:]


def test_the_document_sums_up_the_findings_beyond_the_paper(built):
    _, page, parsed = built
    text = " ".join("".join(parsed.text).split())
    for notebook in ("notebook 08", "notebook 09", "notebook 10", "notebook 11", "notebook 12"):
        assert notebook in text, notebook
    for name in report.FINDINGS:                 # each section's table, row for row
        rows = report.findings(name)
        assert len(rows) > 0
        quantities = {cell for t in parsed.tables for row in t for cell in row}
        assert {unit_text(q) for q in rows.quantity} <= quantities, name
    assert page.count("data:image/png;base64,") >= 1 + len(
        {figure for _, figure, words in report.FINDINGS.values() if not words})


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


@pytest.mark.skipif(document.find_chromium() is None or shutil.which("pdftotext") is None,
                    reason="needs Chromium and poppler-utils (pdftotext, pdfimages)")
@pytest.mark.parametrize("paper, width_pt", [("A4", 595), ("letter", 612)])
def test_the_pdf_holds_every_note_on_pages_that_are_not_blank(checkout, built, tmp_path,
                                                              paper, width_pt):
    _, page, _ = built
    html_path = tmp_path / "report.html"
    html_path.write_text(page.replace(document.print_css("A4"), document.print_css(paper)),
                         encoding="utf-8")
    pdf = document.print_pdf(html_path, tmp_path / "report.pdf")
    info = subprocess.run(["pdfinfo", str(pdf)], capture_output=True, text=True).stdout
    width = float(re.search(r"Page size:\s+([\d.]+) x", info).group(1))
    assert abs(width - width_pt) < 1.5, info            # A4 595 pt, Letter 612 pt wide
    pages = int(re.search(r"Pages:\s+(\d+)", info).group(1))
    text = subprocess.run(["pdftotext", "-layout", str(pdf), "-"], capture_output=True,
                          text=True).stdout
    words = text.split()
    table = pd.read_csv(checkout / "data" / "results" / "reproduction.csv", dtype=str,
                        keep_default_na=False)
    notes = [unit_text(n) for n in table.loc[table.verdict == "differs", "note"] if n]
    lost = [n for n in notes if not _printed(n.split(), words)]
    assert not lost, f"{len(lost)} notes of the differs table are not in the PDF: {lost[:3]}"
    # a page holds text or a figure: none is blank
    per_page = text.split("\f")[:pages]
    images = subprocess.run(["pdfimages", "-list", str(pdf)], capture_output=True,
                            text=True).stdout.splitlines()[2:]
    with_image = {int(line.split()[0]) for line in images if line.strip()}
    blank = [i + 1 for i, t in enumerate(per_page) if not t.strip() and i + 1 not in with_image]
    assert not blank, f"blank pages: {blank}"


def _printed(note, words, spread=12):
    """True when the words of ``note`` stand in ``words`` (a page's text) in order, each
    within ``spread`` words of the one before: a table cell's lines are interleaved with
    the lines of the cells beside it, and a long word may be broken across two lines."""
    def match(i, word):
        """Index after ``word`` read at position i (whole, or split in two lines of its
        cell), or None."""
        if words[i] == word:
            return i + 1
        if words[i] and word.startswith(words[i]):
            rest = word[len(words[i]):]
            return next((k + 1 for k in range(i + 1, min(i + spread, len(words)))
                         if words[k] == rest), None)
        return None

    for start in (i for i, w in enumerate(words) if match(i, note[0])):
        at, ok = match(start, note[0]), True
        for word in note[1:]:
            hit = next((match(j, word) for j in range(at, min(at + spread, len(words)))
                        if match(j, word)), None)
            if hit is None:
                ok = False
                break
            at = hit
        if ok:
            return True
    return False
