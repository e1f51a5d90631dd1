"""The dynamic model's part of a scene file (docs/model.md §3), for harness/core/scenes.py.

A scene with `model = "dynamic"` may hold, besides the paper keys:

    stages = ["init", "collide", "simulate"]   # optional here; must end with simulate
    [dynamics]
    frames = 300            # F ≥ 1             --frames
    frame_dt = 0.016666…    # Δt > 0 (s)        --frame-dt
    substeps = 8            # S ≥ 1             --substeps
    iterations = 2          # I ≥ 1             --iterations
    solver = "xpbd"         # xpbd | ftl | rigid  --solver
    gravity = 981.0         # g0 ≥ 0            --gravity
    drag = 0.5              # c_d ≥ 0           --drag
    damping = 0.5           # β ≥ 0             --damping
    ftl_damping = 0.9       # s in [0, 1]       --ftl-damping
    output_every = 1        # K ≥ 1             --output-every
    collide_once = true     # xpbd: collide in a substep's last iteration alone  --collide-once
    [constraints]
    stretch_compliance = 0.0   # α_s ≥ 0        --stretch-compliance
    bend_compliance = 1e-6     # α_b ≥ 0        --bend-compliance (declares bend)
    shape_compliance = 1e-4    # α_g ≥ 0        --shape-compliance (declares shape)
    shape_range = 0.5          # ρ_g in (0, 1]  --shape-range (needs shape_compliance)
    collision_margin = 0.0     # c_m ≥ 0        --collision-margin
    collider = true            # false → --no-collider
    [wind]
    speed = 150.0              # U ≥ 0 (cm/s)   --wind-speed
    angle = 3.14159…           # ψ (shared with the paper wind)
    gust_amplitude = 0.5       # A_g ≥ 0        --gust-amplitude
    gust_frequency = 1.0       # f_g ≥ 0 (Hz)   --gust-frequency
    gust_wavelength = 60.0     # λ_g > 0 (cm)   --gust-wavelength
    [head]
    motion = "nod"             # still | nod | shake | tilt | track   --head-motion
    motion_amplitude = 0.25    # A ≥ 0 (rad)    --motion-amplitude
    motion_frequency = 1.0     # f ≥ 0 (Hz)     --motion-frequency
    motion_track = "turn.csv"  # with motion = "track": a CSV track, relative to the scene file
                               #                --motion-track (docs/interfaces.md, "Motion tracks")
    [grid]                     # the hair–hair grid (§3.16); a table declares it
    nodes = 32                 # n_g in 2 … 512 --grid
    rebuild = "frame"          # frame | substep | held  --grid-rebuild
    box = [x0, y0, z0, x1, y1, z1]  # cm, head frame  --grid-box (default: the rest shape's bounds)
    padding = 2.0              # b ≥ 0 (cm)     --grid-padding
    friction = [0.05, 0.01]    # f_r[, f_t] in [0, 1]  --grid-friction
    volume = 2000.0            # K_v ≥ 0 (cm²/s²)  --grid-volume
    [body]                     # colliders and friction (§3.17)
    colliders = "FILE"         # relative to the scene file's folder  --colliders
    friction = [0.3, 0.2]      # the head sphere's μ_s[, μ_k]  --friction
    depenetration_speed = 200  # V > 0 (cm/s)   --depenetration-speed
    collider_sweeps = 4        # N in 1 … 8     --collider-sweeps (the collision sweep again while it moves a point)
    contact_planes = 5.0       # M > 0 (cm)     --contact-planes (the colliders as planes found once a frame)
    motion = "rise"            # still | sway | rise  --body-motion
    amplitude = 20.0           # A_b ≥ 0 (cm)   --body-amplitude
    frequency = 2.0            # f_b ≥ 0 (Hz)   --body-frequency

A key left out is not passed, so the binary's default (docs/model.md §3) applies. Unknown
keys, wrong types, NaN/∞ and values out of range are refused naming the key; the dynamic
keys in a scene whose model is not "dynamic" are refused too.
"""

import math
import os

from harness.core.limits import limits

DEFAULT_STAGES = ("init", "collide", "simulate")
SOLVERS = ("xpbd", "ftl", "rigid")  # rigid: no dynamics (docs/model.md §3.13)
MOTIONS = ("still", "nod", "shake", "tilt", "track")  # track: --motion-track FILE

