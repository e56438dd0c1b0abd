#!/usr/bin/env python3
"""Checks the case-study runs of scripts/case_studies.sh against two conditions.

  scripts/check_case_studies.py OUTDIR [--text]

For each record of OUTDIR/records.tsv it reads OUTDIR/<record>.json (`diagnose --follow
--json`) and reports:

- every step's validation MSE and its change from the previous step; a rise above 1 % fails;
- every parameter of the final model whose two-standard-error interval contains its null value:
  the hysteresis half-width a and the dead-zone half-width b (null 0), the preload's steps e1
  and e2 (null 0; the preload is null when both are), the saturation limits z1, z2 (null: the
  limit outside the training input's range, so that the saturation never acts; both must be
  for the saturation to be null), the play weights w1..w6 (null 0; the operator is null when
  every kept weight is, or when a weight is clearly against the gain p), the output map's
  coefficients c2, c3 (null 0; the map is null when both are). An effect that is null fails.
  The interval is the one the guided loop's own rules use (value +- 2 standard errors); the
  library's preload and play rules are sharper (the jump e1 - e2 with its covariance, the F
  test of the plays together), so an effect flagged here is one to look at, not proof.

It prints one table (record, steps, validation MSE per step with its change, rises > 1 %, null
parameters, wall time); with --text it also writes OUTDIR/<record>.txt, a readable account of
each run (steps, checks, final check, final model with its standard errors).
"""
import csv
import json
import math
import os
import sys

RISE = 0.01  # a validation-MSE rise above 1 % fails


