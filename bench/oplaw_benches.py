#!/usr/bin/env python3
"""Smooth operating-point law benches for the HGANN (issue 47), and the study that scores them.

    bench/oplaw_benches.py make  PIEZOID OUT_ROOT FAMILY SEED...
    bench/oplaw_benches.py study PIEZOID OUT_ROOT FAMILY SEED... [-- IDENTIFY_ARGS...]
    bench/oplaw_benches.py next  PIEZOID OUT_ROOT FAMILY SEED... [-- IDENTIFY_ARGS...]
    bench/oplaw_benches.py oracle PIEZOID OUT_ROOT FAMILY SEED...
    bench/oplaw_benches.py smooth PIEZOID OUT_ROOT FAMILY SEED...

`make` writes, per seed, OUT_ROOT/FAMILY-SEED-four (the paper's training cases 1, 5, 6, 7) and
OUT_ROOT/FAMILY-SEED-corner (the same nine cases, case 9 at (750 V, 1 Hz) trained as well): the
paper's nine operating points of a fin bench whose mu, delta, a1 and a2 follow smooth laws of V and
f drawn from SEED, with alpha, beta, gamma constant (the nominal bench's loop) and the nominal
bench's saturations; simulated, jittered and quantised as scripts/make_trend_benches.py does (the
CVODE path, not the identification's modal path). truth.json and truth_params.csv beside them.

Two families, drawn by different rules, with v = (V - 375) / 375 and l = ln(f / 0.25) / ln 4:
  - "dev" (the one developed on): each parameter c + a v + b l, plus d v l for an even SEED;
  - "check" (only checked with, never tuned on): each parameter c + a v^p + b g(f) + d v (f -
    0.25) / 0.75 with p in [0.6, 1.6], g = sqrt((f - 0.25) / 0.75) or (f - 0.25) / 0.75 (linear
    in f, not in log f), the V f term for SEED divisible by 3;
  - "fresh" (written after the law's shape in f became a choice among ln f, sqrt f and f, which
    was measured on "check" as well: only checked with, once): each parameter c + a e(v) + b
    t(l) + d v x, e(v) = (1 - exp(-k v)) / (1 - exp(-k)) with k in [-2.5, 2.5] (concave or convex
    in V), t(l) = tanh(s l) / tanh(s) with s in [0.3, 2.5] (a sigmoid in log f, no power of f),
    x = (f - 0.25) / 0.75, the V f term for odd SEED.
Each law's corner values are drawn uniformly inside the parameter's band (mu 72-108 1/s, delta
0.04-0.28 s, a1 and a2 0.02-0.28 deg), the interaction moving the (750 V, 1 Hz) corner by up to
25 % of the band; a draw leaving the band anywhere on the nine points is drawn again.

`study` runs the default `piezoid identify` (or with IDENTIFY_ARGS) on both splits of each bench
and prints, per run, the training cost, each case's PI over its truth's PI (the truth's
parameters, `piezoid pi --saturation given`), the worst withheld ratio, and how many withheld
cases are within 3 x; then the totals. The runs' folders are kept under OUT_ROOT/runs.

`next` trains, on each bench's paper split, the case identify proposes to measure next (query by
committee, report.md) as a fifth case, and each other withheld case instead, and prints how many
of the rest are within 3 x their truth's PI for each choice.

`oracle` fits the truth's own law shape with free coefficients to the training cases (oracle()):
where even that misses 3 x, the loss is in the identification, not in the law's shape. `smooth`
fits a law of no chosen shape with a curvature prior the same way (smooth()).
"""

import csv
import math
import os
import random
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import make_trend_benches as mtb  # noqa: E402  (the simulation, jitter and quantisation)
import score_trend_bench  # noqa: E402  (the truth's PI)

BANDS = {"mu": (72.0, 108.0), "delta": (0.04, 0.28), "a1": (0.02, 0.28), "a2": (0.02, 0.28)}
POINTS = [(v, f) for v in (375, 500, 750) for f in (0.25, 0.5, 1.0)]


