"""`python -m harness animate` (harness/bench/animate_dynamic.py, drawn by
harness/render/animation_dynamic.py): a tiny dynamic state becomes a GIF with the frames the docs
promise (the rest frame, then every K-th simulated frame); bad input is one line, exit status 2, and
no file (nor a temporary one) left behind."""

import pytest
from PIL import Image

from harness.cli.main import main as harness_main
from support.statecheck import run, tmp_leftovers

FRAMES = 5


@pytest.fixture(scope="module")
def tiny_state(cpu_bin, tmp_path_factory):
    d = tmp_path_factory.mktemp("anim")
    path = d / "tiny.h5"
    run(
        cpu_bin,
        "--strands",
        "4",
        "--points",
        "6",
        "--hair-length",
        "5",
        "--stages",
        "init,collide,simulate",
        "--frames",
        FRAMES,
        "--substeps",
        "2",
        "--head-motion",
        "nod",
        "--output",
        path,
    )
    return path


@pytest.mark.parametrize("every,expected", [(1, 1 + FRAMES), (2, 1 + FRAMES // 2)])
def test_tiny_state_gives_a_gif_with_the_expected_frames(tiny_state, tmp_path, capsys, every, expected):
    gif = tmp_path / "a.gif"
    assert harness_main(["animate", str(tiny_state), "--out", str(gif), "--every", str(every)]) == 0
    with Image.open(gif) as im:
        assert im.format == "GIF" and im.n_frames == expected
        assert im.size[0] > 2 * 200 and im.size[1] > 200  # two panels side by side
    assert f"{expected} frames" in capsys.readouterr().out
    assert tmp_leftovers(tmp_path) == []


def _refused(capsys, argv, words):
    try:
        code = harness_main(argv)
    except SystemExit as e:  # argparse's refusals
        code = e.code
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("harness: error: ") and words in err[0], err
    assert "Traceback" not in err[0]


def test_not_a_state_is_refused_without_output(tmp_path, capsys):
    bad = tmp_path / "bad.h5"
    bad.write_text("not an HDF5 file\n")
    gif = tmp_path / "a.gif"
    _refused(capsys, ["animate", str(bad), "--out", str(gif)], "bad.h5")
    assert not gif.exists() and tmp_leftovers(tmp_path) == []


def test_paper_state_is_refused_without_output(cpu_bin, tmp_path, capsys):
    paper = tmp_path / "paper.h5"
    run(cpu_bin, "--strands", "3", "--points", "4", "--hair-length", "5", "--output", paper)
    gif = tmp_path / "a.gif"
    _refused(capsys, ["animate", str(paper), "--out", str(gif)], "paper-model state")
    assert not gif.exists()


def test_existing_output_is_kept_unless_forced(tiny_state, tmp_path, capsys):
    gif = tmp_path / "a.gif"
    gif.write_bytes(b"keep me")
    _refused(capsys, ["animate", str(tiny_state), "--out", str(gif)], "exists (use --force")
    assert gif.read_bytes() == b"keep me"
    assert harness_main(["animate", str(tiny_state), "--out", str(gif), "--force"]) == 0
    assert gif.read_bytes()[:3] == b"GIF"


@pytest.mark.parametrize(
    "args,words",
    [(["--out", "{tmp}/x.png"], "must name a .gif"), (["--every", "0", "--out", "{tmp}/x.gif"], "at least 1")],
)
def test_bad_options_are_refused(tiny_state, tmp_path, capsys, args, words):
    _refused(capsys, ["animate", str(tiny_state), *[a.format(tmp=tmp_path) for a in args]], words)
    assert list(tmp_path.iterdir()) == []
