"""harness/core/variants.py: the variant names come from the binaries' --list-variants, read
defensively (keys added later are ignored), and a missing binary means no names."""

import json

import pytest

from harness import HarnessError
from harness.core import variants
from harness.io import sweepfile
from support.fakebackend import install


@pytest.fixture
def build_dir(tmp_path, monkeypatch):
    d = tmp_path / "build"
    d.mkdir()
    monkeypatch.setenv("HAIRBENCH_BUILD_DIR", str(d))
    variants.clear_cache()
    yield d
    variants.clear_cache()


def script(path, stdout, rc=0):
    path.write_text(f"#!/bin/sh\ncat <<'EOF'\n{stdout}\nEOF\nexit {rc}\n")
    path.chmod(0o755)


def test_names_come_from_the_fake_binaries(build_dir):
    install(build_dir, ["hairsim-cpu", "hairsim-cuda", "hairsim-cuda-strict"])
    assert variants.names("cpu") == ("ref", "simd")
    strict = variants.declared("cuda", "strict")
    assert strict.build == "strict" and strict.default_variant == "fused"
    assert strict.variants == ("paper", "soa", "fused")


def test_keys_added_later_are_ignored(build_dir):
    listing = {
        "backend": "cpu",
        "build": "default",
        "default_variant": "ref",
        "precisions": ["fp32", "fp64"],
        "solvers": ["pbd"],
        "variants": [
            {"name": "ref", "stages": ["init", "collide", "wind", "simulate"], "summary": "s", "extra": 1},
            {"name": "simd", "stages": ["init"]},
        ],
    }
    script(build_dir / "hairsim-cpu", json.dumps(listing))
    d = variants.declared("cpu")
    assert d.variants == ("ref", "simd") and d.stages["ref"][-1] == "simulate"
    assert d.solvers == ("pbd",) and d.running("simulate") == ("ref",) and d.running("init") == ("ref", "simd")


def test_a_missing_binary_has_no_names_and_sweeps_keep_their_cases(build_dir):
    assert variants.names("cuda") == ()
    with pytest.raises(HarnessError, match="not found: run make"):
        variants.declared("cpu")
    assert sweepfile.known_variants("cuda") == ()


def test_a_binary_that_prints_no_listing_is_one_clear_error(build_dir):
    script(build_dir / "hairsim-cpu", "not json")
    with pytest.raises(HarnessError, match="did not print the documented JSON object"):
        variants.declared("cpu")


def test_sweeps_refuse_a_variant_the_binary_does_not_declare(build_dir):
    install(build_dir, ["hairsim-cpu"])
    assert sweepfile.known_variants("cpu") == ("ref", "simd")
    with pytest.raises(sweepfile.SweepError, match="'fast' is not one of ref, simd"):
        sweepfile._check_axis("sweep.toml", "cpu.variant", ["fast"], "cpu")


def test_the_real_binaries_declare_their_default(cpu_bin, monkeypatch):
    monkeypatch.delenv("HAIRBENCH_BUILD_DIR", raising=False)
    variants.clear_cache()
    d = variants.declared("cpu")
    assert d.backend == "cpu" and d.default_variant in d.variants


def test_a_study_that_draws_the_point_count_runs_a_variant_without_a_point_limit(build_dir):
    listing = {
        "backend": "cuda",
        "build": "default",
        "default_variant": "fused",
        "precisions": ["fp32"],
        "solvers": ["xpbd"],
        "variants": [
            {"name": "fused", "stages": ["init", "collide", "wind"]},
            {"name": "warpreg", "stages": ["init", "simulate"], "max_points": 32},
            {"name": "warp", "stages": ["init", "simulate"]},
        ],
    }
    script(build_dir / "hairsim-cuda", json.dumps(listing))
    assert variants.simulating("cuda") == "warp"
    listing["variants"].pop()
    script(build_dir / "hairsim-cuda", json.dumps(listing))
    variants.clear_cache()
    with pytest.raises(HarnessError, match="declares no variant that simulates any point count"):
        variants.simulating("cuda")


def test_the_features_a_variant_runs_come_from_its_declaration(build_dir):
    """A variant that lists §3.14 features runs only those; one that lists none runs them all."""
    listed = {
        "backend": "cpu",
        "default_variant": "ref",
        "variants": [
            {"name": "ref", "stages": ["simulate"], "features": ["guides", "lra", "sagfree", "lod"]},
            {"name": "simd", "stages": ["simulate"], "features": ["lra", "sagfree", "lod"]},
            {"name": "old", "stages": ["simulate"]},
        ],
    }
    script(build_dir / "hairsim-cpu", json.dumps(listed))
    d = variants.declared("cpu")
    assert d.runs_features("ref", ("guides", "lod")) and d.runs_features("old", ("guides",))
    assert not d.runs_features("simd", ("guides",)) and d.runs_features("simd", ("lra", "lod"))
