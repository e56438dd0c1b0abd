"""The cost of calling a fit from Python over the same fit in Rust, on a 2000-sample record.

Run from the repository's root, with the package installed (``pip install ./python``):

    python python/bench/fit_overhead.py [--repeats 15]

It writes the record to a temporary CSV, times ``Hammerstein(effects=...).fit(u, y)`` from
Python and the same fit in Rust (``python/examples/fit_time.rs``, built with the same release
profile), the two interleaved run by run so that the machine's load falls on both alike, and
prints the medians and minima of the wall-clock and of the CPU time (every thread of the
process: the cost of a fit on a machine whose other work stretches the wall clock) and the
overhead in per cent. The Python figure includes the argument
checks, the copies of the arrays and the wrapping of the model.
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import hammerstein as hs

HERE = os.path.dirname(os.path.abspath(__file__))
CRATE = os.path.dirname(HERE)


def record(n=2000, seed=11):
    """A saturation-with-hysteresis actuator into a second-order block, with output noise."""
    rng = np.random.default_rng(seed)
    levels = rng.uniform(-2.5, 2.5, size=n // 8 + 1)
    u = np.repeat(levels, 8)[:n] + 0.1 * rng.standard_normal(n)
    v = np.empty(n)
    state = 0.0
    for k in range(n):  # a play operator of width 0.3, then a saturation at ±1.5
        state = min(max(state, u[k] - 0.3), u[k] + 0.3)
        v[k] = np.clip(state, -1.5, 1.5)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 1.2 * y[k - 1] - 0.5 * y[k - 2] + v[k - 1] + 0.4 * v[k - 2]
    return u, y + 0.01 * rng.standard_normal(n)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--effects", default="saturation,hysteresis")
    args = ap.parse_args()
    env = dict(os.environ)
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "--example", "fit_time"],
        cwd=CRATE, check=True, env=env,
    )
    target = env.get("CARGO_TARGET_DIR", os.path.join(CRATE, "target"))
    exe = os.path.join(target, "release", "examples", "fit_time")
    u, y = record()
    est = hs.Hammerstein(effects=args.effects.split(","))
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "record.csv")
        with open(path, "w") as f:
            f.write("u,y\n")
            for a, b in zip(u, y):
                f.write(f"{float(a)!r},{float(b)!r}\n")
        est.fit(u, y)  # warm-up: the first call loads the pages
        py_t, py_c, rs_t, rs_c, rs_mse = [], [], [], [], None
        for _ in range(args.repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            m = est.fit(u, y)
            py_t.append(time.perf_counter() - t0)
            py_c.append(time.process_time() - c0)
            out = subprocess.run([exe, path, args.effects, "1"], capture_output=True, text=True, check=True)
            wall, cpu = out.stdout.split("\n")[0].split()
            rs_t.append(float(wall))
            rs_c.append(float(cpu))
            rs_mse = float(out.stdout.split("train_mse")[1])
    print(f"record: {len(u)} samples, effects {args.effects}, order auto; {args.repeats} runs each")
    for name, py, rs in (("wall", py_t, rs_t), ("CPU", py_c, rs_c)):
        pm, rm = statistics.median(py), statistics.median(rs)
        print(f"{name:>4}: Rust median {rm * 1e3:8.1f} ms (min {min(rs) * 1e3:7.1f}), "
              f"Python median {pm * 1e3:8.1f} ms (min {min(py) * 1e3:7.1f}): overhead "
              f"{100.0 * (pm / rm - 1.0):+.2f} % (medians), {100.0 * (min(py) / min(rs) - 1.0):+.2f} % (minima)")
    print(f"train MSE: Rust {rs_mse:.9e}, Python {m.report['train_mse']:.9e}")
    if rs_mse != m.report["train_mse"]:
        print("warning: the two fits differ", file=sys.stderr)


if __name__ == "__main__":
    main()
