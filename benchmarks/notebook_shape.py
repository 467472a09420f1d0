"""Static shape of the notebooks: code lines, the longest cell, piezolib imports, definitions.

    python benchmarks/notebook_shape.py

Prints one row per notebook and the total; ``tests/test_notebooks_clean.py`` asserts the limits
(cells of at most 15 lines but the parameters cell, no def/class/lambda, at most 3 piezolib
import statements, at most 1,300 code lines in all).
"""

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PIEZOLIB_IMPORT = re.compile(r"^\s*(from\s+piezolib\b|import\s+piezolib\b)", re.M)


def shape(path):
    """(code lines, longest non-parameters cell, piezolib import statements, definitions)."""
    cells = [c for c in json.loads(path.read_text())["cells"] if c["cell_type"] == "code"]
    lines, longest, imports, defs = 0, 0, 0, 0
    for cell in cells:
        src = "".join(cell["source"])
        n = sum(1 for line in src.splitlines() if line.strip())
        lines += n
        if "parameters" not in cell.get("metadata", {}).get("tags", []):
            longest = max(longest, n)
        imports += len(PIEZOLIB_IMPORT.findall(src))
        defs += len(re.findall(r"^\s*(def|class)\s|\blambda\b", src, re.M))
    return lines, longest, imports, defs


def main():
    total = 0
    print(f"{'notebook':34s} {'code lines':>10s} {'longest cell':>12s} {'piezolib imports':>16s} "
          f"{'defs':>5s}")
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        lines, longest, imports, defs = shape(path)
        total += lines
        print(f"{path.stem:34s} {lines:10d} {longest:12d} {imports:16d} {defs:5d}")
    print(f"{'all':34s} {total:10d}")


if __name__ == "__main__":
    main()
