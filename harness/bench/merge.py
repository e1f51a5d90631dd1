"""Shard folders: what `--shard K/N` records (shard.json) and `harness merge OUT SHARD...`,
which joins N shard folders into one results folder.

A shard folder holds shard.json: the shard, the revision, the machine (CPU model, cores,
GPU names), the sweep files' contents (SHA-256) and the command. Merging refuses, in one
line and before writing anything, shards of different revisions, machines, sweeps or
commands, shards of different N, a shard given twice and a missing one. Then every file
under the shards is joined by its relative path:
  - a CSV in several shards: the rows of all of them under the one header (headers must match);
  - a sweep's env.json (with sessions): shard 1's record with every shard's sessions, each
    marked with its shard;
  - validation.json: every shard's comparisons (each node validates before it times);
  - any other file: the first shard's that has it (a study measured once has its files in
    one shard only).
merge.json in OUT names the shards.

A shard records its completeness: shard.json says `finished: false` while it runs and, when its
command ends, `finished: true` with the cases each of its runs.csv holds (`cases`). A merge
refuses, in one line naming the file (and line), a shard that did not finish, one whose runs.csv
lost cases or holds a torn or short row, and a shard.json, env.json or CSV that is damaged."""

import csv
import hashlib
import json
import shutil
from pathlib import Path

from harness import HarnessError
from harness.core import env, inputs
from harness.core.paths import display
from harness.io import files, runfolder
from harness.io.files import write_json
from harness.studies.sweep import machine_of

RECORD = "shard.json"
MATCH = ("revision", "machine", "sweeps", "command")  # what every shard of one run shares


