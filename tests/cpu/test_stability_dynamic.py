"""Stability of the dynamic model at the extremes (docs/model.md §3): a property-based
search over the dynamic scene space on the CPU (and, marked `gpu`, on the strict CUDA
build against the CPU), a slice of the stability map whose verdicts are known, and the
map's verdict and wording rules. The map itself is `python -m harness stability`
(harness/studies/stability_dynamic.py); what the searches found and the regressions named after it are in
docs/decisions.md ("Stability search of the dynamic model").
"""

import json
import math
import os
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from harness import HarnessError
from harness.check import diff_dynamic, invariants_dynamic
from harness.cli.main import main as harness_main
from harness.core import runner, tolerances, variants
from harness.io.trajectory import open_trajectory
from harness.render import stability_dynamic_report as stability_report
from harness.studies import stability_dynamic as stability
from harness.studies import stability_slices_dynamic as stability_slices
from support.statecheck import run

# CI: 120 derandomized examples (about 30 s on the 2-core CI machine); a deeper search:
# HAIRBENCH_DYN_STABILITY_EXAMPLES=2000 pytest tests/cpu/test_stability_dynamic.py -k search
CPU_SETTINGS = settings(
    max_examples=int(os.environ.get("HAIRBENCH_DYN_STABILITY_EXAMPLES", "120")),
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
# the GPU part: 60 examples in the suite; HAIRBENCH_GPU_DYN_STABILITY_EXAMPLES=300 for more
GPU_SETTINGS = settings(
    max_examples=int(os.environ.get("HAIRBENCH_GPU_DYN_STABILITY_EXAMPLES", "60")),
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def _gpu_variants():
    """The strict build's variants that simulate, their point limits and their block limits."""
    try:
        d = variants.declared("cuda", "strict")
    except HarnessError:
        return ("not-built",), {}, {}  # the GPU tests skip without it
    return d.running("simulate"), d.max_points, d.max_block


GPU_VARIANTS, GPU_MAX_POINTS, GPU_MAX_BLOCK = _gpu_variants()

HAIR_LENGTH = 30.0
HUGE = (1e10, 1e30, 1e38, 1e300)  # compliances, drag and damping far past any physical value


def loguniform(lo, hi):
    return st.floats(lo, hi).map(lambda e: 10.0**e)


def compliance():
    return st.one_of(st.just(0.0), loguniform(-12, 2), st.sampled_from(HUGE))


@st.composite
def dyn_scenes(draw):
    """A dynamic scene (docs/model.md §3 table) over its allowed ranges and their edges.
    Values the model leaves undeclared are None (the flag is not passed)."""
    s = {
        "precision": draw(st.sampled_from(["fp32", "fp64"])),
        "solver": draw(st.sampled_from(["xpbd", "ftl"])),
        "strands": draw(st.integers(1, 4)),
        "points": draw(st.one_of(st.sampled_from([2, 3, 4, 32, 128]), st.integers(2, 128))),
        "seed": draw(st.integers(0, 2**32)),
        "frames": draw(st.integers(1, 4)),
        "substeps": draw(st.one_of(st.sampled_from([1, 2, 64]), st.integers(1, 64))),
        "iterations": draw(st.integers(1, 8)),
        "frame_dt": draw(st.one_of(st.sampled_from([1 / 60, 1 / 24, 1 / 240, 1.0]), loguniform(-5, 0.5))),
        "gravity": draw(st.one_of(st.just(0.0), st.floats(0, 5000), st.sampled_from([981.0, 1e5, *HUGE]))),
        "stretch_compliance": draw(st.one_of(st.none(), compliance())),
        "bend_compliance": draw(st.one_of(st.none(), compliance())),
        "shape_compliance": draw(st.one_of(st.none(), compliance())),
        "drag": draw(st.one_of(st.none(), st.just(0.0), loguniform(-3, 3), st.sampled_from(HUGE))),
        "damping": draw(st.one_of(st.none(), st.just(0.0), loguniform(-3, 3), st.sampled_from(HUGE))),
        "wind_speed": draw(st.one_of(st.just(0.0), st.floats(0, 2000), st.sampled_from([2000.0, 8000.0, 1e5]))),
        "wind_angle": draw(st.one_of(st.sampled_from([math.pi, 0.0, math.pi / 2]), st.floats(-7, 7))),
        "gust_amplitude": draw(st.one_of(st.just(0.0), st.floats(0, 2), st.sampled_from([10.0, 1e39]))),
        "gust_frequency": draw(st.floats(0, 50)),
        "gust_wavelength": draw(st.one_of(loguniform(-2, 4), st.just(1e-40))),
        "motion": draw(st.sampled_from(["still", "nod", "shake", "tilt"])),
        "motion_amplitude": draw(st.one_of(st.floats(0, 4), st.just(0.0))),
        "motion_frequency": draw(st.one_of(st.floats(0, 30), st.just(0.0))),
        "collision_margin": draw(st.one_of(st.just(0.0), st.floats(0, 5), st.sampled_from([30.0, 100.0, 1e30]))),
        "collider": draw(st.booleans()),
        "ftl_damping": draw(st.floats(0, 1)),
    }
    s["shape_range"] = (
        draw(st.one_of(st.just(1.0), st.floats(1e-3, 1), st.just(1e-3))) if s["shape_compliance"] is not None else None
    )
    return s


def scene_args(s):
    """The binary's flags of a drawn scene: the geometry, then dynamic_args."""
    geometry = ["--strands", s["strands"], "--points", s["points"], "--seed", s["seed"], "--hair-length", HAIR_LENGTH]
    return [*geometry, "--precision", s["precision"], *dynamic_args(s)]


# the drawn keys that are not a `--key value` flag of the simulate stage
APART = ("precision", "solver", "strands", "points", "seed", "motion", "collider")


def dynamic_args(s):
    """The simulate stage's flags of a drawn scene (None: the flag is left out)."""
    args = ["--solver", s["solver"], "--head-motion", s["motion"]]
    for key, value in s.items():
        if key not in APART and value is not None:
            args += ["--" + key.replace("_", "-"), repr(value) if isinstance(value, float) else value]
    if not s["collider"]:
        args.append("--no-collider")
    return args


def simulate(cpu_bin, s, out, *extra):
    """Run a drawn scene on the CPU; the CompletedProcess (exit 2 = refused)."""
    return run(cpu_bin, *scene_args(s), "--stages", "init,collide,simulate", *extra, "--output", out, check=False)


def refused_cleanly(p):
    """A refusal is exit 2, one line on stderr that names a flag, and no file."""
    lines = p.stderr.strip().splitlines()
    return p.returncode == 2 and len(lines) == 1 and "--" in lines[0]


def check_contract(path):
    """harness.check.invariants_dynamic on every frame (the reference's roots bit for bit); the report."""
    with open_trajectory(path) as t:
        rep = invariants_dynamic.check(t, exact=True)
        blown = int(t.observables["blown_up_strands"].max())
    assert rep.ok, "; ".join(v.message for v in rep.all_violations()[:4])
    return blown


# The examples the search found and that are fixed now (docs/decisions.md): each failed
# before its fix and is kept as an explicit example besides its named regression test.
BASE = dict(
    precision="fp32",
    solver="xpbd",
    strands=2,
    points=8,
    seed=1,
    frames=2,
    substeps=1,
    iterations=1,
    frame_dt=1 / 60,
    gravity=981.0,
    stretch_compliance=None,
    bend_compliance=None,
    shape_compliance=None,
    shape_range=None,
    drag=None,
    damping=None,
    wind_speed=0.0,
    wind_angle=math.pi,
    gust_amplitude=0.0,
    gust_frequency=1.0,
    gust_wavelength=100.0,
    motion="still",
    motion_amplitude=0.25,
    motion_frequency=1.0,
    collision_margin=0.0,
    collider=True,
    ftl_damping=0.9,
)


@CPU_SETTINGS
@given(s=dyn_scenes())
@example(s=dict(BASE, stretch_compliance=1e36))
@example(s=dict(BASE, solver="ftl", bend_compliance=1e300, substeps=64, precision="fp64", frame_dt=1e-3))
@example(s=dict(BASE, drag=1e30, wind_speed=1e10))
@example(s=dict(BASE, drag=0.5, wind_speed=150.0, gust_amplitude=0.5, gust_wavelength=1e-40))
def test_search_cpu_contract_holds_across_the_dynamic_scene_space(cpu_bin, tmp_path_factory, s):
    """Every drawn scene is refused cleanly (exit 2, one line naming a flag, no file) or
    runs with every frame within the contract: no NaN/Inf, roots bit for bit at Q(t)·X̄0,
    no point inside the collider, FTL segments of length ℓ, observables that agree with
    the positions. A blow-up (a point beyond 2L) is the solver's limit, not a failure,
    except where it cannot happen: FTL sets every segment to ℓ and the collider (margin 0)
    at most doubles one, so an ftl strand never reaches 2L."""
    out = tmp_path_factory.mktemp("dynstab") / "s.h5"
    p = simulate(cpu_bin, s, out, "--velocities", "all")
    if p.returncode not in runner.COMPLETED:  # 5: it ran and blew up (docs/interfaces.md, "Exit status")
        assert refused_cleanly(p), (p.returncode, p.stderr)
        assert not out.exists()
        event("refused")
        return
    blown = check_contract(out)
    event("blown up" if blown else "not blown up")
    if s["solver"] == "ftl" and (s["collision_margin"] == 0.0 or not s["collider"]):
        assert blown == 0, "an ftl strand blew up, which FTL's segment lengths rule out"


@pytest.mark.gpu
@GPU_SETTINGS
@given(s=dyn_scenes(), variant=st.sampled_from(GPU_VARIANTS), block=st.sampled_from([32, 96, 256, 1024]))
@example(s=dict(BASE, points=33, substeps=4, iterations=2), variant=GPU_VARIANTS[0], block=32)
def test_search_gpu_frame_agrees_with_cpu(cpu_bin, tmp_path_factory, s, variant, block):
    """A drawn scene on the strict CUDA build: one frame from the CPU's state (positions and
    velocities, --input --input-frame) against the CPU's next frame, by the rule of
    tests/gpu/test_gpu_dynamic.py (harness.check.diff_dynamic.compare: bit for bit without gusts, the
    DYN_STEP_K rule with them); a scene the CPU refuses must be refused by the GPU too."""
    from conftest import CUDA_STRICT_BIN

    d = tmp_path_factory.mktemp("dynstabgpu")
    cpu, gpu = d / "cpu.h5", d / "gpu.h5"
    s = dict(s, frames=max(2, s["frames"]))
    p = simulate(cpu_bin, s, cpu, "--velocities", "all")
    if p.returncode not in runner.COMPLETED:
        q = run(CUDA_STRICT_BIN, *scene_args(s), "--stages", "init,collide,simulate", "--output", gpu, check=False)
        assert p.returncode == q.returncode == 2, (p.stderr, q.stderr)
        return
    with open_trajectory(cpu) as t:
        k = t.n_frames - 2  # resume from the before-last frame
        gusts = "gust" in t.features.split("+")
        step = int(t.step[k + 1])
        blown = int(t.observables.set_index("step").loc[step, "blown_up_strands"])
    g = run(
        CUDA_STRICT_BIN,
        "--input",
        cpu,
        "--input-frame",
        k,
        "--stages",
        "simulate",
        *dynamic_args(dict(s, frames=1)),
        "--variant",
        variant,
        "--block-size",
        block,
        "--output",
        gpu,
        "--quiet",
        check=False,
    )
    if g.returncode == 2 and "shared memory" in g.stderr:  # the warp variant's block does not fit: refused
        event("warp variant: block too large for shared memory, refused")
        return
    limit = GPU_MAX_POINTS.get(variant)
    if limit and s["points"] > limit:  # a variant's declared point limit: refused, naming --points
        assert g.returncode == 2 and "--points" in g.stderr, (g.returncode, g.stderr)
        event(f"{variant}: more than {limit} points, refused")
        return
    most = GPU_MAX_BLOCK.get(variant)
    if most and block > most:  # a variant's declared block limit: refused, naming --block-size
        assert g.returncode == 2 and "--block-size" in g.stderr, (g.returncode, g.stderr)
        event(f"{variant}: a block of more than {most} threads, refused")
        return
    assert g.returncode in runner.COMPLETED, g.stderr
    what = f"strict {variant} block {block} {s['solver']} {s['precision']}"
    exact = tolerances.GPU_DYN_STRICT_EXACT_WITHOUT_GUSTS and not gusts
    if exact or blown == 0:  # the rule of tests/gpu/test_gpu_dynamic.py and the bench (harness.check.diff_dynamic)
        r = diff_dynamic.compare(cpu, gpu, frames=[step], exact=exact, check_paper=False, spread=not exact)
        assert r.equivalent, f"{what}: " + "; ".join(r.failures()[:5])
    else:
        event("gusts and a blown-up CPU frame: compared for finiteness only")
        with open_trajectory(gpu) as tg, open_trajectory(cpu) as tc:
            assert np.isfinite(tg.frame(-1)).all() == np.isfinite(tc.frame(k + 1)).all()


# ---- a slice of the map whose verdicts are known (measured: docs/decisions.md) -----------
def slice_named(name):
    return next(s for s in stability_slices.SLICES if s.name == name)


CPU = stability.Backend("cpu", "default", variants.declared("cpu").default_variant if variants.names("cpu") else "")
KNOWN_CELLS = [
    # slice, row, col, solver, precision, verdict (worst measured value, margin to its bound)
    ("substeps-points", 64, 32, "xpbd", "fp32", "ok"),  # stretch 0.0094, 10× under 0.1
    ("substeps-points", 8, 32, "xpbd", "fp64", "over-stretched"),  # 0.40, 4× over
    ("substeps-points", 1, 32, "xpbd", "fp32", "escaped"),  # from frame 15, in 46 of 60 frames; all finite
    # iteration starvation at S = 1 in the default scene: I = 1 stretches 300 %, I = 128 2.1 %
    ("substeps-iterations", 1, 1, "xpbd", "fp64", "over-stretched"),  # 3.0, 30× over
    ("substeps-iterations", 1, 128, "xpbd", "fp64", "ok"),  # 0.021, 4.7× under
    ("substeps-wind", 1, 0, "ftl", "fp32", "ok"),  # a stiff chain at S = 1: 0.051, 2× under
    ("substeps-wind", 1, 8000, "ftl", "fp64", "over-stretched"),  # a gale at S = 1: 0.20, 2× over
    # a 16000 cm/s gale at I = 1: a point escapes past 2L without long-range attachments (stretch 4.2, blown
    # up in 5 frames), and LRA holds every point within its arc (stretch 0.70; the segments still stretch)
    ("lra-wind", "off", 16000, "xpbd", "fp32", "escaped"),
    ("lra-wind", 1, 16000, "xpbd", "fp32", "over-stretched"),
    # a soft chain (α_s = 1e-4) hangs at L + α_s·g0·P(P − 1)/2 = 78.7 cm, past 2L = 60 cm in 45 frames (the
    # model's blown-up count) but within twice its hanging length (reach 0.82 of it): its springs' physics,
    # judged by its stretch (6.2), not an escape
    ("substeps-stretch", 64, 1e-4, "xpbd", "fp64", "over-stretched"),
]


@pytest.mark.parametrize("name,row,col,solver,precision,want", KNOWN_CELLS)
def test_map_cells_with_known_verdicts(cpu_bin, name, row, col, solver, precision, want):
    cell = stability.run_cell(slice_named(name), row, col, solver, precision, CPU, stability.STRANDS, stability.FRAMES)
    assert cell["verdict"] == want, cell
    assert cell["violations"] == "", cell


def test_a_cell_past_its_timeout_is_timed_out_not_refused(cpu_bin):
    """A cell killed by --timeout is "timed out" (exit 124 of runner.TimedOut), never "refused"
    (exit 2: the binary declined the scene): a map once showed slow GPU cells as refused."""
    cell = stability.run_cell(
        slice_named("substeps-iterations"), 64, 128, "xpbd", "fp64", CPU, 64, stability.FRAMES, timeout=0.05
    )
    assert cell["verdict"] == "timed out", cell
    assert "did not finish within 0.05 s" in cell["message"]


def test_the_map_starts_its_heaviest_cells_first_and_keeps_its_row_order(cpu_bin, monkeypatch):
    started = []

    def fake_cells(jobs, *rest):
        rows = []
        for slc, row, col, solver, precision, be in jobs:
            started.append((row, col))
            rows.append({"slice": slc.name, "row": row, "col": col, "solver": solver, "precision": precision})
        return rows

    monkeypatch.setattr(stability, "run_cells", fake_cells)
    rows, _, _ = stability.measure(["substeps-iterations"], quick=True, gpu="no", jobs=1, log=lambda *_: None)
    slc = slice_named("substeps-iterations")
    cells = [(r, c) for r, c in ((r["row"], r["col"]) for r in rows)]
    assert cells[:: 2 * 2] == [(r, c) for r in slc.rows.quick for c in slc.cols.quick]  # × solvers × precisions
    work = [float(r) * float(c) for r, c in started]
    assert work == sorted(work, reverse=True) and work[0] > work[-1]


def test_a_gpu_cell_runs_the_fastest_variant_that_runs_it():
    """A GPU cell takes the first of variants.FASTEST_FIRST its build declares that runs its
    points, solver and features (the S = 64, I = 128 cell took 13–34 s on strand and about 1 s
    on lanes); the CPU keeps its variant; with none that runs it, the build's own."""
    sim = ("init", "simulate")
    gpu = variants.Declared(
        backend="cuda",
        build="strict",
        default_variant="fused",
        precisions=("fp32", "fp64"),
        variants=("fused", "strand", "warp", "warpreg", "lanes"),
        stages={"fused": ("init",), "strand": sim, "warp": sim, "warpreg": sim, "lanes": sim},
        max_points={"warpreg": 32, "lanes": 128},
        solvers=("xpbd", "ftl"),
        variant_features={"lanes": ("sagfree", "lod")},
    )
    be = stability.Backend("cuda", "strict", "strand")

    def variant(name, row, col, solver="xpbd", declared=gpu):
        return stability.cell_backend(be, declared, slice_named(name), row, col, solver, "fp32", 16, 60).variant

    assert variant("substeps-iterations", 64, 128) == "lanes"
    assert variant("substeps-points", 4, 128, "ftl") == "lanes"
    assert variant("lra-nod", 1, 16) == "warpreg"  # lanes runs no long-range attachments
    assert variant("lra-nod", "off", 16) == "lanes"
    no_lanes = replace(gpu, variants=gpu.variants[:-1])
    assert variant("substeps-points", 4, 16, declared=no_lanes) == "warpreg"
    assert variant("substeps-points", 4, 128, declared=no_lanes) == "warp"  # warpreg: at most 32 points
    only_ftl = replace(gpu, variant_solvers={v: ("ftl",) for v in ("warp", "warpreg", "lanes")})
    assert variant("substeps-wind", 4, 0, declared=only_ftl) == "strand"
    none = replace(gpu, variant_solvers={v: ("ftl",) for v in gpu.variants})
    assert variant("substeps-wind", 4, 0, declared=none) == "strand"  # be's own: the binary refuses it
    assert stability.cell_backend(CPU, gpu, slice_named("lra-nod"), 1, 16, "xpbd", "fp32", 16, 60) == CPU
    # a groom's per-segment rest lengths (the accuracy study's GPU reference asks for them)
    assert variants.fastest(replace(gpu, per_segment=("strand", "warp")), 32, (), "xpbd", per_segment=True) == "warp"
    assert variants.fastest(gpu, 32, (), "xpbd", per_segment=True) is None


def test_verdict_takes_the_worst_that_applies():
    s_max, p_rel = tolerances.STABILITY_STRETCH_MAX, tolerances.STABILITY_PENETRATION_REL
    assert stability.verdict(0.0, 0.0, 0) == "ok"
    assert stability.verdict(s_max, p_rel, 0) == "ok"  # at the bound is still ok
    assert stability.verdict(s_max * 1.01, 0.0, 0) == "over-stretched"
    assert stability.verdict(s_max * 1.01, p_rel * 1.01, 0) == "penetrating"
    assert stability.verdict(0.0, 0.0, 1) == "escaped"  # blown up, every number finite
    assert stability.verdict(0.0, 0.0, 45, reach=0.82) == "ok"  # past 2L, within twice its hanging length
    assert stability.verdict(0.0, 0.0, 0, reach=1.2) == "escaped"
    assert stability.hanging_length(30.0, 32, 981.0, 1e-4, "xpbd") == pytest.approx(30 + 1e-4 * 981 * 496)
    assert stability.hanging_length(30.0, 32, 981.0, 1e-4, "ftl") == 30.0
    assert stability.verdict(float("nan"), float("nan"), 3, diverged=True) == "diverged"


def _panel(verdicts, rows=(1, 2, 4, 8), cols=(0, 1000)):
    import pandas as pd

    return pd.DataFrame(
        [
            dict(row=str(r), col=str(c), row_key="--substeps", col_key="--wind-speed", verdict=verdicts[i][j])
            for i, r in enumerate(rows)
            for j, c in enumerate(cols)
        ]
    )


def test_boundaries_are_named_from_the_data():
    b, o, k = "escaped", "over-stretched", "ok"
    words = stability_report.boundaries(_panel([[b, b], [o, b], [k, o], [k, k]]), "substeps-wind")
    assert words == (
        "escapes (a point past twice its hanging length, finite) at S = 1 (U = 0 cm/s); S ≤ 2 (U = 1000 cm/s); "
        "over-stretches at S = 2 (U = 0 cm/s); S = 4 (U = 1000 cm/s)"
    )
    d = "diverged"
    assert stability_report.boundaries(_panel([[d, b]] * 4), "substeps-wind") == (
        "diverges (NaN/Inf) at every S (U = 0 cm/s); escapes (a point past twice its hanging length, finite) at "
        "every S (U = 1000 cm/s); ok in no cell"
    )
    assert stability_report.boundaries(_panel([[k, k]] * 4), "substeps-wind") == "ok in every cell"
    assert stability_report.boundaries(_panel([[b, b]] * 4), "substeps-wind") == (
        "escapes (a point past twice its hanging length, finite) at every S (every U); ok in no cell"
    )


def test_stability_command_writes_the_map(cpu_bin, tmp_path, capsys):
    """The command end to end on a small grid: CSV, env.json, heatmap and Markdown."""
    out, rep = tmp_path / "res", tmp_path / "rep"
    args = ["stability", "--quick", "--slice", "motion", "--strands", "2", "--frames", "3", "--jobs", "2"]
    assert harness_main([*args, "--gpu", "no", "--out", str(out), "--report-dir", str(rep)]) == 0
    md = (rep / "dynamic_stability.md").read_text()
    assert "### nodding head" in md and "(stability_motion.png)" in md
    assert (rep / "stability_motion.png").stat().st_size > 0
    rows = stability_report.load(out / "stability.csv")
    assert len(rows) == 3 * 3 * 2 * 2 and set(rows["verdict"]) <= set(stability_slices.VERDICTS)
    assert not list(out.glob("*.tmp*")) and not list(rep.glob("*.tmp*"))


def test_a_map_measured_over_two_calls_is_one_map(cpu_bin, tmp_path, capsys):
    """--add: a second call's slice joins the first's in one CSV, in the slices' order, env.json naming
    both calls; its slice measured again replaces its rows; a map of another size is refused, unchanged."""
    out = tmp_path / "res"
    base = ["stability", "--quick", "--strands", "2", "--frames", "3", "--jobs", "2", "--gpu", "no"]
    base += ["--out", str(out), "--report-dir", str(tmp_path / "rep")]
    assert harness_main([*base, "--slice", "motion"]) == 0
    one = stability_report.load(out / "stability.csv")
    assert harness_main([*base, "--slice", "substeps-wind", "--add"]) == 0
    both = stability_report.load(out / "stability.csv")
    assert list(dict.fromkeys(both["slice"])) == ["substeps-wind", "motion"]  # SLICES' order
    assert len(both) > len(one) and (both[both["slice"] == "motion"]["verdict"].tolist() == one["verdict"].tolist())
    env = json.loads((out / "env.json").read_text())
    assert [p["slices"] for p in env["parts"]] == [["motion"], ["substeps-wind"]]
    assert harness_main([*base, "--slice", "motion", "--add"]) == 0  # measured again: replaced, not doubled
    assert len(stability_report.load(out / "stability.csv")) == len(both)
    assert [p["slices"] for p in json.loads((out / "env.json").read_text())["parts"]] == [["substeps-wind"], ["motion"]]
    before = (out / "stability.csv").read_bytes()
    capsys.readouterr()
    assert harness_main([*base[:3], "3", *base[4:], "--slice", "motion", "--add"]) == 2  # 3 strands, not 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "another strands" in err[0]
    assert (out / "stability.csv").read_bytes() == before
    assert harness_main([*base[:-4], "--out", str(tmp_path / "none"), "--slice", "motion", "--add"]) == 2
    (out / "env.json").write_text("{not json")  # a damaged map: one line, nothing written
    capsys.readouterr()
    assert harness_main([*base, "--slice", "motion", "--add"]) == 2
    assert "not valid JSON" in capsys.readouterr().err and (out / "stability.csv").read_bytes() == before


def test_stability_bad_input_is_one_line(tmp_path, capsys):
    assert harness_main(["stability", "--from-csv", str(tmp_path / "none.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("harness: error:")


# ---- regression tests, one per instability the search found -------------------------------
# dynamic_constant_overflow: a derived constant of docs/model.md §3.4 (α/h², c_d·U, κ, A_g,
# −g0) rounded to Inf in the working precision, or a length the model squares (R + c_m, the
# fall of one substep) left its range; the first substep then made NaN in every strand.
# Such scenes are refused now, naming the flags; a neighbour just inside the range runs, and
# a scene refused in fp32 runs in fp64.
SIM = ["--stages", "init,collide,simulate", "--strands", 2, "--points", 8, "--frames", 2]
OVERFLOW = [
    # (id, flags refused, words the message holds, precision, flags of a neighbour that runs)
    (
        "stretch",
        ["--stretch-compliance", "1e36"],
        "--stretch-compliance / h^2",
        "fp32",
        ["--stretch-compliance", "1e30"],
    ),
    (
        "bend-fp64",
        ["--bend-compliance", "1e300", "--frame-dt", "1e-3", "--substeps", 64],
        "--bend-compliance / h^2",
        "fp64",
        ["--bend-compliance", "1e280", "--frame-dt", "1e-3", "--substeps", 64],
    ),
    ("shape", ["--shape-compliance", "1e36"], "--shape-compliance / h^2", "fp32", ["--shape-compliance", "1e34"]),
    (
        "drag-wind",
        ["--drag", "1e30", "--wind-speed", "1e10"],
        "--drag x --wind-speed",
        "fp32",
        ["--drag", "1e30", "--wind-speed", "1e3"],
    ),
    (
        "gust-wavelength",
        ["--drag", "0.5", "--wind-speed", "150", "--gust-amplitude", "0.5", "--gust-wavelength", "1e-40"],
        "2 pi / --gust-wavelength",
        "fp32",
        ["--drag", "0.5", "--wind-speed", "150", "--gust-amplitude", "0.5", "--gust-wavelength", "1e-30"],
    ),
    (
        "gust-amplitude",
        ["--drag", "0.5", "--wind-speed", "150", "--gust-amplitude", "1e39"],
        "--gust-amplitude",
        "fp32",
        ["--drag", "0.5", "--wind-speed", "150", "--gust-amplitude", "1e3"],
    ),
    (
        "wind-times-gust",
        ["--drag", "1e36", "--wind-speed", "100", "--gust-amplitude", "5"],
        "--drag x --wind-speed x (1 + --gust-amplitude)",
        "fp32",
        ["--drag", "1e36", "--wind-speed", "100", "--gust-amplitude", "1"],
    ),
    (
        "gust-phase",
        ["--drag", "0.5", "--wind-speed", "150", "--gust-amplitude", "0.5", "--gust-wavelength", "1e-37"],
        "2 pi / --gust-wavelength x",
        "fp32",
        ["--drag", "0.5", "--wind-speed", "150", "--gust-amplitude", "0.5", "--gust-wavelength", "1e-35"],
    ),
    ("gravity", ["--gravity", "1e39"], "--gravity", "fp32", ["--gravity", "1e5"]),
    ("fall", ["--gravity", "1e30"], "one substep moves a point", "fp32", ["--gravity", "1e30", "--substeps", 100000]),
    ("margin", ["--collision-margin", "1e30"], "--collision-margin", "fp32", ["--collision-margin", "1e17"]),
]


@pytest.mark.parametrize("refused,words,precision,runs", [o[1:] for o in OVERFLOW], ids=[o[0] for o in OVERFLOW])
def test_regression_dynamic_constant_overflow_is_refused(cpu_bin, tmp_path, refused, words, precision, runs):
    out = tmp_path / "s.h5"
    p = run(cpu_bin, *SIM, "--precision", precision, *refused, "--output", out, check=False)
    assert refused_cleanly(p) and words in p.stderr, p.stderr
    assert not out.exists()
    done = runner.COMPLETED  # within the contract may blow up (exit 5): §3.8 allows it
    run(cpu_bin, *SIM, "--precision", precision, *runs, "--velocities", "all", "--output", out, "--quiet", ok=done)
    check_contract(out)
    if precision == "fp32":  # the message's advice: the same scene runs in fp64, within the contract
        assert "--precision fp64" in p.stderr, p.stderr
        wide = tmp_path / "fp64.h5"
        run(cpu_bin, *SIM, "--precision", "fp64", *refused, "--velocities", "all", "--output", wide, "--quiet", ok=done)
        check_contract(wide)


@pytest.mark.parametrize(
    "flags",
    [
        ["--damping", "1e300"],  # 1 + h·β is Inf in fp32: v/Inf = 0, the limit of infinite damping
        ["--points", 2, "--bend-compliance", "1e300"],  # P = 2 has no bend constraint
        ["--shape-compliance", "1e300", "--shape-range", "0.1"],  # K = ⌊0.1·7⌋ = 0 shape constraints
        ["--solver", "ftl", "--stretch-compliance", "1e300"],  # ftl has no stretch constraint
    ],
    ids=["damping", "bend-at-P2", "shape-K0", "ftl-stretch"],
)
def test_regression_dynamic_constant_overflow_unused_constant_is_accepted(cpu_bin, tmp_path, flags):
    """The overflow rule checks only the constants a run evaluates: these overflow fp32 but
    are never used, so they run, within the contract."""
    out = tmp_path / "s.h5"
    run(cpu_bin, *SIM, *flags, "--velocities", "all", "--output", out, "--quiet", ok=runner.COMPLETED)
    check_contract(out)
    if flags[0] == "--damping":  # infinitely damped: no point falls (rounding of the constraints aside)
        with open_trajectory(out) as t:
            moved = np.abs(t.frame(-1).astype(np.float64) - t.frame(t.paper_frames - 1)).max()
        free_fall = 0.5 * 981.0 * (2 / 60) ** 2  # 2 frames of the default gravity and Δt, undamped
        assert moved < 1e-3 * free_fall, moved
