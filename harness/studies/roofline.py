"""The roofline, in one place: the bytes each stage must move, and the copy
bandwidth measured on the device that ran it.

Bytes a stage must move, for N strands of P points at s bytes per coordinate (4 for fp32,
8 for fp64):
  init          writes x, y, z of every point:                     N·P·3·s
  wind          reads and writes y and z of every point:           N·P·2·s·2
  collide       reads y and z of every point, writes y and z of
                the points it moves (M = the record's moved_points): N·P·2·s + M·2·s
                (when M is unknown, every point is counted as written: N·P·2·s·2)
  wind+collide  (fused into one kernel) counted once:              N·P·2·s·2
  simulate      per frame (docs/model.md §3): reads and writes x and v of every point,
                and reads the rest shape X̄ when bend, shape or head motion uses it:
                N·P·3·s·4 (+ N·P·3·s); substeps and iterations stay on chip, so the
                bytes do not grow with S·I (the arithmetic does)
x never changes after init, so wind and collide need not touch it (the root's x is not
needed either). A skipped stage (w = 0) and the collide half of a fused pair
("into-previous") move nothing. These are lower bounds of the traffic: a kernel that
moves more (e.g. reads x, or strided loads that fetch whole cache lines) gets a lower
fraction of the limit, which is the point of the measure.

The limit is the device's measured copy bandwidth, `copy_gbps` = (bytes read + bytes
written) / time of a large device-to-device copy (GPU) or of a STREAM-style copy over all
cores (CPU), as printed by `hairsim-* --measure-bandwidth --json`.

On a shared CPU node the copy bandwidth drifts within minutes (docs/decisions/studies.md
has the figures), so a CPU row that is judged against it is measured in
rounds (`in_rounds`): each round measures the copy just before the row, and the row
reported is the round with the median fraction; every round is kept beside it.
"""

from harness.core.runner import BackendError, run_binary


def real_size(precision):
    return 8 if precision == "fp64" else 4


def stage_bytes(stage, strands, points, precision, fused="", skipped=False, moved=None):
    """Bytes the stage must move (see the module comment)."""
    if skipped or fused == "into-previous":
        return 0
    s = real_size(precision)
    if stage == "init":
        return strands * points * 3 * s
    if stage == "collide" and not fused and moved is not None:
        # a collide pass leaves the points it does not move untouched: reading y, z is the floor
        return strands * points * 2 * s + moved * 2 * s
    if stage in ("wind", "collide"):
        return strands * points * 2 * s * 2
    raise ValueError(f"no roofline for stage '{stage}'")


def simulate_bytes(strands, points, precision, features=()):
    """Bytes one simulated frame must move (see the module comment); `features` the names of
    the declared features (bend, shape, motion read the rest shape)."""
    s = real_size(precision)
    nbytes = strands * points * 3 * s * 4
    if {"bend", "shape", "motion"} & set(features):
        nbytes += strands * points * 3 * s
    return nbytes


def achieved_gbps(nbytes, ms):
    """GB/s (10^9 bytes per second) of moving nbytes in ms milliseconds; None if undefined."""
    if not nbytes or not ms or ms <= 0:
        return None
    return nbytes / (ms * 1e-3) / 1e9


def measure_bandwidth(binary, timeout=None):
    """The record of `binary --measure-bandwidth --json` (copy_gbps; the CPU adds triad_gbps
    and threads, the GPU its device); BackendError when it fails."""
    return run_binary(binary, ["--measure-bandwidth"], timeout=timeout, expect_keys=("copy_gbps",))


def in_rounds(binary, rounds, measure, key="fraction", ms_key="median_ms", first_copy=None):
    """`rounds` rounds of (the copy bandwidth of `binary`, then `measure(copy_gbps)` -> a row
    whose `key` is its fraction of that copy); returns the round whose fraction is the median
    (the lower middle one for an even count) with "copy_gbps" (that round's copy) and
    "rounds" (every round's copy_gbps, `ms_key` and fraction) added, and with `first_copy`
    (the run's first copy measurement) `key` + "_of_first_copy": the same row against it."""
    done = []
    for _ in range(max(1, int(rounds))):
        copy = measure_bandwidth(binary)["copy_gbps"]
        done.append((copy, measure(copy)))
    ranked = sorted(done, key=lambda cr: cr[1].get(key) or 0.0)
    copy, row = ranked[(len(ranked) - 1) // 2]
    rounds_kept = [{"copy_gbps": c, ms_key: r.get(ms_key), "fraction": r.get(key)} for c, r in done]
    out = dict(row, copy_gbps=copy, rounds=rounds_kept)
    if first_copy:
        out[f"{key}_of_first_copy"] = row[key] * copy / first_copy if row.get(key) is not None else None
    return out


def measure_copy_bandwidth(binary, timeout=300):
    """measure_bandwidth for a sweep: (copy_gbps or None, note), never an error."""
    try:
        rec = measure_bandwidth(binary, timeout=timeout)
    except BackendError as e:
        return None, (f"{binary.name} --measure-bandwidth failed ({e}); bandwidth fractions are left empty")
    gbps = rec.get("copy_gbps")
    if not isinstance(gbps, (int, float)) or gbps <= 0:
        return None, f"{binary.name} --measure-bandwidth gave copy_gbps = {gbps!r}; fractions left empty"
    return float(gbps), f"{binary.name}: copy bandwidth {gbps:.1f} GB/s over {rec.get('bytes')} bytes"
