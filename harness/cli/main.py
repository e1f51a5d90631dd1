"""`python -m harness COMMAND …`: the command line of the hairbench harness.

Commands: run, diff, stepdiff, sweep, plot, report, report-dynamic, bench, merge, compare, accuracy, headline,
export, groom, motion, calibrate, analytic, featurecost, reduced, peer, animate, render, stability, judge, budget, hair,
docs (`--help` on each; docs/harness.md lists them). User errors print one line
`harness: error: …` and exit non-zero, never a traceback."""

import os
import sys

from harness import HarnessError, __version__
from harness.cli.commands import accuracy, bench, files, pictures, results, runs, studies
from harness.cli.options import OneLineParser, command
from harness.core import interrupts


def cmd_docs(args):
    """Remake the command and module reference of docs/harness.md from this parser and the modules' docstrings
    (what `make docs` runs); --check only says whether it is current (exit 1 if not)."""
    from harness.cli import docs

    return docs.run(parser(), check=args.check)


def add_docs(sub):
    dc = command(sub, cmd_docs, help="remake docs/harness.md's command and module reference")
    dc.add_argument("--check", action="store_true", help="write nothing; exit 1 when the page is out of date")


# the subcommands in the order --help lists them
COMMANDS = (
    runs.add_run,
    runs.add_stepdiff,
    runs.add_diff,
    results.add_sweep,
    results.add_plot_and_report,
    results.add_report_dynamic,
    bench.add_bench,
    results.add_merge,
    results.add_compare,
    accuracy.add_accuracy,
    accuracy.add_headline,
    files.add_export,
    files.add_groom,
    studies.add_budget,
    studies.add_hair,
    files.add_motion,
    studies.add_calibrate,
    studies.add_analytic,
    studies.add_featurecost,
    studies.add_world,
    studies.add_reduced,
    studies.add_peer,
    pictures.add_animate,
    pictures.add_render,
    studies.add_stability,
    studies.add_judge,
    add_docs,
)


def parser():
    p = OneLineParser(
        prog="python -m harness",
        description="hairbench harness: run, diff, sweep, plot and report the hair-strand backends (docs/harness.md)",
    )
    p.add_argument("--version", action="version", version=f"hairbench harness {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for add in COMMANDS:
        add(sub)
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    from harness.core import gpus, runner
    from harness.io import runfolder

    try:
        gpus.wanted()  # a bad HB_GPUS is refused on every machine, with or without a GPU
        with runner.forwarding(), interrupts.redelivered():
            try:
                rc = args.func(args)
            except SystemError as e:  # a signal's exception raised inside a C extension's callback
                signalled = interrupts.signal_cause(e, (KeyboardInterrupt, runner.Stopped))
                if signalled is None:
                    raise
                raise signalled from None
            sys.stdout.flush()  # a closed pipe shows here, inside the handlers below
        return rc
    except runner.Stopped as e:  # forwarded to every child, each waited for: nothing runs on
        runfolder.abandon_unused()
        print(f"harness: stopped by {e}", file=sys.stderr)
        return 128 + e.signum
    except HarnessError as e:  # one line, whatever a library's text it quotes holds
        runfolder.abandon_unused()  # a refused command creates nothing
        print(f"harness: error: {' '.join(str(e).split(chr(10)))}", file=sys.stderr)
        return e.code if e.code else 2
    except BrokenPipeError:  # the reader went away (`| head`): quiet, as other tools
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit
        return 141
    except OSError as e:  # a path given that cannot be read or written, or a full disk: no traceback
        where = f"{e.filename}: " if e.filename else ""
        print(f"harness: error: {where}{e.strerror or e}", file=sys.stderr)
        return (
            2
            if isinstance(
                e, (FileNotFoundError, FileExistsError, IsADirectoryError, NotADirectoryError, PermissionError)
            )
            else 4
        )
    except KeyboardInterrupt:
        print("harness: interrupted", file=sys.stderr)
        return 130
