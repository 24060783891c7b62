"""piezoid: the Python client of the piezoid identification service.

    import piezoid
    c = piezoid.Client("tcp://127.0.0.1:5556")
    job = c.submit("job.json")           # a spec with its case data embedded (dict, file or text)
    info = c.watch(job)                  # progress bar until the job ends
    result = c.fetch(job, count=3)       # best individuals, log, spec, networks
    result.networks[0].predict(500, 0.5) # {'mu': …, 'delta': …, …}
    result.log_frame()                   # the generation log as a pandas DataFrame (if pandas is installed)
    m = piezoid.Model.load("fit.json")   # a fitted model: m.init(u0), m.step(u), m.inverse_step(y)

The protobuf bindings (piezoid._proto) are generated from the checkout's proto/ when the package is built.
"""
from .client import (Client, FetchResult, InvalidSpec, NotFound, PiezoidError, Unreachable, load_spec,
                     records_frame, state_name)
from .model import Model
from .network import PARAMETERS, Network
from .reports import read_report

__all__ = ["Client", "FetchResult", "InvalidSpec", "NotFound", "PiezoidError", "Unreachable", "load_spec",
           "records_frame", "state_name", "Model", "Network", "PARAMETERS", "read_report"]
__version__ = "0.1.0"