def v_of(v):
    return (v - 375.0) / 375.0


def l_of(f):
    return math.log(f / 0.25) / math.log(4.0)


def draw_law(rng, family, seed, name):
    lo, hi = BANDS[name]
    span = hi - lo
    while True:
        p00, p10, p01 = (rng.uniform(lo, hi) for _ in range(3))
        if family == "dev":
            inter = seed % 2 == 0
            d = rng.uniform(-0.25, 0.25) * span if inter else 0.0
            a, b = p10 - p00, p01 - p00
            fn = (lambda c, a, b, d: lambda v, f: c + a * v_of(v) + b * l_of(f)
                  + d * v_of(v) * l_of(f))(p00, a, b, d)
            basis = [v_of, lambda v, f: l_of(f), lambda v, f: v_of(v) * l_of(f)]
            text = (f"{name} = {p00:.4g} + {a:.4g} v + {b:.4g} l" + (f" + {d:.4g} v l" if d else "")
                    + "   v = (V - 375) / 375, l = ln(f / 0.25) / ln 4")
        elif family == "fresh":
            inter = seed % 2 == 1
            k = rng.uniform(-2.5, 2.5) or 1e-3
            sl = rng.uniform(0.3, 2.5)
            d = rng.uniform(-0.25, 0.25) * span if inter else 0.0
            a, b = p10 - p00, p01 - p00

            def e(v, k=k):
                return (1 - math.exp(-k * v_of(v))) / (1 - math.exp(-k))

            def t(f, sl=sl):
                return math.tanh(sl * l_of(f)) / math.tanh(sl)

            fn = (lambda c, a, b, d, e, t: lambda v, f: c + a * e(v) + b * t(f)
                  + d * v_of(v) * (f - 0.25) / 0.75)(p00, a, b, d, e, t)
            basis = [lambda v, f, e=e: e(v), lambda v, f, t=t: t(f),
                     lambda v, f: v_of(v) * (f - 0.25) / 0.75]
            text = (f"{name} = {p00:.4g} + {a:.4g} (1 - exp({-k:.3f} v)) / (1 - exp({-k:.3f}))"
                    f" + {b:.4g} tanh({sl:.3f} l) / tanh({sl:.3f})"
                    + (f" + {d:.4g} v (f - 0.25) / 0.75" if d else "")
                    + "   v = (V - 375) / 375, l = ln(f / 0.25) / ln 4")
        else:
            inter = seed % 3 == 0
            power = rng.uniform(0.6, 1.6)
            use_sqrt = rng.random() < 0.5
            d = rng.uniform(-0.25, 0.25) * span if inter else 0.0
            a, b = p10 - p00, p01 - p00

            def g(f, use_sqrt=use_sqrt):
                x = (f - 0.25) / 0.75
                return math.sqrt(x) if use_sqrt else x

            fn = (lambda c, a, b, d, p, g: lambda v, f: c + a * v_of(v) ** p + b * g(f)
                  + d * v_of(v) * (f - 0.25) / 0.75)(p00, a, b, d, power, g)
            basis = [lambda v, f, p=power: v_of(v) ** p, lambda v, f, g=g: g(f),
                     lambda v, f: v_of(v) * (f - 0.25) / 0.75]
            text = (f"{name} = {p00:.4g} + {a:.4g} v^{power:.3f} + {b:.4g} "
                    + ("sqrt((f - 0.25) / 0.75)" if use_sqrt else "(f - 0.25) / 0.75")
                    + (f" + {d:.4g} v (f - 0.25) / 0.75" if d else "") + "   v = (V - 375) / 375")
        if all(lo <= fn(v, f) <= hi for v, f in POINTS):
            # The law's own shape (the oracle's basis): 1, the V term, the f term, and the V f term
            # where the law has one; its coefficients.
            shape = [lambda v, f: 1.0] + basis[:2] + (basis[2:] if d else [])
            return fn, text, shape, [p00, a, b] + ([d] if d else [])


