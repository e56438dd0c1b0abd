"""The feedback model: a Duffing-type record (cubic stiffness in feedback) fitted, simulated,
saved and loaded; the same model file and the same fit as the command line's."""

import json
import math
import subprocess

import numpy as np
import pytest

import hammerstein as hs
from conftest import write_csv


def run(binary, *args):
    p = subprocess.run([binary, *map(str, args)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    return p.stdout


def duffing_record(n=1500, seed=3, c3=0.8, noise=0.005):
    """Random levels through y = G (u − c3 y³), G of order 2 (poles 0.9 e^{±2πi 0.05})."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.5, 1.5, size=n // 10 + 1), 10)[:n] + 0.1 * rng.standard_normal(n)
    r, th = 0.9, 2 * math.pi * 0.05
    a1, a2 = -2 * r * math.cos(th), r * r
    g = 0.5 * (1 + a1 + a2)
    y = np.zeros(n)
    e = np.zeros(n)
    for k in range(n):
        v = 0.0
        if k >= 1:
            v += g * e[k - 1] - a1 * y[k - 1]
        if k >= 2:
            v += g * e[k - 2] - a2 * y[k - 2]
        y[k] = v
        e[k] = u[k] - c3 * v**3
    return u, y + noise * rng.standard_normal(n)


@pytest.fixture(scope="module")
def record():
    return duffing_record()


@pytest.fixture(scope="module")
def fitted(record):
    u, y = record
    return hs.Feedback("poly3", on="output", order=2).fit(u, y)


def test_feedback_fit_finds_the_stiffness(record, fitted):
    u, y = record
    m = fitted
    assert isinstance(m, hs.FeedbackModel)
    assert m.order == 2 and m.on == "output"
    assert set(m.parameters) == {"c3"}
    # the stiffness in the input's units: u − 0.8 z³ drives the block, so w = f(z) ≈ −0.8 z³
    lo, hi = m.z_range
    assert lo < 0 < hi
    z = np.array([lo, 0.5 * lo, 0.5 * hi, hi])
    assert np.allclose(m.f(z), -0.8 * z**3, rtol=0.15), (m.f(z), -0.8 * z**3)
    r = m.report
    assert r["train_rms"] < 0.5 * r["linear_rms"], r
    assert r["order"] == 2 and r["nonlinearity"] == m.nonlinearity == "poly3"
    c = hs.compare(m, u, y)
    assert c.fit_percent > 95, c
    assert c.mse == pytest.approx(r["train_rms"] ** 2, rel=0.05)
    assert c.nrmse == pytest.approx(1 - c.fit_percent / 100)
    # the linear model does much worse on this record
    lin = hs.Hammerstein(order=2).fit(u, y)
    assert hs.compare(lin, u, y).fit_percent < c.fit_percent - 5
    assert m.simulate(u).shape == (len(u),)
    A, B, C, D, E = m.linear
    assert A.shape == (2, 2) and E.shape == (2, 1) and len(m.poles) == 2


def test_feedback_validation_is_reported(record):
    u, y = record
    m = hs.Feedback("poly3", order=2, max_iterations=30).fit(u, y, validate=0.3)
    assert m.report["validation_fit_percent"] > 90
    assert m.report["validation_rms"] > 0


def test_feedback_save_load_round_trip(record, fitted, tmp_path):
    u, _ = record
    path = tmp_path / "fb.json"
    fitted.save(path)
    again = hs.load(path)
    assert isinstance(again, hs.FeedbackModel)
    assert again.report is None
    assert again.to_json() == fitted.to_json()
    assert np.array_equal(again.simulate(u), fitted.simulate(u))
    assert json.loads(fitted.to_json())["kind"] == "feedback"
    assert isinstance(hs.loads(fitted.to_json()), hs.FeedbackModel)


def test_feedback_fit_equals_the_cli(cli_bin, record, fitted, tmp_path):
    u, y = record
    csv = tmp_path / "rec.csv"
    write_csv(csv, u, y)
    saved = tmp_path / "cli.json"
    out = json.loads(run(cli_bin, "fit", csv, "--feedback-nonlinearity", "poly3", "--order", 2,
                         "--json", "--save", saved))
    r = fitted.report
    for k in ("order", "nonlinearity", "feedback_on", "iterations"):
        assert out[k] == r[k], k
    for k in ("linear_rms", "train_rms"):
        assert out[k] == pytest.approx(r[k], rel=1e-9), k
    # the command line's file read in Python simulates as the Python fit does
    cli_model = hs.load(saved)
    assert isinstance(cli_model, hs.FeedbackModel)
    assert np.allclose(cli_model.simulate(u), fitted.simulate(u), rtol=1e-9, atol=1e-12)
    # the Python file read by the command line: compare and simulate agree
    mine = tmp_path / "py.json"
    fitted.save(mine)
    cmp = json.loads(run(cli_bin, "compare", mine, csv, "--json"))
    assert cmp["fit_percent"] == pytest.approx(hs.compare(fitted, u, y).fit_percent, rel=1e-9)
    sim = tmp_path / "sim.csv"
    run(cli_bin, "simulate", mine, csv, "--out", sim)
    s = np.genfromtxt(sim, delimiter=",", names=True)
    assert np.allclose(s["y_hat"], fitted.simulate(u), rtol=1e-12, atol=1e-12)


def test_bad_feedback_input_raises(record):
    u, y = record
    with pytest.raises(hs.InputError, match="unknown feedback nonlinearity"):
        hs.Feedback("cubic").fit(u, y)
    with pytest.raises(hs.InputError, match="'output', 'velocity' or 'state'"):
        hs.Feedback(on="position").fit(u, y)
    with pytest.raises(hs.InputError, match="algebraic"):
        hs.Feedback(on="velocity", feedthrough="on", order=2).fit(u, y)
    with pytest.raises(hs.InputError, match="one input"):
        hs.Feedback().fit(np.column_stack([u, u]), y)
    bad = y.copy()
    bad[7] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        hs.Feedback().fit(u, bad)
    with pytest.raises(hs.InputError, match="unknown setting"):
        hs.Feedback().set_params(degree=3)


def resonant_loop(v):
    """The resonant second-order block of the Rust feedback tests (poles 0.95 e^{±0.3j}) with
    a cubic stiffness −0.02 x₁³ in its loop, driven by v; returns x₁."""
    a1, a2 = 2 * 0.95 * math.cos(0.3), -0.95 * 0.95
    x1 = x2 = 0.0
    out = np.empty(len(v))
    for k, vk in enumerate(v):
        w = -0.02 * x1**3
        out[k] = x1
        x1, x2 = a1 * x1 + x2 + vk + w, a2 * x1 + 0.5 * (vk + w)
    return out


def loop_record(seed, n=3000, saturate=False, c3_out=0.0):
    """Training and validation halves of 2n samples of the resonant loop (40 dB output noise):
    the input saturated a quarter of the time (`saturate`), and the output measured through
    g(x) = x + c3_out x³ / r², r the RMS of x (`c3_out`)."""
    rng = np.random.default_rng(seed)
    e = rng.uniform(-1, 1, 2 * n)
    u = np.empty(2 * n)
    s = 0.0
    for k in range(2 * n):
        s = 0.7 * s + e[k]
        u[k] = 0.06 * s
    v = np.clip(u, *(np.quantile(np.abs(u), 0.75) * np.array([-1, 1]))) if saturate else u
    x = resonant_loop(v)
    x = x + c3_out * x**3 / np.mean(x**2)
    sd = math.sqrt(np.mean(x**2) / 1e4)
    y = x + sd * rng.standard_normal(2 * n)
    return (u[:n], y[:n]), (u[n:], y[n:]), sd * sd


def test_feedback_with_an_input_saturation_before_the_loop():
    (u, y), (uv, yv), s2 = loop_record(21, saturate=True)
    alone = hs.Feedback("poly3", order=2).fit(u, y)
    m = hs.Feedback("poly3", order=2, effects=["saturation"]).fit(u, y)
    assert alone.input_nonlinearity is None and alone.input_map(u) is None
    assert m.input_nonlinearity is not None, m.report["warnings"]
    assert m.report["input_nonlinearity"] == m.input_nonlinearity
    assert m.output_nonlinearity is None and m.output_map(y) is None
    # nested: never worse on training than the loop alone
    assert m.report["train_rms"] <= alone.report["train_rms"] * (1 + 1e-9)
    cw, ca = hs.compare(m, uv, yv), hs.compare(alone, uv, yv)
    assert cw.mse < 1.5 * s2, (cw.mse, s2)
    assert ca.mse > 2 * cw.mse, (ca.mse, cw.mse)
    # the input the block receives is bounded where u is not
    v = m.input_map(np.array([-100.0, 0.0, 100.0]))
    assert v.shape == (3,) and abs(v[0]) < 10 and abs(v[2]) < 10, v
    # the model file round trip keeps N
    again = hs.loads(m.to_json())
    assert again.input_nonlinearity == m.input_nonlinearity
    assert np.array_equal(again.simulate(uv), m.simulate(uv))


def test_feedback_with_an_output_map_after_the_loop():
    (u, y), (uv, yv), s2 = loop_record(31, c3_out=0.12)
    alone = hs.Feedback("poly3", order=2).fit(u, y)
    m = hs.Feedback("poly3", order=2, output_nonlinearity="poly3").fit(u, y)
    assert m.output_nonlinearity == "poly3" == m.report["output_nonlinearity"]
    assert m.input_nonlinearity is None
    assert m.report["train_rms"] <= alone.report["train_rms"] * (1 + 1e-9)
    cw, ca = hs.compare(m, uv, yv), hs.compare(alone, uv, yv)
    assert cw.mse < 1.5 * s2, (cw.mse, s2)
    assert ca.mse > 2 * cw.mse, (ca.mse, cw.mse)
    # g has unit slope and zero value at 0, and bends upward as the truth's map does
    lo, hi = np.min(y), np.max(y)
    g = m.output_map(np.array([0.0, hi]))
    assert abs(g[0]) < 1e-12 and g[1] > hi, g
    d = m.describe()
    assert d["version"] == 3 and d["output_nonlinearity"]["kind"] == "poly"
    again = hs.loads(m.to_json())
    assert again.output_nonlinearity == "poly3"
    assert np.array_equal(again.simulate(uv), m.simulate(uv))


def test_feedback_input_and_output_maps_equal_the_cli(cli_bin, tmp_path):
    (u, y), _, _ = loop_record(31, n=1500, c3_out=0.12)
    csv = tmp_path / "rec.csv"
    write_csv(csv, u, y)
    for py_kw, cli in (
        (dict(effects="saturation"), ["--effects", "saturation"]),
        (dict(input_nonlinearity="poly3"), ["--nonlinearity", "poly3"]),
        (dict(output_nonlinearity="poly3"), ["--output-nonlinearity", "poly3"]),
    ):
        r = hs.Feedback("poly3", order=2, **py_kw).fit(u, y).report
        out = json.loads(run(cli_bin, "fit", csv, "--feedback-nonlinearity", "poly3", "--order",
                             2, "--json", *cli))
        for k in ("input_nonlinearity", "output_nonlinearity", "iterations"):
            assert out[k] == r[k], (k, py_kw)
        assert out["train_rms"] == pytest.approx(r["train_rms"], rel=1e-9), py_kw


def test_bad_input_and_output_maps_raise(record):
    u, y = record
    with pytest.raises(hs.InputError, match="degree must be 2..=9"):
        hs.Feedback(order=2, output_nonlinearity="poly1").fit(u, y)
    with pytest.raises(hs.InputError, match="unknown nonlinearity"):
        hs.Feedback(order=2, input_nonlinearity="cubic").fit(u, y)
    with pytest.raises(hs.InputError):
        hs.Feedback(order=2, effects=["friction"]).fit(u, y)
    with pytest.raises(hs.InputError, match="a name"):
        hs.Feedback(order=2, output_nonlinearity=3).fit(u, y)
    assert "effects" in hs.Feedback().get_params()
