"""The reproduction report as a document: notebook 07 executed and exported without its code.

``python -m piezolib report`` executes the reproduction report (notebook 07)
for a study, with its figures drawn inline, and writes it as one
self-contained HTML file in which a reader sees the text, the tables, the
figures and the closing summary, and no code:
``runs/report/<study>.html`` (git-ignored) unless another path is given.
``--pdf`` also prints that page to PDF with a Chromium found on the ``PATH``.

::

    from piezolib.workbook import document

    path = document.build("reference")        # runs/report/reference.html
"""

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from piezolib._checks import check_path, check_positive
from piezolib.files import atomic_write
from piezolib.workbook import reproduce
from piezolib.workbook import study as studies
from piezolib.workbook.outputs import project_root, report_dir

__all__ = ["REPORT_NOTEBOOK", "INLINE_BACKEND", "CHROMIUM_NAMES", "PAPER_SIZES", "print_css",
           "report_notebook", "default_output", "export_html",
           "find_chromium", "print_pdf", "build"]

#: Name prefix of the reproduction report among the numbered notebooks.
REPORT_NOTEBOOK = "07_"

#: matplotlib backend of the document's kernel: figures become outputs of their cells
#: (the headless runs' Agg draws nothing into the notebook).
INLINE_BACKEND = "module://matplotlib_inline.backend_inline"

#: Programs tried, in order, by :func:`find_chromium` (Debian: ``apt-get install chromium``).
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


#: Paper sizes of the printed document (CSS ``@page size``): A4 by default, US Letter on request.
PAPER_SIZES = {"A4": "210mm 297mm", "letter": "8.5in 11in"}


def print_css(paper="A4"):
    """The style sheet that makes the exported page print as a document.

    Tables take the page's width and wrap their text (no column is cut at the
    margin), their header repeats on each page and a row is never split;
    headings stay with what follows; figures scale to the page.

    Parameters
    ----------
    paper : {"A4", "letter"}
        The paper size (:data:`PAPER_SIZES`).

    Returns
    -------
    str
        A ``<style>`` element.

    Examples
    --------
    >>> "210mm 297mm" in print_css("A4") and "8.5in 11in" in print_css("letter")
    True
    """
    if paper not in PAPER_SIZES:
        raise ValueError(f"paper must be one of {sorted(PAPER_SIZES)}, got {paper!r}")
    return f"""<style>
@page {{ size: {PAPER_SIZES[paper]}; margin: 14mm 12mm 14mm 12mm; }}
@media print {{
  html, body {{ height: auto !important; min-height: 0 !important; font-size: 10pt; }}
  .jp-Notebook, .jp-Cell, .jp-OutputArea, .jp-OutputArea-child, .jp-OutputArea-output,
  .jp-RenderedHTMLCommon {{ overflow: visible !important; max-width: 100% !important;
    padding-left: 0 !important; margin-left: 0 !important; }}
  .jp-OutputPrompt, .jp-InputPrompt {{ display: none !important; }}
  table {{ width: 100% !important; max-width: 100% !important; table-layout: auto !important;
    border-collapse: collapse; font-size: 7.5pt !important; }}
  thead {{ display: table-header-group; }}
  tr, img, svg {{ break-inside: avoid; page-break-inside: avoid; }}
  th, td {{ padding: 1px 3px !important; vertical-align: top; }}
  td {{ overflow-wrap: anywhere; }}
  th {{ white-space: normal !important; }}
  h1, h2, h3, h4 {{ break-after: avoid; page-break-after: avoid; }}
  /* a heading's cell stays with the output that follows it: no heading ends a page */
  .jp-MarkdownCell {{ break-inside: avoid; break-after: avoid; page-break-after: avoid; }}
  .jp-CodeCell {{ break-before: auto; }}
  img {{ max-width: 100% !important; height: auto !important; }}
  .jp-Cell:last-child, .jp-Notebook > :last-child {{ margin-bottom: 0 !important;
    padding-bottom: 0 !important; }}
}}
</style>
"""


