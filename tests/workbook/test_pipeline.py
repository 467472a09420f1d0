"""The pipeline's controller artifacts: committed for the reference, cached for other studies."""

import json
import logging
from types import SimpleNamespace

import control as ct
import numpy as np
import pytest

from piezolib import paper, robust
from piezolib.problem import analysis
from piezolib.workbook import pipeline, study


def test_study_problem_takes_the_study_weights():
    wide = study.Study().replace(name="wide", weights={"omega_e": 2500.0})
    G, H_m, H_e, H_y, K = pipeline.study_problem(wide)
    published = paper.problem()
    assert np.allclose(H_e.num[0][0], paper.error_weight(omega_e=2500.0).num[0][0])
    assert np.allclose(H_y.den[0][0], published.H_y.den[0][0])
    assert np.allclose(G.den[0][0], published.G.den[0][0])


def test_the_uncertainty_weight_is_a_study_choice():
    reference = study.load("reference")
    published = pipeline.study_uncertainty_weight(reference)
    omega = np.logspace(0, 6, 200)
    np.testing.assert_allclose(published(1j * omega), paper.uncertainty_weight()(1j * omega))
    assert pipeline.study_problem(reference).H_m is published
    # a spread change alone keeps the published H_m, so the design (and its controllers) too
    narrow = reference.replace(name="narrow", uncertainty={"spread": 0.03})
    assert pipeline.design_digest(narrow) == pipeline.design_digest(reference)
    fitted = reference.replace(name="fitted", uncertainty={"weight": "fitted", "weight_order": 3,
                                                           "weight_grid": [1.0, 1e6, 400]})
    H_m = pipeline.study_uncertainty_weight(fitted)
    assert H_m.ninputs == H_m.noutputs == 1 and len(H_m.poles()) == 3
    assert H_m.input_labels == ["u_c"] and H_m.output_labels == ["y_Delta"]
    assert np.all(H_m.poles().real < 0) and np.all(H_m.zeros().real < 0)
    # it covers the envelope of the set it was fitted to, on its grid
    from piezolib import robust, uncertainty
    grid = robust.frequency_grid(1.0, 1e6, 400)
    envelope = uncertainty.relative_error_envelope(
        uncertainty.model_set(paper.plant(), 0.05, 3), grid, "stable")
    assert np.all(np.abs(np.ravel(H_m(1j * grid))) >= envelope * (1 - 1e-9))
    # a fitted weight depends on the set: the spread now changes the design
    digests = {pipeline.design_digest(s) for s in
               (reference, fitted, fitted.replace(name="f2", uncertainty={"spread": 0.03}))}
    assert len(digests) == 3


def test_committed_reference_controllers_match_their_recorded_mu():
    found = pipeline.study_controllers("reference")
    assert found.digest == pipeline.design_digest(study.Study())
    assert found.K_fixed.nstates == 6 and found.K_nodelay_reduced.nstates == 6
    G, H_m, H_e, H_y, _ = paper.problem()
    # independent recomputation: mu_RP of eq. 18 of the committed no-delay full-order K is at most
    # the DK value recorded with it (its synthesis plant adds an effort output)
    result = analysis.analyze(found.K_nodelay_full, G, H_m, H_e, H_y)
    assert result.nominal_stability
    assert result.mu_RP <= found.mu["no-delay DK"] + 2e-3
    assert result.mu_RP >= found.mu["no-delay DK"] - 0.02
    assert result.mu_RP < 0.85
    # the reason for the delay-aware design: one sample of delay destabilises the no-delay K
    Kd = robust.discretize(found.K_nodelay_reduced, paper.SAMPLING_FREQUENCY_HZ).K
    radii = [robust.sampled_loop_radius(G, Kd, d) for d in (0, 1)]
    assert radii[0] < 1 < radii[1]


