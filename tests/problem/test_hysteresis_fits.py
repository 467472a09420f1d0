"""The paper's Dahl model (published parameters) and the workbook's fit to the Case I loops."""

import json

import numpy as np
import pytest

from piezolib import hysteresis as hy
from piezolib import paper, signals
from piezolib.problem import hysteresis_fits as ph

FS = paper.SAMPLING_FREQUENCY_HZ


@pytest.mark.parametrize("form", hy.FORMS)
def test_published_model_is_the_printed_parameters(form):
    m = ph.published_dahl(form)
    assert (m.alpha1, m.alpha2, m.beta1, m.beta2, m.gamma_a, m.g_a) == (
        paper.DAHL.alpha1, paper.DAHL.alpha2, paper.DAHL.beta1, paper.DAHL.beta2,
        paper.DAHL.gamma_a, paper.DAHL.g_a)
    assert m.form == form and m.x0 == 0.0 and m.start == "virgin"     # eq. 13 exactly
    assert ph.published_dahl().form == "printed"
    with pytest.raises(TypeError, match="paper.DahlParameters"):
        ph.published_dahl(form, params=dict(alpha1=1.0))


@pytest.mark.parametrize("direction", [1, -1])
def test_printed_form_settles_to_same_H_both_ways(direction):
    m = ph.published_dahl("printed")
    expected = paper.DAHL.beta2 * paper.DAHL.gamma_a / paper.DAHL.alpha2
    assert m.steady_state(direction) == pytest.approx(expected, rel=1e-12)
    # a long stroke either way after a long stroke the other way: H stays at the steady state
    x = np.r_[np.linspace(0, 1, 101), np.linspace(1, -1, 201)[1:]] * direction
    H = hy.dahl_hysteresis(m, x)
    np.testing.assert_allclose(H[50:], expected, rtol=1e-9)


def test_feedforward_of_published_model_is_offset_only():
    """Printed form, published numbers: after the first transient u_f = (x_r + 26.97)/g_a."""
    m = ph.published_dahl("printed")
    t, x_r = signals.triangle(3.6, 10.0, fs=FS, periods=2)
    u_f = hy.feedforward(m, x_r)
    np.testing.assert_allclose(u_f[100:], (x_r[100:] + m.steady_state(1)) / m.g_a, rtol=1e-9)


def test_strongly_underdamped_model_is_not_invertible():
    m = ph.published_dahl("bliman_sorine")   # H overshoots: x + H(x) not monotone
    t, v = signals.triangle(4.0, 10.0, fs=FS, periods=1)
    with pytest.raises(hy.NotInvertibleError, match="not increasing"):
        hy.simulate_dahl(m, v)


def test_candidates_and_workbook_choice():
    assert len(ph.CASE_I_CANDIDATES) == 6 and ph.WORKBOOK_DAHL in ph.CASE_I_CANDIDATES
    assert ("printed", False, "rest") not in ph.CASE_I_CANDIDATES


def test_workbook_fit_is_shared_and_deterministic():
    first = ph.workbook_dahl_fit()
    assert ph.workbook_dahl_fit() is first                    # cached: one model everywhere
    # on the workbook's data: the committed model, checked against the refit
    assert first.model == ph.read_dahl_model(ph.workbook_dahl_path())
    refit = ph.fit_case_I_loops(*ph.WORKBOOK_DAHL)
    np.testing.assert_allclose(first.rms_percent, refit.rms_percent, rtol=1e-5)
    form, offset, start = ph.WORKBOOK_DAHL
    assert (first.model.form, first.offset, first.model.start) == (form, offset, start)
    assert first.model.gamma_a == paper.DAHL.gamma_a          # held at the published value
    ph._clear_cache()
    again = ph.workbook_dahl_fit()
    assert again is not first and again.model == first.model  # refitted, same stored model
    np.testing.assert_array_equal(again.rms_percent, first.rms_percent)
    with pytest.raises(TypeError, match="offset must be True or False"):
        ph.fit_case_I_loops("bliman_sorine", 1, "rest")
    with pytest.raises(ValueError, match="start must be one of"):
        ph.fit_case_I_loops("bliman_sorine", True, "lowered")
    with pytest.raises(ValueError, match="form must be one of"):
        ph.fit_case_I_loops("first_order", True, "rest")


