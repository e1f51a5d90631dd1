"""Every child the harness starts, and the one way it starts them (docs/interfaces.md).

`run_binary` runs a backend binary with --json and returns its parsed record; `run_batch`
runs many in one process; `run_command` runs any other program (a binary without a record, a
tool such as git or nvidia-smi); `supervised` watches a forked child (a study in its own
session). Every child gets a session and process group of its own and is registered while it
lives: SIGINT, SIGTERM, SIGHUP and SIGQUIT reaching the harness (`forwarding`, around every
command) are forwarded to every registered child's group, the child is waited for, what a
killed binary left is removed (harness/core/tempfiles.py), and the command ends with
128 + n. No child starts once a stop was asked for.

A failure is one HarnessError line naming the binary, its exit status and the last line
it wrote on stderr; exit status 3 (state does not fit in memory) is a `DoesNotFit`, so a
sweep can skip the case and go on.
"""

import contextlib
import json
import multiprocessing
import os
import queue
import signal
import subprocess
import tempfile
import threading
from collections.abc import Generator, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from harness import HarnessError
from harness.core import tempfiles
from harness.core.paths import display

RECORD_KEYS = ("backend", "precision", "strands", "points", "stages")
# exit statuses of a run that ended with its record printed and its file written: 0, and 5 when
# a simulated frame blew up (the record's "blown_up" says so; docs/interfaces.md, "Exit status")
EXIT_BLOWN_UP = 5
COMPLETED = (0, EXIT_BLOWN_UP)


class BackendError(HarnessError):
    """The binary failed or printed something that is not the documented record."""


class DoesNotFit(BackendError):
    """The binary refused the state as too large for memory (its exit status 3)."""


class TimedOut(BackendError):
    """The binary did not finish within the caller's timeout (it was killed); exit status 124,
    as timeout(1) gives, not the 2 of a refusal."""

    def __init__(self, message: str) -> None:
        super().__init__(message, code=124)


class MissingBinary(HarnessError):
    pass


FORWARDED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT)


class Stopped(BaseException):
    """A terminating signal other than SIGINT reached the harness (SIGINT is KeyboardInterrupt):
    raised in the main thread after the signal went to every child; the command exits 128 + n."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


_live: dict[int, Any] = {}  # pid → the child (a Popen or a forked process), while it runs
_lock = threading.Lock()
_stopping: list[int] = []  # the signal that asked for the stop, once one did


def _forward(signum: int) -> None:
    """The signal to every live child's process group (the child itself where it has none yet)."""
    with _lock:
        pids = list(_live)
    for pid in pids:
        try:
            os.killpg(pid, signum)
        except (ProcessLookupError, PermissionError):
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(pid, signum)


def _on_signal(signum: int, frame: Any) -> None:
    _stopping.append(signum)
    _forward(signum)
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise Stopped(signum)


def _worker_signals() -> None:
    """A forked pool worker's signals: Ctrl-C ignored (its parent ends it), the others at their
    defaults (the pool's terminate ends it without a traceback), then unblocked."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for s in FORWARDED[1:]:
        signal.signal(s, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, FORWARDED)


def fork_pool(jobs: int) -> Any:
    """A multiprocessing pool of `jobs` forked workers that take no part in the command's signal
    handling (forwarding()): the signals are blocked across the fork, so none reaches a worker
    before its handlers are reset."""
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, FORWARDED)
    try:
        return multiprocessing.get_context("fork").Pool(jobs, _worker_signals)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


@contextlib.contextmanager
def forwarding() -> Iterator[None]:
    """Around a command (harness/cli/main.py): the four signals forwarded to the children and
    raised here (KeyboardInterrupt, Stopped). In the main thread only; elsewhere a no-op."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.getsignal(s) for s in FORWARDED}
    for s in FORWARDED:
        if previous[s] != signal.SIG_IGN:  # a signal the caller ignores stays ignored (nohup)
            signal.signal(s, _on_signal)
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h if h is not None else signal.SIG_DFL)


def reset_after_fork() -> None:
    """In a forked child: its parent's children are not its own."""
    with _lock:
        _live.clear()
    _stopping.clear()