# table → key → (flag, kind)
TABLES = {
    "dynamics": {
        "frames": ("--frames", "count"),
        "frame_dt": ("--frame-dt", "pos"),
        "substeps": ("--substeps", "count"),
        "iterations": ("--iterations", "count"),
        "solver": ("--solver", SOLVERS),
        "gravity": ("--gravity", "nonneg"),
        "drag": ("--drag", "nonneg"),
        "damping": ("--damping", "nonneg"),
        "ftl_damping": ("--ftl-damping", "unit"),
        "output_every": ("--output-every", "count"),
        "collide_once": ("--collide-once", "switch"),
    },
    "constraints": {
        "stretch_compliance": ("--stretch-compliance", "nonneg"),
        "bend_compliance": ("--bend-compliance", "nonneg"),
        "shape_compliance": ("--shape-compliance", "nonneg"),
        "shape_range": ("--shape-range", "range"),
        "collision_margin": ("--collision-margin", "nonneg"),
        "collider": ("--no-collider", "bool"),
    },
    "grid": {
        "nodes": ("--grid", "count"),
        "rebuild": ("--grid-rebuild", ("frame", "substep", "held")),
        "box": ("--grid-box", "box"),
        "padding": ("--grid-padding", "nonneg"),
        "friction": ("--grid-friction", "pair_unit"),
        "volume": ("--grid-volume", "nonneg"),
    },
    "body": {
        "colliders": ("--colliders", "path"),
        "friction": ("--friction", "pair"),
        "depenetration_speed": ("--depenetration-speed", "pos"),
        "collider_sweeps": ("--collider-sweeps", "count"),
        "contact_planes": ("--contact-planes", "pos"),
        "motion": ("--body-motion", ("still", "sway", "rise")),
        "amplitude": ("--body-amplitude", "nonneg"),
        "frequency": ("--body-frequency", "nonneg"),
    },
}
# the flags a scene's [grid] and [body] tables set: one place for the studies that split a scene into them
GRID_FLAGS = frozenset(flag for flag, _ in TABLES["grid"].values())
BODY_FLAGS = frozenset(flag for flag, _ in TABLES["body"].values())
# dynamic keys inside the paper model's [wind] and [head] tables
SHARED = {
    "wind": {
        "speed": ("--wind-speed", "nonneg"),
        "gust_amplitude": ("--gust-amplitude", "nonneg"),
        "gust_frequency": ("--gust-frequency", "nonneg"),
        "gust_wavelength": ("--gust-wavelength", "pos"),
    },
    "head": {
        "motion": ("--head-motion", MOTIONS),
        "motion_amplitude": ("--motion-amplitude", "nonneg"),
        "motion_frequency": ("--motion-frequency", "nonneg"),
        "motion_track": ("--motion-track", "path"),
    },
}


