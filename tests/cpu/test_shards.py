"""Shards: `harness sweep --shard K/N` runs a deterministic share of the cases and records
shard.json; `harness merge` joins the shard folders. Three shards merged hold the rows of
one unsharded run (the deterministic columns; times differ run to run), and shards that
are not one run's are refused in one line, writing nothing. Tiny CPU sweep: seconds."""

import csv
import json
import os
import subprocess
import sys

import pytest

from conftest import CPU_BIN, ROOT
from harness.core import shards
from support.sweeps import sweep_toml

needs_cpu = pytest.mark.skipif(not CPU_BIN.exists(), reason=f"{CPU_BIN} is not built (run make)")

SWEEP = sweep_toml("shard-t", strands=[40, 80, 120], points=[8], precision=["fp32", "fp64"])
# what a case measures that does not depend on the run (times, dates and sessions do)
DETERMINISTIC = (
    "case_id",
    "stage_index",
    "stage",
    "backend",
    "variant",
    "precision",
    "threads",
    "strands",
    "points",
    "repeat",
    "warmup",
    "skipped",
    "fused",
    "n_times",
    "moved_points",
    "bytes_moved",
)


def harness(*args):
    env = dict(os.environ, HAIRBENCH_NO_GPU="1")
    return subprocess.run(
        [sys.executable, "-m", "harness", *map(str, args)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )


def rows(folder):
    with open(folder / "runs.csv", newline="") as f:
        return sorted(tuple(r[c] for c in DETERMINISTIC) for r in csv.DictReader(f))


def test_the_share_is_round_robin_and_covers_every_case_once():
    items = list(range(10))
    parts = [shards.parse(f"{k}/3").share(items) for k in (1, 2, 3)]
    assert parts == [[0, 3, 6, 9], [1, 4, 7], [2, 5, 8]]
    assert shards.parse("1/1").share(items) == items


@pytest.mark.parametrize("text", ["0/3", "4/3", "3", "a/b", "1/0", "1/2/3", ""])
def test_bad_shards_are_refused(text):
    with pytest.raises(Exception, match="--shard needs K/N") as e:
        shards.parse(text)
    assert e.value.code == 2


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """One unsharded run and its three shards, of the same tiny sweep."""
    if not CPU_BIN.exists():
        pytest.skip(f"{CPU_BIN} is not built (run make)")
    d = tmp_path_factory.mktemp("shards")
    sweep = d / "shard-t.toml"
    sweep.write_text(SWEEP)
    whole = d / "whole"
    p = harness("sweep", sweep, "--out", whole)
    assert p.returncode == 0, p.stdout + p.stderr
    parts = []
    for k in (1, 2, 3):
        part = d / f"part{k}"
        p = harness("sweep", sweep, "--out", part, "--shard", f"{k}/3")
        assert p.returncode == 0, p.stdout + p.stderr
        parts.append(part)
    return d, whole, parts


@needs_cpu
def test_three_shards_merged_equal_one_unsharded_run(runs):
    d, whole, parts = runs
    assert all(rows(p) for p in parts) and len({r[0] for p in parts for r in rows(p)}) == 6
    out = d / "merged"
    p = harness("merge", out, *parts)
    assert p.returncode == 0, p.stdout + p.stderr
    assert rows(out) == rows(whole) and len(rows(whole)) == 6 * 4  # 6 cases × 4 paper stages
    env = json.loads((out / "env.json").read_text())
    assert [s["shard"] for s in env["sessions"]] == [1, 2, 3]
    with open(out / "runs.csv", newline="") as f:  # each row's session is its shard's in the merged record
        assert {r["session"] for r in csv.DictReader(f)} == {"0", "1", "2"}
    record = json.loads((out / "merge.json").read_text())
    assert record["n"] == 3 and [s["shard"] for s in record["shards"]] == ["1/3", "2/3", "3/3"]
    # the merged folder renders like any results folder
    p = harness("report", out, "--report-dir", d / "report")
    assert p.returncode == 0, p.stdout + p.stderr


def edited(src, dst, **changes):
    """A copy of the shard folder src with shard.json's fields changed."""
    import shutil

    shutil.copytree(src, dst)
    rec = json.loads((dst / "shard.json").read_text())
    rec.update(changes)
    (dst / "shard.json").write_text(json.dumps(rec))
    return dst


@needs_cpu
@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("missing", "shard(s) 3/3 missing"),
        ("twice", "shard 2/3 given twice"),
        ("revision", "differ in revision"),
        ("machine", "differ in machine"),
        ("sweep", "differ in sweeps"),
        ("n", "differ in n"),
        ("not a shard", "is not a shard folder"),
    ],
)
def test_merge_refuses_shards_of_other_runs_in_one_line(runs, tmp_path, case, message):
    d, whole, (p1, p2, p3) = runs
    given = {
        "missing": lambda: [p1, p2],
        "twice": lambda: [p1, p2, p2, p3],
        "revision": lambda: [p1, p2, edited(p3, tmp_path / "x", revision="0000000-other")],
        "machine": lambda: [
            p1,
            p2,
            edited(p3, tmp_path / "x", machine={"cpu_model": "other", "cpu_cores": 1, "gpus": []}),
        ],
        "sweep": lambda: [p1, p2, edited(p3, tmp_path / "x", sweeps={"sweep": "0" * 64})],
        "n": lambda: [p1, p2, edited(p3, tmp_path / "x", n=4)],
        "not a shard": lambda: [p1, p2, whole],
    }[case]()
    out = tmp_path / "merged"
    p = harness("merge", out, *given)
    assert p.returncode == 2, p.stdout + p.stderr
    assert message in p.stderr and p.stderr.count("\n") == 1 and "Traceback" not in p.stderr
    assert not out.exists()


