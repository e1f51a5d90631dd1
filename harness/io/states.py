"""Read HDF5 states in the layout of docs/interfaces.md and check that layout.

A state file holds F frames of N strands × P points × (x, y, z). On disk a frame is
[N·P][3] (point k of strand i is row i·P + k); `State.frame(f)` returns it as [N][P][3].
Any departure from the layout is a `StateError` (a HarnessError, exit status 2) naming the
file and what is wrong, so `harness diff` can say "could not compare" in one line.
"""

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from harness import HarnessError

POSITION = "particles/hair/position/value"
PARAMETERS = "parameters"
REQUIRED_ATTRS = ("n_strands", "points_per_strand", "precision", "hair_length", "head_radius", "hair_offset")
DTYPE_OF_PRECISION = {"fp32": np.dtype(np.float32), "fp64": np.dtype(np.float64)}


class StateError(HarnessError):
    """The file is missing, unreadable, or not in the documented layout."""


def as_text(value: Any) -> str:
    """An HDF5 attribute or string element as str (h5py gives bytes, str or numpy scalars)."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.shape == ():
        return as_text(value[()])
    if isinstance(value, np.generic):
        return as_text(value.item())
    return str(value)


def as_python(value: Any) -> Any:
    """An HDF5 attribute as a plain Python value (for JSON and comparisons)."""
    if isinstance(value, (bytes, np.bytes_)):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray):
        return [as_python(v) for v in value.tolist()] if value.shape else as_python(value[()])
    if isinstance(value, np.generic):
        return value.item()
    return value


@dataclass
class State:
    """An open state file. Use as a context manager, or call close()."""

    path: str
    n_strands: int
    points: int
    n_frames: int
    precision: str  # "fp32" | "fp64"
    params: dict  # every /parameters attribute, as Python values
    stages: list  # stage name of each frame
    skipped: list  # bool per frame
    fused: list  # "" | "wind+collide" | "into-previous" per frame
    moved: list = field(default_factory=list)  # points each collide changed, -1 where not recorded
    _file: Any = field(repr=False, default=None)
    _dset: Any = field(repr=False, default=None)

    @property
    def dtype(self) -> np.dtype:
        return self._dset.dtype

    @property
    def flags(self) -> str:
        return as_text(self.params.get("flags", ""))

    @property
    def fast_math(self) -> bool:
        """Built with fast math (nvcc --use_fast_math, or -ffast-math)."""
        f = self.flags
        return "use_fast_math" in f or "ffast-math" in f

    @property
    def hair_length(self) -> float:
        return float(self.params["hair_length"])

    @property
    def segment_length(self) -> float:
        """ℓ = L/(P−1), in double (each backend rounds it once to its precision)."""
        return self.hair_length / (self.points - 1)

    @property
    def label(self) -> str:
        backend = as_text(self.params.get("backend", "?"))
        variant = as_text(self.params.get("variant", "?"))
        return f"{backend}/{variant} {self.precision}{' fast-math' if self.fast_math else ''}"

    def frame(self, f: int) -> np.ndarray:
        """Frame f (negative counts from the end) as an [N][P][3] array of the file's dtype."""
        if not -self.n_frames <= f < self.n_frames:
            raise StateError(f"{self.path}: has no frame {f} (it has {self.n_frames})")
        try:
            flat = self._dset[f % self.n_frames]
        except Exception as e:  # h5py raises many kinds for corrupt chunks
            raise StateError(f"{self.path}: cannot read frame {f}: {e}") from None
        return flat.reshape(self.n_strands, self.points, 3)

    def strands(self, f: int, i0: int, i1: int) -> np.ndarray:
        """Strands [i0, i1) of frame f as [n][P][3] in the file's dtype (f ≥ 0)."""
        rows = self._dset[f, i0 * self.points : i1 * self.points]
        return rows.reshape(i1 - i0, self.points, 3)

    def frames(self) -> np.ndarray:
        """Every frame as one [F][N][P][3] array of the file's dtype (small states only)."""
        try:
            flat = self._dset[()]
        except Exception as e:  # h5py raises many kinds for corrupt chunks
            raise StateError(f"{self.path}: cannot read frames: {e}") from None
        return flat.reshape(self.n_frames, self.n_strands, self.points, 3)

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def __enter__(self) -> "State":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _string_list(group: Any, name: str, n_frames: int, default: str | None, path: str) -> list:
    if name not in group:
        return [default] * n_frames
    ds = group[name]
    if ds.shape != (n_frames,):
        raise StateError(f"{path}: /parameters/{name} has shape {ds.shape}, expected ({n_frames},) (one per frame)")
    return [as_text(v) for v in ds[()]]


def open_state(path: str | Path) -> State:
    """Open and check a state file; raise StateError with one clear line if it is not one."""
    from harness.core import inputs

    path = str(path)
    try:
        f = inputs.open_h5(path, "state")
    except HarnessError as e:
        raise StateError(str(e)) from None
    try:
        return _checked_state(f, path)
    except Exception:
        f.close()
        raise


