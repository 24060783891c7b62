#!/usr/bin/env python3
"""Makes the bimorph-fin benches whose truth changes with the operating point (issue 36).

    scripts/make_trend_benches.py build/client/piezoid data/bimorph-fin [NAME ...]

writes data/bimorph-fin/trends-dev, trends-dev2 and trends-dev3 (for developing) and
data/bimorph-fin/trends-check (only for checking), or only the benches NAME given. Each is
the paper's nine cases (V in {375, 500, 750} V, f in {0.25, 0.5, 1} Hz, three cycles from rest at
100 Hz, training cases 1, 5, 6, 7) of a bench whose damping (mu, delta) and
backlash thresholds (a1, a2) follow smooth laws of V and f chosen here (LAWS below: our own, not the
paper's per-case Tables 9-13, which stay an independent check), with the Bouc-Wen loop (alpha, beta,
gamma) constant and the saturations b1, b2 of the nominal bench (the paper's Table B1).

Each case is simulated by `piezoid simulate --solver cvode` (the CVODE path: not the fast modal path
that the identification uses) with its own parameters, then read as the nominal bench is: a
vibration jitter (Gaussian, RMS 0.003 deg, Python's seeded Mersenne Twister) is added and the angle
is quantised to the 2048-line encoder's quantum 360/8192 deg. truth.json holds every case's
parameters and the laws; it is for checking an identification afterwards, never read by one.
The script is deterministic: the same binary and seed give the same files.
"""

import csv
import json
import math
import os
import random
import subprocess
import sys
import tempfile

QUANTUM_DEG = 360.0 / 8192
NOISE_DEG = 0.003
ALPHA, BETA, GAMMA = 2.5e-3, 6e-3, 4e-3  # the nominal bench's loop, constant
CASES = [  # case, V, f, role (the paper's split)
    (1, 375, 0.25, "train"), (2, 375, 0.5, "validate"), (3, 375, 1.0, "validate"),
    (4, 500, 0.25, "validate"), (5, 500, 0.5, "train"), (6, 500, 1.0, "train"),
    (7, 750, 0.25, "train"), (8, 750, 0.5, "validate"), (9, 750, 1.0, "validate")]
# b1, b2 per case [deg]: the nominal bench's (the paper's Table B1).
SATURATIONS = {1: (1.37, -1.5), 2: (1.26, -1.26), 3: (1.16, -1.16), 4: (2.34, -2.12),
               5: (2.05, -1.91), 6: (1.73, -1.66), 7: (4.21, -4.03), 8: (3.74, -3.56),
               9: (3.24, -3.17)}


def x_of(v):  # amplitude as a share of the paper's span 375..750 V
    return (v - 375.0) / 375.0


