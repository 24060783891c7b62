"""A fitted record model (fit.json of `piezoid fit`) in Python, with the numbers of its C header.

    m = piezoid.Model.load("fit-out/fit.json")   # runs `piezoid export`, compiles the header with cc
    y0 = m.init(u0)                              # at rest under drive u0
    y = m.step(u)                                # forward: the response to drive u
    u = m.inverse_step(y_desired)                # compensator: the drive for a desired response
    m.saturated, m.max_clip                      # clipped samples, largest clipping

The header `piezoid export FIT.json` writes is compiled into a small shared object and called through
ctypes: the same C code a controller runs, so the same numbers. One Model is used either forward or as a
compensator after init (like the header's state). Needs the piezoid command (PIEZOID_CLI, or `piezoid` on
PATH) and a C compiler (CC, default cc).
"""
import ctypes
import os
import pathlib
import shutil
import subprocess
import tempfile

__all__ = ["Model"]

_NAME = "pzpy"
_WRAPPER = """#include "pzpy.h"
unsigned long pzpy_state_size(void) { return sizeof(pzpy_state); }
double pzpy_init_(void *s, double u0) { return pzpy_init((pzpy_state *)s, u0); }
double pzpy_step_(void *s, double u) { return pzpy_step((pzpy_state *)s, u); }
double pzpy_inverse_step_(void *s, double y) { return pzpy_inverse_step((pzpy_state *)s, y); }
long pzpy_saturated_(void *s) { return ((pzpy_state *)s)->ctl.saturated; }
double pzpy_max_clip_(void *s) { return ((pzpy_state *)s)->ctl.max_clip; }
void pzpy_limits_(void *s, double *lo, double *hi) { *lo = ((pzpy_state *)s)->ctl.u_lo; *hi = ((pzpy_state *)s)->ctl.u_hi; }
"""


def _cli():
    cli = os.environ.get("PIEZOID_CLI") or shutil.which("piezoid")
    if not cli:
        raise RuntimeError("piezoid.Model: the piezoid command is needed (set PIEZOID_CLI or put it on PATH)")
    return cli


class Model:
    """The model of one fit.json, compiled from its exported C header."""

    def __init__(self, library, folder, fit_path):
        self._lib = library
        self._folder = folder
        self.path = str(fit_path)
        self.header = (pathlib.Path(folder) / f"{_NAME}.h").read_text()
        lib = self._lib
        lib.pzpy_state_size.restype = ctypes.c_ulong
        for fn in ("pzpy_init_", "pzpy_step_", "pzpy_inverse_step_"):
            getattr(lib, fn).restype = ctypes.c_double
            getattr(lib, fn).argtypes = [ctypes.c_void_p, ctypes.c_double]
        lib.pzpy_saturated_.restype = ctypes.c_long
        lib.pzpy_saturated_.argtypes = [ctypes.c_void_p]
        lib.pzpy_max_clip_.restype = ctypes.c_double
        lib.pzpy_max_clip_.argtypes = [ctypes.c_void_p]
        lib.pzpy_limits_.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double)]
        self._state = ctypes.create_string_buffer(lib.pzpy_state_size())
        self._ready = False

    @classmethod
    def load(cls, fit_json, cc=None):
        """Exports fit_json's model as a C header (`piezoid export`) and compiles it. Raises
        RuntimeError with the command's message (a fit.json of another version, a bad field)."""
        fit = pathlib.Path(fit_json)
        folder = tempfile.mkdtemp(prefix="piezoid-model-")
        header = pathlib.Path(folder) / f"{_NAME}.h"
        run = subprocess.run([_cli(), "export", str(fit), "--out", str(header), "--name", _NAME],
                             capture_output=True, text=True)
        if run.returncode != 0:
            shutil.rmtree(folder, ignore_errors=True)
            raise RuntimeError(f"piezoid export {fit}: {run.stderr.strip() or run.stdout.strip()}")
        (pathlib.Path(folder) / "wrapper.c").write_text(_WRAPPER)
        so = pathlib.Path(folder) / "libpzpy.so"
        cc = cc or os.environ.get("CC", "cc")
        build = subprocess.run([cc, "-std=c99", "-O2", "-shared", "-fPIC", "-o", str(so), "wrapper.c", "-lm"],
                               cwd=folder, capture_output=True, text=True)
        if build.returncode != 0:
            raise RuntimeError(f"compiling the exported header failed: {build.stderr.strip()}")
        return cls(ctypes.CDLL(str(so)), folder, fit)

    def init(self, u0):
        """At rest under drive u0; returns the response there. Resets the saturation counter."""
        self._ready = True
        return self._lib.pzpy_init_(self._state, float(u0))

    def _check(self):
        if not self._ready:
            raise RuntimeError("piezoid.Model: call init(u0) first")

    def step(self, u):
        """Forward: the response to drive u (clipped to the limits, counted)."""
        self._check()
        return self._lib.pzpy_step_(self._state, float(u))

    def inverse_step(self, y_desired):
        """Compensator: the drive whose one-step response is y_desired (clipped to the limits, counted)."""
        self._check()
        return self._lib.pzpy_inverse_step_(self._state, float(y_desired))

    def run(self, drive):
        """The forward model over a drive sequence (init at its first sample); a list of responses."""
        drive = list(drive)
        return [self.init(drive[0])] + [self.step(u) for u in drive[1:]]

    @property
    def saturated(self):
        return self._lib.pzpy_saturated_(self._state)

    @property
    def max_clip(self):
        return self._lib.pzpy_max_clip_(self._state)

    @property
    def limits(self):
        lo, hi = ctypes.c_double(), ctypes.c_double()
        self._lib.pzpy_limits_(self._state, ctypes.byref(lo), ctypes.byref(hi))
        return lo.value, hi.value