def _check_not_stopping() -> None:
    if _stopping:
        if _stopping[0] == signal.SIGINT:
            raise KeyboardInterrupt
        raise Stopped(_stopping[0])


def spawn(cmd: Sequence[str], **kw: Any) -> subprocess.Popen[Any]:
    """A child in a session of its own, registered until `reap`; OSError as from Popen."""
    _check_not_stopping()
    child = subprocess.Popen(list(cmd), start_new_session=True, **kw)
    with _lock:
        _live[child.pid] = child
    if _stopping:  # a signal came between the check and the registration
        _forward(_stopping[0])
    return child


GRACE_S = 10.0  # how long a child that was forwarded a stop signal has to remove its files and die of it


def reap(child: Any, kill: bool = False) -> None:
    """Wait for a registered child (killed first, with its group, when `kill`; after a stop
    signal was forwarded to it, only once GRACE_S has passed), then forget it."""
    if kill and _stopping:
        with contextlib.suppress(subprocess.TimeoutExpired):
            child.wait(GRACE_S)
    if kill and child.poll() is None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(child.pid, signal.SIGKILL)
        with contextlib.suppress(ProcessLookupError):
            child.kill()
    child.wait()
    with _lock:
        _live.pop(child.pid, None)


@contextlib.contextmanager
def supervised(process: Any) -> Iterator[None]:
    """A forked child (multiprocessing.Process, started, in a session of its own) registered
    while the block runs, so that a signal reaching the harness reaches it; on any exit from
    the block by an exception it is waited for, and killed if it outlives a grace period."""
    with _lock:
        _live[process.pid] = process
    try:
        yield
    except BaseException:
        process.join(30)
        if process.is_alive():
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(process.pid, signal.SIGKILL)
            process.join()
        raise
    finally:
        with _lock:
            _live.pop(process.pid, None)


def run_command(
    cmd: Sequence[Any],
    timeout: float | None = None,
    env: dict[str, str] | None = None,
    cwd: str | Path | None = None,
) -> subprocess.CompletedProcess[str]:
    """Any program other than a JSON record's run (a binary's stepped run, a tool): its
    CompletedProcess (text, stdout and stderr captured). A timeout kills it and raises TimedOut;
    a binary's temporaries of --output are removed when it died of a signal or was killed;
    OSError when it cannot start."""
    words = [str(c) for c in cmd]
    child = spawn(words, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=cwd)
    try:
        stdout, stderr = child.communicate(timeout=timeout)
    except BaseException as e:
        reap(child, kill=True)
        tempfiles.remove_left_by(child.pid, tempfiles.output_dirs(words))
        if isinstance(e, subprocess.TimeoutExpired):
            raise TimedOut(f"{Path(words[0]).name} did not finish within {timeout} s: {' '.join(words[1:])}") from None
        raise
    reap(child)
    if child.returncode < 0:
        tempfiles.remove_left_by(child.pid, tempfiles.output_dirs(words))
        _check_not_stopping()
    return subprocess.CompletedProcess(words, child.returncode, stdout, stderr)


def require_binary(path: str | Path) -> Path:
    path = Path(path)
    if not path.exists():
        raise MissingBinary(f"{display(path)} not found: run make")
    return path


def last_line(text: str) -> str:
    lines = [ln for ln in (text or "").strip().splitlines() if ln.strip()]
    return lines[-1].strip() if lines else ""


def run_binary(
    binary: str | Path,
    args: Sequence[Any],
    timeout: float | None = None,
    expect_keys: Iterable[str] = RECORD_KEYS,
    env: dict[str, str] | None = None,
) -> dict[str, Any]:
    """Run `binary args… --json --quiet` (`env`: added to the environment); return the JSON
    object it prints."""
    binary = require_binary(binary)
    cmd = [str(binary), *map(str, args), "--json", "--quiet"]
    child_env = dict(os.environ, **env) if env else None
    try:
        proc = run_command(cmd, timeout=timeout, env=child_env)
    except OSError as e:
        raise BackendError(f"cannot run {display(binary)}: {e.strerror}") from None
    if proc.returncode == -signal.SIGINT:
        raise KeyboardInterrupt
    if proc.returncode not in COMPLETED:
        why = last_line(proc.stderr) or last_line(proc.stdout) or "no message"
        cls = DoesNotFit if proc.returncode == 3 else BackendError
        raise cls(f"{binary.name} exited with status {proc.returncode}: {why}", code=proc.returncode)
    return parse_record(binary, proc.stdout, expect_keys)


