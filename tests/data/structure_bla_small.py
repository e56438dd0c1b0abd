# Reproduces tests/data/structure_bla_small.csv and its reference numbers:
#   hammerstein design --samples 256 --band 0.02,0.3 --levels 1 --realizations 4 --periods 3 --seed 11 --out /tmp/small_design.csv
#   python3.12 -m venv venv && venv/bin/pip install best-linear-approximation==0.1.1 && venv/bin/python tests/data/structure_bla_small.py
# (run from the repository root; the package stays out of the crate and of cargo test)
# Replays the design on a Wiener-Hammerstein plant (y = G2(x + 0.3 x^3), x = G1 u) with output
# noise, writes the record, and runs best-linear-approximation 0.1.1 (robust.known_input) on it.
import csv, numpy as np
rows = list(csv.DictReader(open('/tmp/small_design.csv')))
N = 256
def lfilter(b, a, x):
    y = np.zeros_like(x)
    for t in range(len(x)):
        v = b[0]*x[t]
        if t >= 1: v += b[1]*x[t-1] - a[1]*y[t-1]
        if t >= 2: v += b[2]*x[t-2] - a[2]*y[t-2]
        y[t] = v
    return y
rng = np.random.default_rng(2024)
blocks = {}
for r in rows:
    blocks.setdefault(int(r['realization']), []).append(float(r['u']))
out = ['level,realization,period,u,y']
us, ys = [], []
for m in sorted(blocks):
    u = np.array(blocks[m])
    x = lfilter([0.2, 0.1, 0.0], [1.0, -1.2, 0.6], u)
    y = lfilter([0.3, 0.2, 0.0], [1.0, -0.5, 0.3], x + 0.3*x**3) + 0.01*rng.standard_normal(len(u))
    for i in range(len(u)):
        out.append(f'0,{m},{i//N},{float(u[i])!r},{float(y[i])!r}')
    us.append(u[N:2*N]); ys.append(y[N:].reshape(-1, N).T)
open('tests/data/structure_bla_small.csv', 'w').write('\n'.join(out) + '\n')
import best_linear_approximation as bla
from best_linear_approximation import robust
U = np.stack(us, axis=-1)[:, None, :]            # (N, 1, M)
Y = np.stack(ys, axis=-2)[:, None, :, :]         # (N, 1, M, P)
spec = np.abs(np.fft.rfft(us[0]))
exc = np.nonzero(spec > 1e-3*spec.max())[0]
exc = exc[(exc > 0) & (exc < N//2)]
res = robust.known_input(U, Y, fs=1.0, excited_bins=exc)
G = res.G.value.reshape(len(exc))
vt = res.G.total.var.reshape(len(exc))
vn = res.G.noise.var.reshape(len(exc))
lines = ['# best-linear-approximation 0.1.1 (PyPI), robust.known_input(u, y, fs=1, excited_bins) on',
         '# tests/data/structure_bla_small.csv (steady periods 1..3; see tests/structure_python_reference.rs)',
         'k,re,im,var_total,var_noise']
for k, g, a, b in zip(exc, G, vt, vn):
    lines.append(f'{k},{float(g.real)!r},{float(g.imag)!r},{float(a)!r},{float(b)!r}')
open('tests/data/structure_bla_small_reference.csv', 'w').write('\n'.join(lines) + '\n')
print(len(exc), 'lines; first', lines[3])
