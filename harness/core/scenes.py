"""Scene files (configs/scenes/*.toml, docs/model.md §2.6) → validated Scene → backend flags.

A scene file:

    description = "…"            # optional, free text
    model = "paper"              # optional; the only model so far
    stages = ["init", "collide", "wind", "collide"]
    precision = "fp32"           # fp32 | fp64
    seed = 1
    [head]
    radius = 10.0                # R > 0
    face_margin = 1.0            # m ≥ 0
    center = [0.0, 0.0, 0.0]     # with groom = "FILE": the head sphere's centre, not fitted (§3.15)
    [hair]
    strands = 1000               # N ≥ 1
    points = 32                  # P ≥ 2
    length = 30.0                # L > 0
    offset = 0.1                 # h > 0, and ℓ = L/(P−1) ≥ h
    [wind]
    strength = 0.5               # w in [0, 1]
    angle = 3.141592653589793    # ψ in radians from +z toward +y
    [fibre]                      # model = "dynamic": physical hair (docs/hair_physics.md)
    preset = "thick-straight"    # fine | thick-straight | coarse-curly (harness/core/hair_physics.py)
    radius_um = 42.95            # r > 0, µm        each replaces the preset's value
    youngs_modulus_gpa = 3.89    # E > 0, GPa
    density = 1.32               # ρ > 0, g/cm³
    reference_curvature = 0.099  # κ > 0, 1/cm (default: the curl's helix, else 1/(R + h))

Every key is optional except `stages`; missing ones take the backends' defaults (the
values above). A [fibre] sets the bend and stretch compliances (per unit mass, for the
scene's L and P; again after an override of points or length) and is refused beside
constraints.bend_compliance or constraints.stretch_compliance, the low-level interface.
Anything else is refused before any work, naming the key: unknown keys, counts that are not
whole numbers ≥ 1 (≥ 2 for points), NaN or infinite numbers, stages that do not exist or a
list not starting with init, ℓ < h, and a state whose frame (times the copies a backend
holds) would not fit in this machine's memory.
"""

import math
import os
from dataclasses import dataclass, field, replace

from harness import HarnessError
from harness.core import hair_physics, scenes_dynamic
from harness.core.paths import SCENES, config_file, display, read_toml

STAGES = ("init", "collide", "wind", "simulate")
PRECISIONS = ("fp32", "fp64")
MODELS = ("paper", "dynamic")

# table → key → (field name, kind); kinds: int_count, seed, pos, nonneg, unit, real
SCHEMA = {
    "": {
        "description": ("description", "text"),
        "model": ("model", "model"),
        "stages": ("stages", "stages"),
        "precision": ("precision", "precision"),
        "seed": ("seed", "seed"),
        "groom": ("groom", "text"),
        "head": None,
        "hair": None,
        "wind": None,
        "fibre": None,
    },
    "head": {
        "radius": ("head_radius", "pos"),
        "face_margin": ("face_margin", "nonneg"),
        "center": ("head_center", "vec3"),
    },
    "hair": {
        "strands": ("strands", "count1"),
        "points": ("points", "count2"),
        "length": ("hair_length", "pos"),
        "offset": ("hair_offset", "pos"),
        "curl_radius": ("curl_radius", "nonneg"),
        "curl_pitch": ("curl_pitch", "nonneg"),
    },
    "wind": {"strength": ("wind_strength", "unit"), "angle": ("wind_angle", "real")},
    "fibre": {
        "preset": ("fibre_preset", "text"),
        "radius_um": ("fibre_radius_um", "pos"),
        "youngs_modulus_gpa": ("fibre_youngs_gpa", "pos"),
        "density": ("fibre_density", "pos"),
        "reference_curvature": ("fibre_curvature", "pos"),
    },
}

# field name → kind, for overrides given on the command line
FIELD_KINDS = {
    spec[0]: spec[1]
    for table in SCHEMA.values()
    for spec in table.values()
    if spec and spec[1] not in ("stages", "text")
}


class SceneError(HarnessError):
    """A scene that is refused; the message names the file and the key."""


