"""Shared records and the command-line binary for the Python package's tests."""

import os
import shutil

import numpy as np
import pytest


def simulate_block(v, a1=-1.2, a2=0.5, b1=1.0, b2=0.4):
    """y(k) = -a1 y(k-1) - a2 y(k-2) + b1 v(k-1) + b2 v(k-2): poles 0.6 ± 0.37j."""
    y = np.zeros_like(v)
    y[1] = b1 * v[0]  # zero state before the record
    for k in range(2, len(v)):
        y[k] = -a1 * y[k - 1] - a2 * y[k - 2] + b1 * v[k - 1] + b2 * v[k - 2]
    return y


def saturation_record(n=600, seed=1, noise=0.0, limit=1.0):
    """A random-level input through a saturation at ±limit into a second-order block."""
    rng = np.random.default_rng(seed)
    levels = rng.uniform(-2.5, 2.5, size=n // 5 + 1)
    u = np.repeat(levels, 5)[:n] + 0.2 * rng.standard_normal(n)
    v = np.clip(u, -limit, limit)
    y = simulate_block(v)
    if noise:
        y = y + noise * rng.standard_normal(n)
    return u, y


@pytest.fixture(scope="session")
def sat_record():
    """A noise-free saturation record (600 samples)."""
    return saturation_record()


@pytest.fixture(scope="session")
def noisy_sat_record():
    """The saturation record with a little output noise (800 samples)."""
    return saturation_record(n=800, seed=2, noise=0.01)


@pytest.fixture(scope="session")
def cli_bin():
    """The `hammerstein` binary: $HAMMERSTEIN_BIN, else on PATH; the tests that need it are
    skipped without one, unless HAMMERSTEIN_REQUIRE_BIN=1 (CI), where they fail."""
    path = os.environ.get("HAMMERSTEIN_BIN") or shutil.which("hammerstein")
    if path and os.path.isfile(path) and os.access(path, os.X_OK):
        return path
    if os.environ.get("HAMMERSTEIN_REQUIRE_BIN") == "1":
        pytest.fail(f"HAMMERSTEIN_REQUIRE_BIN=1 but no binary at HAMMERSTEIN_BIN={path!r}")
    pytest.skip("no hammerstein binary (set HAMMERSTEIN_BIN)")


def write_csv(path, u, y):
    """A CSV with columns u, y (shortest round-trip repr of each float)."""
    with open(path, "w") as f:
        f.write("u,y\n")
        for a, b in zip(u, y):
            f.write(f"{float(a)!r},{float(b)!r}\n")