def laws_of(family, seed):
    mult = {"dev": 1, "check": 7919, "fresh": 104729}[family]
    rng = random.Random(mult * 100003 + seed)
    laws = {"seed": 5000 + seed + {"dev": 0, "check": 500, "fresh": 900}[family], "text": {}}
    for name in ("mu", "delta", "a1", "a2"):
        fn, text, shape, coef = draw_law(rng, family, seed, name)
        laws[name] = fn
        laws["text"][name] = text
        laws.setdefault("shape", {})[name] = (shape, coef)
    return laws


def make(piezoid, root, family, seed):
    name = f"{family}-{seed}"
    four, corner = os.path.join(root, name + "-four"), os.path.join(root, name + "-corner")
    if os.path.exists(os.path.join(four, "truth_params.csv")) and os.path.exists(corner):
        return four, corner
    mtb.make(piezoid, root, name + "-four", laws_of(family, seed))
    shutil.rmtree(corner, ignore_errors=True)
    shutil.copytree(four, corner)
    with open(os.path.join(corner, "cases.csv"), newline="") as fh:
        rows = list(csv.reader(fh))
    for r in rows[1:]:
        if r[0] == "9":
            r[4] = "train"
    with open(os.path.join(corner, "cases.csv"), "w", newline="") as fh:
        csv.writer(fh, lineterminator="\n").writerows(rows)
    return four, corner


def score(piezoid, bench, out):
    floor = score_trend_bench.truth_pi(piezoid, bench)
    with open(os.path.join(out, "validation.csv")) as fh:
        val = {int(r["case"]): r for r in csv.DictReader(fh)}
    ratio = {c: float(r["pi_deg2"]) / floor[c] for c, r in val.items()}
    train = [c for c, r in val.items() if r["role"] == "train"]
    held = [c for c in sorted(ratio) if c not in train]
    cf = sum(float(val[c]["pi_deg2"]) for c in train)
    return cf, ratio, train, held


def study(piezoid, root, family, seeds, extra):
    totals = {"four": [0, 0], "corner": [0, 0]}
    for seed in seeds:
        for split, bench in zip(("four", "corner"), make(piezoid, root, family, seed)):
            out = os.path.join(root, "runs", f"{family}-{seed}-{split}")
            subprocess.run([piezoid, "identify", "--cases", bench, "--out", out, "--no-plots"]
                           + extra, check=True, stdout=subprocess.DEVNULL)
            cf, ratio, train, held = score(piezoid, bench, out)
            within = sum(ratio[c] <= 3 for c in held)
            totals[split][0] += within
            totals[split][1] += len(held)
            worst = max(held, key=lambda c: ratio[c])
            print(f"{family}-{seed} {split:6s} CF {cf:.3f} | withheld within 3x {within}/{len(held)}"
                  f" | worst case {worst} {ratio[worst]:.1f}x | per case x truth: "
                  + " ".join(f"{c}{'*' if c in train else ''}:{ratio[c]:.1f}" for c in sorted(ratio)),
                  flush=True)
    for split, (w, n) in totals.items():
        print(f"total {split}: {w}/{n} withheld cases within 3x their truth's PI")