def sweep_digest(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def write_record(folder, shard, sweep_files, command):
    """shard.json in `folder` for a run of `shard` over `sweep_files` (name → path)."""
    host = env.collect()
    cpu, cores, gpus = machine_of(host)
    record = {
        "shard": str(shard),
        "k": shard.k,
        "n": shard.n,
        "revision": host["git_revision"],
        "machine": {"cpu_model": cpu, "cpu_cores": cores, "gpus": list(gpus)},
        "sweeps": {name: sweep_digest(p) for name, p in sorted(sweep_files.items())},
        "command": command,
        "hostname": host["hostname"],
        "date": host["date"],
        "finished": False,
    }
    path = Path(folder) / RECORD
    if path.exists():  # a resumed shard: the same shard of the same run, or refused
        before = _read_record(folder)
        differs = [k for k in ("shard",) + MATCH if before.get(k) != record[k]]
        if differs:
            raise HarnessError(
                f"{display(folder)} holds shard {before.get('shard')} of another run or share "
                f"({', '.join(differs)} differ): give another --out"
            )
    Path(folder).mkdir(parents=True, exist_ok=True)
    write_json(path, record)
    return record


def finish_record(folder):
    """shard.json marked finished, with the cases each runs.csv of the shard holds."""
    path = Path(folder) / RECORD
    record = inputs.read_json(path, "shard")
    record["cases"] = {str(c.relative_to(folder)): len(_case_ids(c)) for c in sorted(Path(folder).rglob("runs.csv"))}
    record["finished"] = True
    record["finished_at"] = env.now()
    write_json(path, record)


def _case_ids(path):
    """The distinct case_id of a runs.csv, every row checked (a torn or short row refused)."""
    header, rows = _csv_rows(path)
    i = header.index("case_id") if "case_id" in header else None
    return {r[i] for r in rows} if i is not None else set()


def _csv_rows(path):
    """A CSV's header and rows; a row of another length than the header (a torn last line) refused
    in one line naming the file and the line."""
    text = inputs.read_text(path, "merge:")
    reader = csv.reader(text.splitlines())
    header = next(reader, None) or []
    rows = []
    for row in reader:
        if len(row) != len(header):
            raise HarnessError(
                f"merge: {display(path)} line {reader.line_num}: {len(row)} fields, its header has {len(header)} "
                "(a torn or short row: the shard did not finish writing it)"
            )
        rows.append(row)
    return header, rows


FIELDS = {"k": int, "n": int, "shard": str, "revision": str, "command": str, "machine": dict, "sweeps": dict}


def _read_record(folder):
    path = Path(folder) / RECORD
    if not path.exists():
        raise HarnessError(f"merge: {display(folder)} is not a shard folder (no {RECORD}; run with --shard K/N)")
    record = inputs.read_json(path, "merge:")
    if not isinstance(record, dict):
        raise HarnessError(f"merge: {display(path)}: not a shard record (a JSON object)")
    for key, kind in FIELDS.items():
        if not isinstance(record.get(key), kind) or isinstance(record.get(key), bool):
            raise HarnessError(f"merge: {display(path)}: '{key}' is missing or not a {kind.__name__}")
    if not 1 <= record["k"] <= record["n"]:
        raise HarnessError(
            f"merge: {display(path)}: k = {record['k']} is not a shard of n = {record['n']} (1 <= k <= n)"
        )
    return record


def _check_complete(folder, record):
    """Refuse a shard that did not finish, or whose runs.csv lost the cases it recorded."""
    where = f"shard {record['k']}/{record['n']} ({display(folder)})"
    if record.get("finished") is not True or not isinstance(record.get("cases"), dict):
        raise HarnessError(
            f"merge: {where} did not finish (its {RECORD} is not marked finished): run it again to its end, it resumes"
        )
    for rel, n in record["cases"].items():
        path = Path(folder) / rel
        if not path.is_file():
            raise HarnessError(f"merge: {where}: {rel} is missing (it held {n} case(s) when the shard finished)")
        have = len(_case_ids(path))
        if have != n:
            raise HarnessError(f"merge: {display(path)} holds {have} case(s); the shard finished with {n}")


def check(records):
    """Refuse (HarnessError, exit 2) shards that do not make one run; the records by K."""
    first_folder, first = records[0]
    for folder, r in records[1:]:
        for key in MATCH + ("n",):
            if r.get(key) != first.get(key):
                raise HarnessError(
                    f"merge: {display(folder)} and {display(first_folder)} differ in {key} "
                    f"({json.dumps(r.get(key))} vs {json.dumps(first.get(key))}): shards of one run only"
                )
    n = first["n"]
    by_k = {}
    for folder, r in records:
        if r["k"] in by_k:
            raise HarnessError(f"merge: shard {r['k']}/{n} given twice ({display(by_k[r['k']][0])}, {display(folder)})")
        by_k[r["k"]] = (folder, r)
    missing = [k for k in range(1, n + 1) if k not in by_k]
    if missing:
        raise HarnessError(f"merge: shard(s) {', '.join(f'{k}/{n}' for k in missing)} missing")
    return [by_k[k] for k in range(1, n + 1)]


def merge(out, folders, log=print):
    """Join the shard folders into OUT (which must not exist or be empty); OUT's path."""
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise HarnessError(f"merge: {display(out)} exists and is not an empty folder: give a new OUT")
    for f in folders:
        if not Path(f).is_dir():
            raise HarnessError(f"merge: {f} is not a folder")
    shards = check([(Path(f), _read_record(f)) for f in folders])
    for folder, record in shards:
        _check_complete(folder, record)
    runfolder.claim(out, "merge", what="merge: OUT")  # locked; not the repository or a folder above it
    found_files = {}
    for k, (folder, _) in enumerate(shards, 1):
        for path in sorted(folder.rglob("*")):
            rel = path.relative_to(folder)
            if (
                path.is_file()
                and rel.parts[0] not in ("report", "_scratch")
                and rel.name != RECORD
                and not rel.name.startswith(".hairbench-run")
            ):
                found_files.setdefault(rel, []).append((k, path))
    out.mkdir(parents=True, exist_ok=True)
    try:
        for rel, found in sorted(found_files.items()):
            target = out / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            if rel.suffix == ".csv" and len(found) > 1:
                _join_csv(target, found)
            elif rel.name == "env.json" and len(found) > 1 and "sessions" in _json(found[0][1]):
                _join_env(target, found)
            elif rel.name == "validation.json" and len(found) > 1:
                _join_validation(target, found)
            else:
                files.copy(found[0][1], target)
        n = len(shards)
        write_json(
            out / "merge.json",
            {"shards": [{"folder": display(f), **r} for f, r in shards], **{k: shards[0][1][k] for k in MATCH}, "n": n},
        )
    except BaseException:
        shutil.rmtree(out, ignore_errors=True)  # nothing partial left
        raise
    log(f"harness: merged {len(shards)} shard(s) into {display(out)}")
    return out


def _json(path):
    record = inputs.read_json(path, "merge:")
    if not isinstance(record, dict):
        raise HarnessError(f"merge: {display(path)}: not a JSON object")
    return record


def _join_csv(target, found):
    """The rows of every shard's CSV; a sweep's `session` column renumbered to the merged
    env.json's sessions (each shard's follow the previous shards')."""
    header, rows, offset = None, [], 0
    for k, path in found:
        h, part = _csv_rows(path)
        if header is None:
            header = h
        elif h != header:
            raise HarnessError(f"merge: {display(path)}: its columns differ from shard 1's")
        sessions = _sessions(path.parent / "env.json")
        if header and "session" in header and sessions is not None:
            i = header.index("session")
            for line, row in enumerate(part, 2):
                if row[i] and not row[i].isdigit():
                    raise HarnessError(f"merge: {display(path)} line {line}: session '{row[i]}' is not a whole number")
                row[i] = str(int(row[i]) + offset) if row[i] else row[i]
            offset += sessions
        rows += part
    files.write_rows(target, header, rows)


def _sessions(env_path):
    """How many sessions a sweep's env.json records (None: not a sweep's)."""
    if not Path(env_path).exists():
        return None
    sessions = _json(env_path).get("sessions")
    if not isinstance(sessions, list):
        raise HarnessError(f"merge: {display(env_path)}: no list of sessions (a sweep's env.json has one)")
    return len(sessions)


def _join_env(target, found):
    record = _json(found[0][1])
    record["sessions"] = []
    for k, path in found:
        for s in _json(path).get("sessions", []):
            record["sessions"].append(dict(s, shard=k))
    record.pop("shard", None)
    record["merged_shards"] = len(found)
    write_json(target, record)


def _join_validation(target, found):
    record = _json(found[0][1])
    record["checks"] = [dict(c, shard=k) for k, path in found for c in _json(path).get("checks", [])]
    write_json(target, record)