def parse_record(binary: Path, text: str, expect_keys: Iterable[str] = RECORD_KEYS) -> dict[str, Any]:
    """The JSON record a run printed, checked for the documented keys."""
    try:
        record = json.loads(text)
    except json.JSONDecodeError:
        raise BackendError(f"{binary.name} printed no JSON record on stdout (got: {last_line(text)[:120]!r})") from None
    if not isinstance(record, dict):
        raise BackendError(f"{binary.name} printed JSON that is not an object")
    missing = [k for k in expect_keys if k not in record]
    if missing:
        raise BackendError(f"{binary.name}: JSON record lacks {', '.join(missing)} (docs/interfaces.md)")
    return record


BATCH_MAX = 32  # runs one batch process holds at most


def batches(items: Iterable[Any], key: Any, size: int) -> list[list[Any]]:
    """`items` grouped by key(item) (one binary, one GPU), each group cut into runs of at most
    `size`, in the order the groups first appear."""
    groups: dict[Any, list[Any]] = {}
    for it in items:
        groups.setdefault(key(it), []).append(it)
    return [g[i : i + size] for g in groups.values() for i in range(0, len(g), size)]


def run_batch(
    binary: str | Path,
    runs: Sequence[Sequence[Any]],
    timeout: float | None = None,
    expect_keys: Iterable[str] = RECORD_KEYS,
    env: dict[str, str] | None = None,
) -> Iterator[tuple[int, dict[str, Any] | None, BackendError | None]]:
    """Each argument list of `runs` as run_binary would run it, but all in one process
    (`binary --batch FILE`, docs/interfaces.md "Batches"), so that a GPU's context is made
    once. Yields (index, record, error) in order as each run ends: `error` is what
    run_binary would raise for that run. The process ends at a run that fails; the runs after
    it go on in a new one. `timeout`: for each run."""
    binary = require_binary(binary)
    start = 0
    while start < len(runs):
        start = yield from _one_batch(binary, runs, start, timeout, expect_keys, env)


def _one_batch(
    binary: Path,
    runs: Sequence[Sequence[Any]],
    start: int,
    timeout: float | None,
    expect_keys: Iterable[str],
    env: dict[str, str] | None,
) -> Generator[tuple[int, dict[str, Any] | None, BackendError | None], None, int]:
    """Runs runs[start:] in one process until one fails; returns the index to go on from."""
    lines = []
    for args in runs[start:]:
        words = [*map(str, args), "--json", "--quiet"]
        if any(c in w for w in words for c in "\t\n\r"):
            raise HarnessError(f"{binary.name}: a batched run's flags hold a tab or a line break: {' '.join(words)}")
        lines.append("\t".join(words))
    child_env = dict(os.environ, **env) if env else None
    with tempfile.TemporaryDirectory(prefix="hairbench-batch-") as tmp:
        batch = Path(tmp) / "runs.txt"
        batch.write_text("\n".join(lines) + "\n")
        with open(Path(tmp) / "stderr.txt", "w+") as err:
            try:
                child = spawn(
                    [str(binary), "--batch", str(batch)], stdout=subprocess.PIPE, stderr=err, text=True, env=child_env
                )
            except OSError as e:
                raise BackendError(f"cannot run {display(binary)}: {e.strerror}") from None
            out: queue.Queue[str | None] = queue.Queue()

            def read() -> None:
                assert child.stdout is not None
                for line in child.stdout:
                    out.put(line)
                out.put(None)

            reader = threading.Thread(target=read, name=f"{binary.name} batch", daemon=True)
            reader.start()
            i = start
            try:
                while i < len(runs):
                    try:
                        line = out.get(timeout=timeout)
                    except queue.Empty:
                        _kill(child, runs[i])
                        cmd = " ".join(map(str, runs[i]))
                        yield i, None, TimedOut(f"{binary.name} did not finish within {timeout} s: {cmd}")
                        return i + 1
                    if line is None:
                        break
                    try:
                        record, error = parse_record(binary, line, expect_keys), None
                    except BackendError as e:
                        record, error = None, e
                    yield i, record, error
                    i += 1
                    if error is not None:
                        _kill(child, runs[i - 1])
                        return i
                reap(child)
                rc = child.returncode
            except BaseException:  # an interrupt, or the caller stopped early: the child dies
                _kill(child, runs[i] if i < len(runs) else [])
                raise
            finally:
                reader.join(timeout=5)
            if i == len(runs) and rc in COMPLETED:
                return i
            if rc < 0:
                _check_not_stopping()
            if rc == -signal.SIGINT:
                raise KeyboardInterrupt
            if rc < 0:
                tempfiles.remove_left_by(child.pid, tempfiles.output_dirs(runs[i]))
            err.seek(0)
            why = last_line(err.read()) or "no message"
            if rc == 0:
                why = "printed fewer records than it had runs"
            cls = DoesNotFit if rc == 3 else BackendError
            yield i, None, cls(f"{binary.name} exited with status {rc}: {why}", code=rc)
            return i + 1


