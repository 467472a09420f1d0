"""Records: the loader's errors name file and line; helpers."""

import numpy as np
import pytest

from piezolib import records as R

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


def test_record_checks_its_arrays():
    with pytest.raises(R.RecordError, match="equal lengths"):
        R.Record(np.zeros(5), np.zeros(4), FS)
    with pytest.raises(ValueError, match="output"):
        R.Record(np.zeros(5), [0, 1, np.nan, 0, 0], FS)
    with pytest.raises(R.RecordError, match="time sample 3"):
        R.Record.from_time([0, 1, 2, 2, 3], np.arange(5.0), np.arange(5.0))
    rec = R.Record.from_time(0.5 + np.arange(10) / FS, np.arange(10.0), np.arange(10.0))
    assert rec.fs == pytest.approx(FS) and rec.t0 == 0.5
    seg = rec.segment(4, 8)
    assert len(seg) == 4 and seg.t0 == pytest.approx(0.5 + 4 / FS)


def loop_record(periods=4, fs=FS, f=10.0, rest=250, noise=0.0):
    n = int(periods * fs / f)
    u = np.r_[np.zeros(rest), 2.0 + 1.5 * np.sin(2 * np.pi * f * np.arange(n) / fs)]
    y = 3 * u + noise * np.random.default_rng(0).standard_normal(len(u))
    return R.Record(u, y, fs, output_unit="um")


def test_turning_points_and_cut_ignore_noise_and_the_start():
    rec = loop_record()
    points = R.turning_points(rec.input)
    quarter = FS / 10 / 4
    expected = 250 + quarter + 2 * quarter * np.arange(8)
    assert len(points) == 8 and np.all(np.abs(points - expected) <= 1)
    noisy = rec.input + 0.003 * np.random.default_rng(1).standard_normal(len(rec))
    assert len(R.turning_points(noisy)) == 8                       # noise makes no extra points
    cut = R.cut_at_turning_points(rec)
    assert cut.metadata["cut"] == (points[0], points[-1] + 1)
    assert cut.input[0] == rec.input[points[0]] and cut.t0 == pytest.approx(points[0] / FS)
    with pytest.raises(R.RecordError, match="turning point"):
        R.cut_at_turning_points(R.Record(np.arange(100.0), np.arange(100.0), FS))


def test_decimate_filters_before_keeping_samples():
    fs, n = 10e3, 20000
    t = np.arange(n) / fs
    slow, fast = np.sin(2 * np.pi * 20 * t), 0.5 * np.sin(2 * np.pi * 3900 * t)
    rec = R.Record(slow + fast, slow, fs)
    dec = R.decimate(rec, 5)
    assert dec.fs == 2000.0 and len(dec) == n // 5
    inner = slice(100, -100)
    # 3.9 kHz would alias to 100 Hz at 2 kHz: the filter removes it instead
    assert np.max(np.abs(dec.input[inner] - slow[::5][inner])) < 0.01
    assert R.decimate(rec, 1) is rec
    with pytest.raises(R.RecordError, match="too short"):
        R.decimate(R.Record(np.arange(50.0), np.arange(50.0), fs), 5)


def test_split_and_detrend():
    rec = loop_record()
    first, second = R.split(rec, 0.25)
    assert len(first) + len(second) == len(rec)
    assert len(first) == round(0.25 * len(rec))
    assert second.t0 == pytest.approx(len(first) / FS)
    with pytest.raises(ValueError, match="fraction"):
        R.split(rec, 1.0)
    flat = R.detrend(rec.with_signals(output=rec.output + 2.0 + np.arange(len(rec)) * 1e-3),
                     kind="linear")
    assert abs(np.polyfit(np.arange(len(rec)), flat.output, 1)[0]) < 1e-12
    assert np.array_equal(flat.input, rec.input)
    with pytest.raises(ValueError, match="which"):
        R.detrend(rec, which="time")
