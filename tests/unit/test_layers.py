"""harness/ in layers with one-way imports: no import cycle inside the package (imports inside
functions count), each layer imports only itself and the layers below it, and no renderer
reaches the runner (the one module that starts a binary); below render/ nothing makes Markdown,
and a renderer compares nothing with a tolerance (#47: measuring, deciding and drawing apart).
Read statically with ast, so an import hidden in a function cannot slip through."""

import ast
import re

import pytest

from conftest import ROOT

PACKAGE = ROOT / "harness"
# bottom to top; the package root (HarnessError, __version__) sits under all of them
LAYERS = ("core", "io", "check", "studies", "render", "bench", "cli")
RUNNER = "harness.core.runner"


def module_name(path):
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def package_modules():
    return {module_name(p): p for p in PACKAGE.rglob("*.py")}


def imports_of(name, path, modules):
    """The package modules `name` imports, anywhere in its file (line numbers for messages)."""
    is_package = path.name == "__init__.py"
    here = name.split(".") if is_package else name.split(".")[:-1]
    found = {}
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(here[: len(here) - node.level + 1] + ([base] if base else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
        else:
            continue
        for t in targets:
            # `import harness.a.b` also runs harness.a's __init__: count the deepest module named
            while t and t not in modules:
                t = t.rpartition(".")[0]
            if t and t != name:
                found.setdefault(t, node.lineno)
    return found


def import_graph():
    modules = package_modules()
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def cycles(graph):
    """The strongly connected components of more than one module (Tarjan), or a module that
    imports itself."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def reaches(graph, start, target):
    """The import chain from start to target, or None."""
    seen, todo = {start: None}, [start]
    while todo:
        v = todo.pop()
        if v == target:
            chain = []
            while v is not None:
                chain.append(v)
                v = seen[v]
            return chain[::-1]
        for w in graph[v]:
            if w not in seen:
                seen[w] = v
                todo.append(w)
    return None


def layer(name):
    parts = name.split(".")
    return LAYERS.index(parts[1]) if len(parts) > 1 and parts[1] in LAYERS else -1


def module_file(tmp_path, source):
    """A module m.py holding source, for the checks' own known-answer tests."""
    path = tmp_path / "m.py"
    path.write_text(source)
    return path


def test_every_module_is_in_a_layer():
    loose = [n for n in package_modules() if layer(n) < 0 and n not in ("harness", "harness.__main__")]
    assert not loose, f"modules outside the layers {LAYERS}: {loose}"


def test_no_import_cycle_in_harness():
    found = cycles(import_graph())
    assert not found, f"import cycles in harness/: {found}"


def test_layers_import_downwards_only():
    graph = import_graph()
    upward = [
        f"{m} (line {line}) imports {t}"
        for m, targets in graph.items()
        for t, line in targets.items()
        if m != "harness.__main__" and layer(t) > layer(m)
    ]
    assert not upward, "imports of a higher layer:\n" + "\n".join(upward)


def test_renderers_never_reach_the_runner():
    """No renderer measures: none reaches the runner, except through harness.core.variants, which
    asks a binary for its declarations (--list-variants), and harness.core.encode, which has
    ffmpeg encode frames already drawn: through the runner like every child, measuring nothing."""
    graph = import_graph()
    graph = {m: ({} if m in ("harness.core.variants", "harness.core.encode") else t) for m, t in graph.items()}
    render = [m for m in graph if m.startswith("harness.render")]
    assert render, "no module under harness/render"
    chains = [" -> ".join(c) for m in render if (c := reaches(graph, m, RUNNER))]
    assert not chains, "renderers that import the runner:\n" + "\n".join(chains)


def test_the_checks_see_a_hidden_cycle(tmp_path):
    """The graph counts an import inside a function, and finds the cycle it closes."""
    modules = {"harness.a": tmp_path / "a.py", "harness.b": tmp_path / "b.py"}
    modules["harness.a"].write_text("from harness import b\n")
    modules["harness.b"].write_text("def f():\n    from . import a\n    return a\n")
    graph = {n: imports_of(n, p, modules) for n, p in modules.items()}
    assert graph["harness.b"] == {"harness.a": 2}
    assert cycles(graph) == [["harness.a", "harness.b"]]
    assert reaches(graph, "harness.b", "harness.a") == ["harness.b", "harness.a"]


@pytest.mark.parametrize("command", ["report", "report-dynamic", "plot"])
def test_rendering_commands_live_in_render(command):
    """The rendering commands call only harness.render (and the paths they print)."""
    graph = import_graph()
    name = f"cmd_{command.replace('-', '_')}"
    trees = [ast.parse(p.read_text()) for p in sorted((PACKAGE / "cli" / "commands").glob("*.py"))]
    func = next(f for tree in trees for f in tree.body if isinstance(f, ast.FunctionDef) and f.name == name)
    used = {n.module for n in ast.walk(func) if isinstance(n, ast.ImportFrom)}
    assert used and all(m in ("harness.render", "harness.core.paths") for m in used), used
    assert graph["harness.cli.main"]


def calls_and_imports(path):
    """(imported module names, dotted names called) of a file, read with ast."""
    tree = ast.parse(path.read_text(), str(path))
    imported, called = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            imported.add(node.module)
        elif isinstance(node, ast.Call):
            called.add(ast.unparse(node.func))
    return imported, called


def test_every_child_starts_through_the_runner():
    """#47: harness/core/runner.py is the one module that starts a program (subprocess); no
    os.system, os.popen, os.fork or os.exec* anywhere; a forked multiprocessing.Process is watched by
    runner.supervised in the same module, so that a signal reaching the harness reaches it."""
    bad = []
    for path in PACKAGE.rglob("*.py"):
        name = module_name(path)
        imported, called = calls_and_imports(path)
        if "subprocess" in imported and name != RUNNER:
            bad.append(f"{name} imports subprocess (use harness.core.runner.run_command or run_binary)")
        bad += [
            f"{name} calls {c}" for c in called if c in ("os.system", "os.popen", "os.fork") or c.startswith("os.exec")
        ]
        if any(c.endswith(".Process") for c in called) and "runner.supervised" not in called:
            bad.append(f"{name} forks a process without runner.supervised")
    assert not bad, "\n".join(bad)


WRITERS = ("harness.io.files", "harness.io.runlog", RUNNER)  # the one writer; the append-only log; the runner's scratch
WRITE_CALLS = ("os.replace", "os.rename", "shutil.copy", "shutil.copy2", "shutil.copyfile", "shutil.move")
WRITE_METHODS = (".write_text", ".write_bytes", ".savefig", ".rename", ".to_csv", ".to_json")


def file_writes(path):
    """The calls in a file that write a file around harness/io/files.py."""
    tree = ast.parse(path.read_text(), str(path))
    uses_writing = any(
        isinstance(n, ast.Call) and ast.unparse(n.func).endswith("files.writing") for n in ast.walk(tree)
    )
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        func = ast.unparse(node.func)
        modes = [a.value for a in [*node.args[1:2], *(k.value for k in node.keywords if k.arg == "mode")]
                 if isinstance(a, ast.Constant) and isinstance(a.value, str)]  # fmt: skip
        writes_mode = any(set(m) & set("wax+") for m in modes)
        into_temporary = uses_writing and func.split(".")[0].startswith("tmp")  # a name files.writing gave
        if func.startswith("files.") or into_temporary:
            continue
        if func in WRITE_CALLS or func.endswith(WRITE_METHODS) or (func == "open" and writes_mode):
            found.append(f"line {node.lineno}: {func}")
        elif func.endswith("h5py.File") and writes_mode and not uses_writing:
            found.append(f"line {node.lineno}: {func} for writing outside files.writing")
    return found


def test_every_file_write_goes_through_files():
    """#47: every file the harness writes goes through harness/io/files.py (whole or not at all,
    its temporary removed in `finally`); an h5py file written inside files.writing."""
    bad = [
        f"{module_name(p)} {w}" for p in PACKAGE.rglob("*.py") if module_name(p) not in WRITERS for w in file_writes(p)
    ]
    assert not bad, "writes around harness/io/files.py:\n" + "\n".join(bad)


def test_the_write_check_sees_a_hidden_write(tmp_path):
    path = module_file(
        tmp_path, "def f(p, t):\n    with open(p, 'w') as x:\n        x.write(t)\n    t.replace('a', 'b')\n"
    )
    assert file_writes(path) == ["line 2: open"]


MODELS = ("paper", "dynamic")


def model_of(name):
    """The model a studies/ or render/ module names (a word of its file name), or None."""
    words = set(name.rpartition(".")[2].split("_"))
    named = [m for m in MODELS if m in words]
    return named[0] if len(named) == 1 else None


def test_a_module_named_for_one_model_imports_none_named_for_the_other():
    """docs/decisions/code-layout.md: in studies/ and render/ a module serving one model has its
    name as a word of the file name; one named for a model never imports one named for the other."""
    graph = import_graph()
    folders = ("harness.studies.", "harness.render.")
    crossed = [
        f"{m} (line {line}) imports {t}"
        for m, targets in graph.items()
        if m.startswith(folders) and model_of(m)
        for t, line in targets.items()
        if t.startswith(folders) and model_of(t) and model_of(t) != model_of(m)
    ]
    assert not crossed, "modules named for one model importing the other's:\n" + "\n".join(crossed)


def test_the_model_names_are_read_from_words():
    assert model_of("harness.render.plots_paper") == "paper"
    assert model_of("harness.studies.stability_slices_dynamic") == "dynamic"
    assert model_of("harness.studies.sweep") is None
    assert model_of("harness.studies.dynamicish") is None


LONGEST_FUNCTION = 150  # lines, def to last line (#47)


def long_functions(path, limit=LONGEST_FUNCTION):
    """(line, name, lines) of each function in a file longer than `limit` lines."""
    tree = ast.parse(path.read_text(), str(path))
    return [
        (n.lineno, n.name, n.end_lineno - n.lineno + 1)
        for n in ast.walk(tree)
        if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.end_lineno - n.lineno + 1 > limit
    ]


def test_no_function_in_harness_is_over_150_lines():
    long = [
        f"{p.relative_to(ROOT)}:{line} {name} ({n} lines)"
        for p in sorted(PACKAGE.rglob("*.py"))
        for line, name, n in long_functions(p)
    ]
    assert not long, f"functions over {LONGEST_FUNCTION} lines:\n" + "\n".join(long)


def test_the_length_scan_sees_a_long_function(tmp_path):
    path = module_file(tmp_path, "def f():\n" + "    x = 1\n" * 160 + "\n\ndef g():\n    return 2\n")
    assert long_functions(path) == [(1, "f", 161)]


# ---- measuring and drawing apart (#47) ------------------------------------------------------
# Markdown is the renderers' (render/ and above): the layers below it measure, check and decide
# and hand back data. A renderer words what it is given: it compares nothing with a tolerance.

MEASURING = ("core", "io", "check", "studies")
MARKDOWN = re.compile(r"(?m)^(\| |#{2,6} \S)|\| ?:?-{3,}:? ?\|")  # a table row or rule, a ## heading
WRITE_FUNCS = ("files.write_text", "files.write_bytes", "files.write_json", "files.writing", "files.copy", "open")


def _docstrings(tree):
    nodes = (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
    return {
        id(n.body[0].value)
        for n in ast.walk(tree)
        if isinstance(n, nodes) and n.body and isinstance(n.body[0], ast.Expr)
        and isinstance(n.body[0].value, ast.Constant)
    }  # fmt: skip


def markdown_names():
    """Names bound at a module's top level to a Markdown file's name ("analytic.md")."""
    return {
        t.id
        for p in PACKAGE.rglob("*.py")
        for n in ast.parse(p.read_text()).body
        if isinstance(n, ast.Assign) and isinstance(n.value, ast.Constant) and str(n.value.value).endswith(".md")
        for t in n.targets
        if isinstance(t, ast.Name)
    }


def markdown_made(path, md_names):
    """Where a file makes Markdown: a string (not a docstring) holding a table row or a heading,
    and a write whose path names a .md file (a literal or a name of `md_names`)."""
    tree = ast.parse(path.read_text(), str(path))
    skip = _docstrings(tree)
    found = [
        f"line {n.lineno}: Markdown text {n.value[:30]!r}"
        for n in ast.walk(tree)
        if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in skip and MARKDOWN.search(n.value)
    ]
    for n in ast.walk(tree):
        if not isinstance(n, ast.Call):
            continue
        func = ast.unparse(n.func)
        modes = [str(a.value) for a in n.args[1:2] if isinstance(a, ast.Constant)]
        if func.endswith((".write_text", ".write_bytes")) and not func.startswith("files."):
            target = n.func.value  # path.write_text(...)
        elif func in WRITE_FUNCS and n.args and (func != "open" or any(set(m) & set("wax+") for m in modes)):
            target = n.args[0]
        else:
            continue
        named = [
            x for x in ast.walk(target)
            if (isinstance(x, ast.Constant) and str(x.value).endswith(".md"))
            or (isinstance(x, ast.Name) and x.id in md_names) or (isinstance(x, ast.Attribute) and x.attr in md_names)
        ]  # fmt: skip
        if named:
            found.append(f"line {n.lineno}: {func} writes {ast.unparse(target)}")
    return found


def test_the_measuring_layers_make_no_markdown():
    """core/, io/, check/ and studies/ return data; a renderer writes it as Markdown."""
    names = markdown_names()
    bad = [
        f"{module_name(p)} {m}"
        for p in sorted(PACKAGE.rglob("*.py"))
        if module_name(p).split(".")[1:2] and module_name(p).split(".")[1] in MEASURING
        for m in markdown_made(p, names)
    ]
    assert not bad, "Markdown made below harness/render:\n" + "\n".join(bad)


def test_the_markdown_check_sees_a_table_and_a_write(tmp_path):
    path = module_file(
        tmp_path,
        '"""| a docstring may show a table |"""\n'
        'PAGE = "page.md"\n'
        "def f(out, s):\n"
        '    rows = [f"| {s} | 1 |", "| --- | ---: |"]\n'
        "    files.write_text(out / PAGE, s)\n"
        '    (out / "x.md").write_text(s)\n'
        '    files.write_text(out / "x.json", "# not a heading")\n',
    )
    assert sorted(markdown_made(path, {"PAGE"})) == [
        "line 4: Markdown text '| '",
        "line 4: Markdown text '| --- | ---: |'",
        "line 5: files.write_text writes out / PAGE",
        "line 6: (out / 'x.md').write_text writes out / 'x.md'",
    ]


def _applies_tolerance(node, tainted):
    """Whether an expression reads harness.core.tolerances (or a name bound from it): through a
    call only as the callee (tolerances.f(x), a budget's .items()), not through its arguments."""
    if isinstance(node, ast.Call):
        return _applies_tolerance(node.func, tainted)
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "tolerances":
        return True
    if isinstance(node, ast.Name):
        return node.id in tainted
    if isinstance(node, (ast.Lambda, ast.FunctionDef)):
        return False
    return any(_applies_tolerance(c, tainted) for c in ast.iter_child_nodes(node))


def tolerance_comparisons(path):
    """(line, comparison) of each comparison in a file's functions with a value from
    harness.core.tolerances, directly or through names bound from it (for k, v in X.items():
    v, not the key)."""
    tree = ast.parse(path.read_text(), str(path))
    found = set()
    for fn in (n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))):
        tainted, grew = set(), True
        while grew:
            grew = False
            for n in ast.walk(fn):
                if isinstance(n, ast.Assign):
                    pairs = [(t, n.value) for t in n.targets]
                elif isinstance(n, (ast.For, ast.comprehension)):
                    pairs = [(n.target, n.iter)]
                else:
                    continue
                for target, value in pairs:
                    if not _applies_tolerance(value, tainted):
                        continue
                    items = isinstance(value, ast.Call) and ast.unparse(value.func).endswith(".items")
                    if items and isinstance(target, ast.Tuple) and len(target.elts) == 2:
                        target = target.elts[1]
                    new = {x.id for x in ast.walk(target) if isinstance(x, ast.Name)} - tainted
                    tainted |= new
                    grew = grew or bool(new)
        found |= {
            (n.lineno, ast.unparse(n))
            for n in ast.walk(fn)
            if isinstance(n, ast.Compare) and _applies_tolerance(n, tainted)
        }
    return sorted(found)


def test_renderers_compare_nothing_with_a_tolerance():
    """A verdict (a tolerance applied to a measurement) is made in studies/ and handed to the
    renderer as data (as accuracy_dynamic_report.py gets its verdicts from accuracy_verdicts_dynamic.py)."""
    deciding = [
        f"{module_name(p)}: line {line}: {c}"
        for p in sorted((PACKAGE / "render").rglob("*.py"))
        for line, c in tolerance_comparisons(p)
    ]
    assert not deciding, "renderers that apply a tolerance (decide in harness/studies):\n" + "\n".join(deciding)


def test_the_tolerance_check_follows_a_budget_through_names(tmp_path):
    path = module_file(
        tmp_path,
        "def f(r, use):\n"
        "    for name, (rms, _) in tolerances.USES.items():\n"
        "        ratio = rms / r\n"
        "        words = 'yes' if ratio < 1 else 'no'\n"
        "        same = name == use\n"
        "    ok = r <= tolerances.budget(use)\n"
        "    return describe(tolerances.USES) is None\n",
    )
    assert tolerance_comparisons(path) == [(4, "ratio < 1"), (6, "r <= tolerances.budget(use)")]
