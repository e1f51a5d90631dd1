"""Reading the dynamic accuracy study's results folder (studies/accuracy_dynamic.py writes it):
its table, env.json's record of the study, the analytic sweeps, the long runs (observables.csv)
and the reference ensemble (ensemble.csv), each refused in one line where it is not the study's.
Nothing here runs a binary: the renderers read through it."""

import json
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.core.paths import display
from harness.io import tables
from harness.studies.accuracy import ANALYTIC_MD, ANALYTIC_NAME, CSV_NAME, LATER_COLUMNS, REQUIRED_COLUMNS

LONG_CSV = "observables.csv"  # studies/observables_long_dynamic.py's table
ENSEMBLE_CSV = "ensemble.csv"  # studies/accuracy_ensemble_dynamic.py's table


def load(results_dir, csv_path=None):
    """(rows DataFrame, study dict of env.json, env dict, analytic): the rows from csv_path when
    given, else from results_dir's table; analytic the sweeps' data (analytic.json), the
    Markdown lines of a study from before #47 (analytic.md), or None where none ran."""
    results_dir = Path(results_dir)
    csv_path = Path(csv_path) if csv_path else results_dir / CSV_NAME
    try:
        rows = tables.read_csv(csv_path)
    except FileNotFoundError:
        raise HarnessError(f"{display(csv_path)} not found: run `python -m harness accuracy --model dynamic`") from None
    except (OSError, ValueError) as e:
        raise HarnessError(f"{display(csv_path)}: cannot read ({e})") from None
    missing = [c for c in REQUIRED_COLUMNS if c not in rows.columns]
    if missing or rows.empty:
        raise HarnessError(
            f"{display(csv_path)}: not a dynamic accuracy table (missing {', '.join(missing) or 'rows'})"
        )
    for c in LATER_COLUMNS:
        if c not in rows.columns:
            rows[c] = np.nan
    if rows["verdict"].isna().all():  # written before the split by cause
        rows["verdict"] = np.where(rows["blown_up_strands"] > 0, "blown up", "ok")
    try:
        env = json.loads((results_dir / "env.json").read_text())
        study = env["study"]
    except (OSError, ValueError, KeyError, TypeError):
        raise HarnessError(f"{display(results_dir / 'env.json')}: missing or not the study's record") from None
    return rows, study, env, load_analytic(results_dir)


def load_analytic(results_dir):
    """The analytic sweeps of a results folder (see load), or None."""
    path, old = Path(results_dir) / ANALYTIC_NAME, Path(results_dir) / ANALYTIC_MD
    if path.exists():
        try:
            return json.loads(path.read_text())
        except (OSError, ValueError) as e:
            raise HarnessError(f"{display(path)}: cannot read ({e})") from None
    return old.read_text().splitlines() if old.exists() else None


def _read(path):
    if not path.exists():
        return None
    try:
        return tables.read_csv(path)
    except (OSError, ValueError) as e:
        raise HarnessError(f"{display(path)}: cannot read ({e})") from None


def load_long(results_dir):
    """The long runs' table as a DataFrame, or None where the study ran none."""
    return _read(Path(results_dir) / LONG_CSV)


def load_ensemble(results_dir):
    """ensemble.csv as a DataFrame, or None (a study from before the ensemble)."""
    return _read(Path(results_dir) / ENSEMBLE_CSV)