def _checked_state(f: Any, path: str) -> State:
    if POSITION not in f:
        raise StateError(f"{path}: no /{POSITION} dataset (not a hairbench state)")
    dset = f[POSITION]
    if not hasattr(dset, "shape"):
        raise StateError(f"{path}: /{POSITION} is not a dataset")
    if dset.ndim != 3 or dset.shape[2] != 3:
        raise StateError(f"{path}: /{POSITION} has shape {dset.shape}, expected [F][N·P][3]")
    if dset.dtype not in (np.float32, np.float64):
        raise StateError(f"{path}: /{POSITION} has dtype {dset.dtype}, expected float32 or float64")
    if PARAMETERS not in f:
        raise StateError(f"{path}: no /{PARAMETERS} group")
    group = f[PARAMETERS]
    params = {k: as_python(v) for k, v in group.attrs.items()}
    missing = [a for a in REQUIRED_ATTRS if a not in params]
    if missing:
        raise StateError(f"{path}: /{PARAMETERS} lacks attribute(s) {', '.join(missing)}")
    try:
        n = int(params["n_strands"])
        p = int(params["points_per_strand"])
        float(params["hair_length"])
        float(params["head_radius"])
        float(params["hair_offset"])
    except (TypeError, ValueError):
        raise StateError(f"{path}: /{PARAMETERS} has a non-numeric size or length attribute") from None
    if n < 1 or p < 2:
        raise StateError(f"{path}: n_strands = {n}, points_per_strand = {p}: need N ≥ 1, P ≥ 2")
    if dset.shape[1] != n * p:
        raise StateError(
            f"{path}: frames have {dset.shape[1]} points but n_strands × points_per_strand = {n} × {p} = {n * p}"
        )
    precision = as_text(params["precision"])
    if precision not in DTYPE_OF_PRECISION:
        raise StateError(f"{path}: precision attribute is '{precision}', expected fp32 or fp64")
    if DTYPE_OF_PRECISION[precision] != dset.dtype:
        raise StateError(f"{path}: precision attribute says {precision} but positions are {dset.dtype}")
    n_frames = dset.shape[0]
    if n_frames < 1:
        raise StateError(f"{path}: has no frames")
    stages = _string_list(group, "stage", n_frames, None, path)
    if None in stages:
        raise StateError(f"{path}: no /{PARAMETERS}/stage (the stage of each frame)")
    skipped = [bool(int(v)) for v in group["skipped"][()]] if "skipped" in group else [False] * n_frames
    if len(skipped) != n_frames:
        raise StateError(f"{path}: /{PARAMETERS}/skipped has {len(skipped)} entries for {n_frames} frames")
    fused = _string_list(group, "fused", n_frames, "", path)
    moved = [int(v) for v in group["moved_points"][()]] if "moved_points" in group else [-1] * n_frames
    if len(moved) != n_frames:
        raise StateError(f"{path}: /{PARAMETERS}/moved_points has {len(moved)} entries for {n_frames} frames")
    return State(
        path=path,
        n_strands=n,
        points=p,
        n_frames=n_frames,
        precision=precision,
        params=params,
        stages=stages,
        skipped=skipped,
        fused=fused,
        moved=moved,
        _file=f,
        _dset=dset,
    )


@dataclass
class LoadedState:
    """A whole state read into memory: what the tests assert on."""

    path: str
    params: dict
    precision: str
    fast_math: bool
    flags: str
    stages: list
    skipped: np.ndarray  # 0/1 per frame
    fused: list
    moved: np.ndarray  # points each collide changed, -1 where not recorded
    frames: np.ndarray  # [F][N][P][3], the file's dtype

    @property
    def dtype(self) -> np.dtype:
        return self.frames.dtype

    @property
    def segment_length(self) -> float:
        """ℓ = L/(P−1), in double."""
        return float(self.params["hair_length"]) / (self.frames.shape[2] - 1)


def load_state(path: str | Path) -> LoadedState:
    """Open, check and read a whole (small) state file into a LoadedState."""
    with open_state(path) as s:
        return LoadedState(
            path=s.path,
            params=s.params,
            precision=s.precision,
            fast_math=s.fast_math,
            flags=s.flags,
            stages=list(s.stages),
            skipped=np.array([int(v) for v in s.skipped]),
            fused=list(s.fused),
            moved=np.array(s.moved, dtype=np.int64),
            frames=s.frames(),
        )


def h5md_layout(path: str | Path) -> dict[str, Any]:
    """The H5MD metadata of a state file (docs/interfaces.md), for checking the writer:
    h5md version, author and creator attributes, box dimension, the position dataset's
    shape, dtype and chunks, its step list, and the /parameters attributes and datasets."""
    from harness.core import inputs

    with open_state(path):  # the layout of the positions and parameters first
        pass
    with inputs.open_h5(path, "state") as f:
        value = f[POSITION]
        group = f[PARAMETERS]
        return {
            "version": [int(v) for v in f["h5md"].attrs["version"]],
            "author": {k: as_python(v) for k, v in f["h5md/author"].attrs.items()},
            "creator": {k: as_python(v) for k, v in f["h5md/creator"].attrs.items()},
            "dimension": int(f["particles/hair/box"].attrs["dimension"]),
            "shape": tuple(value.shape),
            "dtype": value.dtype,
            "chunks": value.chunks,
            "step": [int(v) for v in f["particles/hair/position/step"][()]],
            "parameters": {k: as_python(v) for k, v in group.attrs.items()},
            "parameter_datasets": {k: len(group[k]) for k in group},
        }
