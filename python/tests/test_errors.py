"""Bad input raises ValueError (hammerstein.InputError); failures HammersteinError."""

import json

import numpy as np
import pytest

import hammerstein as hs


@pytest.fixture(scope="module")
def model(sat_record):
    u, y = sat_record
    return hs.Hammerstein(effects=["saturation"], order=2).fit(u, y)


def test_exception_classes():
    assert issubclass(hs.InputError, ValueError)
    assert issubclass(hs.InputError, hs.HammersteinError)
    assert not issubclass(hs.HammersteinError, ValueError)


def test_nan_and_infinity(sat_record):
    u, y = sat_record
    bad = y.copy()
    bad[17] = np.nan
    with pytest.raises(ValueError, match=r"non-finite.*sample 17"):
        hs.Hammerstein().fit(u, bad)
    bad_u = u.copy()
    bad_u[3] = np.inf
    with pytest.raises(hs.InputError, match="non-finite"):
        hs.Hammerstein().fit(bad_u, y)


def test_mismatched_lengths(sat_record, model):
    u, y = sat_record
    with pytest.raises(ValueError, match="length mismatch"):
        hs.Hammerstein().fit(u, y[:-1])
    with pytest.raises(ValueError, match="length mismatch"):
        hs.compare(model, u[:-3], y)
    with pytest.raises(ValueError, match="length mismatch"):
        hs.diagnose(model, u, y[:10])


def test_wrong_dtype(sat_record, model):
    u, y = sat_record
    with pytest.raises(ValueError, match="dtype"):
        hs.Hammerstein().fit(u.astype(complex), y)
    with pytest.raises(ValueError, match="dtype"):
        hs.Hammerstein().fit(np.array([str(x) for x in u]), y)
    with pytest.raises(ValueError, match="dtype"):
        model.simulate(np.array([object()] * 10))
    with pytest.raises(ValueError):
        hs.Hammerstein().fit([[1.0, 2.0], [3.0]], [1.0, 2.0])  # ragged


def test_integer_arrays_are_taken_as_float(model):
    y = model.simulate(np.arange(50) % 3)
    assert y.dtype == np.float64 and y.shape == (50,)


def test_wrong_shape(sat_record, model):
    u, y = sat_record
    with pytest.raises(ValueError, match="shape"):
        hs.Hammerstein().fit(u.reshape(-1, 2, 1), y)
    with pytest.raises(ValueError, match="one output"):
        hs.Hammerstein().fit(u, np.column_stack([y, y]))
    with pytest.raises(ValueError, match="2 needed"):
        hs.Hammerstein().fit([1.0], [2.0])
    with pytest.raises(ValueError, match="columns"):
        model.simulate(np.column_stack([u, u]))
    with pytest.raises(ValueError, match="shape"):
        hs.subspace(u.reshape(-1, 1, 1), y)


def test_constant_input(sat_record):
    u, y = sat_record
    with pytest.raises(ValueError, match="constant"):
        hs.Hammerstein().fit(np.ones_like(u), y)


def test_bad_settings(sat_record):
    u, y = sat_record
    with pytest.raises(ValueError, match="unknown effect|unknown"):
        hs.Hammerstein(effects=["stiction-ish"]).fit(u, y)
    with pytest.raises(ValueError):
        hs.Hammerstein(order="many").fit(u, y)
    with pytest.raises(ValueError):
        hs.Hammerstein(method="pem").fit(u, y)
    with pytest.raises(ValueError, match="delay"):
        hs.Hammerstein(delay=-1).fit(u, y)
    with pytest.raises(ValueError, match="horizon"):
        hs.Hammerstein(horizon=0).fit(u, y)
    with pytest.raises(ValueError, match="precision"):
        hs.Hammerstein(precision="f16").fit(u, y)
    with pytest.raises(ValueError):
        hs.Hammerstein(nonlinearity="spline").fit(u, y)
    with pytest.raises(ValueError, match="unknown setting"):
        hs.Hammerstein().set_params(colour="red")
    with pytest.raises(ValueError, match="fraction"):
        hs.diagnose(hs.Hammerstein(), u, y, validate=1.5)
    with pytest.raises(ValueError, match="ts|sample time"):
        hs.Hammerstein().fit(u, y, ts=-1.0)


def test_missing_file_and_bad_model_file(tmp_path):
    with pytest.raises(FileNotFoundError):
        hs.load(tmp_path / "nope.json")
    p = tmp_path / "bad.json"
    p.write_text("{not json")
    with pytest.raises(ValueError, match="model file"):
        hs.load(p)


def test_a_diverging_simulation_is_a_hammerstein_error(model, sat_record):
    u, _ = sat_record
    f = json.loads(model.to_json())
    f["linear"]["a"] = [[1.5, 0.0], [0.0, 1.2]]  # poles outside the unit circle
    unstable = hs.loads(json.dumps(f))
    with pytest.raises(hs.HammersteinError, match="diverges") as e:
        unstable.simulate(np.tile(u, 20))
    assert not isinstance(e.value, ValueError)
