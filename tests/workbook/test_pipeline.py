"""The pipeline's controller artifacts: committed for the reference, cached for other studies."""

import json

import control as ct
import numpy as np
import pytest

from piezolib import paper
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
