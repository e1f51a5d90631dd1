"""Read a results CSV into a DataFrame with every float exactly as written.

pandas before 3.1 parses floats with a converter that may land one unit in the last place
off (3.0.6 and 2.2.3 misread a third of a dynamic accuracy table's numbers). Two modes whose
errors differ in that place then swap order, and the same table renders a report that names
another mode on another machine. The round-trip converter is exact; pandas 3.1 parses
exactly by default and deprecates the argument, so it is passed only before 3.1."""

import os
import re


def read_csv(path, what="csv", **kwargs):
    """pandas.read_csv(path, **kwargs), floats parsed exactly on every pandas version; a path is
    checked first (harness.core.inputs: a regular file; `what` names it in the refusal)."""
    import pandas as pd  # lazily: runlog imports this module, and its writers need no pandas

    from harness.core import inputs

    if isinstance(path, (str, os.PathLike)):
        inputs.regular(path, what, empty_ok=True)
    major, minor = (int(x) for x in re.match(r"(\d+)\.(\d+)", pd.__version__).groups())
    if (major, minor) < (3, 1):
        kwargs.setdefault("float_precision", "round_trip")
    return pd.read_csv(path, **kwargs)


def cell(row, key):
    """A table row's (a dict's) value as a float: NaN where absent, empty or not a number."""
    try:
        return float(row[key])
    except (TypeError, ValueError, KeyError):
        return float("nan")