def report_notebook():
    """Path of the reproduction report notebook (``notebooks/07_*.ipynb``).

    Examples
    --------
    >>> report_notebook().name
    '07_reproduction_report.ipynb'
    """
    return reproduce.list_notebooks([REPORT_NOTEBOOK])[0]


def default_output(study=studies.REFERENCE):
    """``runs/report/<study>.html``: where the document of ``study`` goes by default.

    Examples
    --------
    >>> from piezolib.workbook.outputs import project_root
    >>> default_output("wide_error_weight").relative_to(project_root()).as_posix()
    'runs/report/wide_error_weight.html'
    """
    return report_dir() / f"{studies.load(study).name}.html"


def _execute_report(study=None, timeout=600):
    """Execute the reproduction report for ``study`` with figures drawn inline.

    Like ``python -m piezolib reproduce 07`` (the study injected after the
    cell tagged ``parameters``; the reference study rewrites its table and
    figure only where a result changed), but the kernel draws each figure
    into its cell's output, as the document shows it.

    Parameters
    ----------
    study : str or pathlib.Path, optional
        A study name or TOML file; default the notebook's own (the reference).
    timeout : float
        Per-cell time limit [s].

    Returns
    -------
    nbformat.NotebookNode
        The executed notebook.

    Raises
    ------
    piezolib.workbook.reproduce.NotebookFailure
        When a cell raises (an assert of the report, for instance).
    """
    timeout = check_positive("timeout", timeout)
    env = {**reproduce.KERNEL_ENVIRONMENT, "PIEZOLIB_ROOT": str(project_root()),
           **os.environ, "MPLBACKEND": INLINE_BACKEND}
    return reproduce.run_notebook(report_notebook(), timeout=timeout,
                                  study=reproduce.study_spec(study), env=env)


def _read_executed(path):
    """An executed notebook read from ``path`` (e.g. one saved from JupyterLab).

    Raises
    ------
    ValueError
        When there is no such file, or no code cell of it has an output: an
        unexecuted notebook would make a document of headings only.
    """
    import nbformat

    path = check_path("path", path)
    if not path.is_file():
        raise ValueError(f"executed notebook: there is no file at path {path}")
    try:
        nb = nbformat.read(path, as_version=4)
    except (ValueError, KeyError, AttributeError, TypeError) as exc:
        # a CSV, a truncated file or another JSON (NotJSONError, JSONDecodeError and
        # UnicodeDecodeError are ValueErrors): name the file, not nbformat's internals
        raise ValueError(f"executed notebook: {path} is not a readable Jupyter notebook "
                         f"({type(exc).__name__}: {str(exc)[:120]})") from None
    if not any(cell.get("outputs") for cell in nb.cells if cell.cell_type == "code"):
        raise ValueError(f"executed notebook: {path} has no outputs; execute it first "
                         "(or leave --executed out and the report is executed)")
    return nb


def export_html(nb, path, title=None, paper="A4"):
    """Write ``nb`` as one self-contained HTML page without code; return the path.

    Input cells and their ``In [ ]`` / ``Out [ ]`` prompts are left out
    (nbconvert's ``exclude_input``, ``exclude_input_prompt``,
    ``exclude_output_prompt``): the reader sees markdown, printed text,
    tables and figures.

    Parameters
    ----------
    nb : nbformat.NotebookNode
        An executed notebook.
    path : str or pathlib.Path
        The HTML file (its folder is created).
    title : str, optional
        The page title; default the notebook's first heading.
    paper : {"A4", "letter"}
        The paper size the page prints on (:func:`print_css`).
    """
    import nbformat
    from nbconvert import HTMLExporter

    if not isinstance(nb, nbformat.NotebookNode):
        raise TypeError(f"nb must be a notebook read with nbformat, got {type(nb).__name__}")
    path = check_path("path", path)
    exporter = HTMLExporter(template_name="lab", exclude_input=True,
                            exclude_input_prompt=True, exclude_output_prompt=True)
    title = _first_heading(nb) if title is None else str(title)
    css = print_css(paper)
    body, _ = exporter.from_notebook_node(nb, resources={"metadata": {"name": title}})
    body = body.replace("</head>", css + "</head>", 1) if "</head>" in body else css + body
    path.parent.mkdir(parents=True, exist_ok=True)
    return atomic_write(path, body)


