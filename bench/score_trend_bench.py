#!/usr/bin/env python3
"""Scores a `piezoid identify` run on a trend bench (data/bimorph-fin/trends-*) against its truth.

    bench/score_trend_bench.py build/client/piezoid data/bimorph-fin/trends-dev2 OUT_DIR

prints one row: CF (Σ PI over the training cases), the cases below the paper's Table 8, the cases
within 3 × the PI of their true parameters (`piezoid pi --params truth_params.csv --saturation
given`), the worst case by that ratio, and R² of the network's δ, a1, a2 against the truth over the
nine cases (1 − Σ (net − truth)² / Σ (truth − mean)²).

    bench/score_trend_bench.py build/client/piezoid data/bimorph-fin/trends-dev2 OUT_DIR --swap

also prints what a miss is made of: each case's PI with its true parameters but one of them (μ, δ,
α, β, γ, a1, a2, then b1 and b2 together) swapped to the network's value (× the truth's PI), and
how sensitive each case's PI is to each parameter: the truth with that one raised by 10 %; and
what a bound on the extrapolation would give at best: the network's parameters with every withheld
case's μ … a2 clamped to the range of the network's values at the training cases.
"""

import csv
import os
import subprocess
import sys
import tempfile


PARAMS = ("mu", "delta", "alpha", "beta", "gamma", "a1", "a2", "b1", "b2")


def truth_pi(piezoid, bench, params_file=None):
    params_file = params_file or os.path.join(bench, "truth_params.csv")
    out = subprocess.run([piezoid, "pi", "--cases", bench, "--params", params_file,
                          "--saturation", "given"],
                         check=True, capture_output=True, text=True).stdout
    pis = {}
    for line in out.splitlines():
        f = line.split()
        if len(f) >= 10 and f[0].isdigit() and f[-1] == "ok":
            pis[int(f[0])] = float(f[-4])
    return pis


def pi_with(piezoid, bench, rows):
    """Each case's PI with the per-case parameters `rows` (case → {name: value})."""
    with tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False) as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(("case",) + PARAMS)
        for c in sorted(rows):
            w.writerow([c] + [repr(float(rows[c][k])) for k in PARAMS])
        name = fh.name
    try:
        return truth_pi(piezoid, bench, name)
    finally:
        os.unlink(name)


def ratios(pis, floor):
    return " ".join(f"{c}:{pis.get(c, float('nan')) / floor[c]:.1f}" for c in sorted(floor))


def swaps(piezoid, bench, truth, net, floor):
    """The truth with one parameter swapped to the network's value, and raised by 10 %."""
    groups = [(k,) for k in PARAMS[:7]] + [("b1", "b2")]
    print("  PI x truth with one parameter swapped to the network's value, per case:")
    for g in groups:
        rows = {c: dict(truth[c]) for c in truth}
        for c in rows:
            for k in g:
                rows[c][k] = net[c][k]
        pis = pi_with(piezoid, bench, rows)
        print(f"    {'/'.join(g):>7}: " + ratios(pis, floor))
    print("  PI x truth with one parameter of the truth raised by 10 %, per case:")
    for k in PARAMS[:7]:
        rows = {c: dict(truth[c]) for c in truth}
        for c in rows:
            rows[c][k] = 1.1 * float(rows[c][k])
        pis = pi_with(piezoid, bench, rows)
        print(f"    {k:>7}: " + ratios(pis, floor))
    rows = {c: {k: float(net[c][k]) for k in PARAMS} for c in net}
    train = [c for c in net if net[c]["role"] == "train"]
    for c in rows:
        if c in train:
            continue
        for k in PARAMS[:7]:
            values = [float(net[t][k]) for t in train]
            rows[c][k] = min(max(rows[c][k], min(values)), max(values))
    print("  PI x truth of the network with the withheld cases' outputs clamped to the training "
          "cases' range:\n    " + ratios(pi_with(piezoid, bench, rows), floor))


def main():
    if len(sys.argv) not in (4, 5) or (len(sys.argv) == 5 and sys.argv[4] != "--swap"):
        sys.exit("usage: score_trend_bench.py PIEZOID BENCH_DIR IDENTIFY_OUT_DIR [--swap]")
    piezoid, bench, out = sys.argv[1:4]
    floor = truth_pi(piezoid, bench)
    with open(os.path.join(out, "validation.csv")) as fh:
        val = {int(r["case"]): r for r in csv.DictReader(fh)}
    with open(os.path.join(out, "parameters.csv")) as fh:
        net = {int(r["case"]): r for r in csv.DictReader(fh)}
    with open(os.path.join(bench, "truth_params.csv")) as fh:
        truth = {int(r["case"]): r for r in csv.DictReader(fh)}
    cf = sum(float(r["pi_deg2"]) for r in val.values() if r["role"] == "train")
    below = sum(float(r["pi_deg2"]) < float(r["paper_pi_deg2"]) for r in val.values())
    ratio = {c: float(r["pi_deg2"]) / floor[c] for c, r in val.items()}
    within = sum(x <= 3 for x in ratio.values())
    worst = max(ratio, key=ratio.get)
    r2 = []
    for k in ("delta", "a1", "a2"):
        t = [float(truth[c][k]) for c in sorted(truth)]
        n = [float(net[c][k]) for c in sorted(truth)]
        mean = sum(t) / len(t)
        ss = sum((x - mean) ** 2 for x in t)
        r2.append(1 - sum((a - b) ** 2 for a, b in zip(n, t)) / ss)
    print(f"CF {cf:.4f} | below Table 8 {below}/9 | within 3x truth {within}/9 | "
          f"worst case {worst}: "
          f"{float(val[worst]['pi_deg2']):.3g} ({ratio[worst]:.1f}x) | R2 delta/a1/a2 "
          + " / ".join(f"{x:.3f}" for x in r2))
    print("  per case x truth: " + " ".join(f"{c}:{ratio[c]:.1f}" for c in sorted(ratio)))
    if len(sys.argv) == 5:
        swaps(piezoid, bench, truth, net, floor)


if __name__ == "__main__":
    main()
