"""The EMPS reference rigid-body model simulated from the measured force on the test record.

M q'' = F - Fv q' - Fc sgn(q') - offset with the IDIM-LS estimates of the EMPS description
(M = 95.1089 kg, Fv = 203.5034 N s/m, Fc = 20.3935 N, offset = -3.1648 N), integrated at the
record's 1 kHz (semi-implicit Euler) from the measured position and velocity at the start; the
RMS error of the position against qm_m, at 1 kHz and on every 20th sample (the decimated
record of docs/case-studies.md). The sign is also smoothed (tanh(q'/w)) to show the error does
not depend on its width.

    python3 docs/case-study-runs/emps_reference.py [../shared/data/emps/test_pulses.csv]
"""

import csv
import math
import sys

path = sys.argv[1] if len(sys.argv) > 1 else "../shared/data/emps/test_pulses.csv"
rows = list(csv.DictReader(open(path)))
F = [float(r["force_N"]) for r in rows]
q = [float(r["qm_m"]) for r in rows]
t = [float(r["t"]) for r in rows]
Ts = t[1] - t[0]
M, Fv, Fc, off = 95.1089, 203.5034, 20.3935, -3.1648


def simulate(width):
    x, v, out = q[0], (q[1] - q[0]) / Ts, []
    for f in F:
        out.append(x)
        sign = math.tanh(v / width) if width > 0 else (v > 0) - (v < 0)
        v += Ts * (f - Fv * v - Fc * sign - off) / M
        x += Ts * v
    return out


def rms(e):
    return math.sqrt(sum(x * x for x in e) / len(e))


for width in [0.0, 1e-3, 1e-2]:
    e = [a - b for a, b in zip(q, simulate(width))]
    print(
        f"sign width {width:g} m/s: RMS error {1e3 * rms(e):.2f} mm at 1 kHz, "
        f"{1e3 * rms(e[::20]):.2f} mm decimated by 20"
    )
