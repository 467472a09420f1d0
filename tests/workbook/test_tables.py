"""Tables as a reader sees them: one number format, whole texts."""

import re

import numpy as np
import pandas as pd
import pytest

from piezolib.workbook import tables

FIXED = re.compile(r"^-?\d+(\.\d+)?$")
POWER = re.compile(r"^-?\d(\.\d+)?×10⁻?[⁰¹²³⁴⁵⁶⁷⁸⁹]+$")


def test_numbers_of_one_table_share_one_format():
    # the mix the report showed: 9.15e+00 beside 6.17
    assert [tables.format_number(x) for x in (9.15, "9.15e+00", 6.17, "6.170")] == \
        ["9.15", "9.15", "6.17", "6.17"]
    for x in np.geomspace(1e-3, 9.99e5, 200):
        assert FIXED.match(tables.format_number(x)), x
    for x in [*np.geomspace(1e-30, 9.9e-4, 20), *np.geomspace(1e6, 1e30, 20)]:
        assert POWER.match(tables.format_number(x)), x
        assert POWER.match(tables.format_number(-x)), -x


def test_significant_digits_and_no_trailing_zeros():
    assert tables.format_number(0.018523) == "0.01852"
    assert tables.format_number(2100.0) == "2100"
    assert tables.format_number(0.98174, digits=3) == "0.982"
    assert tables.format_number(1.8340e23) == "1.834×10²³"
    assert tables.format_number(2.0e-10) == "2×10⁻¹⁰"
    assert tables.format_number(999999.7) == "1×10⁶"        # the rounded magnitude decides
    assert tables.format_number(0) == "0"


def test_text_booleans_and_missing_values_pass_through():
    assert [tables.format_number(v) for v in ("True", False, "differs", "+-2%", "", None,
                                              float("nan"), "nan")] == \
        ["True", "False", "differs", "+-2%", "", "", "", ""]


@pytest.mark.parametrize("digits", [0, 2.5, True, "4"])
def test_digits_must_be_a_positive_integer(digits):
    with pytest.raises(ValueError, match="digits"):
        tables.format_number(1.0, digits)


def test_readable_shows_whole_notes_whatever_the_display_width():
    note = "a long note, " * 20 + "end of the note"
    frame = pd.DataFrame({"source": ["05_mu_synthesis"], "quantity": ["mu_RP < 1"],
                          "paper": ["0.71"], "ours": [1.4483], "note": [note]},
                         index=[41])
    with pd.option_context("display.max_colwidth", 20):
        page = tables.readable(frame).to_html()
    assert note in page and "..." not in page and "…" not in page
    assert "μ_RP &lt; 1" in page                     # units rule, escaped
    assert "05_mu_synthesis" in page                 # a name is not respelled
    assert ">1.448<" in page and ">0.71<" in page
    assert ">41<" not in page                        # row numbers hidden by default
    assert ">41<" in tables.readable(frame, index=True).to_html()


def test_readable_formats_labels_and_table_cells_alike():
    frame = pd.DataFrame({(10.0, "paper"): [9.15, 0.31], (10.0, "ours"): [9.148, 0.0073]},
                         index=["case_I", "case_III"])
    page = tables.readable(frame, index=True).to_html()
    cells = re.findall(r"<td[^>]*>([^<]*)</td>", page)
    assert cells == ["9.15", "9.148", "0.31", "0.0073"]
    assert ">10<" in page and "10.000000" not in page and ">case_I<" in page


def test_readable_needs_a_frame():
    with pytest.raises(TypeError, match="frame"):
        tables.readable([[1, 2]])