def _kill(child: subprocess.Popen[str], args: Sequence[Any]) -> None:
    """End a batch's process and remove what its current run left."""
    reap(child, kill=True)
    tempfiles.remove_left_by(child.pid, tempfiles.output_dirs(args))


def run_flags(
    scene: Any,
    backend: str,
    variant: str | None = None,
    block_size: int | None = None,
    threads: int | str | None = None,
    repeat: int | None = None,
    warmup: int | None = None,
    output: str | Path | None = None,
    force: bool = False,
    input_file: str | Path | None = None,
    stages: Sequence[str] | None = None,
) -> list[str]:
    """Backend flags for a scene and run options. With input_file, the geometry comes
    from the file and only the wind flags and the stages are passed."""
    if input_file:
        flags = [
            "--input",
            str(input_file),
            "--wind-strength",
            repr(scene.wind_strength),
            "--wind-angle",
            repr(scene.wind_angle),
        ]
        flags += ["--stages", ",".join(stages or scene.stages)]
    else:
        flags = scene.flags()
        if stages:
            i = flags.index("--stages")
            flags[i + 1] = ",".join(stages)
    if variant:
        flags += ["--variant", variant]
    if backend == "cuda" and block_size:
        flags += ["--block-size", str(block_size)]
    if backend == "cpu" and threads:
        flags += ["--threads", str(threads)]
    if repeat:
        flags += ["--repeat", str(repeat)]
    if warmup is not None:
        flags += ["--warmup", str(warmup)]
    if output:
        flags += ["--output", str(output)]
        if force:
            flags.append("--force")
    return flags


def summary(record: dict[str, Any]) -> str:
    """A short human table of a record's stage times."""
    where = (
        f"block size {record.get('block_size')}"
        if record.get("backend") == "cuda"
        else f"{record.get('threads')} thread(s)"
    )
    lines = [
        f"{record.get('backend')}/{record.get('variant')} {record.get('precision')}: "
        f"{record.get('strands')} strands × {record.get('points')} points, {where}, "
        f"repeat {record.get('repeat')}, on {record.get('device')}"
    ]
    lines.append(f"{'frame':>5} {'stage':8} {'median ms':>10} {'min ms':>10} {'max ms':>10} {'moved':>8}  note")
    for s in record.get("stages", []):
        note = "skipped (nil effect)" if s.get("skipped") else (s.get("fused") or "")
        moved = s.get("moved_points")
        lines.append(
            f"{s.get('frame', ''):>5} {s.get('stage', ''):8} {s.get('median_ms', 0):10.3f} "
            f"{s.get('min_ms', 0):10.3f} {s.get('max_ms', 0):10.3f} "
            f"{'' if moved is None else moved:>8}  {note}"
        )
    for key in ("end_to_end_ms", "h2d_ms", "d2h_ms", "hdf5_write_ms"):
        if record.get(key) is not None:
            lines.append(f"{key}: {record[key]:.3f}")
    if record.get("output"):
        lines.append(f"wrote {record['output']}")
    return "\n".join(lines)
