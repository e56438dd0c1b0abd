"""diagnose, follow, the HTML report, subspace."""

import os

import numpy as np
import pytest

import hammerstein as hs
from conftest import simulate_block


@pytest.fixture(scope="module")
def linear_on_saturation(noisy_sat_record):
    u, y = noisy_sat_record
    return hs.diagnose(hs.Hammerstein(order=2), u, y, validate=0.3)


def test_a_linear_model_of_a_saturation_is_not_adequate(linear_on_saturation):
    d = linear_on_saturation
    assert isinstance(d, hs.Diagnosis)
    assert d.adequate is False
    assert d.suggestions, d.summary
    top = d.suggestions[0]
    assert isinstance(top, hs.Suggestion)
    assert top.effect == "saturation", [s.effect for s in d.suggestions]
    assert top.input == "u"
    assert top.train_mse_after < top.train_mse_before
    assert 0.0 < top.expected_gain <= 1.0
    assert isinstance(top.estimate, dict)
    assert all(isinstance(e, hs.Estimate) for e in top.estimates)
    assert d.tests and all("p_adjusted" in t for t in d.tests)
    assert d.validation.n == 240 and d.train.n == 560
    assert d.steps == [] and d.stop is None
    assert isinstance(d.model, hs.Model)
    assert isinstance(d.summary, str) and d.summary


def test_diagnose_a_fitted_model_refits_its_settings(noisy_sat_record):
    u, y = noisy_sat_record
    m = hs.Hammerstein(effects=["saturation"], order=2).fit(u, y)
    d = hs.diagnose(m, u, y, validate=0.3)
    assert d.model.parameters.keys() == m.parameters.keys()
    assert d.train.n == 560
    # a fitted model of the right structure leaves the residuals to the noise
    assert d.validation.fit_percent > 95.0
    # validation given as a record
    d2 = hs.diagnose(m, u[:560], y[:560], validate=(u[560:], y[560:]))
    assert d2.validation.fit_percent == pytest.approx(d.validation.fit_percent, rel=1e-12)


def test_follow_adds_the_saturation(noisy_sat_record, tmp_path):
    u, y = noisy_sat_record
    d = hs.diagnose(hs.Hammerstein(order=2), u, y, validate=0.3, follow=True, max_steps=3)
    assert len(d.steps) >= 2
    assert all(isinstance(s, hs.Step) for s in d.steps)
    assert d.steps[0].change == "start"
    assert d.steps[-1].model is d.model
    assert "saturation" in d.model.effects
    assert d.stop
    first, last = d.steps[0].diagnosis, d.steps[-1].diagnosis
    assert last.validation.fit_percent > first.validation.fit_percent
    page = d.to_html(tmp_path / "report")
    assert os.path.isfile(page) and page.endswith(".html")
    svgs = [f for f in os.listdir(tmp_path / "report") if f.endswith(".svg")]
    assert svgs
    html = open(page).read()
    assert "<svg" in html or ".svg" in html


def test_subspace_recovers_a_linear_block():
    rng = np.random.default_rng(7)
    u = rng.standard_normal(1000)
    y = simulate_block(u) + 0.01 * rng.standard_normal(1000)
    s = hs.subspace(u, y, method="moesp", order="auto")
    assert s.order == 2
    A, B, C, D = s
    assert A.shape == (2, 2) and B.shape == (2, 1) and C.shape == (1, 2) and D.shape == (1, 1)
    truth = np.sort_complex(np.roots([1.0, -1.2, 0.5]))
    assert np.allclose(np.sort_complex(np.linalg.eigvals(A)), truth, atol=1e-2)
    assert abs(D[0, 0]) < 1e-2
    n4 = hs.subspace(u, y, method="n4sid", order=2, horizon=8)
    assert n4.horizon == 8 and n4.method.lower().startswith("n4sid")
    assert np.allclose(np.sort_complex(np.linalg.eigvals(n4.A)), truth, atol=1e-2)
    assert s.singular_values.ndim == 1 and len(s.singular_values) >= 2
    # several outputs
    y2 = np.column_stack([y, 2.0 * y + 0.1 * u])
    s2 = hs.subspace(u, y2, order=2)
    assert s2.C.shape == (2, 2) and s2.D.shape == (2, 1)
    with pytest.raises(ValueError):
        hs.subspace(u, y, method="ls")


def test_float32_records_are_diagnosed_and_identified_in_single_precision(noisy_sat_record):
    u, y = noisy_sat_record
    u32, y32 = u.astype(np.float32), y.astype(np.float32)
    d = hs.diagnose(hs.Hammerstein(effects=["saturation"], order=2), u32, y32, validate=0.3)
    assert d.model.precision == "f32"
    assert d.validation.n == 240 and d.validation.fit_percent > 95.0
    s = hs.subspace(u32, y32, order=2)
    assert s.A.shape == (2, 2)


def test_several_inputs_are_diagnosed_input_by_input(noisy_sat_record, tmp_path):
    u, y = noisy_sat_record
    rng = np.random.default_rng(9)
    u2 = rng.uniform(-1, 1, size=len(u))
    y2 = y + 0.5 * np.concatenate([[0.0], u2[:-1]])
    U = np.column_stack([u, u2])
    est = hs.Hammerstein(effects=[[], []], order=3)
    d = hs.diagnose(est, U, y2, validate=0.3)
    assert not d.adequate and d.suggestions
    top = d.suggestions[0]
    assert (top.input, top.effect) == ("u1", "saturation"), [(s.input, s.effect) for s in d.suggestions]
    assert {t["input"] for t in d.tests} == {"u1", "u2"}
    assert d.model.n_inputs == 2
    f = hs.diagnose(est, U, y2, validate=0.3, follow=True, max_steps=2)
    assert len(f.steps) >= 2 and f.stop
    assert "saturation" in f.model.effects[0]
    assert f.steps[-1].diagnosis.validation.fit_percent > f.steps[0].diagnosis.validation.fit_percent
    # the report as the command line writes it: the whole model's output, every input's
    # nonlinearity, the first input's residual tests
    page = f.to_html(tmp_path / "miso", title="two inputs")
    html = open(page).read()
    assert "Several inputs (u1, u2)" in html
    assert "two inputs" in html
    svgs = [x for x in os.listdir(tmp_path / "miso") if x.endswith(".svg")]
    assert len(svgs) >= 3, svgs
    with pytest.raises(ValueError, match="columns"):
        hs.diagnose(f.model, u, y2)