@dataclass(frozen=True)
class Scene:
    name: str
    stages: tuple
    description: str = ""
    model: str = "paper"
    precision: str = "fp32"
    seed: int = 1
    head_radius: float = 10.0
    face_margin: float = 1.0
    strands: int = 1000
    points: int = 32
    hair_length: float = 30.0
    hair_offset: float = 0.1
    wind_strength: float = 0.5
    wind_angle: float = math.pi
    # init places a groom instead of the drape (docs/model.md §3.15): "curly" or a HAIR file
    groom: str = ""
    curl_radius: float = 1.0
    curl_pitch: float = 2.0
    # a groom file's head sphere given instead of fitted (docs/model.md §3.15): its centre (x, y, z)
    # in the file's cm, () = fitted; head.radius is passed with it only when the scene gives it
    head_center: tuple = ()
    head_radius_given: bool = False
    # a groom file decides its strands unless the scene or an override gives a count (the first N)
    strands_given: bool = False
    # [fibre] (docs/hair_physics.md): a preset and the values that replace its own (0: the preset's)
    fibre_preset: str = ""
    fibre_radius_um: float = 0.0
    fibre_youngs_gpa: float = 0.0
    fibre_density: float = 0.0
    fibre_curvature: float = 0.0
    # model = "dynamic": the binary flags of [dynamics], [constraints], [wind] and [head]
    # (harness/core/scenes_dynamic.py), flag → value text, in the order they were declared
    dynamic: dict = field(default_factory=dict)
    source: str = field(default="", compare=False)

    @property
    def file(self):
        """The scene's TOML file relative to the repository when inside it ("" when made in code):
        what results record, never a path of the machine that ran them."""
        return display(self.source.removeprefix("scene ")) if self.source else ""

    @property
    def segment_length(self):
        return self.hair_length / (self.points - 1)

    @property
    def real_size(self):
        return 8 if self.precision == "fp64" else 4

    def state_bytes(self):
        return self.strands * self.points * 3 * self.real_size

    def with_overrides(self, **overrides):
        """A copy with the given fields replaced (None = keep), validated again."""
        changes = {k: v for k, v in overrides.items() if v is not None}
        for k, v in changes.items():
            if k in FIELD_KINDS:
                converted = _convert(f"scene {self.name}", k, FIELD_KINDS[k], v)
                if k == "head_center":  # a list becomes the tuple the scene holds
                    changes[k] = converted
        if "head_radius" in changes:
            changes["head_radius_given"] = True
        if "strands" in changes:
            changes["strands_given"] = True
        scene = replace(self, **changes)
        _check_values(scene, f"scene {self.name}")
        return with_fibre(scene, f"scene {self.name}")

    @property
    def groom_file(self):
        """The groom file's path (relative to the scene file's folder), or None."""
        if self.groom in ("", "curly"):
            return None
        src = self.source.removeprefix("scene ")
        return str(os.path.join(os.path.dirname(src), self.groom)) if src else self.groom

    def flags(self):
        """The backend flags that run this scene (docs/interfaces.md)."""
        tail = [
            "--wind-strength",
            repr(self.wind_strength),
            "--wind-angle",
            repr(self.wind_angle),
            "--stages",
            ",".join(self.stages),
            "--precision",
            self.precision,
            *scenes_dynamic.flags(self),
        ]
        if self.groom_file:  # the file decides the head and the strands (docs/model.md §3.15)
            head = []
            if self.head_center:  # unless the scene gives the head
                head = ["--head-center", ",".join(repr(c) for c in self.head_center)]
                head += ["--head-radius", repr(self.head_radius)] if self.head_radius_given else []
            count = ["--strands", str(self.strands)] if self.strands_given else []
            return [*count, "--points", str(self.points), "--groom", self.groom_file, *head, *tail]
        curl = ["--groom", "curly", "--curl-radius", repr(self.curl_radius), "--curl-pitch", repr(self.curl_pitch)]
        return [
            *(curl if self.groom == "curly" else []),
            "--strands",
            str(self.strands),
            "--points",
            str(self.points),
            "--seed",
            str(self.seed),
            "--head-radius",
            repr(self.head_radius),
            "--hair-offset",
            repr(self.hair_offset),
            "--hair-length",
            repr(self.hair_length),
            "--face-margin",
            repr(self.face_margin),
            *tail,
        ]


def _number(where, key, value):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(f"{where}: {key} must be a number, got {value!r}")
    if math.isnan(value):
        raise SceneError(f"{where}: {key} is NaN")
    if math.isinf(value):
        raise SceneError(f"{where}: {key} is infinite")
    return float(value)


