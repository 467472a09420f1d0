"""The command line of the workbook (``python -m piezolib``)."""

import argparse
import sys
import time

__all__ = ["main"]


def _parser():
    parser = argparse.ArgumentParser(
        prog="python -m piezolib",
        description="piezo-mu workbook: reproduce the paper's results.")
    sub = parser.add_subparsers(dest="command", required=True)
    rep = sub.add_parser(
        "reproduce",
        help="regenerate data, execute every notebook, write figures and tables")
    rep.add_argument("notebooks", nargs="*", metavar="NN",
                     help="only the notebooks whose names start with these prefixes")
    rep.add_argument("--timeout", type=float, default=600,
                     help="per-cell time limit in seconds (default 600)")
    rep.add_argument("--keep-going", action="store_true",
                     help="run the remaining notebooks after a failure")
    rep.add_argument("--no-data", action="store_true",
                     help="do not regenerate the experiment files first")
    sub.add_parser("data", help="regenerate the virtual-stage experiment files in data/")
    return parser


def _data(stream):
    from piezolib import paper
    from piezolib.problem import stage, stage_data

    start = time.perf_counter()
    for path in stage_data.write_experiment_files():
        print(path, file=stream)
    got = stage.case_I_hysteresis(stage_data.load_hysteresis_loops())
    paper_row = paper.table4().loc["case_I"]
    for amplitude, value in got.items():
        print(f"Case I hysteresis at {amplitude:4.0f} V: {value:6.2f} %  "
              f"(paper {paper_row[amplitude]:.2f} %)", file=stream)
    print(f"done in {time.perf_counter() - start:.1f} s", file=stream)
    return 0


def main(argv=None, stream=sys.stdout):
    """Run the command line; return the exit status (0 ok, 1 failure, 2 usage)."""
    args = _parser().parse_args(argv)
    if args.command == "data":
        return _data(stream)
    from piezolib.workbook import reproduce

    try:
        reproduce.list_notebooks(args.notebooks or None)     # fail early on a bad prefix
    except ValueError as exc:
        print(f"python -m piezolib reproduce: {exc}", file=sys.stderr)
        return 2
    failures = reproduce.run(args.notebooks or None, timeout=args.timeout,
                             keep_going=args.keep_going, data=not args.no_data, stream=stream)
    return 1 if failures else 0
