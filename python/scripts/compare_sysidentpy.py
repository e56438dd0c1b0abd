"""hammerstein against a SysIdentPy NARX polynomial on one real record (docs/python.md).

    python python/scripts/compare_sysidentpy.py ../shared/data/labcontrol_mr_damper_sine/ensaio04.csv \
        --input vel_mm_s --output force_N

Needs ``pip install sysidentpy``. The first 70 % of the record trains both, the last 30 %
validates both, by free-run simulation and the same fit % (100·(1 − ‖y − ŷ‖/‖y − ȳ‖)).
hammerstein: the guided path of ``diagnose(..., follow=True)`` from a linear model (its
validation fraction is the same 30 %), its last model compared on the validation part (initial
state estimated from it). SysIdentPy: FROLS with a polynomial basis and least squares, AIC
order selection, its default model type (input and output lags: a NARX polynomial) — at its documented defaults (degree 2, lags 2) and with
a larger basis (degree 3, lags 4); its simulation starts from the measured first lags.
Times are wall-clock seconds of the fit (for hammerstein: the whole guided loop). A
third row fits hammerstein's UDN with hysteresis and saturation directly (order chosen by BIC).
"""

import argparse
import time

import numpy as np

import hammerstein as hs


def fit_percent(y, y_hat):
    y, y_hat = np.ravel(y), np.ravel(y_hat)
    return 100.0 * (1.0 - np.linalg.norm(y - y_hat) / np.linalg.norm(y - y.mean()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv")
    ap.add_argument("--input", default="u")
    ap.add_argument("--output", default="y")
    ap.add_argument("--validate", type=float, default=0.3)
    args = ap.parse_args()
    table = np.genfromtxt(args.csv, delimiter=",", names=True)
    u, y = table[args.input].astype(float), table[args.output].astype(float)
    n_val = int(np.floor(len(u) * args.validate + 0.5))
    cut = len(u) - n_val
    print(f"{args.csv}: {len(u)} samples, {cut} training, {n_val} validation")

    t0 = time.perf_counter()
    d = hs.diagnose(hs.Hammerstein(), u, y, validate=args.validate, follow=True)
    t_h = time.perf_counter() - t0
    c = hs.compare(d.model, u[cut:], y[cut:])
    steps = " → ".join(s.change for s in d.steps)
    print(f"hammerstein  follow ({steps}; order {d.model.order}): "
          f"{t_h:7.2f} s, validation fit {c.fit_percent:6.2f} %")

    t0 = time.perf_counter()
    m = hs.Hammerstein(effects=["hysteresis", "saturation"]).fit(u[:cut], y[:cut])
    t_f = time.perf_counter() - t0
    c = hs.compare(m, u[cut:], y[cut:])
    print(f"hammerstein  fit, effects hysteresis + saturation (order {m.order}): "
          f"{t_f:7.2f} s, validation fit {c.fit_percent:6.2f} %")

    from sysidentpy.basis_function import Polynomial
    from sysidentpy.model_structure_selection import FROLS
    from sysidentpy.parameter_estimation import LeastSquares

    for degree, lag in ((2, 2), (3, 4)):
        t0 = time.perf_counter()
        m = FROLS(
            ylag=lag, xlag=lag, order_selection=True, info_criteria="aic",
            estimator=LeastSquares(), basis_function=Polynomial(degree=degree),
        )
        m.fit(X=u[:cut].reshape(-1, 1), y=y[:cut].reshape(-1, 1))
        t_s = time.perf_counter() - t0
        y_hat = m.predict(X=u[cut:].reshape(-1, 1), y=y[cut:].reshape(-1, 1))
        f = fit_percent(y[cut:], y_hat) if np.all(np.isfinite(y_hat)) else float("nan")
        print(f"SysIdentPy   FROLS NARX degree {degree}, lags {lag} ({len(m.final_model)} terms): "
              f"{t_s:7.2f} s, validation fit {f:6.2f} %")


if __name__ == "__main__":
    main()
