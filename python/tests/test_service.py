"""The Python client against a real master and workers of this build, next to the C++ client.

The same spec submitted by the C++ client (`piezoid submit`, which reads the case set) and by the
Python client (the spec as the master stored it, as a dict) gives the same networks bit for bit.
"""
import json
import os
import pathlib
import shutil
import subprocess
import tempfile
import time
import unittest

from google.protobuf import json_format

import piezoid
from piezoid._proto import network_pb2

BUILD = pathlib.Path(os.environ.get("PIEZOID_BUILD_DIR", "build")).resolve()
ROOT = pathlib.Path(__file__).resolve().parents[2]
CLI = BUILD / "client" / "piezoid"


class Cluster:
    def __init__(self, workers=2):
        self.dir = pathlib.Path(tempfile.mkdtemp(prefix="pz-python-"))
        self.log = open(self.dir / "processes.log", "w")
        ep = self.dir / "endpoints"
        self.procs = [subprocess.Popen(
            [str(BUILD / "master" / "piezoid-master"), "--workers", "tcp://127.0.0.1:*", "--clients",
             "tcp://127.0.0.1:*", "--endpoints-file", str(ep), "--state-dir", str(self.dir / "state"),
             "--heartbeat-ms", "100", "--liveness", "5", "--log-level", "warn"], stdout=self.log, stderr=self.log)]
        for _ in range(2000):
            lines = ep.read_text().split() if ep.exists() else []
            if len(lines) >= 2:
                break
            time.sleep(0.01)
        else:
            raise RuntimeError(f"the master did not write {ep}")
        self.worker_ep, self.client_ep = lines[0], lines[1]
        for _ in range(workers):
            self.procs.append(subprocess.Popen(
                [str(BUILD / "worker" / "piezoid-worker"), "--master", self.worker_ep, "--threads", "1",
                 "--heartbeat-ms", "100", "--liveness", "5", "--log-level", "warn"], stdout=self.log, stderr=self.log))

    def cli(self, *args):
        r = subprocess.run([str(CLI), *args, "--master", self.client_ep], capture_output=True, text=True, timeout=600)
        if r.returncode != 0:
            raise AssertionError(f"piezoid {' '.join(args)}: exit {r.returncode}\n{r.stderr}")
        return r.stdout

    def close(self):
        for p in reversed(self.procs):
            p.kill()
            p.wait()
        self.log.close()
        shutil.rmtree(self.dir, ignore_errors=True)


def network_without_provenance(f: network_pb2.NetworkFile) -> bytes:
    g = network_pb2.NetworkFile()
    g.CopyFrom(f)
    g.provenance.job_id = ""
    g.provenance.ClearField("created")
    return g.SerializeToString(deterministic=True)


class PythonClientTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.cluster = Cluster(workers=2)
        cls.client = piezoid.Client(cls.cluster.client_ep, timeout_ms=3000)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        cls.cluster.close()

    def test_same_networks_bit_for_bit_as_the_cpp_client(self):
        c, cl = self.client, self.cluster
        cpp_job = cl.cli("submit", str(ROOT / "examples" / "hgann_quick.json"), "--client-token", "cpp").strip()
        cl.cli("watch", cpp_job)
        cpp_dir = cl.dir / "cpp"
        cl.cli("fetch", cpp_job, "--best", "3", "--out", str(cpp_dir), "--no-plots")

        # The spec the master stored (cases embedded), as a dict, submitted by Python.
        spec = json_format.MessageToDict(c.fetch(cpp_job).spec)
        self.assertIn("cases", spec["hgann"])
        py_job = c.submit(spec, client_token="python")
        self.assertNotEqual(py_job, cpp_job)
        events = []
        info = c.watch(py_job, on_event=events.append, progress=True)
        self.assertEqual(piezoid.state_name(info.state), "succeeded")
        self.assertGreater(len(events), 5, "the watch saw the generations go by")
        got = c.fetch(py_job, count=3)
        self.assertEqual(len(got.networks), 3)
        for k, net in enumerate(got.networks):
            cpp_net = piezoid.Network.load(cpp_dir / "networks" / f"best-{k + 1}.pb")
            self.assertEqual(network_without_provenance(net.file), network_without_provenance(cpp_net.file),
                             f"network {k + 1} differs from the C++ client's")
            self.assertEqual(net.file.provenance.fitness, cpp_net.file.provenance.fitness)
        ref = c.fetch(cpp_job)
        self.assertEqual([r.best_cost for r in got.log], [r.best_cost for r in ref.log])
        self.assertEqual([r.median_cost for r in got.log], [r.median_cost for r in ref.log])

        # Predictions from the fetched network equal the C++ report's per-case parameters (10 digits there).
        tables = piezoid.read_report(cpp_dir)
        params = tables["parameters"]
        rows = params.to_dict("records") if hasattr(params, "to_dict") else params
        self.assertEqual(len(rows), 9)
        best = got.networks[0]
        for row in rows:
            p = best.predict(float(row["amplitude_V"]), float(row["frequency_Hz"]))
            for name in ("mu", "delta", "alpha", "beta", "gamma", "a1", "a2"):
                want = float(row[name])
                self.assertAlmostEqual(p[name], want, delta=1e-9 * max(1.0, abs(want)), msg=f"{name} of case {row['case']}")
        self.assertIn("median_cost", tables["progress"][0] if isinstance(tables["progress"], list) else tables["progress"].columns)

        # The C++ client's embedded spec file (`piezoid submit --write-embedded`), submitted from Python:
        # the same networks again. The same spec with the same token is the same job.
        path = cl.dir / "embedded.json"
        subprocess.run([str(CLI), "submit", str(ROOT / "examples" / "hgann_quick.json"), "--write-embedded", str(path)],
                       check=True, capture_output=True)
        file_job = c.submit(path, client_token="file")
        self.assertEqual(c.submit(path, client_token="file"), file_job)
        self.assertEqual(piezoid.state_name(c.wait(file_job).state), "succeeded")
        from_file = c.fetch(file_job, count=3)
        for a, b in zip(from_file.networks, got.networks):
            self.assertEqual(network_without_provenance(a.file), network_without_provenance(b.file))
        dict_path = cl.dir / "spec.json"
        dict_path.write_text(json.dumps(spec))
        self.assertEqual(c.submit(dict_path, client_token="python"), py_job)
        # The log alone, from a generation on.
        tail = c.log(py_job, from_generation=38)
        self.assertEqual([r.generation for r in tail], [38, 39, 40])
        frame = got.log_frame()
        self.assertEqual(len(frame), len(got.log))

    def test_bad_specs_name_the_field(self):
        c = self.client
        with self.assertRaises(piezoid.InvalidSpec) as e:
            c.submit({"version": 1, "seed": "1", "synthetic": {"cost": "COST_FUNCTION", "genome_bits": 64},
                      "ga": {"population": 1, "generations": 5}})
        self.assertTrue(any(f == "ga.population" for f, _ in e.exception.violations), e.exception.violations)
        with self.assertRaises(piezoid.InvalidSpec) as e:
            c.submit({"version": 1, "nope": 3})
        self.assertIn("nope", str(e.exception))
        with self.assertRaises(piezoid.InvalidSpec) as e:
            c.submit(ROOT / "examples" / "hgann_quick.json")
        self.assertIn("hgann.case_set_dir", str(e.exception))
        with self.assertRaises(piezoid.InvalidSpec) as e:
            c.submit("{ not json")
        self.assertIn("not JSON", str(e.exception))
        with self.assertRaises(piezoid.NotFound):
            c.status("j0000000000000000")
        with self.assertRaises(ValueError):
            c.fetch("j0000000000000000", count=33)

    def test_workers_and_an_unreachable_master(self):
        w = self.client.workers()
        self.assertEqual(len(w.workers), 2)
        self.assertTrue(all(x.threads == 1 for x in w.workers))
        lost = piezoid.Client("tcp://127.0.0.1:9", timeout_ms=100, retries=2)
        start = time.monotonic()
        with self.assertRaises(piezoid.Unreachable) as e:
            lost.list()
        self.assertIn("cannot reach the master at tcp://127.0.0.1:9", str(e.exception))
        self.assertLess(time.monotonic() - start, 5)
        lost.close()

    def test_a_synthetic_job_from_a_dict(self):
        c = self.client
        spec = json.loads((ROOT / "examples" / "synthetic_job.json").read_text())
        job = c.submit(spec)
        info = c.wait(job, timeout_s=120)
        self.assertEqual(piezoid.state_name(info.state), "succeeded")
        r = c.fetch(job, count=2)
        self.assertEqual(len(r.best), 2)
        self.assertEqual(r.networks, [])  # only hgann genomes are networks
        self.assertEqual(len(r.log), info.generation)


if __name__ == "__main__":
    unittest.main()
