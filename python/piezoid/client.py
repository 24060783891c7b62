"""The piezoid service client: a ZeroMQ DEALER to the master's client endpoint speaking proto/wire.proto.

Same protocol as the C++ client (svcclient/service_client.h, docs/service.md "For a client in
another language"): one ClientRequest per message, version 1, a fresh request_id each; replies echo it.
Requests are Lazy-Pirate: a timeout closes the socket, opens a fresh one and retries (bounded);
submissions are idempotent through their client token, so a retry is the same job.
"""
from __future__ import annotations

import json
import os
import pathlib
import secrets
import sys
import time
from dataclasses import dataclass, field
from typing import Callable, Iterable, Optional, Union

import zmq
from google.protobuf import json_format

from ._proto import job_pb2, wire_pb2
from .network import Network

PROTOCOL_VERSION = 1
_FINAL_STATES = (job_pb2.JOB_STATE_SUCCEEDED, job_pb2.JOB_STATE_FAILED, job_pb2.JOB_STATE_CANCELLED)
_TRANSIENT = 100  # codes >= 100 are worth a retry


class PiezoidError(Exception):
    """A request the master answered with an error, or could not be sent."""

    def __init__(self, message: str, code: int = 0):
        super().__init__(message)
        self.code = code


class Unreachable(PiezoidError):
    """No answer from the master within the timeout and retries."""


class NotFound(PiezoidError):
    """The master does not know the job."""


class InvalidSpec(PiezoidError):
    """The job spec was refused; `violations` lists (field, description) for every bad field."""

    def __init__(self, message: str, violations: list[tuple[str, str]]):
        super().__init__(message, wire_pb2.CODE_INVALID_ARGUMENT)
        self.violations = violations


def state_name(state: int) -> str:
    """'running', 'succeeded', 'failed', 'cancelled'."""
    return job_pb2.JobState.Name(state).replace("JOB_STATE_", "").lower()


@dataclass
class FetchResult:
    """A job as the master answers a fetch."""

    info: wire_pb2.JobInfo
    best: list  # wire_pb2.Individual, best first
    log: list  # job_pb2.GenerationRecord, one per generation
    spec: job_pb2.JobSpec
    networks: list = field(default_factory=list)  # Network (hgann jobs), best first

    def log_frame(self):
        """The generation log as a pandas DataFrame (a list of dicts without pandas)."""
        return records_frame(self.log)


def _island_columns(r) -> dict:
    """A job of several islands: the best's island, the migration and one best per island."""
    if not len(r.islands):
        return {}
    row = {
        "best_island": r.best_island,
        "migrated": r.migrated,
        "immigrants": sum(i.immigrants for i in r.islands),
        "restarted": sum(1 for i in r.islands if i.restarted),
    }
    for k, i in enumerate(r.islands):
        row[f"island_{k}_best"] = i.best_cost
    return row


def records_frame(records: Iterable):
    rows = [
        {
            "generation": r.generation,
            "best_cost": r.best_cost,
            "median_cost": r.median_cost,
            "mean_cost": r.mean_cost,
            "worst_cost": r.worst_cost,
            "evaluations": r.evaluations,
            "errors": r.errors,
            "penalized": r.penalized,
            "stall": r.stall,
            "best_description": r.best_description,
            **_island_columns(r),
        }
        for r in records
    ]
    try:
        import pandas as pd
    except ImportError:
        return rows
    return pd.DataFrame(rows)


def load_spec(spec: Union[dict, str, os.PathLike, job_pb2.JobSpec]) -> job_pb2.JobSpec:
    """A JobSpec from a dict (protobuf JSON mapping), a JSON file, JSON text or a JobSpec.

    The case data must be embedded (hgann `cases`, records, …): `case_set_dir` is read by the C++
    client only. Unknown fields are errors naming the field.
    """
    if isinstance(spec, job_pb2.JobSpec):
        return spec
    if isinstance(spec, (str, os.PathLike)) and not str(spec).lstrip().startswith("{"):
        path = pathlib.Path(spec)
        try:
            text = path.read_text()
        except OSError as e:
            raise InvalidSpec(f"{path}: cannot read: {e.strerror}", [("file", str(path))]) from None
        source = str(path)
    elif isinstance(spec, str):
        text, source = spec, "spec"
    else:
        text, source = None, "spec"
    try:
        data = json.loads(text) if text is not None else spec
    except json.JSONDecodeError as e:
        raise InvalidSpec(f"{source}:{e.lineno}:{e.colno}: not JSON: {e.msg}", [("json", e.msg)]) from None
    if isinstance(data, dict) and "hgann" in data and "case_set_dir" in data["hgann"]:
        raise InvalidSpec(
            f"{source}: hgann.case_set_dir: the Python client needs the cases embedded (hgann.cases); "
            "submit with `piezoid submit`, or fetch a job's spec (which has them) and submit that",
            [("hgann.case_set_dir", "not read by the Python client")],
        )
    msg = job_pb2.JobSpec()
    try:
        json_format.ParseDict(data, msg)
    except json_format.ParseError as e:
        raise InvalidSpec(f"{source}: {e}", [("spec", str(e))]) from None
    return msg


