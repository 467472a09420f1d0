"""The command line of the workbook (``python -m piezolib``): reproduce, data, controllers,
sweep, compare."""

import argparse
import sys
import time

__all__ = ["main", "parser", "error_line"]


def parser():
    """The command line's :class:`argparse.ArgumentParser` (its subcommands and options)."""
    parser = argparse.ArgumentParser(
        prog="python -m piezolib",
        description="piezo-mu workbook: reproduce the paper's results.")
    sub = parser.add_subparsers(dest="command", required=True)
    rep = sub.add_parser(
        "reproduce",
        help="regenerate data, execute every notebook, write figures and tables")
    rep.add_argument("notebooks", nargs="*", metavar="NN",
                     help="only the notebooks whose names start with these prefixes")
    rep.add_argument("--timeout", type=_positive_seconds, default=600,
                     help="per-cell time limit in seconds (default 600)")
    rep.add_argument("--jobs", type=_positive_int, default=None, metavar="N",
                     help="notebooks run side by side (default 2, 1 on a single core; "
                          "1 runs them one by one in order)")
    rep.add_argument("--keep-going", action="store_true",
                     help="run the remaining notebooks after a failure")
    rep.add_argument("--no-data", action="store_true",
                     help="do not regenerate the experiment files first")
    rep.add_argument("--study", metavar="STUDY",
                     help="a study in studies/ (name) or a .toml file: its outputs go to "
                          "runs/<name>/ (default: reference, which writes figures/ and "
                          "data/results/)")
    rep.add_argument("--list", action="store_true", help="list the studies and exit")
    sub.add_parser("data", help="regenerate the virtual-stage experiment files in data/")
    ctl = sub.add_parser("controllers",
                         help="the reference study's committed optimisation products: the "
                              "controllers (data/controllers/reference_design.json), their "
                              "float32 section exports K_*.json / K_*.h and the workbook Dahl "
                              "model (data/models/workbook_dahl.json)")
    ctl.add_argument("--write-reference", action="store_true",
                     help="re-derive them (Dahl fit, DK-iteration, fixed order, the mixed-mu "
                          "designs) and rewrite those files")
    ctl.add_argument("--write-mixed", action="store_true",
                     help="re-derive only the mixed-mu designs of notebook 09 (about ten "
                          "minutes) and rewrite data/controllers/mixed_design.json and "
                          "K_mixed.json / .h")
    doc = sub.add_parser("report",
                         help="the reproduction report (notebook 07) as an HTML document "
                              "without code: runs/report/<study>.html")
    doc.add_argument("--study", metavar="STUDY",
                     help="a study in studies/ (name) or a .toml file (default: reference)")
    doc.add_argument("--output", metavar="PATH",
                     help="the HTML file to write (default: runs/report/<study>.html)")
    doc.add_argument("--executed", metavar="NOTEBOOK",
                     help="export this executed copy of notebook 07 instead of executing it "
                          "(run with inline figures, e.g. saved from JupyterLab)")
    doc.add_argument("--pdf", action="store_true",
                     help="also print it to PDF beside the HTML file (needs Chromium on the "
                          "PATH; Debian: apt-get install chromium)")
    doc.add_argument("--paper", choices=("A4", "letter"), default="A4",
                     help="paper size of the PDF (default A4)")
    doc.add_argument("--timeout", type=_positive_seconds, default=600,
                     help="per-cell time limit in seconds (default 600)")
    swp = sub.add_parser(
        "sweep", help="run many studies at once (a grid or random sample over a base study), "
                      "locally or on a dask cluster; table and Pareto figure in "
                      "runs/sweeps/<name>/")
    swp.add_argument("spec", help="a sweep in studies/sweeps/ (name) or a .toml file")
    swp.add_argument("--jobs", type=_positive_int, default=None, metavar="N",
                     help="local worker processes (default: one per core; 1 runs the points "
                          "one by one)")
    swp.add_argument("--scheduler", metavar="ADDRESS", type=_scheduler_address,
                     help="run the points on a dask cluster, e.g. tcp://127.0.0.1:8786 "
                          "(instead of local workers)")
    swp.add_argument("--dry-run", action="store_true",
                     help="list the points and whether each is stored; run nothing")
    cmp_ = sub.add_parser("compare", help="key numbers of two studies side by side")
    cmp_.add_argument("first", help="study name (e.g. reference)")
    cmp_.add_argument("second", help="study name")
    return parser


