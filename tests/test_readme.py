"""The toolkit example in README.md runs and prints what README says it prints."""

import contextlib
import io
import pathlib
import re
import warnings

README = pathlib.Path(__file__).resolve().parents[1] / "README.md"


def test_toolkit_example_runs_as_documented():
    text = README.read_text()
    code = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    claimed = re.search(r"prints `(.*?)`", text).group(1)
    out = io.StringIO()
    with contextlib.redirect_stdout(out), warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)     # python-control's own augw
        exec(compile(code, str(README), "exec"), {})
    assert out.getvalue().strip() == claimed
