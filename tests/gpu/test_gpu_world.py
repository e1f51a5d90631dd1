"""GPU tests of the hair–hair grid (docs/model.md §3.16) and the colliders with friction (§3.17)
in the CUDA port: the variants that declare them (--list-variants: `lanes`) against the C
reference, one frame at a time from the reference's frame K−1 (as tests/gpu/test_gpu_dynamic.py):
the strict build bit for bit (the grid's sums are integers, so their order on the GPU changes no
bit; no gusts here), the normal build by the one-frame rule with the scene's spread (diff_dynamic).
Variants that do not declare a feature refuse it in one line. Marked `gpu`; conftest.py skips them
where there is no usable GPU.
"""

import re
from dataclasses import replace

import numpy as np
import pytest

from conftest import CPU_BIN, CUDA_BIN, CUDA_STRICT_BIN, ROOT
from harness import HarnessError
from harness.check import diff_dynamic
from harness.core import scenes, variants
from harness.io.meshes import icosphere, write_obj
from harness.io.trajectory import open_trajectory
from support.statecheck import run, run_json

pytestmark = pytest.mark.gpu

try:
    _DECLARED = variants.declared("cuda")
    VARIANTS = tuple(v for v in _DECLARED.variants if _DECLARED.runs(v, points=24))
except HarnessError:
    _DECLARED, VARIANTS = None, ()
BUILDS = {"normal": CUDA_BIN, "strict": CUDA_STRICT_BIN}
BASE = ["--strands", "300", "--points", "24", "--substeps", "4", "--iterations", "2", "--bend-compliance", "1e-6",
        "--shape-compliance", "1e-4", "--shape-range", "0.5", "--drag", "0.5", "--wind-speed", "150"]  # fmt: skip
BODY = (
    "capsule body 0 -10 -1 0 -24 -1 4.5 mu_s 0.3 mu_k 0.2\n"
    "capsule body -4 -24 -2 -19 -27 -2 5.5 mu_s 0.3 mu_k 0.2\n"
    "sphere head 0 4 9 2 mu_s 0.5\n"
    "plane body 0 -45 0 0 1 0\n"
    "mesh head chin.obj 32 band 4 mu_s 0.2 mu_k 0.1\n"
)
HELD = ["--head-motion", "nod", "--grid", "16", "--grid-friction", "0.1,0.02", "--grid-volume", "2000",
        "--grid-rebuild", "held"]  # fmt: skip
