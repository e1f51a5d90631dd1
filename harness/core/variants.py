"""The variants each binary declares: `hairsim-* --list-variants` (one JSON object).

    {"backend": "cpu", "build": "default", "default_variant": "ref",
     "precisions": ["fp32", "fp64"], "variants": [{"name": "ref", "stages": [...], ...}],
     "solvers": ["xpbd", "ftl", "rigid"]}

A simulating variant may list its own "solvers" (a subset of the binary's); one that lists
none runs every solver the binary declares. "rigid" (NO_DYNAMICS) is the no-simulation
baseline: hair carried with the head, nothing solved (docs/model.md §3.13).

The one place the harness and the tests learn variant names; read once per binary. Keys
other than these are ignored, and missing optional ones get defaults, so a binary that
declares more (solvers, stages) still reads.
"""

import json
from dataclasses import dataclass, field
from functools import lru_cache

from harness import HarnessError
from harness.core.paths import binary_path

NO_DYNAMICS = "rigid"  # the solver that simulates nothing: the accuracy study's baseline


@dataclass(frozen=True)
class Declared:
    backend: str
    build: str
    default_variant: str
    precisions: tuple
    variants: tuple  # names, in the binary's order
    stages: dict  # variant name -> tuple of the stages it runs
    max_points: dict  # variant name -> the most points per strand it simulates (None: no limit)
    solvers: tuple = ()  # the dynamic model's solvers, in the binary's order (none declared: ())
    max_block: dict = field(default_factory=dict)  # variant -> most threads a block of its simulate (absent: 1024)
    variant_solvers: dict = field(default_factory=dict)  # variant -> its solvers (absent: all of `solvers`)
    per_segment: tuple = ()  # variants that simulate a groom's per-segment rest lengths (docs/model.md §3.15)
    variant_features: dict = field(default_factory=dict)  # variant -> its §3.14 features (absent: all of them)

    def runs_features(self, variant, features):
        """Whether a simulating `variant` runs every one of `features` (docs/model.md §3.14:
        "guides", "lra", "sagfree", "lod"); a binary that declares no features per variant runs them all."""
        have = self.variant_features.get(variant)
        return have is None or set(features) <= set(have)

    def solvers_of(self, variant):
        """The solvers `variant` runs, in the binary's order."""
        return tuple(self.variant_solvers.get(variant, self.solvers))

    @property
    def dynamic_solvers(self):
        """The solvers that simulate (every one but the no-simulation baseline)."""
        return tuple(s for s in self.solvers if s != NO_DYNAMICS)

    def runs(self, variant, stage="simulate", points=None, block=None):
        """Whether `variant` runs `stage` (and, for simulate, strands of `points` points with
        `block` threads a block)."""
        if stage not in self.stages.get(variant, ()):
            return False
        limit = self.max_points.get(variant)
        if points is not None and limit is not None and points > limit:
            return False
        most = self.max_block.get(variant)
        return block is None or stage != "simulate" or most is None or int(block) <= most

    def running(self, stage, points=None):
        """The variants that run `stage` (at `points` points a strand), in the binary's order."""
        return tuple(v for v in self.variants if self.runs(v, stage, points))


@dataclass(frozen=True)
class Runner:
    """One binary (backend and build) and one of its variants."""

    backend: str  # cpu | cuda
    build: str  # default | strict | fastmath
    variant: str | None  # None: the binary's default variant

    @property
    def binary(self):
        return binary_path(self.backend, self.build)

    @property
    def label(self):
        """ "cpu ref", "gpu normal fused": how the studies name it."""
        if self.backend == "cpu":
            return f"cpu {self.variant}"
        return f"gpu {'normal' if self.build == 'default' else self.build} {self.variant}"


# The simulate flags that declare a §3.14, §3.16 or §3.17 feature (docs/model.md), and the
# feature each names (a colliders file's own friction is read by the binary, which refuses it
# on a variant without "friction").
FEATURE_FLAGS = {
    "--guides": "guides",
    "--lra": "lra",
    "--sag-free": "sagfree",
    "--render-points": "lod",
    "--grid": "grid",
    "--colliders": "colliders",
    "--friction": "friction",
    "--depenetration-speed": "friction",
    "--collider-sweeps": "colliders",  # the colliders' step repeated (no effect without them)
    "--contact-planes": "planes",  # the colliders met as planes found once a frame
    "--collide-once": "collideonce",  # xpbd's collision step in a substep's last iteration alone
}