def test_write_read_round_trip_is_bit_exact(tmp_path):
    K = ct.ss([[-1.0 / 3.0, 1e-17], [2.0, -7.0]], [[1.0], [np.pi]], [[np.e, 1e300]], [[0.1]],
              inputs=["v_e"], outputs=["u_b"], name="K")
    fake = pipeline.StudyControllers(
        study="reference", digest="abc", source="test", K_full=K, K_reduced=K, K_fixed=K,
        K_nodelay_full=K, K_nodelay_reduced=K, mu={"fixed order": 0.1 + 0.2})
    path = pipeline.write_controllers(fake, tmp_path / "k.json", "reference")
    back = pipeline.read_controllers(path)
    for m in "ABCD":
        assert np.array_equal(getattr(back.K_fixed, m), getattr(K, m))
    assert back.mu == {"fixed order": 0.1 + 0.2} and back.K_full.input_labels == ["v_e"]
    doc = json.loads(path.read_text())
    assert len(doc["content_sha256"]) == 64                     # written with its checksum
    doc["format"] = 99
    path.write_text(json.dumps(doc))
    with pytest.raises(pipeline.ArtifactError, match="format 99"):
        pipeline.read_controllers(path)
    path.write_text('{"format": 1}')
    with pytest.raises(pipeline.ArtifactError, match="not a controller artifact"):
        pipeline.read_controllers(path)


def test_reference_artifact_for_other_choices_is_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    with pytest.raises(pipeline.ArtifactError, match="missing.*--write-reference"):
        pipeline.study_controllers("reference")
    K = ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]], inputs=["v_e"], outputs=["u_b"], name="K")
    stale = pipeline.StudyControllers(
        study="reference", digest="0000", source="test", K_full=K, K_reduced=K, K_fixed=K,
        K_nodelay_full=K, K_nodelay_reduced=K, mu={})
    pipeline.write_controllers(stale, pipeline.reference_design_path(), "reference")
    with pytest.raises(pipeline.ArtifactError, match="designed for other choices"):
        pipeline.study_controllers("reference")


