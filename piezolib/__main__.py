"""Command line: ``python -m piezolib {reproduce,data} [options]``."""

import sys

from piezolib.workbook.cli import main

if __name__ == "__main__":
    sys.exit(main())