def features_of(flags):
    """The features that simulate flags declare (a flag list or a dict keyed by flag)."""
    return {FEATURE_FLAGS[str(a)] for a in flags if str(a) in FEATURE_FLAGS}


# Simulate variants fastest first (16 strands, S = 64, I = 128 on an H200: lanes about 1 s,
# warp 1.4–2.7 s, strand 13–34 s; docs/decisions/bench-runs.md): what a study that needs only
# some variant that runs its scene takes.
FASTEST_FIRST = ("lanes", "warpreg", "warp", "strand")


def fastest(declared, points, features=(), solver=None, per_segment=False):
    """The first of FASTEST_FIRST that `declared` (a Declared) declares and that simulates
    strands of `points` points with `features` and `solver` (and, with `per_segment`, a
    groom's per-segment rest lengths); None where none does."""
    for v in FASTEST_FIRST:
        if (
            v in declared.variants
            and declared.runs(v, "simulate", points=points)
            and declared.runs_features(v, features)
            and (solver is None or solver in declared.solvers_of(v))
            and (not per_segment or v in declared.per_segment)
        ):
            return v
    return None


def simulating(backend, build="default"):
    """The first variant of a binary that simulates strands of any length (no max_points):
    what a study that draws the point count runs."""
    d = declared(backend, build)
    for v in d.running("simulate"):
        if d.max_points.get(v) is None:
            return v
    raise HarnessError(f"{binary_path(backend, build)} declares no variant that simulates any point count")


def ask(path, flag):
    """The JSON object a binary prints for `flag` (--list-variants, --limits); HarnessError in one
    line when it cannot run, fails or prints no JSON."""
    from harness.core import runner

    try:
        p = runner.run_command([path, flag], timeout=60)
    except OSError as e:
        raise HarnessError(f"{path}: cannot run: {e.strerror}") from None
    except runner.TimedOut:
        raise HarnessError(f"{path} {flag} did not finish in 60 s") from None
    if p.returncode != 0:
        raise HarnessError(f"{path} {flag} exited {p.returncode}: {p.stderr.strip()}")
    try:
        return json.loads(p.stdout)
    except ValueError:
        raise HarnessError(f"{path} {flag} did not print the documented JSON object") from None


@lru_cache(maxsize=None)
def _read(path):
    d = ask(path, "--list-variants")
    try:
        variants = [v for v in d["variants"] if isinstance(v, dict) and "name" in v]
        names = tuple(str(v["name"]) for v in variants)
        return Declared(
            backend=str(d.get("backend", "")),
            build=str(d.get("build", "default")),
            default_variant=str(d.get("default_variant") or (names[0] if names else "")),
            precisions=tuple(d.get("precisions", ("fp32", "fp64"))),
            variants=names,
            stages={str(v["name"]): tuple(v.get("stages", ())) for v in variants},
            max_points={str(v["name"]): (int(v["max_points"]) if v.get("max_points") else None) for v in variants},
            solvers=tuple(str(x) for x in d.get("solvers", ())),
            max_block={str(v["name"]): int(v["max_block"]) for v in variants if v.get("max_block")},
            variant_solvers={str(v["name"]): tuple(str(x) for x in v["solvers"]) for v in variants if "solvers" in v},
            per_segment=tuple(str(v["name"]) for v in variants if v.get("per_segment") is True),
            variant_features={
                str(v["name"]): tuple(str(x) for x in v["features"]) for v in variants if "features" in v
            },
        )
    except (ValueError, KeyError, TypeError, AttributeError):
        raise HarnessError(f"{path} --list-variants did not print the documented JSON object") from None


def declared(backend, build="default"):
    """What the binary of `backend`/`build` declares; HarnessError if it is not built."""
    path = binary_path(backend, build)
    if not path.exists():
        raise HarnessError(f"{path} not found: run make")
    return _read(str(path))


def names(backend, build="default"):
    """The variant names of `backend`/`build`, or () when its binary is not built."""
    try:
        return declared(backend, build).variants
    except HarnessError:
        return ()


def clear_cache():
    """Forget what was read (a test that swaps the build directory)."""
    _read.cache_clear()