def test_a_stored_model_off_the_fits_optimum_is_refused(tmp_path, monkeypatch):
    from dataclasses import replace

    model = ph.read_dahl_model(ph.workbook_dahl_path())
    # a rounding-size move (1e-9 of alpha1) is the same optimum; 1 % of alpha2 is not
    for name, factor, ok in (("on the valley", 1.0 + 1e-9, True), ("alpha2", 1.01, False)):
        moved = (replace(model, alpha1=model.alpha1 * factor) if ok else
                 replace(model, alpha2=model.alpha2 * factor))
        path = ph.write_dahl_model(moved, tmp_path / f"{name}.json")
        monkeypatch.setattr(ph, "workbook_dahl_path", lambda path=path: path)
        if ok:
            assert ph.workbook_dahl_fit().model == moved
        else:
            with pytest.raises(ValueError, match="no longer matches the fit"):
                ph.workbook_dahl_fit()
    (tmp_path / "bad.json").write_text('{"format": 1, "model": {"alpha1": 1}}')
    with pytest.raises(ValueError, match="not a Dahl model file"):
        ph.read_dahl_model(tmp_path / "bad.json")
    with pytest.raises(TypeError, match="DahlModel"):
        ph.write_dahl_model("model", tmp_path / "x.json")


def test_a_shared_check_is_keyed_on_the_stored_file_and_still_refuses_a_moved_model(
        tmp_path, monkeypatch):
    from dataclasses import replace

    store, calls = {}, []

    def shared(func, *args):             # a dict as the cache shared between processes
        calls.append(args[1:])
        if args not in store:
            store[args] = func(*args)
        return store[args]

    ph.share_stored_model_check(shared)
    try:
        first = ph.workbook_dahl_fit()
        ph._stored_fit.cache_clear()                    # another process: served by the store
        assert ph.workbook_dahl_fit() is first and len(store) == 1
        model = ph.read_dahl_model(ph.workbook_dahl_path())
        path = ph.write_dahl_model(replace(model, alpha2=model.alpha2 * 1.01), tmp_path / "m.json")
        monkeypatch.setattr(ph, "workbook_dahl_path", lambda: path)
        with pytest.raises(ValueError, match="no longer matches the fit"):
            ph.workbook_dahl_fit()                      # another file: another key, checked
        assert len({key for key in calls}) == 2 and len(store) == 1
    finally:
        ph.share_stored_model_check(None)
    with pytest.raises(TypeError, match="call must be a callable or None"):
        ph.share_stored_model_check("cache")


def test_an_edited_dahl_model_file_is_refused(tmp_path, monkeypatch):
    committed = ph.workbook_dahl_path()
    text = committed.read_text()
    model = ph.read_dahl_model(committed)                     # intact: reads
    # written and read back: the same model, bit for bit, through its checksum
    assert ph.read_dahl_model(ph.write_dahl_model(model, tmp_path / "again.json")) == model
    copy = tmp_path / "workbook_dahl.json"
    edited = text.replace(repr(model.alpha2), repr(float(np.nextafter(model.alpha2, 0))))
    assert edited != text
    copy.write_text(edited)
    with pytest.raises(ValueError, match=r"workbook_dahl\.json: content differs from its "
                                         r"checksum: the file was edited or corrupted"):
        ph.read_dahl_model(copy)
    # at the committed place, the message names the command that writes it anew
    monkeypatch.setattr(ph, "workbook_dahl_path", lambda: copy)
    with pytest.raises(ValueError, match="differs.*`python -m piezolib controllers "
                                         "--write-reference`"):
        ph.read_dahl_model(copy)
    # the committed file carries its checksum, after the format; a file without one is not
    # one this version wrote
    doc = json.loads(text)
    assert list(doc)[:2] == ["format", "content_sha256"]
    del doc["content_sha256"]
    copy.write_text(json.dumps(doc, indent=1) + "\n")
    with pytest.raises(ValueError, match="not a Dahl model file written by this version"):
        ph.read_dahl_model(copy)
    copy.write_text("[]")
    with pytest.raises(ValueError, match="not a Dahl model file"):
        ph.read_dahl_model(copy)


@pytest.mark.parametrize("text", ["{not json", ""])
def test_a_file_that_is_no_model_is_refused_naming_it(tmp_path, text):
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(ValueError, match=r"bad\.json: not a Dahl model file"):
        ph.read_dahl_model(path)


def test_workbook_pi_fit_and_validation_records():
    fit = ph.workbook_pi_fit()
    assert ph.workbook_pi_fit() is fit                         # cached
    assert len(fit.model.thresholds) == ph.PI_PLAYS and fit.model.invertible
    assert fit.worst_rms_percent < 1.0
    records = ph.validation_loops()
    assert list(records)[:3] == [f"triangle {A:.0f} V" for A in ph.VALIDATION_AMPLITUDES_V]
    for u, v_y, first in records.values():
        assert u.shape == v_y.shape and u[0] == 0.0 and 0 < first < u.size
        assert u.min() >= 0.0 and u.max() <= 4.0              # inside the 0-40 V stroke
    with pytest.raises(ValueError, match="n_plays must be >= 1"):
        ph.workbook_pi_fit(n_plays=0)
