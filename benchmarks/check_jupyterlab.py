"""Run notebooks in JupyterLab in a headless browser and check what a reader sees.

For each notebook (default 04, 05, 06) this script opens it in a JupyterLab
started for the purpose, runs "Run All Cells" from the Run menu, waits until
every cell has run and then inspects the page:

* every figure is shown: output images are PNG (``data:image/png`` or the
  PNG bytes of an image widget) and loaded; no ``<Figure size ...>`` text
  stands where a figure should be;
* no progress bar ends red: no tqdm/ipywidgets bar with the danger style,
  no ``piezolib-progress-failed``, and none left running
  (``piezolib-progress-running``) once the kernel is idle;
* no stderr output block and no error output;
* notebook 04 only: the "re-design" button draws its progress inside the
  widget and ends with a finished bar (not in the log console).

It prints one line per notebook and exits 1 when anything is surprising
(2 when JupyterLab or the browser cannot be started).  Not part of
``pytest``: CI has no browser.

Set-up (once, in the workbook's virtual environment; no browser download)::

    apt-get install -y chromium          # Debian/Ubuntu: chromium on the PATH
    pip install playwright==1.65.2       # the Python client only; never `playwright install`

Run from the checkout::

    python benchmarks/check_jupyterlab.py              # notebooks 04 05 06
    python benchmarks/check_jupyterlab.py 02 05 --keep # others; keep the temporary copy

The notebooks run in a temporary copy of the checkout (``PIEZOLIB_ROOT``
points there, so figures and tables are written to the copy, not to the
repository), in a JupyterLab whose environment has no ``MPLBACKEND``,
``PIEZOLIB_STATIC`` or ``PIEZOLIB_PROGRESS``, as a person's would.
"""

import argparse
import json
import os
import secrets
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

from piezolib.workbook.document import find_chromium

CHECKOUT = Path(__file__).resolve().parents[1]
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync"]
# left out of the copy: history, outputs of other studies and caches, virtual environments
COPY_IGNORE = shutil.ignore_patterns(".git", "runs", ".venv*", "__pycache__", ".pytest_cache",
                                     ".ipynb_checkpoints", "*.egg-info")
# environment variables a person's shell would not have (or the workbook must not need)
DROPPED_ENV = ("MPLBACKEND", "PIEZOLIB_STATIC", "PIEZOLIB_PROGRESS")

# the state of the page once every cell has run, read by the browser in one go
INSPECT_JS = """() => {
  const outputs = [...document.querySelectorAll('.jp-Notebook .jp-OutputArea-output')];
  const imgs = outputs.flatMap(o => [...o.querySelectorAll('img')]);
  const png = imgs.filter(i => i.src.startsWith('data:image/png') || i.src.startsWith('blob:'));
  const text = outputs.map(o => o.innerText || '').join('\\n');
  const count = sel => document.querySelectorAll('.jp-Notebook ' + sel).length;
  return {
    figures: png.length,
    notPng: imgs.length - png.length,
    broken: png.filter(i => !(i.complete && i.naturalWidth > 0)).length,
    figureRepr: (text.match(/<Figure size [^>]*>/g) || []).length,
    redBars: count('.progress-bar-danger') + count('.piezolib-progress-failed'),
    runningBars: count('.piezolib-progress-running'),
    doneBars: count('.piezolib-progress-done'),
    stderr: count('.jp-OutputArea-output[data-mime-type="application/vnd.jupyter.stderr"]'),
    firstStderr: ([...document.querySelectorAll('.jp-Notebook .jp-OutputArea-output'
      + '[data-mime-type="application/vnd.jupyter.stderr"]')].map(e => e.textContent)[0] || '')
      .slice(-300),
    failedBar: ([...document.querySelectorAll('.jp-Notebook .piezolib-progress-failed')]
      .map(e => e.textContent)[0] || ''),
    errors: count('.jp-OutputArea-output[data-mime-type="application/vnd.jupyter.error"]'),
    widgetErrors: (text.match(/Error displaying widget/g) || []).length,
    widgets: count('.jp-OutputArea-output .widget-box, .jp-OutputArea-output .jupyter-widgets'),
  };
}"""

# code cells that have not run (no number) or are running ("*")
PENDING_JS = """() => {
  const prompts = [...document.querySelectorAll('.jp-Notebook .jp-CodeCell .jp-InputPrompt')];
  const pending = prompts.filter(p => !/\\[\\d+\\]/.test(p.textContent));
  return {cells: prompts.length, pending: pending.length,
          running: prompts.filter(p => p.textContent.includes('*')).length};
}"""


def free_port():
    """A TCP port nobody listens on now."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def copy_checkout(target):
    """The checkout's files (no history, runs or environments) under ``target``."""
    shutil.copytree(CHECKOUT, target, ignore=COPY_IGNORE)
    return target