def _value(where, key, kind, value, error):
    if kind in ("box", "pair", "pair_unit"):
        items = value if isinstance(value, list) else [value]
        n = (6, 6) if kind == "box" else (1, 2)
        if not n[0] <= len(items) <= n[1]:
            raise error(
                f"{where}: {key} must be {'6 numbers' if kind == 'box' else 'a number or 2 numbers'}, got {value!r}"
            )
        part = "nonneg" if kind == "pair" else "unit" if kind == "pair_unit" else None
        for x in items:
            if part:
                _value(where, key, part, x, error)
            else:  # a box: any finite number
                _value(where, key, "real", x, error)
        if kind == "box" and not all(items[i] < items[i + 3] for i in range(3)):
            raise error(f"{where}: {key} needs x0 < x1, y0 < y1 and z0 < z1, got {value!r}")
        if kind == "pair" and len(items) == 2 and items[1] > items[0]:
            raise error(f"{where}: {key} needs μ_k ≤ μ_s, got {value!r}")
        return list(items)
    if isinstance(kind, tuple):
        if not isinstance(value, str) or value not in kind:
            raise error(f"{where}: {key} must be one of {', '.join(kind)}, got {value!r}")
        return value
    if kind == "path":
        if not isinstance(value, str) or not value:
            raise error(f"{where}: {key} must be a file name, got {value!r}")
        if value.lower().endswith((".usd", ".usda", ".usdc", ".usdz")):
            raise error(
                f"{where}: {key} is a USD file: convert it first (python3 -m harness motion convert {value} "
                "TRACK.csv) and name the CSV"
            )
        return value
    if kind in ("bool", "switch"):
        if not isinstance(value, bool):
            raise error(f"{where}: {key} must be true or false, got {value!r}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise error(f"{where}: {key} must be a number, got {value!r}")
    if isinstance(value, float) and math.isnan(value):
        raise error(f"{where}: {key} is NaN")
    if isinstance(value, float) and math.isinf(value):
        raise error(f"{where}: {key} is infinite")
    if kind == "count":
        if not isinstance(value, int) or value < 1:
            raise error(f"{where}: {key} must be a whole number ≥ 1, got {value!r}")
        if key.endswith(("substeps", "iterations")) and (why := limits().count_error(key.rpartition(".")[2], value)):
            raise error(f"{where}: {key} {why}")
        if key == "grid.nodes" and not limits().grid_n[0] <= value <= limits().grid_n[1]:
            raise error(f"{where}: {key} must lie in {limits().grid_n[0]} … {limits().grid_n[1]}, got {value}")
        if key == "body.collider_sweeps" and not limits().collider_sweeps[0] <= value <= limits().collider_sweeps[1]:
            lo, hi = limits().collider_sweeps
            raise error(f"{where}: {key} must lie in {lo} … {hi}, got {value}")
        return value
    x = float(value)
    if kind == "count" or kind == "real":
        return value
    ok = {"pos": x > 0, "nonneg": x >= 0, "unit": 0 <= x <= 1, "range": 0 < x <= 1}[kind]
    if not ok:
        want = {"pos": "> 0", "nonneg": "≥ 0", "unit": "in [0, 1]", "range": "in (0, 1]"}[kind]
        raise error(f"{where}: {key} must be {want}, got {value!r}")
    return value


def split(data, where, error):
    """(paper part of the scene dict, dynamic flags dict or None when the model is paper)."""
    dynamic = data.get("model") == "dynamic"
    paper = {}
    flags = {}
    for key, value in data.items():
        if key in TABLES or key in SHARED:
            if not isinstance(value, dict):
                raise error(f"{where}: '{key}' must be a table [{key}]")
        if key in TABLES:
            if not dynamic:
                raise error(f'{where}: table [{key}] belongs to model = "dynamic"')
            for sub, v in value.items():
                if sub not in TABLES[key]:
                    raise error(f"{where}: unknown key '{key}.{sub}' (known in [{key}]: {', '.join(TABLES[key])})")
                flag, kind = TABLES[key][sub]
                flags[flag] = _value(where, f"{key}.{sub}", kind, v, error)
            continue
        if key in SHARED:
            rest = {}
            for sub, v in value.items():
                if sub in SHARED[key]:
                    if not dynamic:
                        raise error(f"{where}: '{key}.{sub}' belongs to model = \"dynamic\"")
                    flag, kind = SHARED[key][sub]
                    flags[flag] = _value(where, f"{key}.{sub}", kind, v, error)
                else:
                    rest[sub] = v
            paper[key] = rest
            continue
        paper[key] = value
    if not dynamic:
        return paper, None
    if any(f.startswith("--grid-") for f in flags) and "--grid" not in flags:
        raise error(f"{where}: the [grid] table needs grid.nodes (the grid is off without it)")
    track = flags.get("--head-motion") == "track"
    if track != ("--motion-track" in flags):
        raise error(f'{where}: head.motion = "track" and head.motion_track go together')
    if track and ("--motion-amplitude" in flags or "--motion-frequency" in flags):
        raise error(f'{where}: head.motion_amplitude and head.motion_frequency shape nod, shake and tilt, not "track"')
    if "--shape-range" in flags and "--shape-compliance" not in flags:
        raise error(f"{where}: constraints.shape_range needs constraints.shape_compliance (shape is off without it)")
    if "--frame-dt" in flags or "--substeps" in flags:
        h = float(flags.get("--frame-dt", 1 / 60)) / int(flags.get("--substeps", 1))
        if why := limits().substep_error(h):
            raise error(f"{where}: dynamics.frame_dt / dynamics.substeps: {why}")
    return paper, flags


def check(scene, where, error):
    """The stage list rules of the dynamic model and its track file (called for every scene)."""
    track = track_file(scene)
    if track is not None and not os.path.isfile(track):
        raise error(f"{where}: head.motion_track {track}: no such file")
    if scene.model == "dynamic":
        if scene.stages[-1] != "simulate" or "simulate" in scene.stages[:-1]:
            raise error(
                f"{where}: stages of a dynamic scene must end with simulate, once (got {', '.join(scene.stages)})"
            )
    elif "simulate" in scene.stages:
        raise error(f"{where}: stage 'simulate' needs model = \"dynamic\"")


def track_file(scene):
    """The scene's motion track file (relative to the scene file's folder), or None."""
    name = scene.dynamic.get("--motion-track")
    if name is None:
        return None
    src = scene.source.removeprefix("scene ")
    return os.path.join(os.path.dirname(src), name) if src else name


def flags(scene):
    """The binary flags of a scene's dynamic part ([] for a paper scene); a colliders file is
    taken relative to the scene file's folder."""
    out = []
    for flag, value in scene.dynamic.items():
        if flag == "--no-collider":
            if value is False:
                out.append(flag)
            continue
        if flag == "--collide-once":  # a switch: true passes it alone
            if value is True:
                out.append(flag)
            continue
        if flag == "--motion-track":
            value = track_file(scene)
        if flag == "--colliders":
            src = scene.source.removeprefix("scene ")
            value = str(os.path.join(os.path.dirname(src), value)) if src and not os.path.isabs(value) else value
        if isinstance(value, list):
            value = ",".join(repr(float(v)) for v in value)
        out += [flag, value if isinstance(value, str) else repr(value)]
    return out


def frames(scene):
    return int(scene.dynamic.get("--frames", 1))


# ---- the features of a dynamic scene (what the feature-cost study turns off one at a time) ----

# feature → the flags that declare it (each followed by a value)
DECLARING = {
    "bend": ("--bend-compliance",),
    "shape": ("--shape-compliance", "--shape-range"),
    "wind": ("--wind-speed", "--gust-amplitude", "--gust-frequency", "--gust-wavelength"),
    "gust": ("--gust-amplitude",),
    "motion": ("--head-motion", "--motion-amplitude", "--motion-frequency", "--motion-track"),
    "drag": ("--drag", "--damping"),
}
FEATURES = ("bend", "shape", "wind", "gust", "motion", "collide", "drag")
# a feature that needs another to exist at all (gusts ride on the wind, the wind on drag)
NEEDS = {"gust": ("wind", "drag"), "wind": ("drag",)}
