"""The command line's shared pieces: the parser that errs in one line, argparse types, the option
groups several commands take, and `command`, which makes a subcommand's parser from its function."""

import argparse
import inspect
import math

from harness import HarnessError
from harness.core.limits import limits
from harness.core.paths import CUDA_BUILDS


class OneLineParser(argparse.ArgumentParser):
    """Usage errors as the binaries print them: one line, exit 2."""

    def error(self, message):
        command = self.prog.split()[3:]  # "python -m harness run" → ["run"]
        self.exit(2, f"harness: error: {' '.join(command + [''])[:-1] + ': ' if command else ''}{message}\n")


def whole(low):
    """An argparse type: a whole number ≥ low, refused in one line otherwise."""

    def parse(text):
        try:
            value = int(text, 10)
        except ValueError:
            raise argparse.ArgumentTypeError(f"needs a whole number (got '{text}')") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be at least {low} (got {value})")
        return value

    return parse


def block_size(text):
    """An argparse type: cuda threads per block, as the binaries' --limits allow them."""
    value = whole(1)(text)
    try:
        why = limits().block_size_error(value)
    except HarnessError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    if why:
        raise argparse.ArgumentTypeError(why)
    return value


def real(name, needs, accept, must):
    """An argparse type named `name`: a float that `accept` takes; otherwise one line, "needs
    NEEDS" for what is not a number and "MUST" for one outside the range."""

    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"needs {needs} (got '{text}')") from None
        if not accept(value):
            raise argparse.ArgumentTypeError(f"{must} (got '{text}')")
        return value

    parse.__name__ = name
    return parse


seconds = real("seconds", "a number of seconds", lambda v: 0 < v < math.inf, "must be a finite number of seconds > 0")
nonneg_seconds = real(
    "nonneg_seconds", "a number of seconds", lambda v: 0 <= v < math.inf, "must be a finite number of seconds ≥ 0"
)
unit_interval = real("unit_interval", "a number in [0, 1]", lambda v: 0.0 <= v <= 1.0, "must lie in [0, 1]")
number = real("number", "a number", math.isfinite, "needs a finite number")
positive = real("positive", "a number", lambda v: 0 < v < math.inf, "must be a finite number > 0")


def options(args, names):
    """The parsed options `names` (space-separated attribute names) as keywords of the same names."""
    return {name: getattr(args, name) for name in names.split()}


FORCE_FOLDER_HELP = "write into a folder that holds files but is not a hairbench run folder (no .hairbench-run.json)"
REPORT_DIR_HELP = "where to write (default results/local/report/)"
GPU_CHOICES = ("auto", "yes", "no")
GPU_HELP = "run cuda cases: auto (if a GPU is usable), yes (fail without), no"


def output_options(p, results=None, report=None, from_csv=None):
    """The output options the commands share, each where its text is given: --out (a results
    directory, `results` its default), --report-dir (`report`: its help) and --from-csv (its help)."""
    if results:
        p.add_argument("--out", default=None, help=f"results directory (default {results})")
    if report:
        p.add_argument("--report-dir", default=None, help=report)
    if from_csv:
        p.add_argument("--from-csv", default=None, help=from_csv)


def case_options(p, jobs=None, gpu=None, timeout=None, gpu_choices=GPU_CHOICES, gpu_default="auto"):
    """How a command runs its cases, each option where its help is given: --jobs (at once),
    --gpu (whether GPU cases run) and --timeout (seconds per binary run)."""
    if jobs:
        p.add_argument("--jobs", type=whole(1), default=None, help=jobs)
    if gpu:
        p.add_argument("--gpu", choices=gpu_choices, default=gpu_default, help=gpu)
    if timeout:
        p.add_argument("--timeout", type=seconds, default=None, help=timeout)


def binary_options(p):
    """Which binary runs and how: --backend, --build, --variant, --threads (cpu) and
    --block-size (cuda), as `run` and `featurecost` take them."""
    p.add_argument("--backend", choices=("cpu", "cuda"), default="cpu")
    p.add_argument(
        "--build",
        choices=tuple(CUDA_BUILDS),
        default="default",
        help="cuda build: hairsim-cuda, -strict or -fastmath (default: default)",
    )
    p.add_argument(
        "--variant",
        help="a variant the binary declares (`hairsim-* --list-variants`; default: the binary's default variant)",
    )
    p.add_argument("--threads", type=whole(1), help="cpu OpenMP threads (default: all cores)")
    p.add_argument("--block-size", type=block_size, help="cuda threads per block, as the binaries' --limits allow")


def command(sub, func, help, description=None, name=None):  # noqa: A002 (argparse's own name)
    """A subcommand's parser that runs func(args): named `name`, else as func (cmd_report_dynamic:
    report-dynamic), and described by `description`, else by func's docstring."""
    name = name or func.__name__.removeprefix("cmd_").replace("_", "-")
    p = sub.add_parser(name, help=help, description=description or inspect.cleandoc(func.__doc__ or "") or None)
    p.set_defaults(func=func)
    return p