def next_case(piezoid, root, family, seeds, extra):
    """Part 3 of issue 47: on each bench's paper split, the case identify proposes (report.md's
    "next case to measure") trained as a fifth case, against each other withheld case trained
    instead (every alternative of the same number: no luckier random draw exists); per choice the
    withheld cases within 3 x their truth's PI."""
    for seed in seeds:
        four, _ = make(piezoid, root, family, seed)
        out = os.path.join(root, "runs", f"{family}-{seed}-four")
        if not os.path.exists(os.path.join(out, "report.md")):
            subprocess.run([piezoid, "identify", "--cases", four, "--out", out, "--no-plots"]
                           + extra, check=True, stdout=subprocess.DEVNULL)
        with open(os.path.join(out, "report.md")) as fh:
            line = next(l for l in fh if l.startswith("- next case to measure"))
        proposed = int(line.split("): ", 1)[1].split("case ", 1)[1].split(" ", 1)[0])
        with open(os.path.join(four, "cases.csv"), newline="") as fh:
            rows = list(csv.reader(fh))
        held = [int(r[0]) for r in rows[1:] if r[4] != "train"]
        results = []
        for choice in held:
            bench = os.path.join(root, f"{family}-{seed}-plus{choice}")
            if not os.path.exists(bench):
                shutil.copytree(four, bench)
                for r in rows[1:]:
                    r[4] = "train" if int(r[0]) == choice or r[4] == "train" else r[4]
                with open(os.path.join(bench, "cases.csv"), "w", newline="") as fh:
                    csv.writer(fh, lineterminator="\n").writerows(rows)
                with open(os.path.join(four, "cases.csv"), newline="") as fh:
                    rows = list(csv.reader(fh))
            run = os.path.join(root, "runs", f"{family}-{seed}-plus{choice}")
            subprocess.run([piezoid, "identify", "--cases", bench, "--out", run, "--no-plots"]
                           + extra, check=True, stdout=subprocess.DEVNULL)
            _, ratio, train, rest = score(piezoid, bench, run)
            within = sum(ratio[c] <= 3 for c in rest)
            results.append((choice, within, len(rest), max(ratio[c] for c in rest)))
        for choice, within, n, worst in results:
            print(f"{family}-{seed} + case {choice}{' (proposed)' if choice == proposed else ''}: "
                  f"withheld within 3x {within}/{n}, worst {worst:.1f}x", flush=True)


def nelder_mead(cost, x0, step, max_evals):
    """Minimises cost(x) from x0 (adaptive Nelder-Mead, Gao and Han 2012); returns (x, cost)."""
    n = len(x0)
    a, g, c, sh = 1.0, 1.0 + 2.0 / n, 0.75 - 0.5 / n, 1.0 - 1.0 / n
    simplex = [list(x0)] + [[x0[j] + (step if j == i else 0.0) for j in range(n)] for i in range(n)]
    costs = [cost(x) for x in simplex]
    evals = n + 1
    while evals < max_evals:
        order = sorted(range(n + 1), key=lambda i: costs[i])
        simplex, costs = [simplex[i] for i in order], [costs[i] for i in order]
        if costs[-1] - costs[0] <= 1e-10 * max(1.0, abs(costs[0])):
            break
        mid = [sum(x[j] for x in simplex[:-1]) / n for j in range(n)]

        def at(t):
            return [m + t * (m - w) for m, w in zip(mid, simplex[-1])]
        xr = at(a)
        fr = cost(xr)
        evals += 1
        if fr < costs[0]:
            xe = at(a * g)
            fe = cost(xe)
            evals += 1
            simplex[-1], costs[-1] = (xe, fe) if fe < fr else (xr, fr)
        elif fr < costs[-2]:
            simplex[-1], costs[-1] = xr, fr
        else:
            xc = at(a * c) if fr < costs[-1] else at(-c)
            fc = cost(xc)
            evals += 1
            if fc < min(fr, costs[-1]):
                simplex[-1], costs[-1] = xc, fc
            else:
                for i in range(1, n + 1):
                    simplex[i] = [b + sh * (x - b) for b, x in zip(simplex[0], simplex[i])]
                    costs[i] = cost(simplex[i])
                evals += n
    i = min(range(n + 1), key=lambda k: costs[k])
    return simplex[i], costs[i]


