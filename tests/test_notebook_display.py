"""piezolib.notebook_display: bars and log lines as cell outputs redrawn in place."""

import logging
import sys
import types

import pytest

from piezolib import notebook_display as nd


@pytest.fixture
def cell(monkeypatch):
    """A kernel whose outputs are recorded: {display number: [bundles drawn]}."""
    from IPython import display as ipython_display

    outputs = {}

    class Handle:
        def __init__(self, number):
            self.number = number

        def update(self, bundle, raw=False):
            assert raw
            outputs[self.number].append(bundle)

    def display(bundle, raw=False, display_id=False):
        assert raw and display_id
        outputs[len(outputs)] = [bundle]
        return Handle(len(outputs) - 1)

    monkeypatch.setattr(nd, "in_kernel", lambda: True)
    monkeypatch.setattr(ipython_display, "display", display)
    monkeypatch.setattr(nd, "_request_id", lambda: "cell-1")
    return outputs


@pytest.fixture
def logger(monkeypatch):
    """A logger of the library at INFO with the cell handler, removed afterwards."""
    log = logging.getLogger("piezolib.test_notebook_display")
    log.setLevel(logging.INFO)
    handler = nd.route_logs(log.name)
    yield log
    log.removeHandler(handler)
    log.setLevel(logging.NOTSET)


def test_a_bar_stopped_early_ends_done_with_its_reason(cell):
    with nd.CellBar(total=60, desc="fixed-order 6", unit="step") as bar:
        bar.update(6)
        bar.set_postfix_str("mu 0.9402, grid 412")
        bar.finish("no improvement > 0.001 in 2 steps")
    final = cell[0][-1]
    assert final["text/plain"] == ("✔ fixed-order 6: done: no improvement > 0.001 in 2 steps · "
                                   f"6 of at most 60 step in {nd._duration(bar.elapsed)} · "
                                   "mu 0.9402, grid 412")
    assert "piezolib-progress-done" in final["text/html"]
    assert "&gt; 0.001" in final["text/html"]                       # escaped HTML
    assert "10 %" not in final["text/plain"] and "6/60" not in final["text/plain"]
    bar.close()                                                     # idempotent: no redraw
    assert len(cell) == 1 and cell[0][-1] is final


def test_a_running_bar_shows_its_counts_and_redraws_at_most_five_times_a_second(cell):
    bar = nd.CellBar(range(1000), desc="sweep", unit="point")
    assert bar.total == 1000 and "0/1000 point" in cell[0][0]["text/plain"]
    assert list(bar) == list(range(1000))
    assert len(cell[0]) < 20                                        # not 1000 redraws
    assert cell[0][-1]["text/plain"].startswith("✔ sweep: done · 1000 of at most 1000 point")


def test_reset_counts_again_with_a_new_total(cell):
    """The Dahl fit's use: a counter during the grid search, then a bar over the solves."""
    with nd.CellBar(desc="fit_dahl", unit="solve") as bar:
        bar.set_postfix_str("grid search for starting points")
        bar.update(40)
        bar.reset(total=3)
        assert "0/3 solve" in cell[0][-1]["text/plain"]
        bar.update(3)
    assert cell[0][-1]["text/plain"].startswith("✔ fit_dahl: done · 3 of at most 3 solve")


def test_leaving_a_loop_early_is_done_not_failed(cell):
    for k in nd.CellBar(range(10), desc="search"):
        if k == 3:
            break
    final = cell[0][-1]["text/plain"]
    assert final.startswith("✔ search: done") and "3 of at most 10" in final


def test_an_exception_marks_the_bar_failed(cell):
    def items():
        yield 1
        raise OSError("disk gone")

    with pytest.raises(OSError):
        list(nd.CellBar(items(), desc="read"))
    assert "piezolib-progress-failed" in cell[0][-1]["text/html"]
    assert cell[0][-1]["text/plain"].startswith("✘ read: FAILED: OSError: disk gone")


