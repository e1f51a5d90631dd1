"""docs/harness.md's command and module reference is made from the parser and the module
docstrings (`python -m harness docs`): the committed page must be what it makes today."""

from harness.cli import docs
from harness.cli.main import main, parser


def test_the_committed_reference_is_current():
    text = docs.PAGE.read_text()
    assert docs.updated(text, parser()) == text, "docs/harness.md is out of date: run `make docs`"


def test_the_reference_names_every_command_and_module():
    made = docs.reference(parser())
    for command in ("run", "diff", "stepdiff", "report", "headline", "featurecost", "stability", "docs"):
        assert f"| `{command} " in made or f"| `{command}` |" in made, command
    for module in ("runner", "diff_dynamic", "accuracy_paper", "report_dynamic", "validation"):
        assert f"| `{module}` |" in made, module
    assert "harness/render/" in made and made.startswith(docs.BEGIN) and made.endswith(docs.END)


def test_check_says_when_the_page_is_stale(tmp_path, monkeypatch, capsys):
    page = tmp_path / "harness.md"
    page.write_text(f"intro\n{docs.BEGIN}\nold table\n{docs.END}\nrest\n")
    monkeypatch.setattr(docs, "PAGE", page)
    assert main(["docs", "--check"]) == 1
    assert "out of date" in capsys.readouterr().out
    assert main(["docs"]) == 0 and main(["docs", "--check"]) == 0
    text = page.read_text()
    assert text.startswith("intro\n") and text.endswith("\nrest\n") and "old table" not in text
    page.write_text("no markers\n")
    assert main(["docs"]) == 2
    assert capsys.readouterr().err.strip().startswith("harness: error: ")


def test_every_help_text_stands_alone():
    """`harness --help` and each command's help name the project's own documents only: no
    outside brief, no issue tracker."""
    import re

    p = parser()
    texts = [p.format_help()]
    sub = next(a for a in p._actions if a.dest == "command")
    texts += [c.format_help() for c in sub.choices.values()]
    for text in texts:
        flat = " ".join(text.split())
        assert not re.search(r"\bDESIGN\b|\bissues?\b|\.\./shared", flat), flat[:200]
