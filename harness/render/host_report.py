"""The host's load while a bench ran, at the top of its reports (docs/decisions/honest-timings.md),
worded from studies/host_verdicts.py's record of it: a run on a loaded host says so first, and
every run says how many of its timed figures are noise."""

from harness.core import tolerances
from harness.studies.host_verdicts import host_load


def section(root):
    """Lines for the top of a report of the run in `root` (nothing where no figure carries a load)."""
    h = host_load(root)
    start, total, noisy, typical, limit = h.start, h.total, h.noisy, h.typical, h.limit
    if not start and not total:
        return []
    cores = start.get("cpu_cores")
    at_start = start.get("other_cores")
    facts = []
    if at_start is not None:
        facts.append(f"other processes used {at_start:.2g} of its {cores} cores when the bench started "
                     f"(1-minute load average {start.get('loadavg', float('nan')):.3g})")  # fmt: skip
    if typical is not None:
        facts.append(f"{typical:.2g} cores, the median over the timed figures while they ran")
    share = f"{noisy} of {total} timed figures are flagged as noise" if total else "no timed figure"
    if h.loaded:
        return [
            f"> **This host was loaded while the bench ran**: {'; '.join(facts)} (more than {limit:g} core marks a "
            f"figure as noise). {share}: their times are upper bounds, a ranking between them is a tie, and no "
            "recommendation rests on them. Run the bench again on a quiet host before trusting its times.",
            "",
        ]
    return [
        f"Host load: quiet ({'; '.join(facts) or 'not measured'}). {share} (a relative standard deviation above "
        f"{100 * tolerances.TIMING_MAX_RSD:g} % or a loaded host; core/timing.py).",
        "",
    ]