def _positive_seconds(text):
    try:
        value = float(text)
    except ValueError:
        value = 0.0
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds, got {text!r}")
    return value


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return value


def _scheduler_address(text):
    from piezolib.workbook.sweep import check_scheduler_address

    try:
        return check_scheduler_address(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).replace("scheduler must", "must")) from None


def _sweep(args, stream):
    from piezolib.workbook import sweep, sweep_spec

    try:
        spec = sweep_spec.load_spec(args.spec)
    except sweep_spec.SweepError as exc:
        print(f"python -m piezolib sweep: {exc}", file=sys.stderr)
        return 2
    try:
        result = sweep.run_sweep(spec, jobs=args.jobs, scheduler=args.scheduler,
                                 dry_run=args.dry_run, stream=stream)
    except OSError as exc:                      # an unreachable scheduler, a full disk
        print(f"python -m piezolib sweep: {error_line(exc)}", file=sys.stderr)
        return 2 if args.scheduler and "scheduler" in str(exc) else 1
    except KeyboardInterrupt:
        stored = len(list((spec.directory / "points").glob("*.json")))
        print(f"python -m piezolib sweep: interrupted; {stored} point record(s) stored in "
              f"{spec.directory / 'points'}: run the same command again to resume",
              file=sys.stderr)
        return 130
    return 1 if result.failed or result.problems else 0


def _list_studies(stream):
    """Every study file with its description; a broken file is listed with its error (status 1)."""
    from piezolib.workbook import study as studies

    broken = 0
    for path in studies.study_files():
        try:
            s = studies.load(path)
        except studies.StudyError as exc:
            broken += 1
            print(f"{path.stem:<24s} BROKEN: {exc}", file=stream)
            continue
        print(f"{s.name:<24s} {s.description}", file=stream)
        print(f"{'':<24s} outputs: {s.output_dir}", file=stream)
    return 1 if broken else 0


def _controllers(args, stream):
    from piezolib.workbook import design_run, pipeline

    if args.write_reference:
        path, found = pipeline.write_reference_design()
        record = design_run.write_reference_record(found)
        print(f"wrote {path}, the section exports "
              + ", ".join(f"{stem}.json/.h" for stem in (*pipeline.SECTION_FILES,
                                                         pipeline.FEEDFORWARD_FILE))
              + f", the workbook Dahl model and the searches' record {record}", file=stream)
    if args.write_mixed and not args.write_reference:
        path = pipeline.write_reference_mixed_designs()
        print(f"wrote {path} and the sections {pipeline.MIXED_SECTIONS_FILE}.json/.h", file=stream)
    found = pipeline.read_controllers(pipeline.reference_design_path())
    print(f"{found.source}: designed for choices {found.digest}; mu_RP "
          + ", ".join(f"{k} {v:.4f}" for k, v in found.mu.items()), file=stream)
    return 0


def _compare(args, stream):
    import pandas as pd

    from piezolib.workbook import outputs, report
    from piezolib.workbook import study as studies

    try:
        if args.first == args.second:
            raise ValueError(f"both arguments name the study {args.first!r}")
        for name in (args.first, args.second):
            s = studies.load(name)
            if not s.is_reference and not any(outputs.study_results_dir(s.name).glob("*.csv")):
                raise ValueError(f"study {s.name!r} has no results yet: run `python -m piezolib "
                                 f"reproduce --study {name}` first")
    except (ValueError, studies.StudyError) as exc:
        print(f"python -m piezolib compare: {exc}", file=sys.stderr)
        return 2
    table = report.compare_studies(args.first, args.second).reset_index()
    table["source"] = table["source"].str[:2]        # the notebook's number
    columns = ["source", "quantity", "unit", "paper", args.first, args.second,
               f"verdict ({args.second})"]
    with pd.option_context("display.width", 250, "display.max_colwidth", 64):
        print(table[columns].to_string(index=False), file=stream)
    print(f"{len(table)} numbers differ between {args.first} and {args.second}", file=stream)
    return 0


