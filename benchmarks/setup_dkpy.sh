#!/bin/sh
# Create benchmarks/.dkpy-venv (git-ignored) with the project's pinned dependencies, dkpy and the
# project itself (editable), for the dkpy columns of bench_mussv.py and bench_mu_structures.py
# (and mpmath, for the 60-digit checks of bench_hinf_random.py).
# Run from anywhere:  sh benchmarks/setup_dkpy.sh
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
venv="$here/.dkpy-venv"
python3 -m venv "$venv"
req=$(mktemp)
grep -v '^-e' "$root/environment.txt" > "$req"
"$venv/bin/pip" install -q -r "$req" dkpy mpmath==1.4.1
rm -f "$req"
"$venv/bin/pip" install -q --no-deps -e "$root"
"$venv/bin/python" -c "import dkpy, piezolib; print('dkpy', dkpy.__version__ if hasattr(dkpy, '__version__') else '', 'ready in', '$venv')"
