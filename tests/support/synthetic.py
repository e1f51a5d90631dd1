"""Write state files in the documented layout without a backend (for tests and examples).

`radial_strands` makes a state that meets every invariant of docs/model.md §2.7 by construction:
each strand leaves its root on the head sphere and runs outward, tilted by a per-frame
angle, with segments of exactly ℓ (up to rounding) and x constant. `write_state` writes
any positions array [F][N][P][3] with the /h5md, /particles and /parameters layout of
docs/interfaces.md.
"""

import os

import numpy as np

DEFAULT_PARAMS = {
    "head_radius": 10.0,
    "hair_offset": 0.1,
    "hair_length": 30.0,
    "face_margin": 1.0,
    "wind_strength": 0.5,
    "wind_angle": np.pi,
    "seed": 1,
    "backend": "synthetic",
    "variant": "radial",
    "block_size": -1,
    "threads": 1,
    "repeat": 1,
    "warmup": 0,
    "git_revision": "none",
    "compiler": "none",
    "flags": "",
    "device": "none",
    "driver": "none",
    "version": "0.1.0",
    "end_to_end_ms": 0.0,
    "hdf5_write_ms": 0.0,
}


def radial_strands(
    n_strands,
    points,
    stages=("init", "collide", "wind", "collide"),
    dtype=np.float64,
    seed=0,
    head_radius=10.0,
    hair_length=30.0,
):
    """Positions [F][N][P][3] of strands running outward from their roots.

    Frame f tilts every strand by an angle of f·0.1 rad in its slice plane (still well
    outside the shell circle), so successive frames differ."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n_strands, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    roots = head_radius * v
    theta0 = np.arctan2(roots[:, 1], roots[:, 2])
    ell = hair_length / (points - 1)
    k = np.arange(points)
    frames = []
    for f in range(len(stages)):
        phi = theta0 + 0.1 * f
        state = np.empty((n_strands, points, 3))
        state[:, :, 0] = roots[:, None, 0]
        state[:, :, 1] = roots[:, None, 1] + k[None, :] * ell * np.sin(phi)[:, None]
        state[:, :, 2] = roots[:, None, 2] + k[None, :] * ell * np.cos(phi)[:, None]
        frames.append(state)
    return np.asarray(frames).astype(dtype)


def write_state(path, positions, stages, precision=None, params=None, skipped=None, fused=None, datasets=True):
    """Write positions [F][N][P][3] to `path` in the documented layout (temp file, rename).

    `params` overrides /parameters attributes; `datasets=False` leaves out the optional
    per-frame datasets other than /parameters/stage."""
    import h5py

    positions = np.asarray(positions)
    F, N, P, _ = positions.shape
    precision = precision or ("fp64" if positions.dtype == np.float64 else "fp32")
    attrs = dict(DEFAULT_PARAMS, n_strands=N, points_per_strand=P, precision=precision)
    attrs.update(params or {})
    tmp = f"{path}.tmp.{os.getpid()}"
    with h5py.File(tmp, "w") as f:
        f.create_group("h5md").attrs["version"] = np.array([1, 1], dtype=np.int32)
        f["h5md"].create_group("author").attrs["name"] = "hairbench tests"
        creator = f["h5md"].create_group("creator")
        creator.attrs["name"] = f"hairbench {attrs['backend']}"
        creator.attrs["version"] = attrs["version"]
        box = f.create_group("particles/hair/box")
        box.attrs["dimension"] = 3
        box.attrs["boundary"] = ["none", "none", "none"]
        pos = f.create_group("particles/hair/position")
        pos.create_dataset("value", data=positions.reshape(F, N * P, 3), chunks=(1, min(N * P, 1 << 20), 3))
        pos.create_dataset("step", data=np.arange(F, dtype=np.int64))
        pos.create_dataset("time", data=np.arange(F, dtype=np.float64))
        g = f.create_group("parameters")
        for key, value in attrs.items():
            g.attrs[key] = value
        g.create_dataset("stage", data=np.array(list(stages), dtype=h5py.string_dtype()))
        if datasets:
            g.create_dataset("skipped", data=np.array(skipped or [0] * F, dtype=np.int8))
            g.create_dataset("fused", data=np.array(fused or [""] * F, dtype=h5py.string_dtype()))
            moved = [0 if s == "collide" else -1 for s in stages]
            g.create_dataset("moved_points", data=np.array(moved, dtype=np.int64))
            wind = [attrs["wind_strength"] if s == "wind" else np.nan for s in stages]
            g.create_dataset("wind_strength", data=np.array(wind, dtype=np.float64))
            g.create_dataset(
                "wind_angle",
                data=np.array([attrs["wind_angle"] if s == "wind" else np.nan for s in stages], dtype=np.float64),
            )
            for name in ("stage_median_ms", "stage_min_ms", "stage_max_ms"):
                g.create_dataset(name, data=np.zeros(F))
            g.create_dataset(
                "frame_backend",
                data=np.array([f"{attrs['backend']}/{attrs['variant']}"] * F, dtype=h5py.string_dtype()),
            )
    os.replace(tmp, path)
    return path


# Departures from H5MD that harness.io.h5md.problems must name (tests/cpu/test_readers.py).
H5MD_BREAKS = {
    "variable_length_unit": "'unit' is not a fixed-length ASCII string",
    "no_unit_system": "no 'system' attribute",
    "unknown_unit": "'furlong' is not an SI unit symbol",
    "time_without_unit": "time has no unit 's'",
    "strand_ids_wrong": "strand is not the strand index",
    "variable_length_author": "/h5md/author: 'name' is not a fixed-length ASCII string",
}


def crafted_state(path, strands, precision="fp64", L=3.0):
    """A one-frame state of hand-placed strands (each a list of (x, y, z) points), written at path."""
    pos = np.asarray([strands], dtype=np.float64 if precision == "fp64" else np.float32)
    write_state(
        path,
        pos,
        ["init"],
        precision=precision,
        params={"hair_length": L, "head_radius": 10.0, "hair_offset": 0.1, "face_margin": 1.0},
    )
    return path


def break_h5md(path, how):
    """Change one thing of a state at `path`, in place, so that it departs from H5MD (or
    from the documented strand ids) in the way H5MD_BREAKS[how] names."""
    import h5py

    with h5py.File(path, "r+") as f:
        value, time = f["particles/hair/position/value"], f["particles/hair/position/time"]
        if how == "variable_length_unit":
            value.attrs["unit"] = "cm"  # h5py writes a str as a variable-length UTF-8 string
        elif how == "no_unit_system":
            del f["h5md/modules/units"].attrs["system"]
        elif how == "unknown_unit":
            value.attrs["unit"] = np.bytes_(b"furlong")
        elif how == "time_without_unit":
            del time.attrs["unit"]
        elif how == "strand_ids_wrong":
            ids = f["particles/hair/strand"]
            ids[0] = ids[0] + 1
        elif how == "variable_length_author":
            f["h5md/author"].attrs["name"] = "someone"
        else:
            raise ValueError(how)
