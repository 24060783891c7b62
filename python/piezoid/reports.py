"""The CSV files of an identify / fetch / diagnose report folder as pandas DataFrames (dicts of lists without pandas)."""
from __future__ import annotations

import csv
import pathlib


def read_report(folder) -> dict:
    """{name: table} for every CSV of a report folder (progress, validation, parameters, traces/…).

    With pandas installed each table is a DataFrame, else a list of dicts (numbers as floats where
    they parse). Example: read_report("result")["progress"].plot(x="generation", y=["best_cost", "median_cost"], logy=True)
    """
    root = pathlib.Path(folder)
    if not root.is_dir():
        raise FileNotFoundError(f"{root}: not a report folder")
    try:
        import pandas as pd
    except ImportError:
        pd = None
    tables = {}
    for path in sorted(root.rglob("*.csv")):
        name = str(path.relative_to(root).with_suffix(""))
        if pd is not None:
            tables[name] = pd.read_csv(path)
            continue
        with path.open(newline="") as f:
            rows = list(csv.DictReader(f))
        for row in rows:
            for k, v in row.items():
                try:
                    row[k] = float(v)
                except (TypeError, ValueError):
                    pass
        tables[name] = rows
    return tables
