"""Where things live: the repository root, the built binaries, configs/scenes/,
configs/sweeps/, results/, the report folders.

HAIRBENCH_BUILD_DIR overrides the build directory (the tests use it to point the harness
at stand-in binaries)."""

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CONFIGS = ROOT / "configs"
SCENES = CONFIGS / "scenes"  # scene files (docs/model.md §2.6)
SWEEPS = CONFIGS / "sweeps"  # sweep files
MOTIONS = CONFIGS / "motions"  # head transform tracks (docs/interfaces.md, "Motion tracks")
RESULTS = ROOT / "results"
LOCAL_RUN = RESULTS / "local"  # make bench's run folder (untracked; docs/decisions/bench-runs.md)
REPORT = LOCAL_RUN / "report"  # where reports are rendered unless --report-dir says otherwise
REFERENCE_REPORT = ROOT / "report"  # the committed report of the reference run (make report REPORT_TO=report)

# cuda builds: the same source compiled three ways (docs/interfaces.md)
CUDA_BUILDS = {
    "default": "hairsim-cuda",
    "strict": "hairsim-cuda-strict",
    "fastmath": "hairsim-cuda-fastmath",
}


def build_dir():
    return Path(os.environ.get("HAIRBENCH_BUILD_DIR") or ROOT / "build")


def binary_path(backend, build="default"):
    """The binary that runs `backend` ('cpu' or 'cuda') in `build` (cuda only)."""
    if backend == "cpu":
        return build_dir() / "hairsim-cpu"
    if backend == "cuda":
        if build not in CUDA_BUILDS:
            from harness import HarnessError

            raise HarnessError(f"unknown cuda build '{build}' (known: {', '.join(CUDA_BUILDS)})")
        return build_dir() / CUDA_BUILDS[build]
    from harness import HarnessError

    raise HarnessError(f"unknown backend '{backend}' (known: cpu, cuda)")


def display(path):
    """A path as the user would type it: relative to the repo root when inside it."""
    p = Path(path)
    try:
        return str(p.resolve().relative_to(ROOT))
    except ValueError:
        return str(p)


def config_file(ref, directory):
    """A config path as given, or a bare name looked up as `directory`/<name>.toml (SCENES
    or SWEEPS); None if neither."""
    p = Path(ref)
    if p.is_file() or (p.exists() and not p.is_dir()):  # a FIFO or device: read_toml says what it is
        return p
    candidate = Path(directory) / f"{ref}.toml"
    if p.suffix == "" and candidate.is_file():
        return candidate
    return None


def read_toml(path, where, error):
    """A TOML file as a dict; an unreadable or invalid file raises `error` with one line."""
    import tomllib

    from harness import HarnessError
    from harness.core import inputs

    try:
        data = inputs.read_bytes(path, where)
    except HarnessError as e:
        raise error(str(e)) from None
    try:
        return tomllib.loads(data.decode("utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise error(f"{where}: not valid TOML: {e}") from None
    except UnicodeDecodeError as e:
        raise error(f"{where}: not UTF-8 text (byte {e.start}); TOML files are UTF-8") from None
    except (RecursionError, ValueError) as e:  # nested past the parser's depth, an integer past its digits
        raise error(f"{where}: not valid TOML: {type(e).__name__}: {str(e)[:80]}") from None


def output_dir(path, what="--out"):
    """Make the directory `path` (and its parents) for a command's outputs; a path that
    exists and is not a directory, or cannot be made, is refused in one line."""
    from harness import HarnessError

    path = Path(path)
    if path.exists() and not path.is_dir():
        raise HarnessError(f"{what} {path} exists and is not a directory")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise HarnessError(f"{what} {path}: cannot make the directory ({e.strerror or e})") from None
    return path
