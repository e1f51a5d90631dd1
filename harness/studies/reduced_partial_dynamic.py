"""The reduced-model study's rows kept as they are measured (harness/studies/reduced_dynamic.py), so a
run that is stopped (a node's 10-minute limit) loses none of its timings.

After each timing every row so far is written whole to OUT.partial (io/files.py: whole or not at all),
its case named in a first column `case`; beside it OUT.partial.json holds the plan, the code's
revision and the binaries that time the rows. `--resume` keeps the timing columns of the rows there
and measures everything else again (the checked runs, references and metrics are deterministic, and
the references' ladder needs every row); the finished run writes OUT and removes both files. A
partial file timed on another CPU or GPU, with another plan, other binaries or at another revision
is refused in one line: its times would not be this run's."""

import csv
import dataclasses
import io
import json
from pathlib import Path

from harness import HarnessError
from harness.core import env, inputs
from harness.core.paths import display
from harness.io.files import write_csv, write_json

TEXT_FIELDS = ("backend", "variant", "device")  # the timing columns that are not numbers


def partial_path(out):
    """Where a run with --out `out` keeps its rows while it measures."""
    out = Path(out)
    return out.with_name(out.name + ".partial")


def refuse_unfinished(out):
    """A fresh run would write over the rows a stopped one left: refused."""
    path = partial_path(out)
    if path.exists():
        raise HarnessError(
            f"reduced: {display(path)} holds the rows of a run that did not finish: --resume finishes it "
            "(same options), or move it away to start again"
        )


def foreign_row(rows, cpu, gpus):
    """The first row timed on a device that is not this machine's (a cpu row: its CPU `cpu`, as
    env.cpu_device names it; a cuda row: one of its GPUs' names `gpus`), or None."""
    for r in rows:
        here = {cpu} if r["backend"] == "cpu" else set(gpus)
        if r["device"] not in here:
            return r
    return None


def _number(text, field, path):
    if text == "":
        return None
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        raise HarnessError(f"reduced: {display(path)}: '{text}' in column {field} is not a number") from None


class Partial:
    """The partial file of a run with --out `out`, the plan `plan` and the timing binaries `timers`."""

    def __init__(self, out, plan, timers):
        self.path = partial_path(out)
        self.record_path = self.path.with_name(self.path.name + ".json")
        plain = json.loads(json.dumps(dataclasses.asdict(plan)))  # tuples as lists, as read back
        self.record = {"plan": plain, "git_revision": env.git_revision(), "timers": [list(t) for t in timers]}
        self.started = False

    def write(self, fields, rows):
        """Every row so far ((case key, row) pairs), the record beside them first."""
        if not self.started:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            write_json(self.record_path, self.record)
            self.started = True
        write_csv(self.path, ("case", *fields), [{"case": key, **row} for key, row in rows])

    def remove(self):
        self.path.unlink(missing_ok=True)
        self.record_path.unlink(missing_ok=True)

    def kept(self, fields, timing_fields):
        """{case key: {(backend, variant): its timing columns}} of the rows in the partial file, refused
        in one line where there is none or it is not this run's."""
        if not self.path.is_file():
            done = self.path.with_suffix("")
            why = f" ({display(done)} is there: that run finished)" if done.is_file() else ""
            raise HarnessError(f"reduced: --resume: no {display(self.path)} to resume{why}")
        self._check_record(inputs.read_json(self.record_path, "reduced: --resume:"))
        reader = csv.DictReader(io.StringIO(inputs.read_text(self.path, "reduced: --resume:")))
        if reader.fieldnames != ["case", *fields]:
            raise HarnessError(f"reduced: {display(self.path)} does not have the study's columns: move it away")
        rows = list(reader)
        gpus = [g["name"] for g in env.gpu_info() or []]
        bad = foreign_row(rows, env.cpu_device(), gpus)
        if bad is not None:
            here = env.cpu_device() if bad["backend"] == "cpu" else (", ".join(gpus) or "no GPU")
            raise HarnessError(
                f"reduced: {display(self.path)} holds {bad['backend']}/{bad['variant']} timings on {bad['device']}; "
                f"this machine has {here}: resume it there, or move it away to start again"
            )
        out = {}
        for r in rows:
            timing = {f: r[f] if f in TEXT_FIELDS else _number(r[f], f, self.path) for f in timing_fields}
            if timing["median_ms"] is None:
                raise HarnessError(f"reduced: {display(self.path)}: a row without median_ms: move it away")
            out.setdefault(r["case"], {})[(r["backend"], r["variant"])] = timing
        return out

    def _check_record(self, was):
        where = display(self.path)
        if not isinstance(was, dict) or not isinstance(was.get("plan"), dict):
            raise HarnessError(f"reduced: {display(self.record_path)} is not a partial file's record: move both away")
        plan, now = was["plan"], self.record["plan"]
        for k in sorted(set(plan) | set(now)):
            if plan.get(k) != now.get(k):
                raise HarnessError(
                    f"reduced: {where} was measured with another plan ({k} {plan.get(k)} there, {now.get(k)} "
                    "here): give the same options, or move it away to start again"
                )
        if was.get("git_revision") != self.record["git_revision"]:
            raise HarnessError(
                f"reduced: {where} was measured at revision {was.get('git_revision')}, this is "
                f"{self.record['git_revision']}: resume it there, or move it away to start again"
            )
        if was.get("timers") != self.record["timers"]:
            raise HarnessError(
                f"reduced: {where} was timed by other binaries ({_names(was.get('timers'))}; here "
                f"{_names(self.record['timers'])}): resume it where they run, or move it away to start again"
            )


def _names(timers):
    return ", ".join("/".join(map(str, t)) for t in timers or []) or "none"
