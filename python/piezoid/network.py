"""A fetched HGANN network (proto/network.proto NetworkFile) that predicts the seven model parameters.

The arithmetic is the C++ Network::Forward's, operation for operation (model/network.cc), so the
predictions are the same doubles on the same platform.
"""
from __future__ import annotations

import math

from ._proto import network_pb2

_TF = network_pb2.NetworkTransferFunction
PARAMETERS = ("mu", "delta", "alpha", "beta", "gamma", "a1", "a2")


def _apply(tf: int, n: float) -> float:
    if tf == _TF.NETWORK_TF_HARDLIM:
        return 1.0 if n >= 0 else 0.0
    if tf == _TF.NETWORK_TF_HARDLIMS:
        return 1.0 if n >= 0 else -1.0
    if tf == _TF.NETWORK_TF_SATLIN:
        return 0.0 if n <= 0 else (1.0 if n >= 1 else n)
    if tf == _TF.NETWORK_TF_SATLINS:
        return -1.0 if n <= -1 else (1.0 if n >= 1 else n)
    if tf == _TF.NETWORK_TF_TRIBAS:
        return 1.0 - abs(n) if -1 <= n <= 1 else 0.0
    if tf == _TF.NETWORK_TF_TANSIG:
        return 2.0 / (1.0 + _exp(-2.0 * n)) - 1.0
    if tf == _TF.NETWORK_TF_LOGSIG:
        return 1.0 / (1.0 + _exp(-n))
    if tf == _TF.NETWORK_TF_RADBAS:
        return _exp(-n * n)
    raise ValueError(f"transfer function {tf}: unknown")


def _exp(x: float) -> float:
    try:
        return math.exp(x)
    except OverflowError:  # C's exp gives +inf there; the transfer functions then give their limits
        return math.inf


def _range(tf: int):
    if tf in (_TF.NETWORK_TF_HARDLIMS, _TF.NETWORK_TF_SATLINS, _TF.NETWORK_TF_TANSIG):
        return -1.0, 1.0
    return 0.0, 1.0


class Network:
    """Wraps a NetworkFile; `predict(amplitude_v, frequency_hz)` gives {mu, delta, alpha, beta, gamma, a1, a2}."""

    def __init__(self, file: network_pb2.NetworkFile):
        h = file.hidden
        if file.format_version != 1:
            raise ValueError(f"format_version = {file.format_version}: this client reads version 1")
        for name, got, want in (("input_tf", len(file.input_tf), 2), ("hidden_tf", len(file.hidden_tf), h),
                                ("output_tf", len(file.output_tf), 7), ("w1", len(file.w1), 2 * h),
                                ("c1", len(file.c1), h), ("w2", len(file.w2), 7 * h), ("c2", len(file.c2), 7),
                                ("inputs", len(file.inputs), 2), ("parameters", len(file.parameters), 7)):
            if got != want:
                raise ValueError(f"network.{name}: {got} entries, expected {want} (hidden = {h})")
        self.file = file
        self.hidden = h

    @classmethod
    def load(cls, path) -> "Network":
        """A network file written by `piezoid fetch` / `identify` (.pb binary or .json)."""
        from google.protobuf import json_format
        f = network_pb2.NetworkFile()
        with open(path, "rb") as fh:
            data = fh.read()
        if str(path).endswith(".json"):
            json_format.Parse(data.decode(), f)
        else:
            f.ParseFromString(data)
        return cls(f)

    def describe(self) -> str:
        name = lambda tf: _TF.Name(tf).replace("NETWORK_TF_", "").lower()
        return (f"2-{self.hidden}-7 in[{','.join(map(name, self.file.input_tf))}] "
                f"hidden[{','.join(map(name, self.file.hidden_tf))}] out[{','.join(map(name, self.file.output_tf))}]")

    def predict(self, amplitude_v: float, frequency_hz: float) -> dict:
        if not (math.isfinite(amplitude_v) and math.isfinite(frequency_hz)):
            raise ValueError(f"amplitude_v = {amplitude_v}, frequency_hz = {frequency_hz}: must be finite")
        f, h = self.file, self.hidden
        ins = f.inputs
        x = ((amplitude_v - ins[0].lo) / (ins[0].hi - ins[0].lo), (frequency_hz - ins[1].lo) / (ins[1].hi - ins[1].lo))
        a = [_apply(f.input_tf[i], x[i]) for i in range(2)]
        b = []
        for j in range(h):
            n = f.c1[j]
            for i in range(2):
                n += a[i] * f.w1[h * i + j]
            b.append(_apply(f.hidden_tf[j], n))
        out = {}
        for k in range(7):
            n = f.c2[k]
            for j in range(h):
                n += b[j] * f.w2[7 * j + k]
            o = _apply(f.output_tf[k], n)
            lo, hi = _range(f.output_tf[k])
            s = (o - lo) / (hi - lo)
            p = f.parameters[k]
            out[PARAMETERS[k]] = p.lower + s * (p.upper - p.lower)
        return out