class Client:
    """A client of one master.

    >>> c = Client("tcp://127.0.0.1:5556")
    >>> job = c.submit(spec_dict)
    >>> c.watch(job)                    # progress bar until it ends
    >>> result = c.fetch(job, count=3)
    >>> result.networks[0].predict(500, 0.5)
    """

    def __init__(self, endpoint: str = None, timeout_ms: int = 5000, retries: int = 3,
                 curve_secret_key: bytes = None, curve_public_key: bytes = None, master_public_key: bytes = None):
        self.endpoint = endpoint or os.environ.get("PIEZOID_MASTER", "tcp://127.0.0.1:5556")
        if timeout_ms <= 0:
            raise ValueError(f"timeout_ms = {timeout_ms}: must be > 0")
        if retries < 1:
            raise ValueError(f"retries = {retries}: must be >= 1")
        self.timeout_ms = timeout_ms
        self.retries = retries
        self._curve = (curve_secret_key, curve_public_key, master_public_key)
        if any(self._curve) and not all(self._curve):
            raise ValueError("CURVE needs curve_secret_key, curve_public_key and master_public_key (Z85)")
        self._ctx = zmq.Context.instance()
        self._sock = None
        self._next_id = secrets.randbits(48)

    # ------------------------------------------------------------------ transport
    def _socket(self):
        if self._sock is None:
            s = self._ctx.socket(zmq.DEALER)
            s.setsockopt(zmq.LINGER, 0)
            if all(self._curve):
                s.curve_secretkey, s.curve_publickey, s.curve_serverkey = self._curve
            s.connect(self.endpoint)
            self._sock = s
        return self._sock

    def _reset(self):
        if self._sock is not None:
            self._sock.close(0)
            self._sock = None

    def close(self):
        self._reset()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _request(self, fill: Callable[[wire_pb2.ClientRequest], None]) -> wire_pb2.ClientReply:
        req = wire_pb2.ClientRequest(version=PROTOCOL_VERSION)
        fill(req)
        last = None
        for _ in range(self.retries):
            self._next_id += 1
            req.request_id = self._next_id
            sock = self._socket()
            sock.send(req.SerializeToString())
            deadline = time.monotonic() + self.timeout_ms / 1000
            while True:
                left = deadline - time.monotonic()
                if left <= 0 or not sock.poll(int(left * 1000) + 1):
                    break
                reply = wire_pb2.ClientReply()
                reply.ParseFromString(sock.recv())
                if reply.request_id != req.request_id:
                    continue  # a late answer to an earlier try, or a stray event
                if reply.code >= _TRANSIENT:
                    last = PiezoidError(f"the master is unavailable: {reply.error}", reply.code)
                    break
                return self._check(reply)
            self._reset()  # Lazy Pirate: a fresh socket for the next try
        if last is not None:
            raise last
        raise Unreachable(f"cannot reach the master at {self.endpoint}: is piezoid-master running? "
                          f"(no answer in {self.retries} tries of {self.timeout_ms} ms; "
                          "a master with CURVE needs the keys)")

    @staticmethod
    def _check(reply: wire_pb2.ClientReply) -> wire_pb2.ClientReply:
        if reply.code == wire_pb2.CODE_OK:
            return reply
        if reply.code == wire_pb2.CODE_NOT_FOUND:
            raise NotFound(reply.error, reply.code)
        if reply.code == wire_pb2.CODE_INVALID_ARGUMENT:
            raise InvalidSpec(reply.error, [(v.field, v.description) for v in reply.violations])
        raise PiezoidError(f"{wire_pb2.Code.Name(reply.code)}: {reply.error}", reply.code)

    # ------------------------------------------------------------------ requests
    def submit(self, spec, client_token: Optional[str] = None) -> str:
        """Submits a job spec (dict, JSON file or text, or JobSpec); returns the job id.

        The same spec with the same token is the same job (a retry returns its id); the default
        token is a fresh random one, as in `piezoid submit`.
        """
        msg = load_spec(spec)
        token = client_token if client_token is not None else secrets.token_hex(16)

        def fill(r):
            r.submit.spec.CopyFrom(msg)
            r.submit.client_token = token

        return self._request(fill).submit.job_id

    def status(self, job_id: str) -> wire_pb2.JobInfo:
        return self._request(lambda r: _job_request(r.status, job_id)).status

    def list(self) -> list:
        """The master's jobs (JobInfo each)."""
        return list(self._request(lambda r: r.list.SetInParent()).list.jobs)

    def workers(self) -> wire_pb2.WorkersReply:
        """The connected workers, recent departures and the master's counters."""
        return self._request(lambda r: r.workers.SetInParent()).workers

    def cancel(self, job_id: str) -> None:
        self._request(lambda r: _job_request(r.cancel, job_id))

    def fetch(self, job_id: str, count: int = 1) -> FetchResult:
        """The job's `count` (1 … 32) best individuals, its log, spec and (hgann) networks."""
        if not 1 <= count <= 32:
            raise ValueError(f"count = {count}: must be in [1, 32] (the master keeps a job's 32 best)")

        def fill(r):
            r.fetch.job_id = job_id
            r.fetch.count = count

        f = self._request(fill).fetch
        return FetchResult(f.info, list(f.best), list(f.log), f.spec, [Network(n) for n in f.networks])

    def log(self, job_id: str, from_generation: int = 0) -> list:
        """The job's generation records from `from_generation` on (no individuals travel)."""
        def fill(r):
            r.fetch.job_id = job_id
            r.fetch.log_only = True
            r.fetch.log_from = from_generation

        return [x for x in self._request(fill).fetch.log if x.generation >= from_generation]

    def watch(self, job_id: str, on_event: Callable = None, progress: bool = True,
              timeout_s: float = None) -> wire_pb2.JobInfo:
        """Follows a job until it ends; returns its final JobInfo.

        on_event(JobEvent) is called for every generation (return False to stop watching early).
        progress: a progress bar (tqdm if installed, else one line on stderr).
        """
        info = self.status(job_id)
        bar = _Progress(info.max_generations, enabled=progress)
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        try:
            while info.state not in _FINAL_STATES:
                req = wire_pb2.ClientRequest(version=PROTOCOL_VERSION)
                self._next_id += 1
                req.request_id = self._next_id
                req.watch.job_id = job_id
                sock = self._socket()
                sock.send(req.SerializeToString())
                while True:
                    if deadline is not None and time.monotonic() > deadline:
                        raise PiezoidError(f"watch {job_id}: still running after {timeout_s} s")
                    if not sock.poll(self.timeout_ms):
                        break  # quiet: check the status, register again
                    reply = wire_pb2.ClientReply()
                    reply.ParseFromString(sock.recv())
                    if reply.request_id != req.request_id:
                        continue
                    self._check(reply)
                    if reply.HasField("status"):
                        info = reply.status
                        if info.state in _FINAL_STATES:
                            break
                    elif reply.HasField("event"):
                        e = reply.event
                        if e.HasField("record"):
                            bar.update(e.record, e.workers, e.worker_threads)
                        if on_event is not None and on_event(e) is False:
                            return self.status(job_id)
                        if e.state in _FINAL_STATES:
                            break
                self._reset()
                info = self.status(job_id)
        finally:
            bar.close()
        return info

    def wait(self, job_id: str, timeout_s: float = 600, poll_s: float = 0.2) -> wire_pb2.JobInfo:
        """Polls the status until the job has ended."""
        end = time.monotonic() + timeout_s
        while True:
            info = self.status(job_id)
            if info.state in _FINAL_STATES:
                return info
            if time.monotonic() > end:
                raise PiezoidError(f"job {job_id} still {state_name(info.state)} after {timeout_s} s")
            time.sleep(poll_s)


