"""c_ref/ and cuda/ in layers with one-way includes (docs/decisions/code-layout.md): the
model-free runtime includes only itself, each model only the runtime and itself, the program
(app/) sits above both; in cuda/ the paper and dynamic kernels never include each other. Every
quoted include names one file of the tree, found the way the build's -I folders find it. And no
function outside the CUDA kernels is over 150 lines. Read statically: no compiler needed."""

import pytest

from conftest import ROOT
from support.csource import functions, includes

# each folder's files may include (by quoted path) files of these folders only
ALLOWED = {
    "c_ref/runtime": {"c_ref/runtime"},
    "c_ref/paper": {"c_ref/runtime", "c_ref/paper"},
    "c_ref/dynamic": {"c_ref/runtime", "c_ref/dynamic"},
    "c_ref/simd": {"c_ref/runtime", "c_ref/paper", "c_ref/dynamic", "c_ref/simd"},
    "c_ref/app": {"c_ref/runtime", "c_ref/paper", "c_ref/dynamic", "c_ref/app"},
    "cuda/paper": {"c_ref/runtime", "c_ref/paper", "cuda/shared", "cuda/paper"},
    "cuda/dynamic": {"c_ref/runtime", "c_ref/dynamic", "cuda/shared", "cuda/dynamic"},
    "cuda/draw": {"c_ref/runtime", "c_ref/app", "cuda/shared", "cuda", "cuda/draw"},
}
# cuda/'s top holds the backend and two headers that both models' kernels use
CUDA_SHARED = {"tmath.cuh", "check.cuh"}
LONGEST = 150


def sources():
    c = sorted(p for ext in ("c", "h") for p in (ROOT / "c_ref").rglob(f"*.{ext}"))
    cu = sorted(p for ext in ("cu", "cuh", "h") for p in (ROOT / "cuda").rglob(f"*.{ext}"))
    return c + cu


def folder_of(path):
    rel = path.relative_to(ROOT)
    if rel.parts[0] == "cuda" and len(rel.parts) == 2:
        return "cuda/shared" if rel.name in CUDA_SHARED else "cuda"
    return "/".join(rel.parts[:2]) if len(rel.parts) > 2 else rel.parts[0]


def candidates(path, written):
    """Where the build looks for a quoted include: the file's own folder, then -Ic_ref, then
    (CUDA sources only) -Icuda."""
    roots = [ROOT / "c_ref"] + ([ROOT / "cuda"] if path.relative_to(ROOT).parts[0] == "cuda" else [])
    local = path.parent / written
    found = [r / written for r in roots if (r / written).is_file()]
    return ([local] if local.is_file() else []), found


def resolved_includes():
    out = []
    for path in sources():
        for line, written in includes(path):
            local, found = candidates(path, written)
            out.append((path, line, written, local, found))
    return out


def test_every_include_names_one_file():
    bad = []
    for path, line, written, local, found in resolved_includes():
        where = {p.resolve() for p in local + found}
        if len(where) != 1:
            rel = path.relative_to(ROOT)
            names = sorted(str(p.relative_to(ROOT)) for p in where) or ["nothing"]
            bad.append(f'{rel}:{line}: "{written}" finds {", ".join(names)}')
    assert not bad, "includes that find no file, or more than one:\n" + "\n".join(bad)


def test_includes_run_one_way():
    bad = []
    for path, line, written, local, found in resolved_includes():
        here = folder_of(path)
        allowed = ALLOWED.get(here)
        target = (local + found)[:1]
        if allowed is None or not target:
            continue
        there = folder_of(target[0])
        if there not in allowed:
            bad.append(f'{path.relative_to(ROOT)}:{line}: "{written}" ({there}) from {here}')
    assert not bad, "includes against the layers:\n" + "\n".join(bad)


def test_the_layers_are_checked():
    """The table covers every folder that holds sources but the tops (backends, host checks)."""
    folders = {folder_of(p) for p in sources()}
    assert folders - set(ALLOWED) == {"c_ref", "cuda", "cuda/shared", "cuda/hostcheck"}


@pytest.mark.parametrize("path", sources(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_long_function(path):
    """Kernels (__global__) aside: one job a function, and a job fits on a few screens."""
    long = [f for f in functions(path) if f.lines > LONGEST and "__global__" not in f.header]
    assert not long, ", ".join(f"{f.name} (line {f.line}, {f.lines} lines)" for f in long)


def test_the_scan_finds_functions(tmp_path):
    src = tmp_path / "a.c"
    body = "\n".join(f"    x += {i};" for i in range(LONGEST))
    src.write_text(
        '#include "x.h"\n/* f() { */\nstruct s { int a; };\nstatic const char *t = "{";\n'
        f"static int f(int x)\n{{\n{body}\n    return x;\n}}\n"
        '#define M(a) { a }\nextern "C" {\nint g(void) { return 0; }\n}\n'
    )
    got = {f.name: f.lines for f in functions(src)}
    assert got == {"f": LONGEST + 4, "g": 1}
