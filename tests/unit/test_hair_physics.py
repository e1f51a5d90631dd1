"""Physical hair (harness/core/hair_physics.py, docs/hair_physics.md): a preset's compliances
recomputed by hand, the scene's [fibre] table, and `python -m harness hair`."""

import math

import pytest

from harness.cli.main import main as harness_main
from harness.core import hair_physics, scenes


def test_thick_straight_recomputed_by_hand():
    """r = 85.9/2 µm, E = 3.89 GPa, ρ = 1.32 g/cm³ on L = 30 cm, P = 32, κ = 1/10.1 cm, by hand:
    ℓ = 30/31 = 0.967742 cm; m = 1.32·π·(42.95e-4)²·ℓ = 7.4030e-5 g; EA = 3.89e10·π·(42.95e-4)²
    = 2.25437e6 dyn, k_s = EA/ℓ = 2.32952e6 dyn/cm; EI = 3.89e10·π·(42.95e-4)⁴/4 = 10.3966 dyn·cm²;
    θ₀ = 2·asin(0.967742/20.2) = 0.0958527 rad, sin²(θ₀/2) = 2.29571e-3, k_b = EI/(ℓ³·2.29571e-3)
    = 4998.0 dyn/cm; α_s = m/k_s = 3.1779e-11 s², α_b = m/k_b = 1.48120e-8 s²."""
    m = hair_physics.mapped(hair_physics.PRESETS["thick-straight"], 30.0, 32, 1 / 10.1)
    assert m.segment == pytest.approx(0.967742, rel=1e-6)
    assert m.mass == pytest.approx(7.4030e-5, rel=1e-4)
    assert m.ea == pytest.approx(2.25437e6, rel=1e-5) and m.k_stretch == pytest.approx(2.32952e6, rel=1e-5)
    assert m.ei == pytest.approx(10.3966, rel=1e-5) and m.turn == pytest.approx(0.0958527, rel=1e-6)
    assert m.k_bend == pytest.approx(4998.0, rel=1e-4)
    assert m.stretch_compliance == pytest.approx(3.1779e-11, rel=1e-4)
    assert m.bend_compliance == pytest.approx(1.48120e-8, rel=1e-4)


def test_the_closed_forms_per_unit_mass():
    """α_s = ρℓ²/E and α_b = 4ρℓ⁴·sin²(θ₀/2)/(E·r²): the radius drops out of α_s, and α_b
    scales as 1/r² (a thicker fibre is stiffer per unit of its mass)."""
    f = hair_physics.PRESETS["fine"]
    m = hair_physics.mapped(f, 20.0, 11, 0.5)
    r, e, ell = f.radius_um * 1e-4, f.youngs_gpa * 1e10, 2.0
    assert m.stretch_compliance == pytest.approx(f.density * ell**2 / e, rel=1e-12)
    sin2 = math.sin(math.asin(ell * 0.5 / 2)) ** 2
    assert m.bend_compliance == pytest.approx(4 * f.density * ell**4 * sin2 / (e * r * r), rel=1e-12)
    thick = hair_physics.mapped(hair_physics.Fibre(2 * f.radius_um, f.youngs_gpa, f.density), 20.0, 11, 0.5)
    assert thick.bend_compliance == pytest.approx(m.bend_compliance / 4, rel=1e-12)
    assert thick.stretch_compliance == pytest.approx(m.stretch_compliance, rel=1e-12)


def test_a_curvature_too_tight_for_the_segments_is_refused():
    with pytest.raises(ValueError, match="does not fit segments"):
        hair_physics.mapped(hair_physics.PRESETS["fine"], 30.0, 4, 1.0)  # ℓ = 10 cm on a 1 cm radius


def write_scene(tmp_path, fibre, extra=""):
    path = tmp_path / "s.toml"
    path.write_text(f'model = "dynamic"\n[fibre]\n{fibre}\n{extra}')
    return str(path)


def test_a_scene_fibre_sets_the_compliances_for_its_strand(tmp_path):
    s = scenes.load_scene(write_scene(tmp_path, 'preset = "thick-straight"'))
    want = hair_physics.mapped(hair_physics.PRESETS["thick-straight"], 30.0, 32, 1 / 10.1)
    assert s.dynamic["--bend-compliance"] == want.bend_compliance
    assert s.dynamic["--stretch-compliance"] == want.stretch_compliance
    fewer = s.with_overrides(points=16)  # another ℓ: the compliances follow
    again = hair_physics.mapped(hair_physics.PRESETS["thick-straight"], 30.0, 16, 1 / 10.1)
    assert fewer.dynamic["--bend-compliance"] == again.bend_compliance


def test_the_curly_groom_takes_its_helix_curvature(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('model = "dynamic"\ngroom = "curly"\nstages = ["init", "simulate"]\n[fibre]\npreset = "fine"\n')
    s = scenes.load_scene(str(path))
    kappa = 1.0 / (1.0 + (2.0 / (2 * math.pi)) ** 2)  # a = 1 cm, pitch 2 cm
    assert (
        s.dynamic["--bend-compliance"]
        == hair_physics.mapped(hair_physics.PRESETS["fine"], 30.0, 32, kappa).bend_compliance
    )


@pytest.mark.parametrize(
    "fibre,extra,message",
    [
        ('preset = "wool"', "", "not known"),
        ("radius_um = 40.0", "", "all needed"),
        ('preset = "fine"', "[constraints]\nbend_compliance = 1e-6\n", "give one or the other"),
        ("radius_um = -3.0", "", "must be > 0"),
    ],
)
def test_a_bad_fibre_is_refused_naming_the_key(tmp_path, fibre, extra, message):
    with pytest.raises(scenes.SceneError, match=message):
        scenes.load_scene(write_scene(tmp_path, fibre, extra))


def test_the_hair_command_prints_the_mapping_and_the_scene_table(capsys):
    assert harness_main(["hair", "--preset", "thick-straight"]) == 0
    out = capsys.readouterr().out
    assert "1.4812e-08 s²" in out and "3.17792e-11 s²" in out and 'preset = "thick-straight"' in out
    assert harness_main(["hair", "--radius-um", "40"]) == 2
    assert "all needed" in capsys.readouterr().err
