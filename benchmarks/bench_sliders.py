"""How closely the notebooks' sliders follow the hand, in JupyterLab in a headless browser.

For each notebook (default 02, 03, 04) this script runs it in a JupyterLab
started for the purpose ("Run All Cells", as :mod:`check_jupyterlab` does),
focuses one slider of its interactive control (02: the spread, 03: g_a,
04: omega_e), presses the right arrow key ``--presses`` times as fast as the
browser takes them, and records in the page every change of the control's
figure.  Once the figure has not changed for ``--quiet`` seconds it prints,
per slider:

* the readout after the presses and the summary line under the figure
  (the last value must be the one drawn);
* ``frames``: how many figures were drawn after the first key press;
* ``first``: seconds from the first key press to the first new figure;
* ``last``: seconds from the last key press to the final figure, the
  latency a reader waits for.

With ``--redesign`` it then presses notebook 04's "re-design" button and
prints the seconds between the figure of the new controller and its green
"done" line (positive: the line came after the figure).

``--at REV`` runs the notebooks of git revision REV (``git archive``) instead
of the working tree: ``--at <commit before a change>`` then the working tree
gives the before and after figures.  Not part of ``pytest`` (CI has no
browser); set-up as in ``benchmarks/check_jupyterlab.py`` (Chromium on the
PATH, ``pip install playwright==1.65.2``, the client only).  Run with
``nice -n 10`` on a shared machine; the latencies count what the machine's
load adds.

    python benchmarks/bench_sliders.py                 # notebooks 02 03 04
    python benchmarks/bench_sliders.py 04 --redesign   # and the re-design
    python benchmarks/bench_sliders.py --at 15b6208    # before
"""

import argparse
import secrets
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import check_jupyterlab as lab                          # noqa: E402 -- the JupyterLab driver

#: The slider pressed in each notebook: a piece of its label.
SLIDERS = {"02": "spread", "03": "g_a", "04": "ω_e"}

# mark the control holding the slider and log, with performance.now(), every new figure,
# every key press and every "done" line of a re-design
INSTRUMENT_JS = """(label) => {
  const sliders = [...document.querySelectorAll('.jp-OutputArea-output .widget-slider')];
  const slider = sliders.find(s => (s.querySelector('.widget-label') || {}).textContent
                                   ?.includes(label));
  if (!slider) return false;
  const out = slider.closest('.jp-OutputArea-output');
  const img = out.querySelector('img');
  if (!img) return false;
  slider.setAttribute('data-bench', 'slider');
  out.setAttribute('data-bench', 'panel');
  const log = window.__bench = {frames: [], keys: [], done: []};
  new MutationObserver(() => log.frames.push(performance.now()))
    .observe(img, {attributes: true, attributeFilter: ['src']});
  let done = !!out.querySelector('.piezolib-progress-done');
  new MutationObserver(() => {
    const now = !!out.querySelector('.piezolib-progress-done');
    if (now && !done) log.done.push(performance.now());
    done = now;
  }).observe(out, {childList: true, subtree: true, characterData: true});
  document.addEventListener('keydown', () => log.keys.push(performance.now()), true);
  return true;
}"""

# the text of the notebook's error and stderr outputs
ERRORS_JS = """() => [...document.querySelectorAll('.jp-Notebook .jp-OutputArea-output'
  + '[data-mime-type="application/vnd.jupyter.error"], .jp-Notebook .jp-OutputArea-output'
  + '[data-mime-type="application/vnd.jupyter.stderr"]')].map(e => e.innerText).join('\\n')"""

STATE_JS = """() => {
  const out = document.querySelector('[data-bench=panel]');
  const readout = out.querySelector('[data-bench=slider] .widget-readout');
  const texts = [...out.querySelectorAll('.widget-html-content')].map(e => e.innerText.trim())
    .filter(t => t);
  return {...window.__bench, now: performance.now(),
          readout: readout ? (readout.value || readout.textContent).trim() : '',
          summary: texts[0] || ''};
}"""


def checkout_at(revision, target):
    """The files of git revision ``revision`` of the checkout under ``target``."""
    target.mkdir(parents=True)
    archive = subprocess.run(["git", "-C", str(lab.CHECKOUT), "archive", revision],
                             check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(target)], input=archive, check=True)
    return target


def wait_for_quiet(page, quiet_s, timeout_s):
    """Poll the log until the figure has not changed for ``quiet_s`` after the last key."""
    deadline = time.monotonic() + timeout_s
    while True:
        state = page.evaluate(STATE_JS)
        last = max(state["frames"][-1:] + state["keys"][-1:])
        if (state["now"] - last) / 1e3 >= quiet_s or time.monotonic() > deadline:
            return state
        time.sleep(0.5)