@needs_cpu
def test_merge_never_writes_into_an_existing_folder(runs, tmp_path):
    _, _, parts = runs
    out = tmp_path / "taken"
    out.mkdir()
    (out / "mine.txt").write_text("the user's")
    p = harness("merge", out, *parts)
    assert p.returncode == 2 and "exists and is not an empty folder" in p.stderr
    assert [q.name for q in out.iterdir()] == ["mine.txt"]


@needs_cpu
def test_a_folder_of_one_share_is_not_resumed_as_another(runs):
    d, whole, (p1, _, _) = runs
    for folder, shard in ((p1, "2/3"), (whole, "1/3")):
        p = harness("sweep", d / "shard-t.toml", "--out", folder, "--shard", shard)
        assert p.returncode == 2 and "give another --out" in p.stderr and p.stderr.count("\n") == 1
    assert json.loads((p1 / "shard.json").read_text())["shard"] == "1/3"  # its record kept


def damaged(src, dst, damage):
    """A copy of the shard folder src, damaged by damage(folder)."""
    import shutil

    shutil.copytree(src, dst)
    damage(dst)
    return dst


def record_with(**changes):
    def damage(folder):
        rec = json.loads((folder / "shard.json").read_text())
        rec.update(changes)
        for k, v in changes.items():
            if v is None:
                rec.pop(k)
        (folder / "shard.json").write_text(json.dumps(rec))

    return damage


def csv_edit(edit):
    def damage(folder):
        lines = (folder / "runs.csv").read_text().splitlines(keepends=True)
        (folder / "runs.csv").write_text("".join(edit(lines)))

    return damage


def session_abc(lines):
    header = lines[0].rstrip("\n").split(",")
    row = lines[1].rstrip("\n").split(",")
    row[header.index("session")] = "abc"
    return [lines[0], ",".join(row) + "\n", *lines[2:]]


DAMAGE = {  # #46 D13, D14, M8: what a merge met, and the words of its one line
    "record a list": (lambda f: (f / "shard.json").write_text("[1, 2]"), "not a shard record"),
    "record without k": (record_with(k=None), "'k' is missing"),
    "n a string": (record_with(n="3"), "'n' is missing or not a int"),
    "k out of range": (record_with(k=7), "k = 7 is not a shard of n = 3"),
    "record binary": (lambda f: (f / "shard.json").write_bytes(bytes(range(256))), "not UTF-8"),
    "torn last line": (csv_edit(lambda ls: [*ls[:-1], ls[-1][: len(ls[-1]) // 2]]), "runs.csv line"),
    "short row": (csv_edit(lambda ls: [*ls[:2], "a,b\n", *ls[2:]]), "runs.csv line 3"),
    "session abc": (csv_edit(session_abc), "session 'abc'"),
    "env.json binary": (lambda f: (f / "env.json").write_bytes(b"\xff\xfe{"), "env.json"),
    "env.json a list": (lambda f: (f / "env.json").write_text("[]"), "env.json: not a JSON object"),
    "not finished": (record_with(finished=False), "did not finish"),
    "no runs.csv": (lambda f: (f / "runs.csv").unlink(), "runs.csv is missing"),
    "cases lost": (csv_edit(lambda ls: ls[:-4]), "holds 1 case(s); the shard finished with 2"),
}


@needs_cpu
@pytest.mark.parametrize("case", list(DAMAGE))
def test_merge_refuses_a_damaged_or_incomplete_shard_naming_it(runs, tmp_path, case):
    d, whole, (p1, p2, p3) = runs
    damage, words = DAMAGE[case]
    bad = damaged(p3, tmp_path / "bad", damage)
    out = tmp_path / "merged"
    p = harness("merge", out, p1, p2, bad)
    assert p.returncode == 2 and "Traceback" not in p.stderr and p.stderr.count("\n") == 1, p.stderr
    assert words in p.stderr and ("bad" in p.stderr or case in ("k out of range",)), p.stderr
    assert not out.exists()
