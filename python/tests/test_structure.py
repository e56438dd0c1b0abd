"""The structure tools: a multisine design replayed on plants simulated in Python, the BLA
and the structure verdict naming the plant's family, and the same answers as the command
line's on the same record."""

import json
import math
import subprocess

import numpy as np
import pytest

import hammerstein as hs
from conftest import simulate_block, write_csv


def run(binary, *args):
    p = subprocess.run([binary, *map(str, args)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    return p.stdout


# a smaller experiment than the command line's default (1024 samples per period): the same
# levels, realizations and periods
DESIGN = dict(samples=512, levels=(0.25, 0.5, 1.0), realizations=4, periods=2, seed=11)


@pytest.fixture(scope="module")
def experiment():
    return hs.design(**DESIGN)


def noisy(y, seed, snr_db=40.0):
    rng = np.random.default_rng(seed)
    return y + np.std(y) * 10 ** (-snr_db / 20) * rng.standard_normal(len(y))


@pytest.fixture(scope="module")
def hammerstein_plant(sat_record):
    """A fitted Hammerstein model (a saturation at about ±1 into a second-order block)."""
    u, y = sat_record
    return hs.Hammerstein(effects=["saturation"], order=2).fit(u, y)


def duffing(u, c3=0.5):
    """y = G (u − c3 y³): a second-order block (poles 0.85 e^{±2πi 0.08}) with a hardening
    cubic stiffness in feedback."""
    r, th = 0.85, 2 * math.pi * 0.08
    a1, a2 = -2 * r * math.cos(th), r * r
    b1, b2 = 1.0, 0.3
    g = (1 + a1 + a2) / (b1 + b2)
    b1, b2 = b1 * g, b2 * g
    y = np.zeros(len(u))
    e = np.zeros(len(u))
    for k in range(len(u)):
        v = 0.0
        if k >= 1:
            v += b1 * e[k - 1] - a1 * y[k - 1]
        if k >= 2:
            v += b2 * e[k - 2] - a2 * y[k - 2]
        y[k] = v
        e[k] = u[k] - c3 * v**3
    return y


@pytest.fixture(scope="module")
def measured(experiment, hammerstein_plant):
    """The experiment replayed on the Hammerstein model and on the feedback plant (40 dB)."""
    h = experiment.replay(hammerstein_plant.simulate)
    h = h.with_output(noisy(h.y, 1))
    f = experiment.replay(duffing)
    f = f.with_output(noisy(f.y, 2))
    return {"hammerstein": h, "feedback": f}


def test_design_is_the_record_format(experiment):
    e = experiment
    n = 3 * 4 * (2 + 1) * 512
    assert len(e) == n and e.samples == 512
    assert e.level.dtype == np.int64 and set(e.level) == {0, 1, 2}
    assert set(e.period) == {0, 1, 2}
    blocks = list(e.blocks())
    assert len(blocks) == 12 and all(s.stop - s.start == 3 * 512 for _, _, s in blocks)
    # each level's steady input has the RMS asked for
    for lv, want in enumerate(DESIGN["levels"]):
        steady = e.u[(e.level == lv) & (e.period > 0)]
        assert np.sqrt(np.mean(steady**2)) == pytest.approx(want, rel=1e-6)
    # random odd: only odd lines excited, inside the band
    assert np.all(e.excited % 2 == 1)
    assert e.excited.min() >= 0.01 * 512 and e.excited.max() <= 0.2 * 512
    assert e.y is None


def test_design_equals_the_cli_design(cli_bin, tmp_path):
    out = tmp_path / "design.csv"
    run(cli_bin, "design", "--multisine", "full", "--samples", 128, "--band", "0.05,0.3",
        "--levels", "0.5,2", "--realizations", 2, "--periods", 1, "--seed", 5, "--out", out)
    e = hs.design(kind="full", samples=128, band=(0.05, 0.3), levels=[0.5, 2],
                  realizations=2, periods=1, seed=5)
    cli = hs.Experiment.from_csv(out)
    for c in ("level", "realization", "period", "u"):
        assert np.array_equal(getattr(e, c), getattr(cli, c)), c
    assert list(e.excited) == list(range(7, 39))  # every line of 0.05..0.3 of 128 samples


def test_structure_names_the_plant_family(measured):
    s = hs.structure(measured["hammerstein"])
    assert s.verdict == "single-branch", (s.verdict, s.notes)
    assert len(s.levels) == 3 and all(lv.poles for lv in s.levels)
    assert "hammerstein" in s.candidates, s.candidates
    f = hs.structure(measured["feedback"])
    assert f.verdict == "feedback", (f.verdict, f.notes)
    assert f.moved and f.moved[0].kind == "pole"


def test_bla_sees_the_distortion(measured, tmp_path):
    b = hs.bla(measured["hammerstein"], plot=tmp_path / "bla.svg")
    svg = (tmp_path / "bla.svg").read_text()
    assert svg.startswith("<svg") and svg.count("<path") + svg.count("<polyline") >= 3
    assert len(b.levels) == 3 and b.period == 512
    top = b.levels[-1]
    assert top.method == "robust"
    assert top.nonlinear is True
    assert len(top.bla) == len(b.excited) == len(top.frequencies)
    assert np.all(np.isfinite(top.var_noise)) and np.all(top.var_distortion >= 0)
    # the saturation lowers the BLA's gain as the level rises
    gain = [np.mean(np.abs(lv.bla[:3])) for lv in b.levels]
    assert gain[2] < 0.95 * gain[0], gain
    # frequencies in Hz with a sampling time
    bt = hs.bla(measured["hammerstein"], ts=0.01)
    assert np.allclose(bt.levels[0].frequencies, b.levels[0].frequencies / 0.01)


def close(a, b, path=""):
    """Equal JSON values, floats to 1e-7 relative (the binary of the tests is a debug build,
    the package a release build: derived quantities such as standard errors differ in their
    last digits)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), path
        for k in a:
            close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            close(x, y, f"{path}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-7, abs=1e-12), path
    else:
        assert a == b, path


def test_bla_and_structure_equal_the_cli(cli_bin, measured, tmp_path):
    rec = measured["feedback"]
    path = tmp_path / "measured.csv"
    rec.to_csv(path)
    close(hs.bla(rec).raw, json.loads(run(cli_bin, "bla", path, "--json")))
    s = hs.structure(rec, order=2, alpha=1e-3)
    close(s.raw, json.loads(run(cli_bin, "structure", path, "--order", 2, "--json")))
    # a band around the mode, in Hz with a sampling time
    s = hs.structure(rec, ts=0.01, band=(2.0, 15.0), max_order=4)
    assert s.freq_unit == "Hz"
    close(s.raw, json.loads(run(cli_bin, "structure", path, "--ts", 0.01, "--band", "2,15",
                                "--max-order", 4, "--json")))
    # a plain periodic record (one level, its first period a transient)
    one = rec.level == 2
    u, y = rec.u[one & (rec.realization == 0)], rec.y[one & (rec.realization == 0)]
    plain = tmp_path / "plain.csv"
    write_csv(plain, u, y)
    close(hs.bla(u, y, period=512).raw, json.loads(run(cli_bin, "bla", plain, "--period", 512, "--json")))


def test_structure_by_rms_equals_the_cli(cli_bin, tmp_path):
    # a non-periodic record whose amplitude grows fivefold: noise through a saturation at ±1
    # into a second-order block
    rng = np.random.default_rng(4)
    n = 4000
    u = np.linspace(0.4, 2.0, n) * np.repeat(rng.standard_normal(n // 4), 4)
    y = simulate_block(np.clip(u, -1.0, 1.0)) + 0.01 * rng.standard_normal(n)
    path = tmp_path / "rec.csv"
    write_csv(path, u, y)
    s = hs.structure(u, y, by_rms=2, window=200)
    assert s.verdict in ("linear", "single-branch", "parallel", "feedback")
    assert len(s.levels) == 2 and s.levels[0].rms < s.levels[1].rms
    close(s.raw, json.loads(run(cli_bin, "structure", path, "--by-rms", 2, "--window", 200, "--json")))


def test_bad_structure_input_raises(experiment):
    with pytest.raises(hs.InputError, match="multisine kind"):
        hs.design(kind="square")
    with pytest.raises(ValueError, match="band"):
        hs.design(band=(0.3, 0.1))
    with pytest.raises(hs.InputError, match="no output"):
        hs.bla(experiment)
    with pytest.raises(hs.InputError, match="alpha"):
        hs.structure(experiment.with_output(experiment.u), alpha=2)
    with pytest.raises(hs.InputError, match="period"):
        hs.bla(np.ones(100), np.ones(100))
    bad = experiment.u.copy()
    bad[5] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        experiment.with_output(bad)
    with pytest.raises(hs.InputError, match="samples"):
        experiment.replay(lambda u: u[:-1])