def press_slider(page, label, presses, quiet_s, timeout_s):
    """Press the right arrow on the slider ``label`` ``presses`` times; return the record."""
    if not page.evaluate(INSTRUMENT_JS, label):
        errors = page.evaluate(ERRORS_JS)
        raise RuntimeError(f"no live slider {label!r} (was the control drawn as a figure?)"
                           + (f"; an error output ends: {errors[-300:]}" if errors else ""))
    handle = page.locator("[data-bench=slider] .noUi-handle").first
    handle.scroll_into_view_if_needed()
    page.wait_for_timeout(2000)                          # the page settles
    page.evaluate("() => { window.__bench.frames = []; window.__bench.keys = []; }")
    handle.focus()
    for _ in range(presses):
        page.keyboard.press("ArrowRight")
    state = wait_for_quiet(page, quiet_s, timeout_s)
    keys, frames = state["keys"], [t for t in state["frames"] if t > state["keys"][0]]
    return {"readout": state["readout"], "summary": state["summary"], "keys": len(keys),
            "frames": len(frames),
            "first": (frames[0] - keys[0]) / 1e3 if frames else float("nan"),
            "last": (frames[-1] - keys[-1]) / 1e3 if frames else float("nan")}


def press_redesign(page, timeout_s):
    """Notebook 04: press "re-design"; seconds from the first new figure to the done line."""
    page.evaluate("() => { window.__bench.frames = []; window.__bench.done = []; }")
    start = page.evaluate("performance.now()")
    page.locator("[data-bench=panel] button", has_text="re-design").first.click()
    page.wait_for_function("() => window.__bench.done.length > 0", timeout=timeout_s * 1000,
                           polling=500)
    try:                                                 # a figure drawn after the line
        page.wait_for_function("() => window.__bench.frames.some(t => t > window.__bench.done[0])",
                               timeout=30_000, polling=250)
    except Exception:                                    # noqa: BLE001 -- none within 30 s
        pass
    state = page.evaluate(STATE_JS)
    done = state["done"][0]
    frames = [t for t in state["frames"] if t > start]
    if not frames:
        return "re-design: no new figure"
    before = [t for t in frames if t <= done]
    after = [t for t in frames if t > done]
    text = f"re-design: {(done - start) / 1e3:.1f} s; new figures: {len(before)} before"
    if before:
        text += f" (the last {(done - before[-1]) / 1e3:.2f} s before)"
    text += f" and {len(after)} after the done line"
    if after:
        text += f" (the first {(after[0] - done) / 1e3:.2f} s after)"
    return text


def bench_notebook(browser, base, token, name, args):
    """Run one notebook, press its slider; return its line."""
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    try:
        page.goto(f"{base}/lab/tree/{name}?token={token}&reset", wait_until="domcontentloaded")
        page.locator(".jp-Notebook .jp-Cell").first.wait_for(timeout=120_000)
        lab.wait_for(lambda: lab.kernel_state(base, token, name) == "idle", 120,
                     "kernel started")
        lab.run_all_cells(page)
        seconds = lab.wait_until_done(page, base, token, name, args.timeout)
        page.wait_for_timeout(1500)
        label = SLIDERS[name[:2]]
        r = press_slider(page, label, args.presses, args.quiet, args.timeout)
        line = (f"{name[:2]} {label:<7s} {r['keys']} keys -> readout {r['readout']:<8s} "
                f"frames {r['frames']:2d}  first {r['first']:5.2f} s  last {r['last']:5.2f} s"
                f"   (notebook ran in {seconds:.0f} s)\n    summary: {r['summary'][:110]}")
        if args.redesign and name.startswith("04"):
            line += "\n    " + press_redesign(page, args.timeout)
        return line
    finally:
        page.close()
        lab.shut_down_kernels(base, token)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("prefixes", nargs="*", default=sorted(SLIDERS),
                        help="notebook prefixes (default 02 03 04)")
    parser.add_argument("--presses", type=int, default=20, help="key presses (default 20)")
    parser.add_argument("--quiet", type=float, default=10.0,
                        help="seconds without a new figure that end a measurement (default 10)")
    parser.add_argument("--timeout", type=float, default=900.0,
                        help="seconds a notebook, or its slider, may take (default 900)")
    parser.add_argument("--redesign", action="store_true",
                        help="notebook 04: also time the re-design's figure and done line")
    parser.add_argument("--at", default=None, metavar="REV",
                        help="run git revision REV instead of the working tree")
    parser.add_argument("--chromium", default=None, help="browser executable")
    args = parser.parse_args(argv)
    unknown = [p for p in args.prefixes if p not in SLIDERS]
    if unknown:
        raise SystemExit(f"no slider is known for notebooks {unknown}; known: {sorted(SLIDERS)}")
    tools = lab.browser_tools(args.chromium)
    if tools is None:
        return 2
    chromium, sync_playwright = tools
    home = Path(tempfile.mkdtemp(prefix="bench_sliders_"))
    root = (checkout_at(args.at, home / "checkout") if args.at
            else lab.copy_checkout(home / "checkout"))
    names = lab.notebook_names(root, args.prefixes)
    port, token = lab.free_port(), secrets.token_hex(16)
    print(f"code: {args.at or 'working tree'}; {args.presses} right-arrow presses per slider")
    jupyter = lab.start_lab(root, home, port, token)
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=str(chromium), args=lab.CHROMIUM_ARGS,
                                         headless=True)
            for name in names:
                try:
                    line = bench_notebook(browser, f"http://127.0.0.1:{port}", token, name, args)
                except Exception as exc:                 # noqa: BLE001 -- one line per notebook
                    line = f"{name[:2]} could not be measured ({exc!s:.300})"
                print(line, flush=True)
            browser.close()
    finally:
        lab.stop_lab(jupyter)
        shutil.rmtree(home, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