def lab_environment(root, home):
    """The environment of JupyterLab and its kernels: the copy's library, no headless switches."""
    env = {k: v for k, v in os.environ.items() if k not in DROPPED_ENV}
    env.update(PIEZOLIB_ROOT=str(root), PYTHONPATH=str(root),
               JUPYTER_CONFIG_DIR=str(home / "config"), JUPYTER_RUNTIME_DIR=str(home / "runtime"),
               JUPYTERLAB_SETTINGS_DIR=str(home / "settings"),
               JUPYTERLAB_WORKSPACES_DIR=str(home / "workspaces"))
    return env


def start_lab(root, home, port, token):
    """Start JupyterLab on the copy's notebooks; return the process once it answers."""
    log = open(home / "jupyterlab.log", "w")
    process = subprocess.Popen(
        [sys.executable, "-m", "jupyter", "lab", "--no-browser", "--allow-root",
         f"--port={port}", "--ServerApp.ip=127.0.0.1", f"--ServerApp.token={token}",
         f"--ServerApp.root_dir={root / 'notebooks'}", "--LabApp.news_url=",
         "--ServerApp.port_retries=0"],
        cwd=root / "notebooks", env=lab_environment(root, home), stdout=log,
        stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}/api/status?token={token}"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError(f"JupyterLab exited ({process.returncode}); see {log.name}")
        try:
            with urllib.request.urlopen(url, timeout=2):
                return process
        except OSError:
            time.sleep(0.5)
    process.terminate()
    raise RuntimeError(f"JupyterLab did not answer within 120 s; see {log.name}")


def stop_lab(process):
    """Stop the JupyterLab ``process`` (killed if it does not end within 30 s)."""
    process.terminate()
    try:
        process.wait(timeout=30)
    except subprocess.TimeoutExpired:
        process.kill()


def browser_tools(chromium=None):
    """(Chromium's path, playwright's ``sync_playwright``), or None after saying what is
    missing; ``chromium`` overrides the browser found on the PATH."""
    chromium = chromium or find_chromium()     # the report's --pdf looks it up the same way
    if chromium is None:
        print("needs Chromium on the PATH (Debian: apt-get install chromium) or --chromium PATH")
        return None
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        print("needs the playwright client: pip install playwright==1.65.2 (see the docstring)")
        return None
    return chromium, sync_playwright


def run_all_cells(page):
    """Run > Run All Cells, from the menu as a person would."""
    page.locator(".lm-MenuBar-itemLabel", has_text="Run").first.click()
    page.locator(".lm-Menu-itemLabel", has_text="Run All Cells").first.click()


def kernel_state(base, token, name):
    """The execution state of the kernel of notebook ``name`` (the server's sessions), or None."""
    with urllib.request.urlopen(f"{base}/api/sessions?token={token}", timeout=10) as reply:
        sessions = json.load(reply)
    for session in sessions:
        if session.get("path", "").endswith(name):
            return session["kernel"].get("execution_state")
    return None


def shut_down_kernels(base, token):
    """Stop every notebook session's kernel (one notebook at a time shares the cores)."""
    with urllib.request.urlopen(f"{base}/api/sessions?token={token}", timeout=10) as reply:
        sessions = json.load(reply)
    for session in sessions:
        request = urllib.request.Request(f"{base}/api/sessions/{session['id']}?token={token}",
                                         method="DELETE")
        urllib.request.urlopen(request, timeout=30).close()


def wait_for(condition, timeout_s, what):
    """Poll ``condition()`` once a second until it is true; TimeoutError naming ``what``."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            raise TimeoutError(f"{what} not within {timeout_s:.0f} s")
        time.sleep(1.0)


def wait_until_done(page, base, token, name, timeout_s):
    """Wait until no cell is queued or running and the kernel is idle; return the seconds."""
    start = time.monotonic()
    prompts = lambda: page.evaluate(PENDING_JS)          # noqa: E731
    # "Run All Cells" queues every cell ([*]) before the first one finishes
    wait_for(lambda: prompts()["running"] > 0 or prompts()["pending"] == 0, 60,
             "cells queued")
    wait_for(lambda: prompts()["running"] == 0 and kernel_state(base, token, name) == "idle",
             timeout_s, "all cells run")
    return time.monotonic() - start


def click_redesign(page, timeout_s):
    """Notebook 04: press "re-design" and wait for its bar under the button to finish."""
    button = page.locator(".jp-OutputArea-output button", has_text="re-design").first
    if button.count() == 0:
        return "no re-design button (the control was drawn as a static figure)"
    button.scroll_into_view_if_needed()
    button.click()
    # the panel: the outermost box holding the button (its row is a box too)
    widget = page.locator(".jp-OutputArea-output .widget-box",
                          has=page.locator("button", has_text="re-design")).first
    try:
        widget.locator(".piezolib-progress-done, .piezolib-progress-failed").first.wait_for(
            timeout=timeout_s * 1000)
        page.wait_for_function(
            "() => ![...document.querySelectorAll('.jp-OutputArea-output .piezolib-progress')]"
            ".some(e => e.classList.contains('piezolib-progress-running'))",
            timeout=timeout_s * 1000, polling=500)
    except Exception:                                    # noqa: BLE001 -- reported, not raised
        return "re-design: no finished bar in the widget"
    if widget.locator(".piezolib-progress-failed").count():
        return "re-design: its bar ended failed"
    return None


def surprises(state):
    """What a reader would not expect to see, from :data:`INSPECT_JS`'s result."""
    found = []
    if state["pending"]:
        found.append(f"{state['pending']} code cells did not run")
    if state["figures"] == 0:
        found.append("no figure shown")
    for key, what in (("notPng", "images not PNG"), ("broken", "images not loaded"),
                      ("figureRepr", "'<Figure size ...>' instead of a figure"),
                      ("redBars", "red progress bars"),
                      ("runningBars", "bars still running after the cells finished"),
                      ("stderr", "stderr output blocks"), ("errors", "error outputs"),
                      ("widgetErrors", "widgets that cannot be displayed")):
        if state[key]:
            found.append(f"{state[key]} {what}")
    return found