def _convert(where, key, kind, value):
    if kind == "text":
        if not isinstance(value, str):
            raise SceneError(f"{where}: {key} must be a string")
        return value
    if kind == "model":
        if value not in MODELS:
            raise SceneError(f"{where}: model '{value}' is not known (known: {', '.join(MODELS)})")
        return value
    if kind == "precision":
        if value not in PRECISIONS:
            raise SceneError(f"{where}: precision '{value}' is not fp32 or fp64")
        return value
    if kind == "stages":
        return parse_stages(value, where, key)
    if kind == "vec3":
        if not isinstance(value, (list, tuple)) or len(value) != 3:
            raise SceneError(f"{where}: {key} must be a list of three numbers [x, y, z], got {value!r}")
        return tuple(_number(where, f"{key}[{i}]", v) for i, v in enumerate(value))
    if kind in ("count1", "count2", "seed"):
        if isinstance(value, float):
            _number(where, key, value)  # NaN/inf named as such
        low = {"count1": 1, "count2": 2, "seed": 0}[kind]
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise SceneError(f"{where}: {key} must be a whole number ≥ {low}, got {value!r}")
        if kind == "seed" and value >= 2**64:
            raise SceneError(f"{where}: {key} must fit in 64 bits, got {value}")
        return value
    x = _number(where, key, value)
    if kind == "pos" and not x > 0:
        raise SceneError(f"{where}: {key} must be > 0, got {value!r}")
    if kind == "nonneg" and not x >= 0:
        raise SceneError(f"{where}: {key} must be ≥ 0, got {value!r}")
    if kind == "unit" and not 0 <= x <= 1:
        raise SceneError(f"{where}: {key} must be in [0, 1], got {value!r}")
    return x


MAX_STAGES = 64  # HB_MAX_STAGES in c_ref/runtime/params.h


def parse_stages(value, where="scene", key="stages"):
    """The stage-list rules of the binaries' --stages (c_ref/runtime/cli.c): known names, no empty
    item (\"init,,wind\" is refused, not skipped), at most MAX_STAGES, init only first."""
    if isinstance(value, str):
        if value == "" or value.startswith(",") or value.endswith(",") or ",," in value:
            raise SceneError(f"{where}: {key}: empty item in '{value}' (write e.g. init,collide,wind)")
        value = value.split(",")
    if not isinstance(value, list) or not value:
        raise SceneError(f"{where}: {key} must be a non-empty list of stage names")
    if len(value) > MAX_STAGES:
        raise SceneError(f"{where}: {key}: at most {MAX_STAGES} stages")
    for i, s in enumerate(value):
        if not isinstance(s, str) or s not in STAGES:
            raise SceneError(f"{where}: {key}[{i}] {s!r} is not a stage (known: {', '.join(STAGES)})")
        if s == "init" and i > 0:
            raise SceneError(f"{where}: {key}: init may only come first (it would replace the state)")
    return tuple(value)


# copies of one frame a backend holds: the state, its saved copy for --repeat/--warmup, and
# the host frame written to the file (c_ref/app/driver.c)
FRAME_COPIES = 3


def memory_bytes():
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return None


def _check_values(scene, where):
    scenes_dynamic.check(scene, where, SceneError)
    if scene.groom:
        if scene.model != "dynamic":
            raise SceneError(f'{where}: groom needs model = "dynamic"')
        bad = [s for s in scene.stages if s in ("collide", "wind")]
        if bad:
            raise SceneError(
                f"{where}: a groom runs init then simulate; stage '{bad[0]}' keeps strands in slice planes, which a "
                "groom's strands are not"
            )
        if scene.groom == "curly" and scene.curl_radius == 0 and scene.curl_pitch == 0:
            raise SceneError(f"{where}: hair.curl_radius and hair.curl_pitch are both 0 (no helix)")
    elif (scene.curl_radius, scene.curl_pitch) != (1.0, 2.0):
        raise SceneError(f'{where}: hair.curl_radius and hair.curl_pitch need groom = "curly"')
    if scene.head_center and not scene.groom_file:
        raise SceneError(f'{where}: head.center needs groom = "FILE" (a HAIR or USD file; otherwise the head is at 0)')
    if scene.groom_file and scene.head_radius_given and not scene.head_center:
        raise SceneError(f"{where}: head.radius with a groom file needs head.center (the head is fitted to the roots)")
    if scene.stages[0] != "init":
        raise SceneError(f"{where}: stages must start with init (got '{scene.stages[0]}')")
    if "init" in scene.stages[1:]:
        raise SceneError(f"{where}: stages may contain init only first")
    if scene.segment_length < scene.hair_offset:
        raise SceneError(
            f"{where}: hair.length/(hair.points − 1) = {scene.segment_length:g} is "
            f"below hair.offset = {scene.hair_offset:g} (ℓ ≥ h is required)"
        )
    # frames are streamed to the file one at a time: a backend holds a few copies of one
    # frame (FRAME_COPIES), never all of them; simulate adds velocities, rest shape and saved copies
    need = scene.state_bytes() * (FRAME_COPIES + (3 if scene.model == "dynamic" else 0))
    have = memory_bytes()
    if have and need > have:
        raise SceneError(
            f"{where}: {scene.strands} strands × {scene.points} points need "
            f"{need / 2**30:.1f} GiB ({FRAME_COPIES} copies of one frame), more than this "
            f"machine's {have / 2**30:.1f} GiB (hair.strands too large)"
        )