def oracle(piezoid, root, family, seeds):
    """Issue 47 part 2's diagnosis: the truth's own law shape (its basis functions of V and f,
    the loop constant) with free coefficients, fitted to the training cases by Nelder-Mead on their
    sum of PI (the saturations given), from the truth's coefficients and from a neutral start
    (each law flat at its band's middle, the loop the truth's), the lower kept; each withheld case's
    PI over its truth's. Within 3 x here and not in `study`: the law's shapes are the gap; missed
    here too: the training cases do not identify the law (mu against delta, noise)."""
    loop = ("alpha", "beta", "gamma")
    for seed in seeds:
        laws = laws_of(family, seed)
        for bench in make(piezoid, root, family, seed):
            floor = score_trend_bench.truth_pi(piezoid, bench)
            with open(os.path.join(bench, "truth_params.csv")) as fh:
                truth = {int(r["case"]): r for r in csv.DictReader(fh)}
            with open(os.path.join(bench, "cases.csv")) as fh:
                rows = list(csv.DictReader(fh))
            vf = {int(r["case"]): (float(r["amplitude_V"]), float(r["frequency_Hz"])) for r in rows}
            train = [int(r["case"]) for r in rows if r["role"] == "train"]
            sizes = [len(laws["shape"][k][1]) for k in BANDS]

            def params_of(x):
                out, at = {}, 0
                for c in truth:
                    out[c] = dict(truth[c])
                at = 0
                for k, nk in zip(BANDS, sizes):
                    lo, hi = BANDS[k]
                    shape = laws["shape"][k][0]
                    for c, (v, f) in vf.items():
                        out[c][k] = sum(x[at + j] * (hi - lo) * shape[j](v, f) for j in range(nk))
                    at += nk
                for j, k in enumerate(loop):
                    for c in out:
                        out[c][k] = x[at + j] * 1e-3
                return out

            def pis_of(x):
                p = params_of(x)
                if any(float(p[c][k]) < 0 for c in p for k in ("mu", "delta", "a1", "a2")):
                    return {}
                return score_trend_bench.pi_with(piezoid, bench, p)

            def cost(x):
                pis = pis_of(x)
                return sum(pis.get(c, 1e6) for c in train)

            x_truth = [cf / (BANDS[k][1] - BANDS[k][0]) for k in BANDS for cf in
                       laws["shape"][k][1]] + [float(truth[1][k]) * 1e3 for k in loop]
            x_flat = [v for k, nk in zip(BANDS, sizes) for v in
                      [sum(BANDS[k]) / 2 / (BANDS[k][1] - BANDS[k][0])] + [0.0] * (nk - 1)]
            x_flat += x_truth[-3:]
            fits = [nelder_mead(cost, x0, 0.05, 3000) + (name,)
                    for x0, name in ((x_truth, "truth"), (x_flat, "flat"))]
            x, cf, start = min(fits, key=lambda t: t[1])
            pis = pis_of(x)
            held = [c for c in sorted(floor) if c not in train]
            ratio = {c: pis.get(c, float("inf")) / floor[c] for c in floor}
            within = sum(ratio[c] <= 3 for c in held)
            split = "corner" if 9 in train else "four"
            print(f"oracle {family}-{seed} {split:6s} CF {cf:.3f} (truth "
                  f"{sum(floor[c] for c in train):.3f}; from {start}, the other "
                  f"{max(t[1] for t in fits):.3f}) | withheld within 3x {within}/{len(held)} | "
                  + " ".join(f"{c}{'*' if c in train else ''}:{ratio[c]:.1f}" for c in sorted(ratio)),
                  flush=True)


