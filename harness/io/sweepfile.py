"""Sweep files (configs/sweeps/<sweep>.toml) → the list of cases to run.

    name = "default"          # results/<name>/ (optional; defaults to the file's stem)
    description = "…"
    scene = "paper"           # a scene name in configs/scenes/ or a path
    frames = 3                # dynamic scenes: simulated frames per case (else the scene's)
    repeat = 9                # the first round's timed repetitions per stage (≥ 9: median and IQR)
    warmup = 1                # untimed runs per stage before them
    timeout_s = 600           # per case
    [timing]                  # the stopping rule (harness/core/timing.py; each key optional,
    min_samples = 10          # nvbench's defaults as shown): samples ≥ min_samples (and ≥ repeat)
    min_seconds = 0.5         # and their total ≥ min_seconds, then stop once the relative
    max_rsd = 0.005           # standard deviation ≤ max_rsd, or after timeout_s per case, or at
    timeout_s = 3.0           # max_samples per stage. Without [timing]: `repeat` samples, once
    max_samples = 2000
    [axes]                    # shared by every backend
    strands = [1000, 10000]
    points = [32]
    precision = ["fp32", "fp64"]
    solver = ["xpbd", "ftl"]  # dynamic scenes only (default: the scene's solver)
    [cpu]                     # leave the table out to run no cpu case
    variant = ["ref", "simd"]
    threads = [1, "all"]      # "all" = every core (the binary's default)
    [cuda]
    build = ["default"]       # default | strict | fastmath (binaries hairsim-cuda[-…])
    variant = ["paper", "soa", "fused"]
    block_size = [32, 64, 128, 256, 512, 1024]

A backend table may also set strands, points or precision, replacing the shared axis for
that backend (e.g. fewer strands for the single-thread CPU), and `scene = "NAME"`: that group
runs another scene of the same model (e.g. the default scene on a body with the hair–hair grid,
configs/scenes/body.toml), its rows named by it in the `scene` column. Write [[cpu]] / [[cuda]]
(arrays of tables) for several groups of one backend, e.g. every block size for the
default build but one for the fast-math build. The cases are the product of the axes of
each group; a case that two groups both produce runs once.
"""

import itertools
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

from harness import HarnessError
from harness.core.limits import limits
from harness.core.paths import CUDA_BUILDS, SWEEPS, config_file, read_toml
from harness.core.scenes import PRECISIONS, is_scene_file, load_scene, with_frames
from harness.core.scenes_dynamic import SOLVERS
from harness.core.timing import RULE, StopRule, fixed
from harness.core.variants import declared
from harness.core.variants import names as declared_variants

MIN_REPEAT = 9
SHARED_AXES = ("strands", "points", "precision", "solver")  # solver: dynamic scenes only
BACKEND_AXES = {"cpu": ("variant", "threads"), "cuda": ("build", "variant", "block_size")}
DEFAULTS = {
    "cpu": {"variant": ["ref"], "threads": ["all"]},
    "cuda": {"build": ["default"], "variant": ["fused"], "block_size": [256]},
}
TOP_KEYS = ("name", "description", "scene", "frames", "repeat", "warmup", "timeout_s", "timing", "axes", "cpu", "cuda")


class SweepError(HarnessError):
    pass


@dataclass(frozen=True)
class Case:
    scene: str
    backend: str
    build: str  # cuda build, "" for cpu
    variant: str
    precision: str
    block_size: int  # 0 for cpu
    threads: str  # "1", "2", … or "all"; "" for cuda
    strands: int
    points: int
    repeat: int
    warmup: int
    solver: str = ""  # dynamic scenes: xpbd | ftl ("" = the scene's own)

    @property
    def case_id(self):
        where = f"t{self.threads}" if self.backend == "cpu" else f"{self.build}:b{self.block_size}"
        return (
            f"{self.scene}:{self.backend}:{self.variant}:{where}:{self.precision}:"
            f"N{self.strands}:P{self.points}:r{self.repeat}w{self.warmup}" + (f":{self.solver}" if self.solver else "")
        )