HELD_BODY = ["--friction", "0.3", "--colliders", "BODY"]
SCENES = {
    "grid-frame": ["--head-motion", "nod", "--grid", "16", "--grid-friction", "0.1,0.02", "--grid-volume", "2000"],
    "grid-substep": ["--head-motion", "shake", "--grid", "20", "--grid-friction", "0.05", "--grid-rebuild", "substep"],
    "grid-still": ["--grid", "12", "--grid-volume", "5000"],
    "grid-held": HELD,
    # `held` with colliders: k_grid_hold's samples used by the colliders' kernel
    "grid-held-body": [*HELD, *HELD_BODY],
    "body": ["--head-motion", "nod", "--friction", "0.4,0.3", "--depenetration-speed", "150", "--colliders", "BODY"],
    "body-sway": ["--colliders", "BODY", "--body-motion", "sway", "--body-amplitude", "3"],
    "all": [
        "--head-motion",
        "tilt",
        "--grid",
        "16",
        "--grid-friction",
        "0.05",
        "--grid-volume",
        "1000",
        "--friction",
        "0.3",
        "--colliders",
        "BODY",
    ],  # fmt: skip
}
# --contact-planes (docs/model.md §3.17): planes turned with the head (the chin mesh, the head sphere
# collider), shifted with the swaying body, and kept between the launches of a frame whose grid is built
# every substep
PLANES = ["--contact-planes", "3"]
SCENES["body-planes"] = [*SCENES["body"], *PLANES]
SCENES["body-sway-planes"] = [*SCENES["body-sway"], *PLANES]
SCENES["grid-substep-planes"] = [*SCENES["grid-substep"], "--friction", "0.3", "--colliders", "BODY", *PLANES]
# Hair faster than the splat's one-word momentum bound (docs/cuda.md, "The hair–hair grid"): at
# 300 strands a splat block holds 8 strands of 24 points, so the block's sums take the split words
# once a speed passes about 10,900 cm/s; with ftl this gravity gives 17,000 cm/s at the input
# frame and 62% of the points pass it (measured on the CPU's files; xpbd exits 5 here, so ftl
# alone). The strict build alone: the normal build's one-frame rule is for the scenes above.
FAST = "grid-fast"
SCENES[FAST] = ["--gravity", "1000000", "--grid", "16", "--grid-friction", "0.1,0.02", "--grid-volume", "2000"]
# Enough substeps that the lanes kernel's staged colliders (16 KB a block) take a frame in
# several launches: 18 substeps a launch in fp64 with these five colliders, 36 in fp32. The strict
# build alone: at 40 substeps with friction the one-frame rule does not hold for an honest free
# build (the CPU's own FMA build is 4.83 cm off at 41 of 7,200 points in ftl fp32, measured here).
LAUNCHES = "body-launches"
SCENES[LAUNCHES] = ["--head-motion", "nod", "--friction", "0.4,0.3", "--substeps", "40", "--colliders", "BODY"]
LAUNCHES_PLANES = "body-launches-planes"  # the planes kept in m.contacts between the launches
SCENES[LAUNCHES_PLANES] = [*SCENES[LAUNCHES], *PLANES]
STRICT_ONLY = (FAST, LAUNCHES, LAUNCHES_PLANES)
# --collide-once (docs/model.md §3.6, xpbd alone): the head sphere alone (the default scene's own
# kernel), the body with the bounded depenetration, the body as planes, and with the grid built every
# substep (a launch a substep)
ONCE = {
    "once-head": ["--head-motion", "nod", "--collide-once"],
    "once-body": [*SCENES["body"], "--collide-once"],
    "once-body-planes": [*SCENES["body-planes"], "--collide-once"],
    "once-grid-substep": [*SCENES["grid-substep"], "--friction", "0.3", "--colliders", "BODY", "--collide-once"],
}
SCENES.update(ONCE)
FRAMES = 3
RUNS = [
    (v, s)
    for v in VARIANTS
    for s in SCENES
    if s not in (*STRICT_ONLY, *ONCE) and _DECLARED.runs_features(v, variants.features_of(SCENES[s]))
]
FAST_RUNS = [v for v in VARIANTS if _DECLARED.runs_features(v, variants.features_of(SCENES[FAST]))]
REFUSING = [v for v in VARIANTS if not _DECLARED.runs_features(v, {"grid"})]


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    w = tmp_path_factory.mktemp("gpu_world")
    v, f = icosphere(3, radius=4.0, center=(0.0, -9.0, 5.0), scale=(1.0, 0.8, 1.0))
    write_obj(w / "chin.obj", v, f)
    (w / "body.txt").write_text(BODY)
    return w


def scene_args(work, scene):
    return body_path(work, SCENES[scene])


def body_path(work, flags):
    """flags with BODY as the module's body file"""
    return [str(work / "body.txt") if a == "BODY" else a for a in flags]