def check_notebook(browser, base, token, name, timeout_s):
    """Open, run and inspect one notebook; return (line, ok)."""
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    page.goto(f"{base}/lab/tree/{name}?token={token}&reset", wait_until="domcontentloaded")
    page.locator(".jp-Notebook .jp-Cell").first.wait_for(timeout=120_000)
    # the kernel must be up before "Run All Cells" is offered
    wait_for(lambda: kernel_state(base, token, name) == "idle", 120, "kernel started")
    run_all_cells(page)
    seconds = wait_until_done(page, base, token, name, timeout_s)
    page.wait_for_timeout(1500)                          # last display updates and images
    state = {**page.evaluate(INSPECT_JS), "pending": page.evaluate(PENDING_JS)["pending"]}
    found = surprises(state)
    if name.startswith("04"):
        problem = click_redesign(page, timeout_s)
        if problem:
            found.append(problem)
        else:
            state["redesign"] = "re-design bar finished in the widget"
    page.close()
    shut_down_kernels(base, token)
    summary = (f"{state['figures']} figures (PNG), {state['doneBars']} finished bars, "
               f"{state['widgets']} widgets, {seconds:.0f} s")
    if "redesign" in state:
        summary += f"; {state['redesign']}"
    verdict = "ok" if not found else "SURPRISE: " + "; ".join(found)
    if state["failedBar"]:
        summary += "\n    failed bar: " + state["failedBar"]
    if state["firstStderr"]:                             # what the reader would read first
        summary += "\n    first stderr block ends: " + state["firstStderr"].replace("\n", " | ")
    return f"{name:<32s} {verdict} — {summary}", not found


def notebook_names(root, prefixes):
    """Notebook file names of ``root/notebooks`` that start with the prefixes, in order."""
    names = sorted(p.name for p in (root / "notebooks").glob("[0-9][0-9]_*.ipynb"))
    chosen = [n for n in names if any(n.startswith(p) for p in prefixes)]
    missing = [p for p in prefixes if not any(n.startswith(p) for n in names)]
    if missing:
        raise SystemExit(f"no notebook starts with {missing}")
    return chosen


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("prefixes", nargs="*", default=["04", "05", "06"],
                        help="notebook prefixes (default 04 05 06)")
    parser.add_argument("--chromium", default=None,
                        help="browser executable (default: chromium or chrome on the PATH)")
    parser.add_argument("--timeout", type=float, default=900.0,
                        help="seconds one notebook may take (default 900)")
    parser.add_argument("--keep", action="store_true", help="keep the temporary copy")
    args = parser.parse_args(argv)
    tools = browser_tools(args.chromium)
    if tools is None:
        return 2
    chromium, sync_playwright = tools
    home = Path(tempfile.mkdtemp(prefix="check_jupyterlab_"))
    root = copy_checkout(home / "checkout")
    names = notebook_names(root, args.prefixes)
    port, token = free_port(), secrets.token_hex(16)
    try:
        lab = start_lab(root, home, port, token)
    except RuntimeError as exc:
        print(exc)
        return 2
    ok = True
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=str(chromium), args=CHROMIUM_ARGS,
                                         headless=True)
            for name in names:
                try:
                    line, good = check_notebook(browser, f"http://127.0.0.1:{port}", token,
                                                name, args.timeout)
                except Exception as exc:                 # noqa: BLE001 -- one line per notebook
                    line, good = f"{name:<32s} SURPRISE: could not run it ({exc!s:.200})", False
                print(line, flush=True)
                ok &= good
            browser.close()
    finally:
        stop_lab(lab)
        if args.keep:
            print(f"kept {home} (JupyterLab's log: jupyterlab.log)")
        else:
            shutil.rmtree(home, ignore_errors=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
