"""tools/sass_profile.py reads Nsight Compute's source-page export: executed warp instructions by
opcode (predicates and modifiers taken off), the regions where one run of a kernel executes more
than another, and one-line refusals of what it cannot read."""

import gzip
import importlib.util

import pytest

from conftest import ROOT

spec = importlib.util.spec_from_file_location("sass_profile", ROOT / "tools" / "sass_profile.py")
sass_profile = importlib.util.module_from_spec(spec)
spec.loader.exec_module(sass_profile)

HEADER = '"Address","Source","Warp Stall Sampling (All Samples)","Instructions Executed","Thread Instructions Executed"'


def export(path, base, rows, gz=False):
    """A source-page export: the kernel's name line, the header, one line a SASS instruction."""
    lines = ['"Kernel Name","k_lanes"', HEADER]
    for i, (sass, n) in enumerate(rows):
        a = f"0x{base + 16 * i:x}"
        lines.append(f'"{a}","{sass.replace("ADDR", f"0x{base + 256:x}")}","0","{n}","{32 * n}"')
    text = "\n".join(lines) + "\n"
    if gz:
        with gzip.open(path, "wt") as f:
            f.write(text)
    else:
        path.write_text(text)
    return path


KERNEL = [
    ("      FFMA R1, R2, R3, R1", 100),
    ("@P0   LDS.128 R20, [R11+0x40]", 40),
    ("@!P2  BRA ADDR", 40),
    ("HFMA2.MMA R10, -RZ, RZ, 0, 0", 10),
    ("@!UP0 FFMA R4, R4, R4, R4", 5),
    ("LDL R5, [R1+0x8]", 7),
]


def test_opcodes_are_counted_without_predicates_or_modifiers(tmp_path):
    df = sass_profile.read(export(tmp_path / "a.csv", 0x7F00, KERNEL))
    ops = sass_profile.by_opcode(df)
    assert ops.to_dict() == {"FFMA": 105.0, "LDS": 40.0, "BRA": 40.0, "LDL": 7.0, "HFMA2": 10.0}
    assert df["n"].sum() == 202


def test_two_runs_compare_line_by_line_despite_addresses(tmp_path):
    a = sass_profile.read(export(tmp_path / "a.csv", 0x7F00, KERNEL))
    more = [(s, n + (500 if s.startswith("LDL") else 0)) for s, n in KERNEL]
    b = sass_profile.read(export(tmp_path / "b.csv.gz", 0x9A00, more, gz=True))
    assert sass_profile.same_code(a, b)
    first = sass_profile.regions(a, b, window=2)[0]
    assert first == (4, 500.0, 12.0, 512.0)  # lines 4–5 hold the LDL that B runs 500 more times


def test_a_different_kernel_is_refused(tmp_path, capsys):
    a = export(tmp_path / "a.csv", 0x7F00, KERNEL)
    b = export(tmp_path / "b.csv", 0x7F00, KERNEL[:-1] + [("STL [R1+0x8], R5", 7)])
    assert sass_profile.main([str(a), str(b)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"error: {a} and {b} are not the same kernel's code: compare runs of one binary's kernel"


@pytest.mark.parametrize(
    "content, says",
    [
        (None, "cannot be read as an ncu source-page CSV (FileNotFoundError)"),
        ('"Kernel Name","k"\n"Address","Source"\n"0x1","FFMA R1, R2, R3, R1"\n', "no column 'Instructions Executed'"),
    ],
)
def test_what_is_not_an_export_is_refused_in_one_line(tmp_path, capsys, content, says):
    p = tmp_path / "p.csv"
    if content is not None:
        p.write_text(content)
    assert sass_profile.main([str(p)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {p}: {says}")


def test_bad_arguments_are_refused(tmp_path, capsys):
    a = export(tmp_path / "a.csv", 0x7F00, KERNEL)
    assert sass_profile.main([str(a), str(a), str(a)]) == 2
    assert capsys.readouterr().err.strip() == "error: give one or two profiles"
    assert sass_profile.main([str(a), "--window", "0"]) == 2
    assert capsys.readouterr().err.strip() == "error: --top and --window must be at least 1"