def scene_from_dict(data, name, where):
    values = {}
    data, values["dynamic"] = scenes_dynamic.split(data, where, SceneError)
    if "stages" not in data and values["dynamic"] is not None:
        data = dict(data, stages=list(scenes_dynamic.DEFAULT_STAGES))
    if values["dynamic"] is None:
        values["dynamic"] = {}
    for key, value in data.items():
        if key not in SCHEMA[""]:
            raise SceneError(f"{where}: unknown key '{key}' (known: {', '.join(SCHEMA[''])})")
        if SCHEMA[""][key] is None:  # a table
            if not isinstance(value, dict):
                raise SceneError(f"{where}: '{key}' must be a table [{key}]")
            for sub, subvalue in value.items():
                if sub not in SCHEMA[key]:
                    raise SceneError(f"{where}: unknown key '{key}.{sub}' (known in [{key}]: {', '.join(SCHEMA[key])})")
                name_, kind = SCHEMA[key][sub]
                values[name_] = _convert(where, f"{key}.{sub}", kind, subvalue)
        else:
            name_, kind = SCHEMA[""][key]
            values[name_] = _convert(where, key, kind, value)
    if "stages" not in values:
        raise SceneError(f"{where}: missing key 'stages' (the ordered list of stages to run)")
    values["head_radius_given"] = "head_radius" in values
    values["strands_given"] = "strands" in values
    scene = Scene(name=name, source=where, **values)
    _check_values(scene, where)
    if "fibre" in data:
        given = [f"constraints.{k[2:].replace('-', '_')}" for k in COMPLIANCES if k in scene.dynamic]
        if given:
            raise SceneError(f"{where}: [fibre] sets {' and '.join(given)}: give one or the other")
    return with_fibre(scene, where)


COMPLIANCES = ("--bend-compliance", "--stretch-compliance")  # what a [fibre] sets


def fibre_of(scene, where="scene"):
    """The scene's [fibre] as a hair_physics.Fibre (its preset with the values given), or None."""
    own = [v or None for v in (scene.fibre_radius_um, scene.fibre_youngs_gpa, scene.fibre_density)]
    if not scene.fibre_preset and not any(own):
        return None
    try:
        return hair_physics.fibre(scene.fibre_preset or None, *own, where=f"given in {where}")
    except ValueError as e:
        raise SceneError(f"{where}: [fibre]: {e}") from None


def fibre_curvature(scene):
    """κ of the fibre mapping: given, else the curly groom's helix, else the scalp's 1/(R + h)."""
    if scene.fibre_curvature:
        return scene.fibre_curvature
    if scene.groom == "curly":
        return hair_physics.helix_curvature(scene.curl_radius, scene.curl_pitch)
    return 1.0 / (scene.head_radius + scene.hair_offset)


def with_fibre(scene, where):
    """The scene with the bend and stretch compliances its [fibre] gives (unchanged without one)."""
    fibre = fibre_of(scene, where)
    if fibre is None:
        return scene
    if scene.model != "dynamic":
        raise SceneError(f'{where}: [fibre] needs model = "dynamic"')
    try:
        m = hair_physics.mapped(fibre, scene.hair_length, scene.points, fibre_curvature(scene))
    except ValueError as e:
        raise SceneError(f"{where}: [fibre]: {e}") from None
    dyn = {**scene.dynamic, COMPLIANCES[1]: m.stretch_compliance, COMPLIANCES[0]: m.bend_compliance}
    return replace(scene, dynamic=dyn)


def find_scene_file(ref):
    """A scene path, or a name looked up as configs/scenes/<name>.toml."""
    found = config_file(ref, SCENES)
    if found:
        return found
    known = sorted(q.stem for q in SCENES.glob("*.toml"))
    raise SceneError(f"no scene '{ref}' (not a file; scenes in configs/scenes/: {', '.join(known) or 'none'})")


def is_scene_file(path):
    """A file with a `stages` key: a scene, not a sweep (a check; the directory is the rule)."""
    from harness import HarnessError

    try:
        data = read_toml(path, str(path), HarnessError)
    except HarnessError:  # not readable TOML: the sweep's own reading says why
        return False
    return "stages" in data or data.get("model") == "dynamic"


def load_scene(ref):
    path = find_scene_file(ref)
    where = f"scene {path}"
    data = read_toml(path, where, SceneError)
    return scene_from_dict(data, path.stem, where)


def with_frames(scene, n):
    """A copy of a dynamic scene simulating n frames."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise SceneError(f"--frames must be a whole number ≥ 1, got {n!r}")
    return replace(scene, dynamic={**scene.dynamic, "--frames": n})
