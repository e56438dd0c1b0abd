"""The walk-through of docs/python.md, as one script: fit, diagnose, follow, save, plot.

    python python/scripts/walkthrough.py ../shared/data/labcontrol_mr_damper_sine/ensaio04.csv \
        --input vel_mm_s --output force_N --plot docs/img/python-mr-damper.png

The plot needs matplotlib (optional: without it the script says so and skips the figure).
"""

import argparse
import os
import tempfile

import numpy as np

import hammerstein as hs


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv")
    ap.add_argument("--input", default="u")
    ap.add_argument("--output", default="y")
    ap.add_argument("--plot", help="write the figure (PNG) here")
    args = ap.parse_args()

    # the record: a CSV with a time column
    table = np.genfromtxt(args.csv, delimiter=",", names=True)
    u, y = table[args.input], table[args.output]
    ts = float(np.median(np.diff(table["t"])))
    data = hs.IoData(u, y, ts=ts)
    print(data)

    # a linear model first: training part = the first 70 %
    train, valid = data.split(0.3)
    lin = hs.Hammerstein().fit(train)
    print(lin)
    print("train MSE", f"{lin.report['train_mse']:.4g}", "termination", lin.report["termination"])
    print("validation", hs.compare(lin, valid))

    # what is it missing?
    d = hs.diagnose(lin, data, validate=0.3)
    print(d)
    print(d.summary)
    for s in d.suggestions:
        print(f"  {s.effect:<20} expected gain {s.expected_gain:6.1%}  estimate {s.estimate}")

    # follow the suggestions, one refit at a time
    f = hs.diagnose(hs.Hammerstein(), data, validate=0.3, follow=True)
    for i, st in enumerate(f.steps):
        print(f"  {i}  {st.change:<22} effects {st.model.effects!s:<28} order "
              f"{st.model.order:>2}  validation fit {st.diagnosis.validation.fit_percent:6.2f} %")
    print("stopped:", f.stop, "| validation rose at steps", f.validation_rose_at)
    print("parameters", {k: round(v, 4) for k, v in f.model.parameters.items()})

    # the model file is the command line's (hammerstein compare MODEL.json RECORD.csv)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "model.json")
        f.model.save(path)
        print("reloaded:", hs.load(path))
        print("report:", f.to_html(os.path.join(tmp, "report")))

    if args.plot:
        try:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            print("matplotlib is not installed: no figure")
            return
        t = np.arange(len(valid)) * ts
        fig, ax = plt.subplots(figsize=(9, 3.2))
        ax.plot(t, valid.y[:, 0], "k", lw=1.2, label="measured")
        ax.plot(t, hs.compare(lin, valid).y_hat, lw=1, label="linear (start)")
        ax.plot(t, hs.compare(f.model, valid).y_hat, lw=1, label="followed (last step)")
        ax.set_xlabel("time in the validation part [s]")
        ax.set_ylabel(args.output)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
        fig.tight_layout()
        fig.savefig(args.plot, dpi=110)
        print("figure:", args.plot)


if __name__ == "__main__":
    main()