@pytest.fixture(scope="module")
def cpu_files(work):
    cache = {}

    def get(scene, solver, precision):
        key = (scene, solver, precision)
        if key not in cache:
            out = work / f"cpu_{scene}_{solver}_{precision}.h5"
            args = [*BASE, *scene_args(work, scene), "--solver", solver, "--precision", precision]
            run(CPU_BIN, "--stages", "init,collide,simulate", *args, "--frames", FRAMES, "--velocities", "all",
                "--output", out, "--quiet")  # fmt: skip
            cache[key] = out
        return cache[key]

    return get


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
@pytest.mark.parametrize("variant,scene", RUNS)
@pytest.mark.parametrize("build", tuple(BUILDS))
def test_gpu_frame_matches_cpu(work, cpu_files, build, variant, scene, solver, precision):
    check_frame(work, cpu_files, build, variant, scene, solver, precision)


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize(
    "variant,scene",
    [(v, s) for v in VARIANTS for s in ONCE if _DECLARED.runs_features(v, variants.features_of(ONCE[s]))],
)
@pytest.mark.parametrize("build", tuple(BUILDS))
def test_gpu_collide_once_matches_cpu(work, cpu_files, build, variant, scene, precision):
    check_frame(work, cpu_files, build, variant, scene, "xpbd", precision)


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("variant", FAST_RUNS)
def test_gpu_fast_hair_splat_matches_cpu_bit_for_bit(work, cpu_files, variant, precision):
    check_frame(work, cpu_files, "strict", variant, FAST, "ftl", precision)


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
@pytest.mark.parametrize(
    "variant,scene",
    [
        (v, s)
        for v in VARIANTS
        for s in (LAUNCHES, LAUNCHES_PLANES)
        if _DECLARED.runs_features(v, variants.features_of(SCENES[s]))
    ],
)
def test_gpu_frame_in_several_launches_matches_cpu_bit_for_bit(work, cpu_files, variant, scene, solver, precision):
    check_frame(work, cpu_files, "strict", variant, scene, solver, precision)


@pytest.mark.parametrize("scene", ["body-planes", "body-sway-planes", LAUNCHES_PLANES])
def test_the_planes_scenes_meet_planes_not_the_exact_colliders(work, cpu_files, scene):
    """the reference's planes change the frame (so the GPU's frame, equal to it, ran them)"""
    i = SCENES[scene].index("--contact-planes")
    exact = SCENES[scene][:i] + SCENES[scene][i + 2 :]
    key = f"{scene}-exact"
    SCENES.setdefault(key, exact)
    with open_trajectory(cpu_files(scene, "xpbd", "fp32")) as a, open_trajectory(cpu_files(key, "xpbd", "fp32")) as b:
        assert not np.array_equal(a.frame(-1), b.frame(-1))


def check_frame(work, cpu_files, build, variant, scene, solver, precision):
    cpu = cpu_files(scene, solver, precision)
    frame_matches(work, cpu, build, variant, f"{scene}_{solver}_{precision}")


def frame_matches(work, cpu, build, variant, label):
    """The build's frame from the CPU file's frame K−1 against the CPU's frame K: bit for bit (strict)
    or by the one-frame rule with the scene's spread (diff_dynamic, as tests/gpu/test_gpu_dynamic.py):
    the FMA-contracted reference itself puts a point of body-planes' ftl fp32 frame 1.1e-4 cm off, over
    the plain rule, the normal build one 1.4e-4 near a capsule with friction (measured 2026-11-28).
    Returns the build's JSON record."""
    with open_trajectory(cpu) as t:
        k = t.n_frames - 2
        step = int(t.step[-1])
    out = work / f"gpu_{build}_{variant}_{label}.h5"
    rec = run_json(BUILDS[build], "--input", cpu, "--input-frame", k, "--stages", "simulate", "--frames", 1,
                   "--variant", variant, "--output", out, "--force")  # fmt: skip
    exact = build == "strict"
    r = diff_dynamic.compare(cpu, out, frames=[step], exact=exact, check_paper=False, spread=not exact)
    assert r.equivalent, f"{build} {variant} {label}: " + "; ".join(r.failures()[:5])
    return rec


def cpu_scene_file(work, name, flags, precision, frames=FRAMES):
    """The C reference's file of a scene whose flags are given whole (BODY: the module's body file), made
    once a module."""
    cpu = work / f"cpu_{name}_{precision}.h5"
    if not cpu.exists():
        args = body_path(work, flags)
        run(CPU_BIN, "--stages", "init,collide,simulate", *args, "--precision", precision, "--frames", frames,
            "--velocities", "all", "--output", cpu, "--quiet")  # fmt: skip
    return cpu