def _job_request(msg, job_id: str) -> None:
    msg.SetInParent()
    msg.job_id = job_id


class _Progress:
    def __init__(self, total: int, enabled: bool):
        self.enabled = enabled
        self.bar = None
        self.last = None
        if not enabled:
            return
        try:
            from tqdm.auto import tqdm
            self.bar = tqdm(total=total or None, unit="gen", desc="generations")
        except ImportError:
            self.bar = None

    def update(self, record, workers: int, threads: int):
        if not self.enabled:
            return
        text = f"best {record.best_cost:.6g} median {record.median_cost:.6g}, {workers} workers / {threads} threads"
        if len(record.islands):
            bests = [i.best_cost for i in record.islands]
            text += f", island {record.best_island}/{len(bests)} (islands {min(bests):.4g}…{max(bests):.4g})"
        if self.bar is not None:
            self.bar.n = record.generation
            self.bar.set_postfix_str(text, refresh=True)
        else:
            now = time.monotonic()
            self.pending = f"\rgeneration {record.generation}: {text}   "
            if self.last is None or now - self.last > 0.5:
                sys.stderr.write(self.pending)
                sys.stderr.flush()
                self.last, self.pending = now, None

    def close(self):
        if self.bar is not None:
            self.bar.close()
        elif self.enabled and self.last is not None:
            sys.stderr.write((getattr(self, "pending", None) or "") + "\n")
