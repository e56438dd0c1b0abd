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