def _report(args, stream):
    """Write the report document; print its path (and the PDF's)."""
    from piezolib.workbook import document, reproduce
    from piezolib.workbook import study as studies

    try:
        if args.study is not None:
            studies.load(args.study)                 # a bad study is a usage error
        written = document.build(args.study, executed=args.executed, output=args.output,
                                 pdf=args.pdf, timeout=args.timeout, paper=args.paper)
    except (ValueError, FileNotFoundError, studies.StudyError) as exc:
        print(f"python -m piezolib report: {exc}", file=sys.stderr)
        return 2
    except (reproduce.NotebookFailure, RuntimeError) as exc:
        print(f"python -m piezolib report: FAILED: {exc}", file=sys.stderr)
        return 1
    for path in written:
        print(path, file=stream)
    return 0


def _data(stream):
    from piezolib import files
    from piezolib.problem import paper
    from piezolib.problem import stage_calibration, stage_data
    from piezolib.workbook.outputs import data_dir

    start = time.perf_counter()
    files.remove_stale_temporaries(data_dir())       # what a killed earlier run left
    for path in stage_data.write_experiment_files():
        print(path, file=stream)
    got = stage_calibration.case_I_hysteresis(stage_data.load_hysteresis_loops())
    paper_row = paper.table4().loc["case_I"]
    for amplitude, value in got.items():
        print(f"Case I hysteresis at {amplitude:4.0f} V: {value:6.2f} %  "
              f"(paper {paper_row[amplitude]:.2f} %)", file=stream)
    print(f"done in {time.perf_counter() - start:.1f} s", file=stream)
    return 0


def main(argv=None, stream=sys.stdout):
    """Run the command line; return the exit status (0 ok, 1 failure, 2 usage, 130 interrupted).

    An error of the file system (a read-only or full disk, a missing permission), a data
    file that fails its check, a sweep another process runs, or Ctrl-C is one line on
    stderr naming the command and the file, never a traceback.
    """
    from piezolib import files
    from piezolib.records import RecordError

    args = parser().parse_args(argv)
    try:
        return _command(args, stream)
    except KeyboardInterrupt:
        print(f"python -m piezolib {args.command}: interrupted", file=sys.stderr)
        return 130
    except (OSError, RecordError, files.LockHeld) as exc:
        print(f"python -m piezolib {args.command}: {error_line(exc)}", file=sys.stderr)
        return 1


def error_line(exc):
    """One line saying what went wrong: the message of ``exc`` (an OSError's without its
    errno prefix, with the file it names).

    Examples
    --------
    >>> error_line(OSError(30, "cannot write data/a.csv: Read-only file system", "data/a.csv"))
    'cannot write data/a.csv: Read-only file system'
    >>> error_line(PermissionError(13, "Permission denied", "runs/x"))
    'runs/x: Permission denied'
    """
    if not isinstance(exc, BaseException):     # str(exc) would pass any object on as text
        raise TypeError(f"exc must be an exception, got {type(exc).__name__}")
    if isinstance(exc, OSError) and exc.strerror:
        text = exc.strerror
        if exc.filename is not None and str(exc.filename) not in text:
            text = f"{exc.filename}: {text}"
    else:
        text = str(exc) or type(exc).__name__
    lines = text.strip().splitlines() or [type(exc).__name__]
    return lines[0]


def _command(args, stream):
    if args.command == "data":
        return _data(stream)
    if args.command == "controllers":
        return _controllers(args, stream)
    if args.command == "compare":
        return _compare(args, stream)
    if args.command == "report":
        return _report(args, stream)
    if args.command == "sweep":
        return _sweep(args, stream)
    if args.list:
        return _list_studies(stream)
    from piezolib.workbook import reproduce
    from piezolib.workbook import study as studies

    try:
        reproduce.list_notebooks(args.notebooks or None)     # fail early on a bad prefix
        if args.study is not None:
            studies.load(args.study)                        # ... and on a bad study
    except (ValueError, studies.StudyError) as exc:
        print(f"python -m piezolib reproduce: {exc}", file=sys.stderr)
        return 2
    failures = reproduce.run(args.notebooks or None, timeout=args.timeout,
                             keep_going=args.keep_going, data=not args.no_data, stream=stream,
                             study=args.study, jobs=args.jobs)
    return 1 if failures else 0
