"""The estimator, the fitted model and its file."""

import json
import threading
import time

import numpy as np
import pytest

import hammerstein as hs
from conftest import saturation_record


def test_fit_recovers_the_saturation_and_the_block(sat_record):
    u, y = sat_record
    model = hs.Hammerstein(effects=["saturation"], order=2).fit(u, y)
    assert isinstance(model, hs.Model)
    assert model.order == 2 and model.n_inputs == 1 and model.precision == "f64"
    assert "saturation" in model.effects
    assert model.report["train_mse"] < 1e-10
    assert model.report["order"] == 2
    assert isinstance(model.report["termination"], str)
    poles = np.sort_complex(model.poles)
    truth = np.sort_complex(np.roots([1.0, -1.2, 0.5]))
    assert np.allclose(poles, truth, atol=1e-5), poles
    tf = model.transfer_function
    assert tf.denominator.shape == (3,) and tf.denominator[0] == pytest.approx(1.0)
    assert np.allclose(tf.denominator, [1.0, -1.2, 0.5], atol=1e-5)
    A, B, C, D = model.linear
    assert A.shape == (2, 2) and B.shape == (2, 1) and C.shape == (1, 2) and D.shape == (1, 1)
    assert np.allclose(np.sort_complex(np.linalg.eigvals(A)), truth, atol=1e-5)
    params = model.parameters
    assert isinstance(params, dict) and params and all(isinstance(v, float) for v in params.values())
    assert set(model.standard_errors) == set(params)
    y_hat = model.simulate(u)
    assert y_hat.shape == y.shape and y_hat.dtype == np.float64
    assert np.max(np.abs(y_hat - y)) < 1e-4 * np.max(np.abs(y))


def test_plain_lists_ioData_and_sample_time(sat_record):
    u, y = sat_record
    m1 = hs.Hammerstein(effects="saturation", order=2).fit(list(u), list(y), ts=0.01)
    m2 = hs.Hammerstein(effects=["saturation"], order=2).fit(hs.IoData(u, y, ts=0.01))
    assert m1.sample_time == pytest.approx(0.01) and m2.sample_time == pytest.approx(0.01)
    assert m1.parameters == m2.parameters


def test_float32_arrays_fit_in_single_precision(sat_record):
    u, y = sat_record
    m = hs.Hammerstein(effects=["saturation"], order=2).fit(u.astype(np.float32), y.astype(np.float32))
    assert m.precision == "f32"
    y_hat = m.simulate(u.astype(np.float32))
    assert y_hat.dtype == np.float32
    assert hs.compare(m, u.astype(np.float32), y.astype(np.float32)).fit_percent > 99.0
    # float64 input to an f32 model is cast, float32 to an f64 one too
    m64 = hs.Hammerstein(effects=["saturation"], order=2).fit(u, y)
    assert m64.simulate(u.astype(np.float32)).dtype == np.float64
    assert m.simulate(u).dtype == np.float32
    # the precision can be asked for
    assert hs.Hammerstein(order=2, precision="f32").fit(u, y).precision == "f32"


def test_linear_default_and_auto_order(sat_record):
    u, y = sat_record
    m = hs.Hammerstein().fit(u, y)  # linear, order auto: as `hammerstein fit`
    assert m.effects == [] or m.effects is not None
    assert m.order >= 1
    assert len(m.report["order_selection"]) >= 2


def test_output_nonlinearity(sat_record):
    u, y = sat_record
    m = hs.Hammerstein(order=2, output_nonlinearity="poly3").fit(u, y)
    on = m.output_nonlinearity
    assert on is not None and on["parameters"]


def test_compare_metrics(noisy_sat_record):
    u, y = noisy_sat_record
    m = hs.Hammerstein(effects=["saturation"], order=2).fit(u[:500], y[:500])
    c = hs.compare(m, u[500:], y[500:])
    assert isinstance(c, hs.Comparison)
    assert c.n == 300 and c.y_hat.shape == (300,)
    assert c.fit_percent == pytest.approx(100.0 * (1.0 - c.nrmse))
    assert c.mse == pytest.approx(np.mean((y[500:] - c.y_hat) ** 2), rel=1e-9)
    assert 95.0 < c.fit_percent < 100.0
    lin = hs.Hammerstein(order=2).fit(u[:500], y[:500])
    assert hs.compare(lin, u[500:], y[500:]).fit_percent < c.fit_percent


def test_save_load_round_trip(tmp_path, sat_record):
    u, y = sat_record
    m = hs.Hammerstein(effects=["saturation", "dead-zone"], order=2).fit(u, y)
    path = tmp_path / "model.json"
    m.save(path)
    text = path.read_text()
    assert json.loads(text)["format_version"] >= 1
    back = hs.load(path)
    assert back.parameters == m.parameters
    assert np.array_equal(back.simulate(u), m.simulate(u))
    again = hs.loads(m.to_json())
    assert again.parameters == m.parameters
    assert "Model" in repr(m)


def test_several_inputs(sat_record):
    u, y = sat_record
    rng = np.random.default_rng(5)
    u2 = rng.uniform(-1, 1, size=len(u))
    y2 = y + 0.5 * np.concatenate([[0.0], u2[:-1]])
    U = np.column_stack([u, u2])
    m = hs.Hammerstein(effects=[["saturation"], []], order=3).fit(U, y2)
    assert m.n_inputs == 2
    assert len(m.effects) == 2 and "saturation" in m.effects[0]
    assert all("." in k for k in m.parameters)
    assert m.simulate(U).shape == y2.shape
    assert hs.compare(m, U, y2).fit_percent > 95.0
    with pytest.raises(ValueError):
        m.simulate(u)
    with pytest.raises(ValueError):
        hs.Hammerstein(effects=["saturation"]).fit(U, y2)


def test_the_fit_releases_the_gil():
    u, y = saturation_record(n=20000, seed=3, noise=0.01)
    est = hs.Hammerstein(effects=["saturation", "hysteresis"])
    done = threading.Event()
    fits = []

    def work():
        # fits until 0.3 s have passed, so that the check does not depend on the machine's speed
        start = time.perf_counter()
        while time.perf_counter() - start < 0.3:
            est.fit(u, y)
            fits.append(1)
        done.set()

    t = threading.Thread(target=work)
    t0 = time.perf_counter()
    t.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    t.join()
    elapsed = time.perf_counter() - t0
    # a fit holding the GIL would stop this loop for its whole duration: the loop could then run
    # only between fits, about once per fit
    assert ticks > max(10, 2 * len(fits), 0.1 * elapsed / 0.0011), (ticks, len(fits), elapsed)


def test_help_and_docstrings():
    assert "effects" in hs.Hammerstein.__doc__
    assert hs.diagnose.__doc__ and hs.compare.__doc__ and hs.subspace.__doc__
    assert hs.__version__
