"""The strict CSV reader (piezolib.records.reader): every loader error names the file and the
line; locale numbers, encodings, the fast read against the line-by-line reader."""

import codecs
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from piezolib import records as R
from piezolib.records import reader

FS = 5000.0


def write(path, lines):
    path.write_text("".join(line + "\n" for line in lines))
    return path


def good_lines(n=40, fs=FS, header=True):
    lines = ["# experiment = test", "# gain = 10"] + (["t,v,x"] if header else [])
    lines += [f"{k / fs:.6f},{np.sin(k / 5):.5f},{3 * np.sin(k / 5):.5f}" for k in range(n)]
    return lines


def test_load_csv_with_header_names_units_and_scaling(tmp_path):
    path = write(tmp_path / "a.csv", good_lines())
    rec = R.load_csv(path, time="t", input="v", output="x", header=True, input_unit="V",
                     output_unit="nm", output_scale=1e3, input_name="v_a", output_name="d")
    assert len(rec) == 40 and rec.fs == pytest.approx(FS) and rec.t0 == 0.0
    assert rec.output_unit == "nm" and rec.input_name == "v_a"
    assert np.allclose(rec.output, 3e3 * rec.input, atol=1e-2)
    assert rec.metadata["experiment"] == "test" and rec.metadata["gain"] == 10
    assert rec.metadata["source"] == str(path)
    assert not rec.input.flags.writeable


def test_load_csv_without_header_by_column_number_and_rate(tmp_path):
    path = write(tmp_path / "b.csv", good_lines(header=False))
    rec = R.load_csv(path, input=1, output=2, fs=FS)
    assert len(rec) == 40 and np.allclose(rec.time[:3], [0, 2e-4, 4e-4])
    with pytest.raises(ValueError, match="names a column but header=False"):
        R.load_csv(path, input="v", output=2, fs=FS)
    with pytest.raises(ValueError, match="fs"):
        R.load_csv(path, input=1, output=2)
    with pytest.raises(R.RecordError, match="time column gives 5000 Hz, but fs=1000"):
        R.load_csv(path, time=0, input=1, output=2, fs=1000.0)


@pytest.mark.parametrize("mutate, line, message", [
    (lambda ls: ls, None, None),                                       # intact: loads
    (lambda ls: ls[:2] + ["t,w,x"] + ls[3:], 3, "missing column 'v'"),
    (lambda ls: ls[:20] + ["0.003400,abc,1.0"] + ls[21:], 21, "'abc' is not a number"),
    (lambda ls: ls[:10] + ["0.001400,nan,1.0"] + ls[11:], 11, "not a finite number"),
    (lambda ls: ls[:15] + ["0.0024"] + ls[16:], 16, "1 field"),
    (lambda ls: ls[:30] + [ls[26]] + ls[31:], 31, "time must increase"),
    (lambda ls: ls[:30] + ["0.005560" + ls[30][8:]] + ls[31:], 31, "uneven sampling"),
    (lambda ls: ls[:12], 12, "too short"),
    (lambda ls: ls[:2], None, "no header line"),
])
def test_each_loader_error_names_file_and_line(tmp_path, mutate, line, message):
    path = write(tmp_path / "c.csv", mutate(good_lines()))
    load = dict(time="t", input="v", output="x", header=True)
    if message is None:
        assert len(R.load_csv(path, **load)) == 40
        return
    with pytest.raises(R.RecordError, match=message) as info:
        R.load_csv(path, **load)
    assert info.value.path == str(path) and info.value.line == line
    assert str(path) in str(info.value)
    if line is not None:
        assert f"line {line}:" in str(info.value)


