"""The hair's volume from written frames (docs/model.md §3.16, "Observables of the hair's
volume"), for any run, grid or not: the hair volume (distinct 1-cm cells of the head frame that
hold a point), the envelope radius (the 90th percentile of the tips' distance from the head's
centre) and the close pairs (segment pairs of different strands, among 256 strands taken at a
stride, closer than 0.05 cm)."""

import math

import numpy as np

from harness.check.invariants_dynamic import head_rotation

CELL_CM = 1.0
CLOSE_CM = 0.05
SAMPLE_STRANDS = 256


def head_frame(points, rotation):
    """Points [..., 3] in the head's frame: Qᵀ·x (rotation: Q, row-major 3×3, or None)."""
    return points if rotation is None else points @ np.asarray(rotation, float).reshape(3, 3)


def hair_volume(points, rotation=None, cell=CELL_CM):
    """cm³ of the distinct cells of side `cell` (head frame) that hold at least one point."""
    p = head_frame(np.asarray(points, float).reshape(-1, 3), rotation)
    p = p[np.all(np.isfinite(p), axis=1)]
    cells = np.unique(np.floor(p / cell).astype(np.int64), axis=0)
    return float(len(cells)) * cell**3


def envelope_radius(strands):
    """The 90th percentile of the distance of the strands' tips from the head's centre, cm."""
    tips = np.asarray(strands, float)[:, -1, :]
    return float(np.percentile(np.linalg.norm(tips, axis=1), 90))


def _segment_distance(p0, p1, q0, q1):
    """Distances between segments p0–p1 and q0–q1 ([M][3] each, pairwise by row)."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a = np.einsum("ij,ij->i", d1, d1)
    e = np.einsum("ij,ij->i", d2, d2)
    f = np.einsum("ij,ij->i", d2, r)
    c = np.einsum("ij,ij->i", d1, r)
    b = np.einsum("ij,ij->i", d1, d2)
    den = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(den > 1e-30 * np.maximum(a * e, 1e-300), np.clip((b * f - c * e) / den, 0, 1), 0.0)
        t = np.where(e > 0, (b * s + f) / e, 0.0)
        s = np.where(
            t < 0,
            np.where(a > 0, np.clip(-c / a, 0, 1), 0.0),
            np.where(t > 1, np.where(a > 0, np.clip((b - c) / a, 0, 1), 0.0), s),
        )
        t = np.clip(t, 0, 1)
    return np.linalg.norm(p0 + d1 * s[:, None] - (q0 + d2 * t[:, None]), axis=1)


def close_pairs(strands, sample=SAMPLE_STRANDS, close=CLOSE_CM):
    """Segment pairs of different strands closer than `close` cm, among `sample` strands taken at
    the stride ⌈N/sample⌉ (a sampled count of hair passing through hair)."""
    x = np.asarray(strands, float)
    n, p = x.shape[:2]
    stride = max(1, math.ceil(n / sample))
    s = x[::stride]
    seg0, seg1 = s[:, :-1].reshape(-1, 3), s[:, 1:].reshape(-1, 3)
    owner = np.repeat(np.arange(len(s)), p - 1)
    lo, hi = np.minimum(seg0, seg1) - close, np.maximum(seg0, seg1) + close
    count = 0
    for i in range(len(seg0)):  # bounding boxes first: the distance only where they overlap
        cand = np.nonzero((owner > owner[i]) & np.all(lo <= hi[i], axis=1) & np.all(hi >= lo[i], axis=1))[0]
        if len(cand):
            d = _segment_distance(
                np.repeat(seg0[i : i + 1], len(cand), 0),
                np.repeat(seg1[i : i + 1], len(cand), 0),
                seg0[cand],
                seg1[cand],
            )
            count += int(np.count_nonzero(d < close))
    return count


def frame_volume(trajectory, f):
    """The three observables of frame f of an open harness.io.trajectory."""
    x = trajectory.frame(f).reshape(trajectory.n_strands, trajectory.points, 3)
    q = None
    params = trajectory.dynamic_params if trajectory.is_dynamic else {}
    if params and trajectory.head_motion != "still":
        q = head_rotation(
            trajectory.head_motion,
            float(params["motion_amplitude"]),
            float(params["motion_frequency"]),
            float(trajectory.time[f]),
            trajectory.motion_track,
        )
    return {"hair_volume": hair_volume(x, q), "envelope_radius": envelope_radius(x), "close_pairs": close_pairs(x)}
