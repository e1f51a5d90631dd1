"""A tiny plan of the dynamic accuracy study, for tests that run it for real in seconds."""

from harness.core.timing import fixed

TINY = dict(
    strands=4,
    seconds=2 / 60,
    horizon=2 / 60,
    substeps=(1, 2),
    iterations=(1,),
    time_strands=8,
    repeat=1,
    stop_rule=fixed(1),  # one timed run a mode: the tests check the study, not the times
    ref_start=64,
    ref_max=4096,
    analytic="none",
    jobs=2,
    ftl_damping=(0.9, 1.0),
    long_seconds=6 / 60,
    long_strands=2,
)
