"""The project stands alone: no tracked file cites a document that is not in the repository
(the design brief the project was started from, or a `shared/` folder beside it), every
relative Markdown link in README.md and docs/ leads to a file that exists, and so does every
repository path that README.md and docs/ name in backticks. The binaries' `--help` describes
both models and every stage the binary runs, and cites nothing outside the repository."""

import itertools
import json
import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# Excluded for now: harness/ and tests/ are being reorganised on another branch; their
# citations are retargeted after that merge, and then these two entries are removed.
NOT_YET_CHECKED: tuple = ()
THIS_FILE = "tests/cpu/test_docs_standalone.py"  # names the patterns it looks for

# The brief as a document: its name in capitals (with a section sign or ".md" after it), and the
# background folder and files by name. Lower-case "design" is ordinary prose.
BRIEF = "DES" + "IGN"  # spelt in two parts so that this file does not name it itself
OUTSIDE_DOCUMENT = re.compile(rf"\b{BRIEF}\b|(?<![\w.-])shared/|\bANCHORS\.md\b|\bSTYLE\.md\b")

# Repository paths named in backticks in the docs: these top-level folders, a plain path
# (no placeholder such as <name>, no glob, no ellipsis).
NAMED_PATH = re.compile(r"`((?:c_ref|cuda|configs|docs|harness|tests|results/reference-h200)/[\w./-]*)`")


def tracked_files():
    out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    return [p for p in out.decode().split("\0") if p]


def text_of(rel):
    data = (ROOT / rel).read_bytes()
    if b"\0" in data:
        return None  # binary: images, HDF5 states
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def doc_files():
    return [p for p in tracked_files() if p == "README.md" or (p.startswith("docs/") and p.endswith(".md"))]


def test_no_tracked_file_cites_a_document_outside_the_repository():
    found = []
    for rel in tracked_files():
        if rel.startswith(NOT_YET_CHECKED) or rel == THIS_FILE or not (ROOT / rel).is_file():
            continue
        text = text_of(rel)
        if text is None:
            continue
        for n, line in enumerate(text.splitlines(), 1):
            if OUTSIDE_DOCUMENT.search(line):
                found.append(f"{rel}:{n}: {line.strip()[:100]}")
    assert not found, "cites a document outside the repository:\n" + "\n".join(found)


def test_the_pattern_tells_a_citation_from_ordinary_words():
    assert OUTSIDE_DOCUMENT.search(f"the paper model ({BRIEF} §3)")
    assert OUTSIDE_DOCUMENT.search(f"see /work/shared/{BRIEF}.md")
    assert OUTSIDE_DOCUMENT.search("as shared/ANCHORS.md says")
    assert not OUTSIDE_DOCUMENT.search("### Design")
    assert not OUTSIDE_DOCUMENT.search("the design of the kernels; the shared C objects")
    assert not OUTSIDE_DOCUMENT.search("tests/support/shared_state.py")


def markdown_links(text):
    """Targets of inline links [text](target), code spans removed first."""
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    text = re.sub(r"`[^`\n]*`", "", text)
    return re.findall(r"\[[^\]\n]*\]\(([^)\s]+)\)", text)


def test_every_relative_markdown_link_leads_to_a_file():
    broken = []
    for rel in doc_files():
        base = (ROOT / rel).parent
        for target in markdown_links((ROOT / rel).read_text()):
            if re.match(r"[a-z]+:", target) or target.startswith("#"):
                continue  # a web address or an anchor in the same file
            path = target.split("#", 1)[0]
            if not (base / path).exists():
                broken.append(f"{rel}: ({target})")
    assert not broken, "links to files that do not exist:\n" + "\n".join(broken)


def test_every_repository_path_the_docs_name_exists():
    missing = []
    for rel in doc_files():
        for n, line in enumerate((ROOT / rel).read_text().splitlines(), 1):
            for path in NAMED_PATH.findall(line):
                if path.startswith(NOT_YET_CHECKED):
                    continue
                if not (ROOT / path).exists():
                    missing.append(f"{rel}:{n}: {path}")
    assert not missing, "names a path that is not in the repository:\n" + "\n".join(missing)


def test_the_link_and_path_checks_can_fail(tmp_path):
    assert markdown_links("see [the model](model.md#s2) and `[not](a-link.md)`") == ["model.md#s2"]
    assert NAMED_PATH.findall("`configs/dynamic.toml` and `results/<name>/runs.csv`") == ["configs/dynamic.toml"]
    assert not (ROOT / "configs/dynamic.toml").exists()


def test_help_describes_both_models_and_every_stage(cpu_bin):
    p = subprocess.run([str(cpu_bin), "--help"], capture_output=True, text=True, timeout=30)
    assert p.returncode == 0, p.stderr
    text = p.stdout
    assert not OUTSIDE_DOCUMENT.search(text), text
    assert "paper model" in text and "dynamic model" in text
    variants = json.loads(
        subprocess.run([str(cpu_bin), "--list-variants"], capture_output=True, text=True, check=True).stdout
    )["variants"]
    stages = {s for v in variants for s in v["stages"]}
    assert {"init", "collide", "wind", "simulate"} <= stages
    lines = text.splitlines()
    first = next(i for i, line in enumerate(lines) if line.strip().startswith("--stages"))
    continued = itertools.takewhile(lambda s: s.startswith(" " * 8), lines[first + 1 :])
    stages_line = " ".join([lines[first], *continued])
    for stage in stages:
        assert re.search(rf"\b{stage}\b", stages_line), f"--stages help does not name {stage}: {stages_line}"
    for doc in re.findall(r"docs/[\w.-]+\.md", text):
        assert (ROOT / doc).is_file(), doc
