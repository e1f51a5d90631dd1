"""What the stability study measures, as the study and its renderer both read it: the
slices (two axes over a base scene each) and the verdicts of a cell. Runs nothing."""

from dataclasses import dataclass
from pathlib import Path

from harness.core.paths import MOTIONS
from harness.io.motion_tracks import FAST_TURN_FILE

# mildest first; a blown-up cell (docs/model.md §3.8) is split by cause: escaped (a point
# farther than 2L from its root, every number finite) or diverged (a NaN or Inf)
VERDICTS = ("ok", "over-stretched", "penetrating", "escaped", "diverged")
BLOWN_UP = ("escaped", "diverged")
OTHER = ("refused", "timed out", "failed")
LEGACY = ("blown up",)  # a map measured before the split by cause still reads
OFF = "off"  # an axis value that leaves its feature undeclared (and the flags named after it: --grid-*)


@dataclass(frozen=True)
class Axis:
    key: str  # a flag of the simulate stage (--substeps, …), "points" or "strands"
    label: str  # how the report names it
    values: tuple  # OFF = leave the flag out (the feature undeclared)
    quick: tuple  # the subset `--quick` runs
    unit: str = ""


@dataclass(frozen=True)
class Slice:
    name: str
    title: str
    scene: str  # base scene in configs/scenes/
    fixed: tuple  # (flag, value) changes to the base scene
    rows: Axis
    cols: Axis
    settles: bool = False  # starts inside a collider: penetration judged by its last frame and its fall