def input_positions(cpu):
    """Positions [N, P, 3] of the CPU file's frame K−1, the GPU run's input."""
    with open_trajectory(cpu) as t:
        return t.frame(t.n_frames - 2).astype(np.float64)


def input_velocities(cpu):
    """Velocities [N, P, 3] of the CPU file's frame K−1 (written with --velocities all)."""
    with open_trajectory(cpu) as t:
        v = t.velocity_at_step(int(t.step[t.n_frames - 2]))
        assert v is not None, f"{cpu}: no velocities at the input frame"
        return v.astype(np.float64)


# A window node's mass sum past 32 bits (docs/cuda.md "The hair–hair grid": a mass share is summed
# in one 32-bit shared word, the carries out of it counted in another, joined into 64 bits). One cell whose
# low corner sits at the hair, so every point's weight at node 0 is above 0.7 and a splat block of at
# least 8 whole strands of 64 points (the fewest a block takes below SPLAT_RUN_STRANDS) adds more than
# 2^32 there. The strict build bit for bit.
CARRY = ["--strands", "300", "--points", "64", "--substeps", "4", "--iterations", "2", "--bend-compliance", "1e-6",
         "--shape-compliance", "1e-4", "--drag", "0.5", "--wind-speed", "150", "--grid", "2",
         "--grid-box=-13,-45,-13,250,250,250", "--grid-friction", "0.1,0.02", "--grid-volume", "2000"]  # fmt: skip
MASS_SCALE = 2**24  # HB_GRID_MASS_SCALE, c_ref/dynamic/contact_impl.h
SPLAT_STRANDS_MIN = 8  # kSplatWarps, cuda/dynamic/world.cu
# below this many strands a splat block takes whole strands (kSplatRunStrands, cuda/dynamic/world.cu)
SPLAT_RUN_STRANDS = int(
    re.search(r"kSplatRunStrands = (\d+);", (ROOT / "cuda/dynamic/world.cu").read_text())[1]  # type: ignore[index]
)


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("variant", FAST_RUNS)
def test_gpu_splat_whose_window_sums_carry_matches_cpu_bit_for_bit(work, variant, precision):
    cpu = cpu_scene_file(work, "carry", CARRY, precision)
    x = input_positions(cpu)
    lo, hi = np.array([-13.0, -45.0, -13.0]), np.array([250.0, 250.0, 250.0])
    weight = np.prod(1.0 - (x - lo) / (hi - lo), axis=-1)  # each point's trilinear weight at node 0
    assert x.shape[0] < SPLAT_RUN_STRANDS and SPLAT_STRANDS_MIN * x.shape[1] * weight.min() * MASS_SCALE > 2**32
    frame_matches(work, cpu, "strict", variant, f"carry_{precision}")