def smooth(piezoid, root, family, seeds, sigma2=2.25e-4, tau=0.5):
    """A law of no chosen shape: each of mu, delta, a1, a2 an additive law g(V) + h(f) free at the
    grid's three amplitudes and three frequencies (five values each: every additive law on the nine
    points), the loop constant, fitted to the training cases by their sum of PI plus a smoothness
    prior, sigma2 * sum of (second difference / tau)^2 of g in v and of h in log f (band units;
    sigma2 the residual variance a sample, as the law's prior is weighted; tau = 0.5 as its
    slopes'). What a curvature prior, not a shape library, predicts at the withheld cases."""
    loop = ("alpha", "beta", "gamma")
    vs, fs = (375.0, 500.0, 750.0), (0.25, 0.5, 1.0)
    for seed in seeds:
        for bench in make(piezoid, root, family, seed):
            floor = score_trend_bench.truth_pi(piezoid, bench)
            with open(os.path.join(bench, "truth_params.csv")) as fh:
                truth = {int(r["case"]): r for r in csv.DictReader(fh)}
            with open(os.path.join(bench, "cases.csv")) as fh:
                rows = list(csv.DictReader(fh))
            vf = {int(r["case"]): (float(r["amplitude_V"]), float(r["frequency_Hz"])) for r in rows}
            train = [int(r["case"]) for r in rows if r["role"] == "train"]

            def params_of(x):
                out = {c: dict(truth[c]) for c in truth}
                for i, k in enumerate(BANDS):
                    lo, hi = BANDS[k]
                    g = dict(zip(vs, x[5 * i:5 * i + 3]))
                    h = dict(zip(fs, [0.0] + x[5 * i + 3:5 * i + 5]))
                    for c, (v, f) in vf.items():
                        out[c][k] = lo + (hi - lo) * (g[v] + h[f])
                for j, k in enumerate(loop):
                    for c in out:
                        out[c][k] = x[20 + j] * 1e-3
                return out

            def prior(x):
                total = 0.0
                for i in range(4):
                    g0, g1, g2, h1, h2 = x[5 * i:5 * i + 5]
                    d2g = (g2 - g1) / (2 / 3) - (g1 - g0) / (1 / 3)
                    d2h = h2 - 2 * h1
                    total += (d2g / tau) ** 2 + (d2h / tau) ** 2
                return sigma2 * total

            def pis_of(x):
                p = params_of(x)
                if any(float(p[c][k]) < 0 for c in p for k in ("mu", "delta", "a1", "a2")):
                    return {}
                return score_trend_bench.pi_with(piezoid, bench, p)

            def cost(x):
                pis = pis_of(x)
                return sum(pis.get(c, 1e6) for c in train) + prior(x)

            x0 = [0.5, 0.5, 0.5, 0.0, 0.0] * 4 + [float(truth[1][k]) * 1e3 for k in loop]
            x, cf = nelder_mead(cost, x0, 0.05, 4000)
            x, cf = nelder_mead(cost, x, 0.02, 2000)  # a restart: NM stalls in 23 dimensions
            pis = pis_of(x)
            held = [c for c in sorted(floor) if c not in train]
            ratio = {c: pis.get(c, float("inf")) / floor[c] for c in floor}
            within = sum(ratio[c] <= 3 for c in held)
            split = "corner" if 9 in train else "four"
            print(f"smooth {family}-{seed} {split:6s} cost {cf:.3f} (truth "
                  f"{sum(floor[c] for c in train):.3f}) | withheld within 3x {within}/{len(held)} | "
                  + " ".join(f"{c}{'*' if c in train else ''}:{ratio[c]:.1f}" for c in sorted(ratio)),
                  flush=True)


def main():
    args = sys.argv[1:]
    extra = []
    if "--" in args:
        extra = args[args.index("--") + 1:]
        args = args[:args.index("--")]
    if (len(args) < 5 or args[0] not in ("make", "study", "next", "oracle", "smooth")
            or args[3] not in ("dev", "check", "fresh")):
        sys.exit("usage: oplaw_benches.py make|study|next|oracle|smooth PIEZOID OUT_ROOT dev|check|fresh SEED... "
                 "[-- IDENTIFY_ARGS...]")
    cmd, piezoid, root, family = args[:4]
    seeds = [int(s) for s in args[4:]]
    if not os.access(piezoid, os.X_OK):
        sys.exit(f"{piezoid}: not an executable piezoid binary")
    os.makedirs(root, exist_ok=True)
    if cmd == "make":
        for seed in seeds:
            make(piezoid, root, family, seed)
    elif cmd == "study":
        study(piezoid, root, family, seeds, extra)
    elif cmd == "oracle":
        oracle(piezoid, root, family, seeds)
    elif cmd == "smooth":
        smooth(piezoid, root, family, seeds)
    else:
        next_case(piezoid, root, family, seeds, extra)


if __name__ == "__main__":
    main()