def test_missing_file_and_bad_arguments(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing.csv"):
        R.load_csv(tmp_path / "nothing.csv", input=0, output=1, fs=FS)
    path = write(tmp_path / "d.csv", good_lines(header=False))
    with pytest.raises(ValueError, match="output_scale"):
        R.load_csv(path, input=1, output=2, fs=FS, output_scale=0)
    with pytest.raises(ValueError, match="fs"):
        R.load_csv(path, input=1, output=2, fs=-1.0)


def data_lines(n=40, sep=","):
    return [sep.join([f"{k / FS:.6f}", f"{np.sin(k / 5):.5f}", f"{3 * np.sin(k / 5):.5f}"])
            for k in range(n)]


LOAD = dict(time="t", input="v", output="x", header=True)


@pytest.mark.parametrize("sep, cell, line, says", [
    (";", "1,234.5", 7, "a thousands separator ',': pass thousands=','"),
    ("\t", "1,234.5", 7, "a thousands separator ',': pass thousands=','"),
    (";", "1.234,5", 7, "a decimal comma and a thousands separator '.': pass decimal=',', "
                        "thousands='.'"),
    (";", "0,25", 7, "a decimal comma: pass decimal=','"),
    (";", "1,234", 7, "a thousands separator ',' or a decimal comma: pass thousands=',' or "
                      "decimal=','"),
])
def test_locale_numbers_are_refused_with_how_to_read_them(tmp_path, sep, cell, line, says):
    rows = data_lines(sep=sep)
    rows[4] = sep.join([rows[4].split(sep)[0], "0.5", cell])
    path = write(tmp_path / "eu.csv", ["# instrument = X", sep.join("tvx")] + rows)
    with pytest.raises(R.RecordError) as info:
        R.load_csv(path, delimiter=sep, **LOAD)
    assert info.value.line == line and f"line {line}:" in str(info.value)
    assert f"column 'x' (output): {cell!r} is not a number; it looks like" in str(info.value)
    assert says in str(info.value)


def test_comma_numbers_in_a_comma_file_are_not_read_as_extra_columns(tmp_path):
    # 2,001.5 in a comma-delimited file is two fields: the old loader read y = 2.0 throughout
    rows = [f"{k / FS:.6f},{0.1 * k:.1f},{2000 + k:,.1f}" for k in range(40)]
    path = write(tmp_path / "c.csv", ["t,v,x"] + rows)
    with pytest.raises(R.RecordError, match=r"line 2: 4 fields, but the header \(line 1\) "
                                            "names 3 columns; with ','") as info:
        R.load_csv(path, **LOAD)
    assert "decimal mark or thousands separator splits in two" in str(info.value)


def test_a_short_row_and_a_long_row_do_not_cancel_out(tmp_path):
    # only some columns are read: a row without the unused last field is fine, one with an
    # extra field is not, even when the two together hold the expected number of delimiters
    rows = [line + ",0" for line in data_lines()]
    rows[5], rows[9] = rows[5][:-2], rows[9] + ",7"
    path = write(tmp_path / "d.csv", ["t,v,x,spare"] + rows)
    with pytest.raises(R.RecordError, match=r"line 11: 5 fields, but the header \(line 1\) "
                                            "names 4 columns"):
        R.load_csv(path, **LOAD)
    rows[9] = rows[9][:-2]
    assert len(R.load_csv(write(path, ["t,v,x,spare"] + rows), **LOAD)) == 40


def test_decimal_comma_and_thousands_arguments(tmp_path):
    lines = [f"{k / FS:.6f};{1000 + k:.2f};{-2000.5 - k:,.1f}".replace(",", "_")
             for k in range(40)]
    european = [line.replace(".", ",").replace("_", ".") for line in lines]
    path = write(tmp_path / "eu.csv", ["# gain = 10", "t;v;x"] + european)
    rec = R.load_csv(path, delimiter=";", decimal=",", thousands=".", **LOAD)
    assert rec.fs == pytest.approx(FS) and rec.metadata["gain"] == 10
    assert rec.input[3] == 1003.0 and rec.output[3] == -2003.5
    english = [line.replace("_", ",") for line in lines]
    rec = R.load_csv(write(tmp_path / "en.csv", ["t;v;x"] + english), delimiter=";",
                     thousands=",", **LOAD)
    assert rec.output[3] == -2003.5
    plain = [line.replace(",", "") for line in english]          # decimal="," alone
    rec = R.load_csv(write(tmp_path / "p.csv", ["t;v;x"] + [p.replace(".", ",") for p in plain]),
                     delimiter=";", decimal=",", **LOAD)
    assert rec.input[3] == 1003.0
    with pytest.raises(R.RecordError, match=r"line 2: column 'v' \(input\): '1000.00' is not "
                                            "a number; it looks like a decimal point: pass "
                                            "decimal='.'"):
        R.load_csv(write(tmp_path / "r.csv", ["t;v;x"] + plain), delimiter=";", decimal=",",
                   **LOAD)
    for bad in (dict(decimal=","), dict(decimal=";", delimiter=","),
                dict(delimiter=";", thousands="."), dict(delimiter=";", thousands="1")):
        with pytest.raises(ValueError):
            R.load_csv(path, **{"delimiter": ",", **bad}, **LOAD)


def test_a_duplicated_column_name_is_refused_when_asked_for(tmp_path):
    path = write(tmp_path / "dup.csv", ["# gain = 10", "t,v,v"] + data_lines())
    with pytest.raises(R.RecordError, match=r"line 2: column name 'v' \(columns\['input'\]\) "
                                            r"appears 2 times in the header \(columns 1, 2\)"):
        R.load_csv(path, **LOAD | dict(output=2))
    # a duplicated name nobody asks for is no ambiguity
    rec = R.load_csv(write(path, ["t,x,v,v"] + data_lines()), time="t", input=2, output="x",
                     header=True)
    assert len(rec) == 40


def test_header_true_on_a_file_without_header(tmp_path):
    path = write(tmp_path / "nh.csv", ["# gain = 10", ""] + data_lines())
    with pytest.raises(R.RecordError, match=r"line 3: the header line holds only numbers "
                                            r"\('0.000000', '0.00000', '0.00000'\): it looks "
                                            "like data; pass header=False"):
        R.load_csv(path, time=0, input=1, output=2, header=True)
    assert len(R.load_csv(path, time=0, input=1, output=2)) == 40


@pytest.mark.parametrize("ending, delimiter", [(",", ","), ("", " ")])
def test_header_true_on_data_with_empty_fields_is_refused(tmp_path, ending, delimiter):
    # a trailing delimiter, or runs of spaces, gave the first data row an empty "name":
    # header=True then dropped that row without a word
    rows = [f"{np.sin(k / 5):.5f}{delimiter}{np.cos(k / 5):.5f}{ending}" for k in range(40)]
    rows = [" " + row.replace(" ", "  ") for row in rows] if delimiter == " " else rows
    path = write(tmp_path / "data.csv", rows)
    with pytest.raises(R.RecordError, match=r"line 1: the header line holds only numbers "
                                            r"\('0.00000', '1.00000'\): it looks like data"):
        R.load_csv(path, input=0, output=1, fs=FS, header=True, delimiter=delimiter)


def test_one_column_for_two_signals_is_refused(tmp_path):
    path = write(tmp_path / "a.csv", good_lines())
    with pytest.raises(ValueError, match=r"input and output name the same column 1 \('v'\)"):
        R.load_csv(path, time="t", input="v", output=1, header=True)
    with pytest.raises(ValueError, match=r"input and time name the same column 0"):
        R.load_csv(write(tmp_path / "b.csv", good_lines(header=False)), time=0, input=0,
                   output=1)


@pytest.mark.parametrize("codec, encoding", [
    ("utf-8-sig", None), ("utf-16", None), ("utf-16-be", None), ("utf-32", None),
    ("latin-1", "latin-1"), ("cp1252", "cp1252"), ("utf-8-sig", "utf-8")])
def test_encodings(tmp_path, codec, encoding):
    text = "".join(f"{line}\r\n" for line in ["# unit = µm at 20 °C", "t,v [V],x [µm]"]
                   + data_lines())
    data = text.encode(codec)
    if codec == "utf-16-be":                       # as "utf-16" writes it, big-endian
        data = codecs.BOM_UTF16_BE + data
    path = tmp_path / "enc.csv"
    path.write_bytes(data)
    given = {} if encoding is None else {"encoding": encoding}      # None: found from the BOM
    rec = R.load_csv(path, time="t", input="v [V]", output="x [µm]", header=True, **given)
    assert len(rec) == 40 and rec.metadata["unit"] == "µm at 20 °C"
    assert rec.output[5] == pytest.approx(3 * np.sin(1.0), abs=1e-5)


def test_undecodable_files_name_the_line_and_the_encoding_to_pass(tmp_path):
    lines = ["t,v,x"] + data_lines()
    lines[6] = lines[6] + " µ"
    path = tmp_path / "l1.csv"
    path.write_bytes("".join(line + "\n" for line in lines).encode("latin-1"))
    with pytest.raises(R.RecordError, match=r"line 7: byte 0xb5 is not UTF-8 text .*"
                                            "pass its encoding, e.g. encoding='latin-1'"):
        R.load_csv(path, **LOAD)
    path.write_bytes("".join(line + "\n" for line in lines[:3]).encode("utf-16-le"))
    with pytest.raises(R.RecordError, match="line 1: NUL character: .* without a byte-order "
                                            "mark .*encoding='utf-16-le'"):
        R.load_csv(path, **LOAD)
    with pytest.raises(ValueError, match="unknown encoding"):
        R.load_csv(path, encoding="no-such-codec", **LOAD)


STRUCTURES = {
    "plain": lambda ls: ls,
    "CRLF": lambda ls: ls,
    "comment among the data": lambda ls: ls[:20] + ["# late = 7"] + ls[20:],
    "blank lines": lambda ls: ls[:9] + ["", "   "] + ls[9:] + ["", ""],
    "unused extra column": lambda ls: ls[:2] + [ls[2] + ",spare"] + [line + ",0.5"
                                                                      for line in ls[3:]],
    "trailing delimiter": lambda ls: ls[:3] + [line + "," for line in ls[3:]],
    "no last line end": lambda ls: ls,
}


@pytest.mark.parametrize("name", STRUCTURES)
def test_fast_read_and_line_by_line_reader_agree(tmp_path, monkeypatch, name):
    lines = STRUCTURES[name](["# gain = 10", "", "t,v,x"] + data_lines())
    end = "\r\n" if name == "CRLF" else "\n"
    path = tmp_path / "s.csv"
    path.write_bytes((end.join(lines) + ("" if name == "no last line end" else end)).encode())
    expected = [k + 1 for k, line in enumerate(lines) if line.strip() and line[0] != "#"][1:]
    columns = {"t": "t", "x": "x"}
    results = []
    for chunk in (reader._CHUNK, 7):              # small chunks: counts carried across chunks
        monkeypatch.setattr(reader, "_CHUNK", chunk)
        results.append(R.read_table(path, columns, header=True))
    monkeypatch.setattr(reader, "_read_fast", lambda *args: None)
    results.append(R.read_table(path, columns, header=True))
    for data, meta, numbers in results:
        assert list(numbers) == expected
        assert meta == results[-1][1] and meta["gain"] == 10
        for key in columns:
            assert np.array_equal(data[key], results[-1][0][key])
    assert results[0][0]["x"][5] == pytest.approx(3 * np.sin(1.0), abs=1e-5)
    if name == "comment among the data":
        assert results[0][1]["late"] == 7


def outcome(path, columns, header):
    try:
        data, meta, numbers = R.read_table(path, columns, header=header)
    except R.RecordError as exc:
        return str(exc)
    return {key: values.tolist() for key, values in data.items()}, meta, numbers.tolist()


cell = st.sampled_from(["1", "2.5", " -3e2 ", "1000", "", "nan", "x", "#1", "1,5"])
row = st.one_of(st.lists(cell, min_size=1, max_size=5).map(",".join),
                st.sampled_from(["", "  ", "# k = 2", " # note"]))


@settings(max_examples=150, deadline=None)
@given(rows=st.lists(row, max_size=8), header=st.booleans(), width=st.integers(1, 4),
       picked=st.lists(st.integers(0, 3), min_size=1, max_size=3),
       end=st.sampled_from(["\n", "\r\n", "\r"]), last_end=st.booleans(),
       chunk=st.sampled_from([3, 1 << 20]))
def test_fast_read_agrees_with_the_line_by_line_reader(rows, header, width, picked, end,
                                                       last_end, chunk):
    lines = ([",".join("abcd"[:width])] if header else []) + rows
    columns = {f"k{n}": col for n, col in enumerate(picked)}
    with tempfile.TemporaryDirectory() as folder, pytest.MonkeyPatch.context() as patch:
        path = Path(folder) / "h.csv"
        path.write_bytes((end.join(lines) + (end if last_end else "")).encode())
        patch.setattr(reader, "_CHUNK", chunk)
        fast = outcome(path, columns, header)
        patch.setattr(reader, "_read_fast", lambda *args: None)
        assert fast == outcome(path, columns, header)


def test_line_numbers_count_comment_lines_among_the_data(tmp_path):
    lines = ["# gain = 10", "t,v,x"] + data_lines()
    lines[30] = "0.005560" + lines[30][8:]                    # uneven step at file line 31
    lines = lines[:10] + ["# a note", ""] + lines[10:]
    with pytest.raises(R.RecordError, match="uneven sampling") as info:
        R.load_csv(write(tmp_path / "n.csv", lines), **LOAD)
    assert info.value.line == 33


@pytest.mark.parametrize("row, thousands, decimal", [
    ("0.001000;0.031411;1234.352240", ".", ","),     # '.' amid digits not grouped in threes
    ("0;1,2,3.5;1.0", ",", "."),                      # ',' between single digits
])
def test_a_thousands_separator_that_groups_no_thousands_is_refused(tmp_path, row, thousands,
                                                                   decimal):
    # pandas reads both (y = 1234352240 and fs = 0.001 Hz; 123.5) without a word
    path = tmp_path / "rec.csv"
    path.write_text("t;u;y\n" + "\n".join([row] * 40) + "\n")
    with pytest.raises(R.RecordError, match="is not a number"):
        R.load_csv(path, time=0, input=1, output=2, header=True, delimiter=";",
                         decimal=decimal, thousands=thousands)


def test_numbers_grouped_in_thousands_read_as_written(tmp_path):
    path = tmp_path / "rec.csv"
    path.write_text("t;u;y\n" + "".join(f"{k},0;1.234,5;-2.000.000,25\n" for k in range(40)))
    rec = R.load_csv(path, time=0, input=1, output=2, header=True, delimiter=";",
                           decimal=",", thousands=".")
    assert rec.fs == 1.0 and set(rec.input) == {1234.5} and set(rec.output) == {-2000000.25}