# Smooth laws, within the paper's ranges (mu 70-110 1/s, delta 0-0.35 s, a1, a2 0-0.35 deg), each
# mildly curved (none is linear in V and f). Dev and check differ in form, not only in numbers.
LAWS = {
    "trends-dev": {
        "seed": 361,
        "text": {
            "mu": "mu = 78 + 26 x^1.5 - 22 ln(f / 0.25) / ln 4   [1/s], x = (V - 375) / 375",
            "delta": "delta = 0.08 + 0.22 exp(-2.2 (f - 0.25))   [s]",
            "a1": "a1 = 0.04 + 0.22 x^2   [deg]",
            "a2": "a2 = 0.08 + 0.20 x (1 - 0.3 (f - 0.25))   [deg]",
        },
        "mu": lambda v, f: 78 + 26 * x_of(v) ** 1.5 - 22 * math.log(f / 0.25) / math.log(4),
        "delta": lambda v, f: 0.08 + 0.22 * math.exp(-2.2 * (f - 0.25)),
        "a1": lambda v, f: 0.04 + 0.22 * x_of(v) ** 2,
        "a2": lambda v, f: 0.08 + 0.20 * x_of(v) * (1 - 0.3 * (f - 0.25)),
    },
    # The second development bench: other shapes again (saturating in V, non-monotone in f, a
    # cross term V * f), so that a search developed on both is not fitted to trends-dev's forms.
    "trends-dev2": {
        "seed": 363,
        "text": {
            "mu": "mu = 92 + 14 tanh(3 (x - 0.4)) - 12 (f - 0.25)   [1/s], x = (V - 375) / 375",
            "delta": "delta = 0.10 + 0.60 (f - 0.25) (1 - f) + 0.10 x f   [s]",
            "a1": "a1 = 0.03 + 0.20 (1 - exp(-3 x))   [deg]",
            "a2": "a2 = 0.06 + 0.18 x f   [deg]",
        },
        "mu": lambda v, f: 92 + 14 * math.tanh(3 * (x_of(v) - 0.4)) - 12 * (f - 0.25),
        "delta": lambda v, f: 0.10 + 0.60 * (f - 0.25) * (1 - f) + 0.10 * x_of(v) * f,
        "a1": lambda v, f: 0.03 + 0.20 * (1 - math.exp(-3 * x_of(v))),
        "a2": lambda v, f: 0.06 + 0.18 * x_of(v) * f,
    },
    # The third development bench (issue 36): a1 falling with V, a2 flat over most of the box and
    # rising towards the high-frequency corner, delta not monotone in V, mu falling along V * f;
    # case 9's a2 lies beyond every training case's, as on trends-dev2, but by another form.
    "trends-dev3": {
        "seed": 364,
        "text": {
            "mu": "mu = 100 - 14 x f   [1/s], x = (V - 375) / 375",
            "delta": "delta = 0.22 - 0.10 f + 0.06 sin(pi x)   [s]",
            "a1": "a1 = 0.25 - 0.18 x^0.7   [deg]",
            "a2": "a2 = 0.08 + 0.16 (max(0, f - 0.4) / 0.6)^2 (0.3 + 0.7 x)   [deg]",
        },
        "mu": lambda v, f: 100 - 14 * x_of(v) * f,
        "delta": lambda v, f: 0.22 - 0.10 * f + 0.06 * math.sin(math.pi * x_of(v)),
        "a1": lambda v, f: 0.25 - 0.18 * x_of(v) ** 0.7,
        "a2": lambda v, f: 0.08 + 0.16 * (max(0.0, f - 0.4) / 0.6) ** 2
        * (0.3 + 0.7 * x_of(v)),
    },
    "trends-check": {
        "seed": 362,
        "text": {
            "mu": "mu = 104 - 0.03 (V - 375) - 18 sqrt(f - 0.25) / sqrt(0.75)   [1/s]",
            "delta": "delta = 0.06 + 0.27 / (1 + 2.5 (f - 0.25)) - 0.04 x   [s], x = (V - 375) / 375",
            "a1": "a1 = 0.03 + 0.25 x^2 (1.1 - 0.4 f)   [deg]",
            "a2": "a2 = 0.12 + 0.15 sin(pi x / 2)   [deg]",
        },
        "mu": lambda v, f: 104 - 0.03 * (v - 375) - 18 * math.sqrt(f - 0.25) / math.sqrt(0.75),
        "delta": lambda v, f: 0.06 + 0.27 / (1 + 2.5 * (f - 0.25)) - 0.04 * x_of(v),
        "a1": lambda v, f: 0.03 + 0.25 * x_of(v) ** 2 * (1.1 - 0.4 * f),
        "a2": lambda v, f: 0.12 + 0.15 * math.sin(math.pi * x_of(v) / 2),
    },
}


def params_of(laws, number, v, f):
    b1, b2 = SATURATIONS[number]
    return {"mu": round(laws["mu"](v, f), 6), "delta": round(laws["delta"](v, f), 6),
            "alpha": ALPHA, "beta": BETA, "gamma": GAMMA,
            "a1": round(laws["a1"](v, f), 6), "a2": round(laws["a2"](v, f), 6), "b1": b1, "b2": b2}


