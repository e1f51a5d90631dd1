"""A stand-in `hairsim-cuda` for the dynamic accuracy study's GPU path on a machine without
a GPU: a script that declares a cuda build with one variant that runs `simulate` (and one
that does not) and runs the real C reference for it, so the study's GPU modes, its GPU fp64
reference and that reference's validation against the CPU can be exercised anywhere.

    install(build_dir, cpu_binary, perturb=False)

writes build_dir/hairsim-cpu (a link to the real binary) and build_dir/hairsim-cuda. With
perturb=True the stand-in runs with another gravity (1500 cm/s²): a "GPU" that disagrees
with the CPU, which the study must reject.
"""

import json
import os
import sys
from pathlib import Path

LISTING = {
    "backend": "cuda",
    "build": "default",
    "default_variant": "fused",
    "precisions": ["fp32", "fp64"],
    "variants": [
        {"name": "fused", "stages": ["init", "collide", "wind"], "summary": "stand-in, no simulate"},
        {"name": "strand", "stages": ["init", "collide", "wind", "simulate"], "summary": "stand-in"},
    ],
    "solvers": ["xpbd", "ftl"],
}

SCRIPT = """#!{python}
import os, sys
args = sys.argv[1:]
if "--list-variants" in args:
    print({listing!r})
    sys.exit(0)

def standin(args):
    args = ["ref" if a == "strand" else a for a in args]  # the stand-in's variant is the C reference
    return args + ["--gravity", "1500"] if {perturb!r} else args

if args[:1] == ["--batch"]:  # each run of the batch, as above
    with open(args[1]) as f:
        lines = ["\\t".join(standin(ln.rstrip("\\n").split("\\t"))) for ln in f if ln.strip()]
    path = args[1] + ".standin"  # beside the batch, in its caller's temporary folder
    with open(path, "w") as f:
        f.write("\\n".join(lines) + "\\n")
    args = ["--batch", path]
else:
    args = standin(args)
os.execv({cpu!r}, [{cpu!r}, *args])
"""


def install(build_dir, cpu_binary, perturb=False):
    build_dir = Path(build_dir)
    build_dir.mkdir(parents=True, exist_ok=True)
    cpu = build_dir / "hairsim-cpu"
    if not cpu.exists():
        os.symlink(Path(cpu_binary).resolve(), cpu)
    cuda = build_dir / "hairsim-cuda"
    cuda.write_text(
        SCRIPT.format(python=sys.executable, listing=json.dumps(LISTING), perturb=perturb, cpu=str(cpu.resolve()))
    )
    cuda.chmod(0o755)
    return cuda
