#!/usr/bin/env python3
"""Scores a `piezoid identify` run on a trend bench (data/bimorph-fin/trends-*) against its truth.

    bench/score_trend_bench.py build/client/piezoid data/bimorph-fin/trends-dev2 OUT_DIR

prints one row: CF (Σ PI over the training cases), the cases below the paper's Table 8, the cases
within 3 × the PI of their true parameters (`piezoid pi --params truth_params.csv --saturation
given`), the worst case by that ratio, and R² of the network's δ, a1, a2 against the truth over the
nine cases (1 − Σ (net − truth)² / Σ (truth − mean)²).
"""

import csv
import os
import subprocess
import sys


def truth_pi(piezoid, bench):
    out = subprocess.run([piezoid, "pi", "--cases", bench, "--params",
                          os.path.join(bench, "truth_params.csv"), "--saturation", "given"],
                         check=True, capture_output=True, text=True).stdout
    pis = {}
    for line in out.splitlines():
        f = line.split()
        if len(f) >= 10 and f[0].isdigit() and f[-1] == "ok":
            pis[int(f[0])] = float(f[-4])
    return pis


def main():
    if len(sys.argv) != 4:
        sys.exit("usage: score_trend_bench.py PIEZOID BENCH_DIR IDENTIFY_OUT_DIR")
    piezoid, bench, out = sys.argv[1:]
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


if __name__ == "__main__":
    main()