def make(piezoid, root, name, laws):
    out = os.path.join(root, name)
    os.makedirs(out, exist_ok=True)
    truth = {}
    for number, v, f, _ in CASES:
        truth[str(number)] = params_of(laws, number, v, f)
    with tempfile.TemporaryDirectory() as tmp:
        template = os.path.join(tmp, "cases")  # the nine drives: a case set with flat angles
        os.makedirs(template)
        with open(os.path.join(template, "cases.csv"), "w", newline="") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(["case", "amplitude_V", "frequency_Hz", "file", "role"])
            for number, v, f, role in CASES:
                w.writerow([number, v, f"{f:g}", f"case{number}.csv", role])
        for number, v, f, _ in CASES:
            n = int(round(3 / f * 100))
            with open(os.path.join(template, f"case{number}.csv"), "w", newline="") as fh:
                w = csv.writer(fh, lineterminator="\n")
                w.writerow(["t_s", "voltage_V", "angle_deg"])
                for k in range(n):
                    t = k / 100.0
                    w.writerow([repr(t), repr(v * math.sin(2 * math.pi * f * t)), "1" if k % 2 else "-1"])
        params = os.path.join(tmp, "params.csv")
        with open(params, "w", newline="") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(["case", "mu", "delta", "alpha", "beta", "gamma", "a1", "a2", "b1", "b2"])
            for number, _, _, _ in CASES:
                p = truth[str(number)]
                w.writerow([number] + [repr(p[k]) for k in
                                       ("mu", "delta", "alpha", "beta", "gamma", "a1", "a2", "b1", "b2")])
        sim = os.path.join(tmp, "sim")
        subprocess.run([piezoid, "simulate", "--cases", template, "--params", params, "--saturation", "given",
                        "--solver", "cvode", "--out", sim], check=True, stdout=subprocess.DEVNULL)
        rng = random.Random(laws["seed"])
        for number, v, f, _ in CASES:
            with open(os.path.join(sim, f"case{number}.csv")) as fh:
                rows = list(csv.DictReader(fh))
            with open(os.path.join(out, f"case{number}.csv"), "w", newline="") as fh:
                w = csv.writer(fh, lineterminator="\n")
                w.writerow(["t_s", "voltage_V", "angle_deg"])
                for r in rows:
                    y = float(r["angle_deg"]) + rng.gauss(0.0, NOISE_DEG)
                    w.writerow([r["t_s"], r["voltage_V"], repr(round(y / QUANTUM_DEG) * QUANTUM_DEG)])
        with open(os.path.join(out, "cases.csv"), "w") as fh, \
                open(os.path.join(template, "cases.csv")) as src:
            fh.write(src.read())
    with open(os.path.join(out, "truth.json"), "w") as fh:
        json.dump({"effects": {}, "laws": laws["text"], "quantum_deg": QUANTUM_DEG, "noise_deg": NOISE_DEG,
                   "seed": laws["seed"], "made_by": "scripts/make_trend_benches.py", "cases": truth},
                  fh, indent=1)
        fh.write("\n")
    with open(os.path.join(out, "truth_params.csv"), "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["case", "mu", "delta", "alpha", "beta", "gamma", "a1", "a2", "b1", "b2"])
        for number, _, _, _ in CASES:
            p = truth[str(number)]
            w.writerow([number] + [repr(p[k]) for k in
                                   ("mu", "delta", "alpha", "beta", "gamma", "a1", "a2", "b1", "b2")])
    print(f"{out}: nine cases written")


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: make_trend_benches.py PIEZOID_BINARY OUT_ROOT [NAME ...] "
                 "(e.g. build/client/piezoid data/bimorph-fin trends-dev2)")
    piezoid, root, names = sys.argv[1], sys.argv[2], sys.argv[3:] or list(LAWS)
    if not os.access(piezoid, os.X_OK):
        sys.exit(f"{piezoid}: not an executable piezoid binary")
    for name in names:
        if name not in LAWS:
            sys.exit(f"bench name = {name}: must be one of {', '.join(LAWS)}")
        make(piezoid, root, name, LAWS[name])


if __name__ == "__main__":
    main()
