"""The Python package and the command line agree: the same model file both ways, the same
fit on the same record."""

import json
import subprocess

import numpy as np
import pytest

import hammerstein as hs
from conftest import write_csv


def run(binary, *args):
    p = subprocess.run([binary, *map(str, args)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    return p.stdout


@pytest.fixture(scope="module")
def record_csv(tmp_path_factory, noisy_sat_record):
    u, y = noisy_sat_record
    path = tmp_path_factory.mktemp("cli") / "record.csv"
    write_csv(path, u, y)
    return path


def test_python_fit_equals_the_cli_fit(cli_bin, record_csv, noisy_sat_record, tmp_path):
    u, y = noisy_sat_record
    saved = tmp_path / "cli.json"
    out = json.loads(
        run(cli_bin, "fit", record_csv, "--effects", "saturation,hysteresis", "--json", "--save", saved)
    )
    m = hs.Hammerstein(effects=["saturation", "hysteresis"]).fit(u, y)
    assert m.order == out["order"]
    assert m.parameters.keys() == out["parameters"].keys()
    for k, v in out["parameters"].items():
        assert m.parameters[k] == pytest.approx(v, rel=1e-12, abs=1e-12), k
    assert m.report["train_mse"] == pytest.approx(out["train"]["mse"], rel=1e-12)
    assert m.report["termination"] == out["termination"]
    assert np.allclose(m.transfer_function.denominator, out["denominator"], rtol=1e-12, atol=1e-12)
    # the CLI's model file read in Python simulates as the Python fit does
    cli_model = hs.load(saved)
    assert np.allclose(cli_model.simulate(u), m.simulate(u), rtol=1e-12, atol=1e-12)
    c = hs.compare(m, u, y)
    assert c.fit_percent == pytest.approx(out["train"]["fit_percent"], rel=1e-12)


def test_a_python_model_file_is_read_by_the_cli(cli_bin, record_csv, noisy_sat_record, tmp_path):
    u, y = noisy_sat_record
    m = hs.Hammerstein(effects=["saturation"], order=2).fit(u, y)
    path = tmp_path / "py.json"
    m.save(path)
    cmp = json.loads(run(cli_bin, "compare", path, record_csv, "--json"))
    assert cmp["fit_percent"] == pytest.approx(hs.compare(m, u, y).fit_percent, rel=1e-12)
    out = tmp_path / "sim.csv"
    run(cli_bin, "simulate", path, record_csv, "--out", out)
    sim = np.genfromtxt(out, delimiter=",", names=True)
    col = sim.dtype.names[-1]
    assert np.allclose(sim[col], m.simulate(u), rtol=1e-12, atol=1e-12)


def test_python_diagnose_equals_the_cli_diagnose(cli_bin, record_csv, noisy_sat_record):
    u, y = noisy_sat_record
    out = json.loads(run(cli_bin, "diagnose", record_csv, "--order", "2", "--json"))
    d = hs.diagnose(hs.Hammerstein(order=2), u, y, validate=0.3)
    assert d.adequate == out["adequate"]
    assert [s.effect for s in d.suggestions] == [s["effect"] for s in out["suggestions"]]
    assert d.validation.mse == pytest.approx(out["validation"]["mse"], rel=1e-12)