# The splat's hash table (docs/cuda.md "The hair–hair grid"): 64 strands on a 256³ grid, so that a
# point's cell is its own and a block of 8 strands (the fewest a block takes; 64 strands give blocks
# of 8 on any GPU) spans a box of more nodes than the window holds (with one momentum word a node,
# WINDOW_SINGLE: the five words' arrays in the window's memory). `fill`: 64 points a strand, so
# that every block touches more nodes than the table has slots and some shares find none (the
# grid directly); `hashed`: 10 points, so that a block's nodes fit the table (one momentum word a
# share); `fast`: the same with ftl under a gravity that takes every strand past the one-word
# bound (SINGLE_SPEED), so that the table keeps the split words. Each premise is checked from the
# CPU's positions and velocities at the input frame; the strict build bit for bit.
WINDOW_NODES = int(re.search(r"^#define HB_SPLAT_WINDOW (\d+)$", (ROOT / "cuda/dynamic/world.cu").read_text(), re.M)[1])
WINDOW_SINGLE = WINDOW_NODES * 8 // 5  # kWindowSingle, cuda/dynamic/world.cu
HASH_SLOTS = (WINDOW_NODES * 8 // 9) & ~31  # kHashSlots, cuda/dynamic/world.cu
HASH_BOX = (-13.0, -45.0, -13.0, 13.0, 13.0, 13.0)
HASH = ["--strands", "64", "--substeps", "4", "--iterations", "2", "--bend-compliance", "1e-6",
        "--shape-compliance", "1e-4", "--drag", "0.5", "--wind-speed", "150", "--grid", "256",
        "--grid-box=" + ",".join(map(str, HASH_BOX)), "--grid-friction", "0.1,0.02",
        "--grid-volume", "2000"]  # fmt: skip
HASH_CASES = {  # points, frames, flags
    "fill": ("64", 3, []),
    "hashed": ("10", 4, []),
    "fast": ("10", 4, ["--solver", "ftl", "--gravity", "8000000"]),
}
# the least |v| component (cm/s) whose block of SPLAT_STRANDS_MIN strands of P points takes split words
SINGLE_SPEED = lambda p: 2**31 / (SPLAT_STRANDS_MIN * p * 1024)  # noqa: E731 (world.cu: `single`)


def corner_nodes(x, box, n):
    """Each point's eight corner nodes [N, P, 8] (−1 outside the grid), from positions [N, P, 3]."""
    lo, hi = np.array(box[:3]), np.array(box[3:])
    g = (x - lo) * ((n - 1) / (hi - lo))
    inside = np.all((g >= 0) & (g < n - 1), axis=-1)
    i = np.floor(np.where(inside[..., None], g, 0)).astype(np.int64)
    nodes = np.stack([(i[..., 0] + a) + n * ((i[..., 1] + b) + n * (i[..., 2] + c))
                      for c in (0, 1) for b in (0, 1) for a in (0, 1)], axis=-1)  # fmt: skip
    return np.where(inside[..., None], nodes, -1)


@pytest.mark.parametrize("case", sorted(HASH_CASES))
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("variant", [v for v in VARIANTS if _DECLARED.runs_features(v, {"grid"})])
def test_gpu_splat_in_its_hash_table_matches_cpu_bit_for_bit(work, variant, precision, case):
    points, frames, flags = HASH_CASES[case]
    cpu = cpu_scene_file(work, f"hash_{case}", [*HASH, "--points", points, *flags], precision, frames)
    nodes = corner_nodes(input_positions(cpu), HASH_BOX, 256)
    assert np.all(nodes >= 0), "a point outside the grid"
    assert len(nodes) < SPLAT_RUN_STRANDS  # blocks of whole strands
    own = [len(np.unique(s)) for s in nodes]  # each strand's nodes
    shared = nodes.size - len(np.unique(nodes))  # shares beyond the first at a node, over all strands
    if case == "fill":  # any 8 strands touch more nodes than the table has slots
        assert SPLAT_STRANDS_MIN * min(own) - shared > HASH_SLOTS
    else:  # every block's box of nodes exceeds its window; 8 strands' shares fit the table
        ijk = np.stack([nodes % 256, (nodes // 256) % 256, nodes // 65536], axis=-1).reshape(len(nodes), -1, 3)
        lo, hi = ijk.min(axis=1), ijk.max(axis=1)
        if case == "hashed":  # each strand's own box past the one-word window
            assert np.prod(hi - lo + 1, axis=-1).min() > max(WINDOW_NODES, WINDOW_SINGLE)
        else:  # straight under this gravity: a block's box holds each of its strands' boxes with the
            # 7 others', so it is past the split words' window where every strand's 7th least pair box is
            pairs = np.prod(np.maximum(hi[:, None], hi[None]) - np.minimum(lo[:, None], lo[None]) + 1, axis=-1)
            np.fill_diagonal(pairs, np.iinfo(np.int64).max)
            assert np.sort(pairs, axis=1)[:, SPLAT_STRANDS_MIN - 2].min() > WINDOW_NODES
        assert SPLAT_STRANDS_MIN * int(points) * 8 <= HASH_SLOTS
    speeds = np.abs(input_velocities(cpu)).max(axis=(1, 2))  # each strand's largest |v| component
    if case == "fast":  # every block's sums in split words
        assert speeds.min() > SINGLE_SPEED(int(points))
    else:  # every block's in one word
        assert speeds.max() < SINGLE_SPEED(int(points))
    frame_matches(work, cpu, "strict", variant, f"hash_{case}_{precision}")


# k_grid_hold over more blocks than a GPU holds at once, and the splat's blocks taking runs of their
# strands' points (docs/cuda.md "The hair–hair grid"): 12,000 strands of 24 points (the hold's 375
# blocks of strands, three of points; the splat's blocks, on a GPU of 132 SMs, 32 strands of 12 points:
# a run whose length is no power of two) or of 32 points (32 strands of 16), with colliders. The strict
# build bit for bit.
HELD_WIDE = ["--strands", "12000", "--substeps", "4", "--iterations", "2", "--bend-compliance",
             "1e-6", "--shape-compliance", "1e-4", "--drag", "0.5", *HELD, *HELD_BODY]  # fmt: skip


@pytest.mark.parametrize("points", ["24", "32"])
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("variant", [v for v in VARIANTS if _DECLARED.runs_features(v, {"grid", "colliders"})])
def test_gpu_held_samples_in_wide_blocks_match_cpu_bit_for_bit(work, variant, precision, points):
    cpu = cpu_scene_file(work, f"held_wide_{points}", [*HELD_WIDE, "--points", points], precision)
    frame_matches(work, cpu, "strict", variant, f"held_wide_{points}_{precision}")


# The lanes variant's one-wave layout (docs/cuda.md "The lanes variant"): where N strands need more
# than one wave of G = 2's blocks but fit one of G = 4's, an fp32 xpbd run of 32 points with the
# default scene's features, with no world or the held grid alone, takes G = 4 on 8 lanes in blocks
# of half the threads (the record's `layout`). The strands a G = 2 wave takes on this GPU come from
# a run of 64 strands; at that count the run stays G = 2 and fp64 does at one wave and 16 strands
# more, where fp32 takes G = 4: both builds' frame there against the reference (strict bit for bit).
WAVE = ["--points", "32", "--substeps", "8", "--iterations", "2", "--solver", "xpbd", "--drag", "0.5",
        "--damping", "0.5", "--bend-compliance", "1e-6", "--shape-compliance", "1e-4", "--shape-range", "0.5",
        "--wind-speed", "150", "--gust-amplitude", "0.5", "--head-motion", "nod"]  # fmt: skip
WAVE_WORLDS = {"none": [], "held": ["--grid", "32", "--grid-friction", "0.05,0.01", "--grid-volume", "2000",
                                    "--grid-rebuild", "held"]}  # fmt: skip


def lanes_layout(strands, flags, precision):
    """The strict build's simulate `layout` for a run of the scene `flags` (one frame)."""
    rec = run_json(CUDA_STRICT_BIN, "--stages", "init,collide,simulate", *flags, "--strands", strands,
                   "--frames", 1, "--variant", "lanes", "--precision", precision)  # fmt: skip
    lay = rec["stages"][-1]["layout"]
    return (lay["points_a_lane"], lay["lanes_a_strand"], lay["block"]), lay["strands_a_wave"]


@pytest.mark.parametrize("build", sorted(BUILDS))
@pytest.mark.parametrize("world", sorted(WAVE_WORLDS))
def test_gpu_lanes_one_wave_layout_matches_cpu(work, world, build):
    if "lanes" not in VARIANTS:
        pytest.skip("this build declares no lanes variant")
    flags = [*WAVE, *WAVE_WORLDS[world]]
    shape, wave = lanes_layout(64, flags, "fp32")
    assert shape == (2, 16, 256) and wave >= 64
    assert lanes_layout(wave, flags, "fp32")[0] == (2, 16, 256)
    assert lanes_layout(wave + 16, flags, "fp64")[0] == (2, 16, 256)
    cpu = cpu_scene_file(work, f"wave_{world}", [*flags, "--strands", str(wave + 16)], "fp32", 2)
    lay = frame_matches(work, cpu, build, "lanes", f"wave_{world}")["stages"][-1]["layout"]
    assert (lay["points_a_lane"], lay["lanes_a_strand"], lay["block"]) == (4, 8, 128)
    assert lay["strands_a_wave"] >= wave + 16


# §3.17 the collision step in 4 sweeps on the body scene (configs/scenes/body.toml: the default
# body, whose shoulders overlap its neck, with friction, the bounded depenetration and the grid):
# the scene's physics without its gusts (the device's sine is not the CPU's) and its rise (the body
# still, so the drape starts inside the shoulders), under a fast nod (16 Hz, 0.5 rad: the jaw mesh
# meets the neck), 300 strands. The lanes kernel sweeps again while any lane's point moved (a warp
# vote), each point while its own sweep moved it: the strict build equals the CPU bit for bit.
SWEEPS = 4


def body_sweeps_flags(solver, precision, planes=False):
    s = scenes.load_scene("body").with_overrides(strands=300, precision=precision)
    drop = ("--gust-amplitude", "--gust-frequency", "--gust-wavelength", "--body-motion", "--body-amplitude",
            "--body-frequency", "--frames", "--output-every")  # fmt: skip
    dyn = {f: v for f, v in s.dynamic.items() if f not in drop}
    dyn.update({"--solver": solver, "--motion-frequency": 16.0, "--motion-amplitude": 0.5, "--collider-sweeps": SWEEPS})
    if planes:
        dyn["--contact-planes"] = 3.0
    return replace(s, dynamic=dyn).flags()


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
@pytest.mark.parametrize(
    "variant,planes",
    [
        (v, planes)
        for v in VARIANTS
        for planes in (False, True)
        if _DECLARED.runs_features(v, {"colliders", "friction", *(("planes",) if planes else ())})
    ],
)
def test_gpu_body_in_sweeps_matches_cpu_bit_for_bit(work, variant, planes, solver, precision):
    cpu = work / f"cpu_sweeps_{solver}_{precision}_{planes}.h5"
    if not cpu.exists():
        run(CPU_BIN, *body_sweeps_flags(solver, precision, planes), "--frames", FRAMES, "--velocities", "all",
            "--output", cpu, "--quiet")  # fmt: skip
    with open_trajectory(cpu) as t:
        assert int(t.dynamic_params["collider_sweeps"]) == SWEEPS
        k = t.n_frames - 2
        step = int(t.step[-1])
    out = work / f"gpu_sweeps_{variant}_{solver}_{precision}_{planes}.h5"
    # the resumed run takes the count from the CPU's file (/parameters/collider_sweeps)
    run(CUDA_STRICT_BIN, "--input", cpu, "--input-frame", k, "--stages", "simulate", "--frames", 1,
        "--variant", variant, "--output", out, "--force", "--quiet")  # fmt: skip
    with open_trajectory(out) as t:
        assert int(t.dynamic_params["collider_sweeps"]) == SWEEPS
    r = diff_dynamic.compare(cpu, out, frames=[step], exact=True, check_paper=False)
    assert r.equivalent, f"strict {variant} sweeps {solver} {precision}: " + "; ".join(r.failures()[:5])


@pytest.mark.parametrize("variant", REFUSING)
@pytest.mark.parametrize(
    "flags", [["--grid", "16"], ["--friction", "0.2"], ["--colliders", "C", *PLANES], ["--collide-once"]]
)
def test_variants_without_the_features_refuse_them(tmp_path, variant, flags):
    out = tmp_path / "o.h5"
    (tmp_path / "c.txt").write_text("sphere head 0 -12 0 3\n")
    flags = [str(tmp_path / "c.txt") if a == "C" else a for a in flags]
    p = run(CUDA_BIN, "--stages", "init,collide,simulate", *BASE, *flags, "--variant", variant, "--output", out,
            "--quiet", check=False)  # fmt: skip
    assert p.returncode == 2 and f"--variant {variant} does not run" in p.stderr
    assert not out.exists()