@dataclass
class Sweep:
    name: str
    path: Path
    scene: object
    repeat: int
    warmup: int
    timeout_s: int
    axes: list  # (backend, {axis: values}) per group; the cases are each group's product
    description: str = ""
    rule: StopRule = RULE  # the stopping rule of its timed repeats ([timing]; else `repeat` once)
    others: dict = field(default_factory=dict)  # name → scene of the groups that set `scene`

    def scene_of(self, case):
        """The scene a case runs: its group's (`scene = …`), else the sweep's."""
        return self.others.get(case.scene, self.scene)

    def at_most(self, strands):
        """This sweep with every strands axis cut at `strands` (a groom file's count), kept there
        when nothing was below it."""
        axes = []
        for backend, a in self.axes:
            keep = [n for n in a["strands"] if n <= strands] or [strands]
            axes.append((backend, {**a, "strands": keep}))
        return replace(self, axes=axes)

    def cases(self):
        out, seen = [], set()
        for backend, axes in self.axes:
            names = list(axes)
            for values in itertools.product(*(axes[n] for n in names)):
                v = dict(zip(names, values))
                out.append(
                    Case(
                        scene=v.get("scene", self.scene.name),
                        backend=backend,
                        build=v.get("build", ""),
                        variant=v["variant"],
                        precision=v["precision"],
                        block_size=int(v.get("block_size", 0)),
                        threads=str(v.get("threads", "")),
                        strands=int(v["strands"]),
                        points=int(v["points"]),
                        repeat=self.repeat,
                        warmup=self.warmup,
                        solver=str(v.get("solver", "")),
                    )
                )
                if out[-1].case_id in seen:
                    out.pop()  # the same case from two groups runs once
                else:
                    seen.add(out[-1].case_id)
        # cheap cases first, so a short run already covers every configuration
        out.sort(key=lambda c: (c.strands * c.points, c.backend, c.case_id))
        return out


def _list(where, key, value):
    if not isinstance(value, list):
        value = [value]
    if not value:
        raise SweepError(f"{where}: {key} is an empty list")
    return value


def _check_axis(where, label, values, backend):
    """Check the values of one axis; `label` names it in messages (e.g. cuda.block_size)."""
    key = label.rsplit(".", 1)[-1]
    for v in values:
        if key in ("strands", "points", "block_size"):
            low = {"strands": 1, "points": 2, "block_size": 1}[key]
            if isinstance(v, bool) or not isinstance(v, int) or v < low:
                raise SweepError(f"{where}: {label} values must be whole numbers ≥ {low}, got {v!r}")
            if key == "block_size" and (why := limits().block_size_error(v)):
                raise SweepError(f"{where}: {label} {why}")
        elif key == "precision" and v not in PRECISIONS:
            raise SweepError(f"{where}: {label} '{v}' is not fp32 or fp64")
        elif key == "threads" and not (v == "all" or (isinstance(v, int) and not isinstance(v, bool) and v >= 1)):
            raise SweepError(f'{where}: {label} values must be whole numbers ≥ 1 or "all", got {v!r}')
        elif key == "build" and v not in CUDA_BUILDS:
            raise SweepError(f"{where}: {label} '{v}' is not one of {', '.join(CUDA_BUILDS)}")
        elif key == "solver" and v not in SOLVERS:
            raise SweepError(f"{where}: {label} '{v}' is not one of {', '.join(SOLVERS)}")
        elif key == "variant":
            known = known_variants(backend)
            if known and v not in known:
                raise SweepError(f"{where}: {label} '{v}' is not one of {', '.join(known)}")
    return values


def known_variants(backend):
    """The variants the backend's binaries declare (every cuda build's); () when none is
    built here, so the cases are kept and later skipped as "not built"."""
    builds = CUDA_BUILDS if backend == "cuda" else ("default",)
    known = []
    for build in builds:
        known += [n for n in declared_variants(backend, build) if n not in known]
    return tuple(known)


def _results_name(where, name):
    """A sweep's name is a directory under results/: one plain path component."""
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]*", name) or ".." in name:
        raise SweepError(
            f"{where}: name must be letters, digits, '.', '_' or '-' (a directory under results/), got {name!r}"
        )
    return name


def find_sweep_file(ref):
    found = config_file(ref, SWEEPS)
    if found and is_scene_file(found):
        raise SweepError(f"{ref} is a scene file (it has `stages`), not a sweep: sweeps live in configs/sweeps/")
    if found:
        return found
    raise SweepError(f"no sweep file '{ref}'")


def _rule(where, table, repeat):
    """The [timing] table as a StopRule (its keys those of StopRule, each optional); the first
    round takes at least `repeat` samples. No table (None): `repeat` samples in one round."""
    if table is None:
        return fixed(repeat)
    if not isinstance(table, dict):
        raise SweepError(f"{where}: 'timing' must be a table [timing]")
    known = tuple(StopRule.__dataclass_fields__)
    given = {}
    for key, value in table.items():
        if key not in known:
            raise SweepError(f"{where}: unknown key 'timing.{key}' (known: {', '.join(known)})")
        whole = key in ("min_samples", "max_samples")
        ok = not isinstance(value, bool) and isinstance(value, int if whole else (int, float))
        if not ok or not (value >= 1 if whole else 0 <= value < float("inf")):
            raise SweepError(f"{where}: timing.{key} must be a {'whole number ≥ 1' if whole else 'number ≥ 0'}")
        given[key] = value
    rule = replace(RULE, **given)
    return replace(rule, min_samples=max(rule.min_samples, repeat), max_samples=max(rule.max_samples, repeat))