def training_input_range(path, column, validate):
    """Min and max of the training part of `column` (the first 1 - validate of the rows)."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    u = [float(r[column]) for r in rows]
    if validate:
        n_val = round(len(u) * float(validate))
        u = u[: len(u) - n_val]
    return min(u), max(u)


def num(x):
    return float("nan") if x is None else float(x)


def nulls(j, u_range):
    """Parameters of the final model whose +-2 se interval contains their null value, and the
    effects found null by the rules of the module doc."""
    p, se = j.get("parameters", {}), j.get("standard_errors", {})
    found, null_effects = [], []

    def interval(k):
        v, s = num(p.get(k)), num(se.get(k))
        if math.isnan(s):
            s = math.inf
        return v, s

    def at_zero(k):
        v, s = interval(k)
        hit = abs(v) <= 2 * s
        if hit:
            found.append(f"{k} = {v:.4g} ± {s:.2g}")
        return hit

    effects = j.get("effects", [])
    if "hysteresis" in effects and at_zero("a"):
        null_effects.append("hysteresis")
    if "dead-zone" in effects and at_zero("b"):
        null_effects.append("dead-zone")
    if "preload" in effects:
        z1, z2 = at_zero("e1"), at_zero("e2")
        if z1 and z2:
            null_effects.append("preload")
    if "saturation" in effects and "z1" in p:
        lo, hi = u_range
        (z1, s1), (z2, s2) = interval("z1"), interval("z2")
        up, down = z1 + 2 * s1 >= hi, z2 - 2 * s2 <= lo
        if up:
            found.append(f"z1 = {z1:.4g} ± {s1:.2g} (max u {hi:.4g})")
        if down:
            found.append(f"z2 = {z2:.4g} ± {s2:.2g} (min u {lo:.4g})")
        if up and down:
            null_effects.append("saturation")
    weights = sorted(k for k in p if k.startswith("w") and k[1:].isdigit())
    if weights:
        gain = math.copysign(1.0, num(p.get("p", 1.0)))
        zero = [at_zero(k) for k in weights]
        against = []
        for k in weights:
            v, s = interval(k)
            if gain * v < -2 * s:
                against.append(k)
                found.append(f"{k} = {v:.4g} ± {s:.2g} against the gain p")
        if all(zero) or against:
            null_effects.append("prandtl-ishlinskii")
    om = j.get("output_nonlinearity")
    if om:
        op, ose = om.get("parameters", {}), om.get("standard_errors", {})
        hits = []
        for k, v in op.items():
            s = num(ose.get(k))
            s = math.inf if math.isnan(s) else s
            if abs(num(v)) <= 2 * s:
                hits.append(k)
                found.append(f"output map {k} = {num(v):.4g} ± {s:.2g}")
        if op and len(hits) == len(op):
            null_effects.append("output map")
    return found, null_effects


def text_of(name, j, wall, command):
    """A readable account of one run."""
    out = [f"record: {name}   wall time: {wall}"]
    if command:
        out.append(f"command: {command}")
    out.append(f"{'step':<5} {'change':<34} {'effects':<34} {'order':>5} {'val MSE':>12} "
               f"{'change':>9} {'fit %':>7}")
    prev, var = None, None
    for i, st in enumerate(j.get("steps", [])):
        mse = num(st["validation"]["mse"])
        fit = num(st["validation"].get("fit_percent"))
        if var is None and not math.isnan(fit) and fit < 100:
            var = mse / (1 - fit / 100) ** 2  # the validation output's variance
        if math.isnan(fit) and var:
            fit = 100 * (1 - math.sqrt(mse / var))  # a feedback step reports its MSE only
        if st.get("kind") == "feedback":
            what = f"feedback {st.get('feedback_nonlinearity')} on {st.get('feedback_on')}"
        else:
            what = ",".join(st.get("effects", [])) or "linear"
        ch = "" if prev is None else f"{100 * (mse / prev - 1):+.2f} %"
        out.append(f"{i:<5} {st['change'][:34]:<34} {what:<34} "
                   f"{st['order']:>5} {mse:>12.6e} {ch:>9} {fit:>7.2f}")
        prev = mse
    for i, st in enumerate(j.get("steps", [])):
        c = st.get("confirmation")
        if c:
            if c.get("note"):
                out.append(f"step {i} on the held-back part of training: not checked: {c['note']}")
            else:
                out.append(
                    f"step {i} on the held-back part of training: held-back MSE "
                    f"{num(c['mse_before']):.4g} -> {num(c['mse_after']):.4g} "
                    f"({100 * (num(c['mse_after']) / num(c['mse_before']) - 1):+.2f} %, DM "
                    f"{num(c['statistic']):.2f}, p = {num(c['p_value']):.3f}, {c['held_back']} "
                    f"samples): {'confirmed' if c['confirmed'] else 'not confirmed'}")
    r = j.get("refused_step")
    if r:
        c = r["confirmation"]
        out.append(f"refused: {r['change']}: held-back MSE {num(c['mse_before']):.4g} -> "
                   f"{num(c['mse_after']):.4g} (DM {num(c['statistic']):.2f}, p = "
                   f"{num(c['p_value']):.3f})")
    out.append(f"stopped: {j.get('stop')}")
    for note in j.get("final_check", []):
        out.append(f"final check: {note}")
    out.append("")
    last = (j.get("steps") or [{}])[-1]
    if last.get("kind") == "feedback" and last.get("taken", True):
        out.append(f"final model: the feedback model of the last step ({last.get('command')}), "
                   f"order {last.get('order')}, validation MSE {num(last['validation']['mse']):.6e}; "
                   "below: the Hammerstein model it extends")
    out.append(f"{'' if last.get('kind') != 'feedback' else 'base '}model: {j.get('nonlinearity')} (effects: {', '.join(j.get('effects', [])) or 'none'}), "
               f"order {j.get('order')}, delay {j.get('delay')}, spectral radius "
               f"{num(j.get('spectral_radius')):.6f}")
    se = j.get("standard_errors", {})
    for k, v in j.get("parameters", {}).items():
        out.append(f"  {k:>4} = {num(v):.6g} ± {num(se.get(k)):.2g}")
    om = j.get("output_nonlinearity")
    if om:
        out.append(f"output map: {om.get('name')}")
        for k, v in om.get("parameters", {}).items():
            out.append(f"  {k:>4} = {num(v):.6g} ± {num(om.get('standard_errors', {}).get(k)):.2g}")
    for part in ("train", "validation"):
        m = j.get(part) or {}
        if m:
            out.append(f"{part}: fit {num(m.get('fit_percent')):.2f} %  MSE {num(m.get('mse')):.6e}")
    out.append(f"adequate: {j.get('adequate')}")
    for u in j.get("unexplained", []):
        out.append(f"  unexplained: {u.get('test')} (p = {num(u.get('p_adjusted')):.3g}); would "
                   f"need: {'; '.join(u.get('model_classes', []))}")
    return "\n".join(out) + "\n"


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    outdir, write_text = sys.argv[1], "--text" in sys.argv[2:]
    failed = False
    print("| record | steps | validation MSE per step (change) | rise > 1 % | null parameters | wall time |")
    print("|---|---|---|---|---|---|")
    with open(os.path.join(outdir, "records.tsv")) as f:
        records = [line.rstrip("\n").split("\t") for line in f if line.strip()]
    for name, path, column, validate, *command in records:
        wall = "?"
        tp = os.path.join(outdir, f"{name}.time")
        if os.path.exists(tp):
            parts = [x.strip() for x in open(tp).read().strip().splitlines()[-1].split(",")]
            wall = parts[0]
            if len(parts) >= 4:  # "W s, U s user, S s sys, M KB"
                cpu = float(parts[1].split()[0]) + float(parts[2].split()[0])
                wall += f" ({cpu:.1f} s CPU)"
        try:
            with open(os.path.join(outdir, f"{name}.json")) as f:
                j = json.load(f)
        except (OSError, ValueError) as e:
            print(f"| {name} | no JSON ({e}) | | | | {wall} |")
            failed = True
            continue
        steps = j.get("steps", [])
        mses = [num(s["validation"]["mse"]) for s in steps]
        shown, rises = [], []
        for i, m in enumerate(mses):
            if i == 0:
                shown.append(f"{m:.4g}")
            else:
                ch = m / mses[i - 1] - 1
                shown.append(f"{m:.4g} ({100 * ch:+.1f} %)")
                if ch > RISE:
                    rises.append(f"step {i} {100 * ch:+.1f} %")
        found, null_effects = nulls(j, training_input_range(path, column, validate))
        changes = ", ".join(s["change"] for s in steps[1:]) or "none"
        nl = "; ".join(found) or "none"
        if null_effects:
            nl += f" — null: {', '.join(null_effects)}"
        print(f"| {name} | {changes} | {' → '.join(shown)} | {', '.join(rises) or 'none'} | {nl} | {wall} |")
        failed |= bool(rises) or bool(null_effects)
        if write_text:
            with open(os.path.join(outdir, f"{name}.txt"), "w") as f:
                f.write(text_of(name, j, wall, command[0] if command else ""))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
