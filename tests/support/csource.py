"""Reading the C and CUDA sources statically for the layout tests: their quoted #include lines
and the length of each function. No compiler: comments and string literals are blanked, then
braces are counted at file scope."""

import re
from dataclasses import dataclass
from pathlib import Path

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
# a comment, or a string or character literal, each blanked (its newlines kept)
_NOISE = re.compile(r'//[^\n]*|/\*.*?\*/|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'', re.S)
# braces that open a scope whose body is itself at file scope (extern "C": its string blanked)
_TRANSPARENT = re.compile(r"(\bnamespace\b[^;{}]*|\bextern\s*)$")
_NOT_FUNCTION = re.compile(r"\b(struct|union|enum|class|typedef)\b|=\s*$")


def includes(path: Path) -> list[tuple[int, str]]:
    """The quoted includes of a file: (line, the path as written)."""
    text = path.read_text()
    return [(text.count("\n", 0, m.start()) + 1, m.group(1)) for m in INCLUDE.finditer(text)]


def _blank(text: str) -> str:
    return _NOISE.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


@dataclass(frozen=True)
class Function:
    name: str
    line: int
    lines: int
    header: str


def _without_directives(text: str) -> str:
    """Preprocessor lines blanked (a continued line too), so a macro's braces are not counted."""
    out, continued = [], False
    for line in text.split("\n"):
        directive = continued or line.lstrip().startswith("#")
        continued = directive and line.rstrip().endswith("\\")
        out.append(" " * len(line) if directive else line)
    return "\n".join(out)


def functions(path: Path) -> list[Function]:
    """Every function defined at file scope (namespaces and extern "C" blocks see through):
    its name, first line (of its header), and its length in lines up to the closing brace."""
    text = _without_directives(_blank(path.read_text()))
    found, depth, start, head_from = [], 0, None, 0
    for i, ch in enumerate(text):
        if ch in ";}" and depth == 0:
            head_from = i + 1
        if ch == "{":
            head = text[head_from:i]
            if depth == 0 and _TRANSPARENT.search(head.strip()):
                head_from = i + 1
                continue
            if depth == 0:
                start = (head, i)
            depth += 1
        elif ch == "}":
            if depth == 0:  # the close of a namespace or extern "C" block
                continue
            depth -= 1
            if depth == 0 and start is not None:
                head, opened = start
                start, head_from = None, i + 1
                words = head.strip()
                name = re.search(r"(~?\w+)\s*\([^()]*(?:\([^()]*\)[^()]*)*\)[^()]*$", words)
                if not name or _NOT_FUNCTION.search(words.split("(")[0]):
                    continue
                first = text.count("\n", 0, opened - len(head) + (len(head) - len(head.lstrip()))) + 1
                last = text.count("\n", 0, i) + 1
                found.append(Function(name.group(1), first, last - first + 1, words))
    return found
