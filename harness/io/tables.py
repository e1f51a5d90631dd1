"""Read a results CSV into a DataFrame with every float exactly as written.

pandas before 3.0 parses floats with a fast converter that may land one unit in the last
place off (on a dynamic accuracy table, a third of the cells). Two modes whose errors differ
in that place then swap order, and the same table renders a report that names another mode
on another machine. The round-trip converter is exact; pandas 3 uses it by default and
deprecates the argument, so it is passed only where needed."""


def read_csv(path, **kwargs):
    """pandas.read_csv(path, **kwargs), floats parsed exactly on every pandas version."""
    import pandas as pd  # here, not at the top: the sweep's workers import this package without pandas

    if int(pd.__version__.split(".")[0]) < 3:
        kwargs.setdefault("float_precision", "round_trip")
    return pd.read_csv(path, **kwargs)
