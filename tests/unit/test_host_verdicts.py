"""The host's load at the top of a report (harness/studies/host_verdicts.py, worded by
harness/render/host_report.py): a run is loaded when other processes used more than
tolerances.TIMING_OTHER_CORES cores when the bench started or, as the median, while its figures
were timed; quiet otherwise; a run with neither a record nor a timed figure says nothing."""

import json

import pandas as pd

from harness.core import tolerances
from harness.render import host_report
from harness.studies import host_verdicts

LIMIT = tolerances.TIMING_OTHER_CORES


def run(tmp_path, start=None, others=()):
    tmp_path.mkdir()
    if start is not None:
        (tmp_path / host_verdicts.HOST_JSON).write_text(json.dumps({"cpu_cores": 8, "other_cores": start}))
    if others:
        (tmp_path / "sweep").mkdir()
        rows = pd.DataFrame({"n_samples": [5] * len(others), "noisy": ["load"] + [""] * (len(others) - 1),
                             "other_cores": list(others)})  # fmt: skip
        rows.to_csv(tmp_path / "sweep" / "runs.csv", index=False)
    return tmp_path


def test_a_load_past_the_limit_at_the_start_or_while_timing_marks_the_run(tmp_path):
    assert host_verdicts.host_load(run(tmp_path / "a", start=2 * LIMIT)).loaded
    typical = host_verdicts.host_load(run(tmp_path / "b", start=0.0, others=(0.0, 2 * LIMIT, 3 * LIMIT)))
    assert typical.loaded and typical.typical == 2 * LIMIT and (typical.total, typical.noisy) == (3, 1)
    quiet = host_verdicts.host_load(run(tmp_path / "c", start=0.5 * LIMIT, others=(0.0, 0.5 * LIMIT, 2 * LIMIT)))
    assert not quiet.loaded
    assert host_report.section(tmp_path / "a")[0].startswith("> **This host was loaded")
    assert host_report.section(tmp_path / "c")[0].startswith("Host load: quiet")


def test_a_run_without_a_record_or_a_timed_figure_says_nothing(tmp_path):
    load = host_verdicts.host_load(tmp_path)
    assert (load.start, load.total, load.typical, load.loaded) == ({}, 0, None, False)
    assert host_report.section(tmp_path) == []
