# %% [markdown]
# # piezoid from Python (notebook-style: run cell by cell in Jupyter, VS Code or `python3 -i`)
#
# Before: a master and workers running (`deploy/local/piezoid-local.sh start --workers 2`), and the
# client installed from the checkout, next to Debian's python3-zmq and python3-protobuf:
#
#     python3 -m venv --system-site-packages ~/pz && ~/pz/bin/pip install --no-build-isolation ./python
#
# The spec must carry its case data. The C++ client embeds a case set for you:
#
#     build/client/piezoid submit examples/hgann_quick.json --write-embedded quick.json

# %% Connect ($PIEZOID_MASTER, else tcp://127.0.0.1:5556)
import json
import piezoid

c = piezoid.Client()
print([piezoid.state_name(j.state) for j in c.list()], len(c.workers().workers), "workers")

# %% Submit: a dict, a JSON file or text. Every bad field is named.
spec = json.load(open("quick.json"))
spec["seed"] = "11"  # another run of the same search
job = c.submit(spec)
print("job", job)

# %% Watch it: a progress bar (tqdm if installed), one callback per generation.
curve = []
info = c.watch(job, on_event=lambda e: curve.append((e.record.generation, e.record.best_cost, e.record.median_cost)))
print(piezoid.state_name(info.state), info.message)

# %% Fetch the best networks, and predict the model parameters of a new drive with the best one.
result = c.fetch(job, count=3)
best = result.networks[0]
print(best.describe(), "cost", best.file.provenance.fitness)
print(best.predict(amplitude_v=600, frequency_hz=0.75))  # {'mu': …, 'delta': …, 'alpha': …, …}

# %% The generation log as a DataFrame (pandas), and the fitness curve (matplotlib), if installed.
log = result.log_frame()
try:
    import matplotlib.pyplot as plt

    ax = log.plot(x="generation", y=["best_cost", "median_cost"], logy=True)
    ax.set_ylabel("cost [deg²]")
    plt.show()
except ImportError:
    print(log if not isinstance(log, list) else log[-3:])

# %% A report written by `piezoid fetch JOB --out result` (or identify / diagnose): its CSVs as tables.
# tables = piezoid.read_report("result"); tables["validation"]
