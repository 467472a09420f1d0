"""Command line: ``python -m piezolib reproduce [options]``."""

import argparse
import sys

from . import reproduce


def main(argv=None):
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
    args = parser.parse_args(argv)
    failures = reproduce.run(args.notebooks or None, timeout=args.timeout,
                             keep_going=args.keep_going, data=not args.no_data)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
