"""Usable defaults (docs/interfaces.md, "Defaults" and "Exit status"): a new simulation with no
physics flag says in one line that the bare defaults are not a tuned setting, and a run whose
simulation blew up says so in its exit status (5) and its record, alone and in a batch, and
still writes its file."""

import json
import subprocess

from harness.core import runner

# the example: curly hair on the binary's bare defaults (S = I = 1, no bend or shape)
BARE = ["--groom", "curly", "--strands", "60", "--points", "32", "--stages", "init,simulate", "--frames", "30"]
NOTE = "note: no physics flag given"


def run(binary, *args):
    return subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True, timeout=120)


def test_bare_defaults_are_named_once_and_blow_up_with_exit_status_5(cpu_bin, tmp_path):
    out = tmp_path / "bare.h5"
    p = run(cpu_bin, *BARE, "--output", out, "--json")
    assert p.returncode == runner.EXIT_BLOWN_UP, p.stderr
    notes = [ln for ln in p.stderr.splitlines() if NOTE in ln]
    assert len(notes) == 1 and "configs/scenes/dynamic.toml" in notes[0]
    assert json.loads(p.stdout)["blown_up"] is True
    assert out.exists()  # the file is complete: the blow-up is in it for the user to see
    assert "BLOWN UP" in p.stderr and "exit status 5" in p.stderr


def test_a_declared_setting_or_quiet_run_has_no_note(cpu_bin):
    tuned = run(cpu_bin, *BARE[:-2], "--frames", "3", "--substeps", "8", "--bend-compliance", "1e-6")
    assert tuned.returncode == 0 and NOTE not in tuned.stderr
    quiet = run(cpu_bin, *BARE[:-2], "--frames", "1", "--quiet")
    assert NOTE not in quiet.stderr
    paper = run(cpu_bin, "--strands", "50")  # no simulate stage: nothing to say
    assert paper.returncode == 0 and NOTE not in paper.stderr


def test_a_resumed_simulation_keeps_its_physics_without_a_note(cpu_bin, tmp_path):
    first = tmp_path / "a.h5"
    assert run(cpu_bin, *BARE[:-2], "--frames", "2", "--substeps", "4", "--output", first).returncode == 0
    resumed = run(cpu_bin, "--input", first, "--stages", "simulate", "--frames", "1")
    assert resumed.returncode == 0 and NOTE not in resumed.stderr


def test_a_blown_up_run_does_not_end_a_batch_and_the_batch_exits_5(cpu_bin, tmp_path):
    small = ["--strands", "50", "--points", "8"]
    runs = [small, BARE, small]
    batch = tmp_path / "runs.txt"
    batch.write_text("".join("\t".join([*r, "--json", "--quiet"]) + "\n" for r in runs))
    p = run(cpu_bin, "--batch", batch)
    assert p.returncode == runner.EXIT_BLOWN_UP, p.stderr
    records = [json.loads(ln) for ln in p.stdout.splitlines()]
    assert [r["blown_up"] for r in records] == [False, True, False]
    ended = list(runner.run_batch(cpu_bin, runs, timeout=120))  # the harness takes it as three good runs
    assert [i for i, _, _ in ended] == [0, 1, 2] and all(e is None for _, _, e in ended)
