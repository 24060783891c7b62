"""piezoid.Model (python/piezoid/model.py) against the C++ stepper of this build.

A Prandtl-Ishlinskii model is fitted by `piezoid fit` on a synthetic record; `piezoid compensate` (the
C++ stepper) writes the drive for a reference and the model's predicted response on it. Model.load of the
same fit.json (the exported C header, compiled) gives that drive from inverse_step and that response from
step, to the last bit; a fit.json of another version is refused with the version needed.
"""
import json
import math
import os
import pathlib
import shutil
import subprocess
import tempfile
import unittest

import piezoid

BUILD = pathlib.Path(os.environ.get("PIEZOID_BUILD_DIR", "build")).resolve()
CLI = BUILD / "client" / "piezoid"


class ModelTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        os.environ["PIEZOID_CLI"] = str(CLI)
        cls.dir = pathlib.Path(tempfile.mkdtemp(prefix="pz-model-"))
        rows = ["t_s,voltage_V,displacement_um"]
        z = 50.0
        for k in range(4000):
            t = k * 1e-3
            u = 50 + 40 * math.sin(2 * math.pi * t) * (0.7 + 0.3 * math.sin(1.3 * t))
            z = max(u - 8, min(u + 8, z))  # a play: hysteresis
            rows.append(f"{t:.6f},{u:.9f},{0.3 * u + 0.2 * z:.9f}")
        (cls.dir / "rec.csv").write_text("\n".join(rows) + "\n")
        subprocess.run([str(CLI), "fit", "--records", str(cls.dir / "rec.csv"), "--family", "prandtl-ishlinskii",
                        "--pi-operators", "6", "--out", str(cls.dir / "fit"), "--no-figures", "--quiet"],
                       check=True, capture_output=True)
        ref = ["t_s,displacement_um"]
        for k in range(1500):
            t = k * 1e-3
            ref.append(f"{t:.6f},{25 + 8 * math.sin(2 * math.pi * 2 * t):.9f}")
        (cls.dir / "ref.csv").write_text("\n".join(ref) + "\n")
        subprocess.run([str(CLI), "compensate", "--model", str(cls.dir / "fit" / "fit.json"), "--reference",
                        str(cls.dir / "ref.csv"), "--out", str(cls.dir / "drive.csv"), "--rest-drive", "50"],
                       check=True, capture_output=True)
        lines = (cls.dir / "drive.csv").read_text().split("\n")[1:]
        cls.ref = [float(r.split(",")[1]) for r in (cls.dir / "ref.csv").read_text().split("\n")[1:] if r]
        cls.drive = [float(r.split(",")[1]) for r in lines if r]
        cls.predicted = [float(r.split(",")[2]) for r in lines if r]

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def test_inverse_and_forward_equal_the_cpp_stepper(self):
        m = piezoid.Model.load(self.dir / "fit" / "fit.json")
        m.init(50.0)
        drive = [50.0] + [m.inverse_step(y) for y in self.ref[1:]]
        self.assertEqual(drive, self.drive)
        f = piezoid.Model.load(self.dir / "fit" / "fit.json")
        self.assertEqual(f.run(self.drive), self.predicted)
        # The compensated chain tracks the reference through the model (exact inverse).
        worst = max(abs(a - b) for a, b in zip(self.predicted[1:], self.ref[1:]))
        self.assertLess(worst, 1e-9 * 16)
        self.assertEqual(m.saturated, 0)

    def test_other_version_is_refused(self):
        fit = json.loads((self.dir / "fit" / "fit.json").read_text())
        fit["format_version"] = 99
        bad = self.dir / "v99.json"
        bad.write_text(json.dumps(fit))
        with self.assertRaises(RuntimeError) as e:
            piezoid.Model.load(bad)
        self.assertIn("format_version 99", str(e.exception))
        self.assertIn("format_version 1", str(e.exception))


if __name__ == "__main__":
    unittest.main()