def _first_heading(nb):
    """Text of the first markdown heading of ``nb`` ("report" when it has none)."""
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            for line in cell.source.splitlines():
                if line.startswith("#"):
                    return line.lstrip("#").strip()
    return "report"


def find_chromium():
    """Path of a Chromium or Chrome on the ``PATH`` (:data:`CHROMIUM_NAMES`), or None."""
    for name in CHROMIUM_NAMES:
        found = shutil.which(name)
        if found:
            return Path(found)
    return None


def print_pdf(html_path, pdf_path, chromium=None, timeout=120):
    """Print an HTML file to PDF with headless Chromium; return the PDF's path.

    Parameters
    ----------
    html_path, pdf_path : str or pathlib.Path
    chromium : str or pathlib.Path, optional
        The browser program; default :func:`find_chromium`.
    timeout : float
        Seconds the browser may take.

    Raises
    ------
    FileNotFoundError
        When no Chromium is found (the requirement: ``chromium`` on the
        ``PATH``, e.g. Debian's ``apt-get install chromium``).
    RuntimeError
        When the browser fails or writes no PDF.
    """
    html_path = check_path("html_path", html_path).resolve()
    pdf_path = check_path("pdf_path", pdf_path).resolve()
    timeout = check_positive("timeout", timeout)
    chromium = find_chromium() if chromium is None else check_path("chromium", chromium)
    if chromium is None:
        raise FileNotFoundError("--pdf needs Chromium or Chrome on the PATH (one of "
                                f"{', '.join(CHROMIUM_NAMES)}; Debian: apt-get install chromium)")
    pdf_path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as profile:
        command = [str(chromium), "--headless", "--disable-gpu", "--no-pdf-header-footer",
                   f"--user-data-dir={profile}", f"--print-to-pdf={pdf_path}",
                   html_path.as_uri()]
        if hasattr(os, "geteuid") and os.geteuid() == 0:
            command.insert(1, "--no-sandbox")     # Chromium refuses to run as root with it
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                              check=False)
    if done.returncode != 0 or not pdf_path.is_file():
        raise RuntimeError(f"{chromium} did not print {html_path} to PDF "
                           f"(status {done.returncode}): {done.stderr.strip()[-500:]}")
    return pdf_path


def build(study=None, executed=None, output=None, pdf=False, timeout=600, paper="A4"):
    """The report document of ``study``: execute notebook 07 (or take an executed copy), export.

    Parameters
    ----------
    study : str or pathlib.Path, optional
        A study name or TOML file (default: the reference).
    executed : str or pathlib.Path, optional
        An executed copy of the report to export as it is, instead of
        executing it (it must have been run with figures drawn inline, e.g.
        in JupyterLab: the copies ``reproduce`` saves draw none).
    output : str or pathlib.Path, optional
        The HTML file; default :func:`default_output` of the study.
    pdf : bool
        Also print the page to a PDF beside it (:func:`print_pdf`).
    timeout : float
        Per-cell time limit [s] of the execution.
    paper : {"A4", "letter"}
        The paper size of the printed page (:data:`PAPER_SIZES`).

    Returns
    -------
    list of pathlib.Path
        The HTML file, then the PDF when asked for.
    """
    print_css(paper)                      # a bad paper size fails before the execution
    chosen = studies.load(studies.REFERENCE if study is None else study)
    output = default_output(chosen) if output is None else check_path("output", output)
    nb = (_read_executed(check_path("executed", executed)) if executed is not None
          else _execute_report(study, timeout))
    heading = _first_heading(nb)
    title = heading if chosen.is_reference else f"{heading} (study {chosen.name})"
    written = [export_html(nb, output, title=title, paper=paper)]
    if pdf:
        written.append(print_pdf(output, output.with_suffix(".pdf")))
    return written