def test_log_records_go_under_the_running_bar_collapsed(cell, logger):
    with nd.CellBar(total=8, desc="musyn DK", unit="iter") as bar:
        for k in range(3):
            logger.info("DK %2d: mu %.4f", k, 1.0 - 0.1 * k)
            bar.update()
        bar.finish("no improvement")
    assert len(cell) == 1                                           # no output of their own
    final = cell[0][-1]
    assert "<details style" in final["text/html"] and "<details open" not in final["text/html"]
    assert "log (3 lines)" in final["text/html"] and "DK  2: mu 0.8000" in final["text/html"]
    assert final["text/plain"].splitlines()[1:] == ["    DK  0: mu 1.0000", "    DK  1: mu 0.9000",
                                                    "    DK  2: mu 0.8000"]


def test_a_warning_opens_the_log_and_is_marked(cell, logger):
    with nd.CellBar(total=2, desc="fit") as bar:
        logger.warning("step rejected")
        bar.update(2)
    html_text = cell[0][-1]["text/html"]
    assert "<details open" in html_text and "1 warning" in html_text
    assert "WARNING: step rejected" in cell[0][-1]["text/plain"]


def test_records_without_a_bar_grow_one_block_per_cell(cell, logger, monkeypatch):
    logger.info("designing the delay-aware controllers")
    logger.info("DK-iteration on the 20-state plant")
    assert len(cell) == 1 and len(cell[0]) == 2                     # one block, redrawn
    assert cell[0][-1]["text/plain"] == ("designing the delay-aware controllers\n"
                                         "DK-iteration on the 20-state plant")
    assert "piezolib-log" in cell[0][-1]["text/html"]
    monkeypatch.setattr(nd, "_request_id", lambda: "cell-2")        # the next cell
    logger.info("another cell")
    assert len(cell) == 2 and cell[1][-1]["text/plain"] == "another cell"
    with nd.CellBar(total=1, desc="between") as bar:
        bar.update()
    logger.info("after the bar")                                    # below it, not above
    assert len(cell) == 4 and cell[3][-1]["text/plain"] == "after the bar"


def test_outside_a_kernel_records_go_where_they_would_without_the_handler(logger, capsys,
                                                                          caplog):
    with caplog.at_level(logging.INFO, logger=logger.name):         # another handler: it gets it
        logger.info("to the other handler")
    assert "to the other handler" in caplog.text
    assert capsys.readouterr().err == ""
    root = logging.getLogger()
    saved = root.handlers[:]
    root.handlers.clear()                                           # none: stderr, as always
    try:
        logger.warning("to stderr")
        logger.info("not shown")                                    # below lastResort's level
    finally:
        root.handlers[:] = saved
    assert capsys.readouterr().err == "to stderr\n"                   # as logging.lastResort does


def test_route_logs_attaches_one_handler(logger):
    handlers = [h for h in logger.handlers if isinstance(h, nd.CellLogHandler)]
    assert len(handlers) == 1 and nd.route_logs(logger.name) is handlers[0]
    with pytest.raises(TypeError, match="name"):
        nd.route_logs(3)


def test_shown_in_joins_the_bars_of_its_block(cell):
    drawn = []
    with nd.shown_in(lambda html_text, text: drawn.append((html_text, text))):
        assert nd.redirected()
        with nd.CellBar(total=2, desc="first") as one:
            one.update(2)
        with nd.CellBar(total=5, desc="second") as two:
            two.update()
            two.finish("converged")
    assert not nd.redirected() and cell == {}                       # nothing in the cell
    html_text, text = drawn[-1]
    assert text.splitlines()[0].startswith("✔ first: done")
    assert text.splitlines()[1].startswith("✔ second: done: converged")
    assert html_text.count("piezolib-progress-done") == 2
    with pytest.raises(TypeError, match="callback"):
        with nd.shown_in("not callable"):
            pass


def test_frontend_cell_id_is_read_from_the_request(monkeypatch):
    parent = {"metadata": {}}
    kernel = types.SimpleNamespace(get_parent=lambda channel: parent)
    fake = types.ModuleType("IPython")
    fake.get_ipython = lambda: types.SimpleNamespace(kernel=kernel)
    monkeypatch.setitem(sys.modules, "IPython", fake)
    assert nd.in_kernel() and nd.frontend_cell_id() is None         # nbclient sends none
    parent["metadata"]["cellId"] = "a1b2"                           # JupyterLab names the cell
    assert nd.frontend_cell_id() == "a1b2"
    fake.get_ipython = lambda: None                                 # plain Python
    assert not nd.in_kernel() and nd.frontend_cell_id() is None