def load_sweep(ref, scene=None):
    """The sweep file `ref` (a name in configs/sweeps/ or a path); `scene` (a scene name or
    path) in place of the file's own: the same axes on another scene (bench --scene)."""
    path = find_sweep_file(ref)
    where = f"sweep {path}"
    data = read_toml(path, where, SweepError)
    for key in data:
        if key not in TOP_KEYS:
            raise SweepError(f"{where}: unknown key '{key}' (known: {', '.join(TOP_KEYS)})")
    if "scene" not in data and scene is None:
        raise SweepError(f"{where}: missing key 'scene'")
    scene = load_scene(scene if scene is not None else data["scene"])
    repeat = data.get("repeat", MIN_REPEAT)
    if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < MIN_REPEAT:
        raise SweepError(f"{where}: repeat must be a whole number ≥ {MIN_REPEAT} (median and IQR), got {repeat!r}")
    warmup = data.get("warmup", 1)
    if isinstance(warmup, bool) or not isinstance(warmup, int) or warmup < 0:
        raise SweepError(f"{where}: warmup must be a whole number ≥ 0, got {warmup!r}")
    if "frames" in data:  # a dynamic scene's frames per case (each timed on its own)
        if scene.model != "dynamic":
            raise SweepError(f"{where}: frames needs a dynamic scene (scene {scene.name} is the paper model)")
        f = data["frames"]
        if isinstance(f, bool) or not isinstance(f, int) or f < 1:
            raise SweepError(f"{where}: frames must be a whole number ≥ 1, got {f!r}")
        scene = with_frames(scene, f)
    timeout = data.get("timeout_s", 600)
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not timeout > 0:
        raise SweepError(f"{where}: timeout_s must be a number > 0")
    shared = data.get("axes", {})
    for key in shared:
        if key not in SHARED_AXES:
            raise SweepError(f"{where}: unknown key 'axes.{key}' (known: {', '.join(SHARED_AXES)})")
    shared_axes = {"strands": [scene.strands], "points": [scene.points], "precision": [scene.precision]}
    if scene.model == "dynamic":
        shared_axes["solver"] = [scene.dynamic.get("--solver", "xpbd")]
    for key, value in shared.items():
        shared_axes[key] = _check_axis(where, f"axes.{key}", _list(where, f"axes.{key}", value), None)
    groups, others = [], {}
    for backend in ("cpu", "cuda"):
        if backend not in data:
            continue
        tables = data[backend] if isinstance(data[backend], list) else [data[backend]]
        for n, table in enumerate(tables):
            label = backend if len(tables) == 1 else f"{backend}[{n}]"
            if not isinstance(table, dict):
                raise SweepError(f"{where}: '{backend}' must be a table [{backend}] or tables [[{backend}]]")
            known = BACKEND_AXES[backend] + SHARED_AXES + ("scene",)
            for key in table:
                if key not in known:
                    raise SweepError(f"{where}: unknown key '{label}.{key}' (known: {', '.join(known)})")
            table = dict(table)
            b = dict(DEFAULTS[backend])
            b.update(shared_axes)
            if "scene" in table:
                other = _group_scene(where, label, table.pop("scene"), scene, data.get("frames"))
                others[other.name] = other
                b["scene"] = [other.name]
            for key, value in table.items():
                b[key] = _check_axis(where, f"{label}.{key}", _list(where, f"{label}.{key}", value), backend)
            groups.append((backend, b))
    axes = groups
    if not axes:
        raise SweepError(f"{where}: no [cpu] or [cuda] table: nothing to run")
    for backend, b in axes:
        for p in b["points"]:
            scene.with_overrides(points=p)  # ℓ ≥ h for every point count
        if "solver" in b and scene.model != "dynamic":
            raise SweepError(f"{where}: a solver axis needs a dynamic scene (scene {scene.name} is the paper model)")
        if scene.model == "dynamic":  # every variant listed must run simulate, at every point count
            for build in b.get("build", ["default"]):
                try:
                    decl = declared(backend, build)
                except HarnessError:
                    continue  # not built here: the case is skipped later, saying so
                for v in b["variant"]:
                    for p in b["points"]:
                        if v in decl.variants and not decl.runs(v, points=p):
                            raise SweepError(
                                f"{where}: the {backend} variant {v} does not simulate {p} points a strand "
                                "(see --list-variants)"
                            )
    return Sweep(
        name=_results_name(where, data.get("name", path.stem)),
        path=path,
        scene=scene,
        repeat=repeat,
        warmup=warmup,
        timeout_s=int(timeout),
        axes=axes,
        description=data.get("description", ""),
        rule=_rule(where, data.get("timing"), repeat),
        others=others,
    )


def _group_scene(where, label, ref, scene, frames):
    """A group's own scene (`scene = "NAME"`): of the sweep scene's model, with the sweep's frames."""
    if not isinstance(ref, str) or not ref:
        raise SweepError(f"{where}: {label}.scene must be a scene name or path, got {ref!r}")
    other = load_scene(ref)
    if other.model != scene.model:
        raise SweepError(f"{where}: {label}.scene {other.name} is the {other.model} model, not {scene.model}")
    return with_frames(other, frames) if frames is not None else other