SUBSTEPS = Axis("--substeps", "S", (1, 2, 4, 8, 16, 32, 64), (1, 4, 16, 64))
ITERATIONS = Axis("--iterations", "I", (1, 2, 4, 8, 16, 32, 64, 128), (1, 8, 128))
# The base is the shipped still scene (gravity, the collider, damping 0.5, S = 8, I = 2),
# so that one slice changes one or two things a user would; wind acts only through drag,
# so the wind slice declares the default scene's drag and gusts.
SLICES = (
    Slice(
        "substeps-wind",
        "substeps against wind speed (drag 0.5/s, gusts 0.5)",
        "still-dynamic",
        (("--drag", 0.5), ("--gust-amplitude", 0.5), ("--gust-wavelength", 60.0)),
        SUBSTEPS,
        Axis("--wind-speed", "U", (0, 500, 1000, 2000, 4000, 8000), (0, 2000, 8000), "cm/s"),
    ),
    Slice(
        "substeps-stretch",
        "substeps against stretch compliance",
        "still-dynamic",
        (),
        SUBSTEPS,
        Axis("--stretch-compliance", "α_s", (0, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4), (0, 1e-6, 1e-4)),
    ),
    Slice(
        "substeps-bend",
        "substeps against bend compliance (off = bend undeclared)",
        "still-dynamic",
        (),
        SUBSTEPS,
        Axis("--bend-compliance", "α_b", (OFF, 0, 1e-8, 1e-6, 1e-4, 1e-2), (OFF, 0, 1e-4)),
    ),
    Slice(
        "substeps-points",
        "substeps against points per strand",
        "still-dynamic",
        (),
        SUBSTEPS,
        Axis("points", "P", (2, 4, 8, 16, 32, 64, 128), (2, 16, 128)),
    ),
    Slice(
        "substeps-iterations",
        "substeps against iterations (the default dynamic scene: wind, gusts, nodding head)",
        "dynamic",
        (),
        SUBSTEPS,
        ITERATIONS,
    ),
    Slice(
        "curly-substeps-iterations",
        "curly hair: substeps against iterations (curly.toml: the default scene's physics on helices)",
        "curly",
        (),
        SUBSTEPS,
        ITERATIONS,
    ),
    Slice(
        "motion",
        "nodding head: frequency against amplitude (S = 32)",
        "still-dynamic",
        (("--head-motion", "nod"), ("--substeps", 32)),
        Axis("--motion-frequency", "f", (0.5, 1, 2, 4, 8, 16), (1, 4, 16), "Hz"),
        Axis("--motion-amplitude", "A", (0.1, 0.25, 0.5, 1, 2, 3), (0.25, 1, 3), "rad"),
    ),
)
# Long-range attachments (docs/model.md §3.14) on and off, at one iteration where stretch is
# weakest: under fast nods and under gales (the still scene with the default scene's drag and gusts).
LRA = Axis("--lra", "LRA s_L", (OFF, 1), (OFF, 1))
SLICES += (
    Slice(
        "lra-nod",
        "long-range attachments against a fast nod (A = 0.5 rad, I = 1; off = LRA undeclared)",
        "still-dynamic",
        (("--head-motion", "nod"), ("--motion-amplitude", 0.5), ("--iterations", 1)),
        LRA,
        Axis("--motion-frequency", "f", (1, 2, 4, 8, 12, 16), (4, 16), "Hz"),
    ),
    Slice(
        "lra-wind",
        "long-range attachments against wind speed (drag 0.5/s, gusts 0.5, I = 1; off = LRA undeclared)",
        "still-dynamic",
        (("--drag", 0.5), ("--gust-amplitude", 0.5), ("--gust-wavelength", 60.0), ("--iterations", 1)),
        LRA,
        Axis("--wind-speed", "U", (0, 1000, 2000, 4000, 8000, 16000), (2000, 16000), "cm/s"),
    ),
)
# A recorded fast motion (docs/model.md §3.2, --head-motion track): the shipped head turn of
# configs/motions/fast-turn.csv (80° and back at a measured peak head speed, 780 °/s), on the
# still scene, substeps against iterations.
SLICES += (
    Slice(
        "fast-turn",
        "a recorded fast head turn (configs/motions/fast-turn.csv: 80° about y and back, peak 780 °/s): "
        "substeps against iterations",
        "still-dynamic",
        (("--head-motion", "track"), ("--motion-track", str(MOTIONS / FAST_TURN_FILE))),
        SUBSTEPS,
        ITERATIONS,
    ),
)
# Hair that touches hair (docs/model.md §3.16): the grid of configs/scenes/body.toml (32³, rebuilt
# once a frame, friction 0.05 at the root to 0.01 at the tip, volume K_v = 2000) on dense hair
# (strands against the volume stiffness, the default scene), under a fast nod and under a gale
# (the grid's size against the motion's frequency and the wind's speed; off = no grid), 64 strands
# where the axis does not set them: a grid over 16 strands holds almost no hair.
GRID = (("--grid", 32), ("--grid-rebuild", "frame"), ("--grid-friction", [0.05, 0.01]), ("--grid-volume", 2000.0))
GRID_SIZE = Axis("--grid", "grid n_g", (OFF, 16, 32, 64), (OFF, 32))
GALE = (("--drag", 0.5), ("--gust-amplitude", 0.5), ("--gust-wavelength", 60.0))
SLICES += (
    Slice(
        "grid-dense",
        "dense hair with the 32³ grid (friction, volume): strands against the volume stiffness (off = no volume)",
        "dynamic",
        GRID,
        Axis("strands", "N", (16, 64, 256, 1024), (16, 256)),
        Axis("--grid-volume", "K_v", (OFF, 500, 2000, 8000, 32000), (OFF, 2000, 32000), "cm²/s²"),
    ),
    Slice(
        "grid-nod",
        "the grid (friction, volume; off = no grid) against a fast nod (A = 0.5 rad, 64 strands)",
        "still-dynamic",
        (*GRID, ("strands", 64), ("--head-motion", "nod"), ("--motion-amplitude", 0.5)),
        GRID_SIZE,
        Axis("--motion-frequency", "f", (1, 2, 4, 8, 12, 16), (4, 16), "Hz"),
    ),
    Slice(
        "grid-gale",
        "the grid (friction, volume; off = no grid) against wind speed (drag 0.5/s, gusts 0.5, 64 strands)",
        "still-dynamic",
        (*GRID, *GALE, ("strands", 64)),
        GRID_SIZE,
        Axis("--wind-speed", "U", (0, 1000, 2000, 4000, 8000, 16000), (2000, 16000), "cm/s"),
    ),
)
# A body to collide with (docs/model.md §3.17): configs/scenes/body.toml without its grid. Fast
# nods against the head sphere's friction (the body's capsules keep the file's); and the same body
# still from the start, so that the drape starts inside the shoulders and chest: the bounded
# depenetration against substeps (off = unbounded), judged by its last frame and its fall.
SLICES += (
    Slice(
        "body-nod",
        "on a body (capsules, face mesh, friction): the head sphere's friction against a fast nod (A = 0.5 rad)",
        "body",
        (("--grid", OFF), ("--motion-amplitude", 0.5)),
        Axis("--friction", "μ_s head", (OFF, 0.1, 0.3, 1.0), (OFF, 1.0)),
        Axis("--motion-frequency", "f", (1, 2, 4, 8, 16), (4, 16), "Hz"),
    ),
    Slice(
        "body-inside",
        "a groom started inside the body (still from the start): depenetration speed (off: unbounded) × substeps",
        "body",
        (("--grid", OFF), ("--body-motion", OFF), ("--body-amplitude", OFF), ("--body-frequency", OFF)),
        Axis("--depenetration-speed", "V", (OFF, 50, 200, 1000), (OFF, 200), "cm/s"),
        SUBSTEPS,
        settles=True,
    ),
)
SLICE_NAMES = tuple(s.name for s in SLICES)


def scene_slice(scene):
    """Substeps against iterations over any dynamic scene (a user's groom: `stability --scene`),
    named after the scene."""
    stem = Path(scene).stem if str(scene).endswith(".toml") else str(scene)
    return Slice(f"{stem}-substeps-iterations", f"{stem}: substeps against iterations ({scene})", str(scene), (),
                 SUBSTEPS, ITERATIONS)  # fmt: skip


def axis(key):
    """An axis of the slices by its flag (the same flag has one label and unit in every slice)."""
    return next((a for s in SLICES for a in (s.rows, s.cols) if a.key == key), None)