def test_derived_controllers_are_cached_on_disk(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    monkeypatch.setenv(pipeline.CACHE_ENV, str(tmp_path / "cache"))
    small = study.Study().replace(name="small", design={"max_iter": 2, "d_order": 1})
    first = pipeline.study_controllers(small)
    assert first.source == "derived (now cached)"
    again = pipeline.derive_controllers(small)
    assert again.source == "disk cache"
    assert np.array_equal(again.K_fixed.A, first.K_fixed.A) and again.mu == first.mu
    written = pipeline.read_controllers(tmp_path / "runs" / "small" / "artifacts" / "controllers.json")
    assert written.digest == pipeline.design_digest(small)
    assert np.array_equal(written.K_fixed.A, first.K_fixed.A)
    # the design honours the study: D-fits of order 1, so at most 14 + 2 x 1 states
    history = first.nodelay.musyn.history
    assert len(history) <= 2 and history.d_order.max() == 1
    assert first.K_nodelay_full.nstates <= 14 + 2 * 1


def test_a_study_with_the_reference_design_choices_uses_the_committed_controllers(
        tmp_path, monkeypatch):
    # e.g. uncertainty_3pct: only the uncertainty section differs, so its controllers must be
    # the reference's (a re-derivation could follow another DK path on another machine)
    reference = pipeline.study_controllers("reference")
    monkeypatch.setattr(pipeline, "derive_controllers",
                        lambda *a, **k: pytest.fail("re-derived the reference design"))
    spread = study.Study().replace(name="spread", uncertainty={"spread": 0.03})
    monkeypatch.setattr(study.Study, "output_dir", property(lambda s: tmp_path / s.name))
    found = pipeline.study_controllers(spread)
    assert np.array_equal(found.K_fixed.A, reference.K_fixed.A) and found.mu == reference.mu
    assert (tmp_path / "spread" / "artifacts" / "controllers.json").is_file()


def test_a_study_with_the_reference_design_choices_uses_the_committed_mixed_designs(
        tmp_path, monkeypatch):
    # the mixed designs depend on the plant, weights, deployed K and loop rate, not on the
    # study's uncertainty: a changed spread must not re-run nine D,G-K searches
    monkeypatch.setattr(pipeline, "derive_mixed_designs",
                        lambda *a, **k: pytest.fail("re-designed the mixed controllers"))
    monkeypatch.setattr(study.Study, "output_dir", property(lambda s: tmp_path / s.name))
    spread = study.Study().replace(name="spread", uncertainty={"spread": 0.03})
    found, committed = pipeline.study_mixed_designs(spread), pipeline.study_mixed_designs(
        "reference")
    assert [d.mu_peak for d in found.designs] == [d.mu_peak for d in committed.designs]
    assert np.array_equal(pipeline.study_mixed_sections(spread).sos,
                          pipeline.study_mixed_sections("reference").sos)
    other = study.Study().replace(name="wide", weights={"M_e": 3.0})
    with pytest.raises(pytest.fail.Exception, match="re-designed"):
        pipeline.study_mixed_designs(other)


def test_reference_sections_are_the_committed_exports(tmp_path, monkeypatch):
    from piezolib.robust import export

    sections = pipeline.study_sections("reference")
    assert set(sections) == set(pipeline.SECTION_FILES)
    committed = pipeline.outputs.data_dir() / "controllers"
    for stem, sos in sections.items():
        np.testing.assert_array_equal(
            sos.sos, export.read_json(committed / f"{stem}.json", "float32").sos)
    # a fresh export of the committed controllers: the float64 coefficients agree to rounding
    # (another BLAS kernel moves them by ~1e-10), so a float32 one moves by one unit at most
    fresh = pipeline.export_sections("reference", tmp_path)
    for stem, sos in sections.items():
        np.testing.assert_allclose(fresh[stem].coefficients("float32"),
                                   sos.coefficients("float32"), rtol=2.0 ** -23, atol=0)
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    with pytest.raises(pipeline.ArtifactError, match="write-reference"):
        pipeline.study_sections("reference")


# --- the disk cache: every entry checked on reading ---------------------------------------------

FAKE_RUNS = []


def fake_design_pair(uncertainty, weights, design, loop, fingerprint):
    """Stands for the DK design (minutes): records of a stable 30-state controller."""
    FAKE_RUNS.append(design)
    rng = np.random.default_rng(design["max_iter"])
    n = 30
    K = ct.ss(-np.diag(np.arange(1.0, n + 1)) + 0.01 * rng.standard_normal((n, n)),
              rng.standard_normal((n, 1)), rng.standard_normal((1, n)), [[0.0]],
              inputs=["v_e"], outputs=["u_b"], name="K")
    record = SimpleNamespace(K_full=K, K_reduced=K, K_fixed=K,
                             musyn=SimpleNamespace(mu_peak=0.9),
                             fixed_order=SimpleNamespace(mu_peak=0.95))
    return record, record


@pytest.fixture
def fake_cache(tmp_path, monkeypatch):
    """A disk cache in tmp_path, in front of :func:`fake_design_pair`; returns the cache folder."""
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    monkeypatch.setenv(pipeline.CACHE_ENV, str(tmp_path / "cache"))
    monkeypatch.setattr(pipeline, "_design_pair", fake_design_pair)
    FAKE_RUNS.clear()
    return tmp_path / "cache"


SMALL = study.Study().replace(name="small", design={"max_iter": 2})


def assert_same_controllers(found, fresh):
    for name in ("K_full", "K_reduced", "K_fixed", "K_nodelay_full", "K_nodelay_reduced"):
        for m in "ABCD":
            np.testing.assert_array_equal(getattr(getattr(found, name), m),
                                          getattr(getattr(fresh, name), m), err_msg=name)
    assert found.mu == fresh.mu


def cached_entry(folder):
    [entry] = folder.rglob("output.pkl")
    return entry


def test_a_cache_entry_with_a_flipped_bit_is_recomputed_not_served(fake_cache, caplog):
    first = pipeline.derive_controllers(SMALL)
    assert first.source == "derived (now cached)" and len(FAKE_RUNS) == 1
    hit = pipeline.derive_controllers(SMALL)
    assert hit.source == "disk cache" and len(FAKE_RUNS) == 1
    entry = cached_entry(fake_cache)
    raw = bytearray(entry.read_bytes())
    raw[len(raw) // 2] ^= 0x08                     # one bit, amid the stored matrices
    entry.write_bytes(bytes(raw))
    with caplog.at_level(logging.WARNING, logger=pipeline.__name__):
        found = pipeline.derive_controllers(SMALL)
    assert_same_controllers(found, pipeline.derive_controllers(SMALL, cache=False))
    assert found.source == "recomputed (cache entry failed its checksum)"
    assert len(FAKE_RUNS) == 3 and "failed its checksum" in caplog.text   # (+1: cache=False)
    # the entry was stored anew: the next call reads it
    again = pipeline.derive_controllers(SMALL)
    assert again.source == "disk cache" and len(FAKE_RUNS) == 3
    assert_same_controllers(again, found)


def test_a_cache_entry_swapped_for_another_calls_is_recomputed_not_served(fake_cache, caplog):
    # two valid entries; the file of one copied over the other's: the seal covers the key the
    # entry belongs to, so the other arguments' value is not served as "disk cache"
    pipeline.checked_cache_call(fake_design_pair, {}, {}, {"max_iter": 3}, {}, "x")
    pipeline.checked_cache_call(fake_design_pair, {}, {}, {"max_iter": 4}, {}, "x")
    first, second = sorted(fake_cache.rglob("output.pkl"), key=lambda p: p.stat().st_mtime)
    second.write_bytes(first.read_bytes())
    with caplog.at_level(logging.WARNING, logger=pipeline.__name__):
        value, source = pipeline.checked_cache_call(fake_design_pair, {}, {}, {"max_iter": 4},
                                                    {}, "x")
    assert source == "recomputed (cache entry failed its checksum)"
    expected = fake_design_pair({}, {}, {"max_iter": 4}, {}, "x")[0].K_full
    np.testing.assert_array_equal(value[0].K_full.A, expected.A)
    assert len(FAKE_RUNS) == 4 and "failed its checksum" in caplog.text


@pytest.mark.filterwarnings("ignore:.*Exception while loading results:UserWarning")
def test_a_truncated_cache_entry_is_recomputed_and_says_so(fake_cache, caplog):
    first = pipeline.derive_controllers(SMALL)
    entry = cached_entry(fake_cache)
    raw = entry.read_bytes()
    entry.write_bytes(raw[:len(raw) // 2])
    with caplog.at_level(logging.WARNING, logger=pipeline.__name__):
        found = pipeline.derive_controllers(SMALL)
    assert found.source == "recomputed (cache entry unreadable)"
    assert len(FAKE_RUNS) == 2 and "could not be read" in caplog.text
    assert_same_controllers(found, first)
    assert pipeline.derive_controllers(SMALL).source == "disk cache"


def test_checked_cache_call_keys_by_function_and_arguments(fake_cache, monkeypatch):
    value, source = pipeline.checked_cache_call(fake_design_pair, {}, {}, {"max_iter": 3}, {}, "x")
    assert source == "derived (now cached)" and value[0].musyn.mu_peak == 0.9
    assert pipeline.checked_cache_call(fake_design_pair, {}, {}, {"max_iter": 3}, {}, "x")[1] \
        == "disk cache"
    assert pipeline.checked_cache_call(fake_design_pair, {}, {}, {"max_iter": 4}, {}, "x")[1] \
        == "derived (now cached)"
    assert len(FAKE_RUNS) == 2
    monkeypatch.setenv(pipeline.CACHE_ENV, "off")
    assert pipeline.derive_controllers(SMALL).source == "derived (disk cache off)"


# --- controller artifacts carry a checksum of their content -------------------------------------

def edit_one_number(text, number):
    """``text`` with the first ``repr(number)`` replaced by the next double down."""
    edited = text.replace(repr(number), repr(float(np.nextafter(number, -np.inf))), 1)
    assert edited != text
    return edited


def test_an_edited_controller_artifact_is_refused(tmp_path, monkeypatch):
    committed = pipeline.reference_design_path()
    text = committed.read_text()
    found = pipeline.read_controllers(committed)                  # intact: reads
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    copy = pipeline.reference_design_path()
    copy.parent.mkdir(parents=True)
    copy.write_text(edit_one_number(text, float(found.K_fixed.A[0, 0])))
    with pytest.raises(pipeline.ArtifactError,
                       match=r"reference_design\.json: content differs from its checksum: the "
                             r"file was edited or corrupted; write it anew with "
                             r"`python -m piezolib controllers --write-reference`"):
        pipeline.read_controllers(copy)
    with pytest.raises(pipeline.ArtifactError, match="differs from its checksum"):
        pipeline.study_controllers("reference")
    # the committed file carries its checksum, after the format, and a file without one is
    # not one this version wrote
    doc = json.loads(text)
    assert list(doc)[:2] == ["format", "content_sha256"]
    del doc["content_sha256"]
    copy.write_text(json.dumps(doc, indent=1) + "\n")
    with pytest.raises(pipeline.ArtifactError,
                       match="not a controller artifact written by this version.*"
                             "--write-reference"):
        pipeline.read_controllers(copy)
    # a study's own file names the run that writes it
    other = tmp_path / "runs" / "small" / "artifacts" / "controllers.json"
    other.parent.mkdir(parents=True)
    other.write_text(edit_one_number(text, found.mu["fixed order"]).replace(
        '"study": "reference"', '"study": "small"'))
    with pytest.raises(pipeline.ArtifactError, match="reproduce --study small"):
        pipeline.read_controllers(other)
    copy.write_text("[1, 2]")
    with pytest.raises(pipeline.ArtifactError, match="not a controller artifact"):
        pipeline.read_controllers(copy)


# --- the mixed-mu designs of notebook 09 --------------------------------------------------------

def _fake_mixed():
    K1 = ct.ss([[-1.0]], [[1.0]], [[0.5]], [[0.1]], inputs=["v_e"], outputs=["u_b"], name="K1")
    K2 = ct.ss([[-2.0]], [[1.0]], [[1 / 3]], [[0.0]], inputs=["v_e"], outputs=["u_b"], name="K2")
    from piezolib.problem.design import MixedDesign
    designs = tuple(MixedDesign(K=K, performance_scale=s, spread=0.05, mu_peak=0.9,
                                mu_lower_peak=0.8, start_mu_peak=1.5,
                                margins={0: 0.06, 1: 0.051}, steps=None)
                    for s, K in ((0.1, K1), (0.2, K2)))
    return pipeline.MixedDesigns(study="reference", designs=designs, source="test")


def test_mixed_designs_round_trip_bit_exact_and_refuse_an_edit(tmp_path):
    designs = _fake_mixed()
    path = pipeline.write_mixed_designs(designs, tmp_path / "mixed.json", "reference")
    back = pipeline.read_mixed_designs(path)
    assert back.chosen.performance_scale == 0.2 and back.chosen.K.name == "K2"
    for a, b in zip(designs.designs, back.designs):
        assert a.margins == b.margins and a.performance_scale == b.performance_scale
        for m in "ABCD":
            np.testing.assert_array_equal(getattr(a.K, m), getattr(b.K, m))
    doc = json.loads(path.read_text())
    doc["designs"][0]["mu_peak"] = 0.5
    path.write_text(json.dumps(doc))
    with pytest.raises(pipeline.ArtifactError, match="mixed.json"):
        pipeline.read_mixed_designs(path)


def test_the_committed_mixed_designs_and_sections_are_readable():
    designs = pipeline.study_mixed_designs("reference")
    chosen = designs.chosen
    assert chosen in designs.designs
    assert chosen.K.nstates == pipeline.study_controllers("reference").K_deployed.nstates
    sections = pipeline.study_mixed_sections("reference")
    # the sections are the chosen controller, discretised: same DC gain to float32 rounding
    k_dc = float(np.real(chosen.K(0.0 + 1e-9j)))
    assert sections.to_statespace("float32").dcgain() == pytest.approx(k_dc, rel=1e-4)
