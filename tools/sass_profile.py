"""Where a kernel's instructions go, from Nsight Compute's source page (not a test: a reading of a
measurement). Export a profile taken with `--set full --import-source yes` as

  ncu -i REPORT.ncu-rep --page source --csv --print-source sass | gzip > KERNEL.csv.gz

and read it here:

  python3 tools/sass_profile.py A.csv.gz              executed warp instructions by opcode
  python3 tools/sass_profile.py A.csv.gz B.csv.gz     the same for B, and where B executes more than A

Two files are compared line by line, so both must be the same kernel's code (the same SASS but
for its addresses, as two runs of one binary's kernel are: a scene with and without a feature);
the regions are windows of --window SASS lines, the largest differences first. Each region prints
its first line's index, so `--show I` prints the lines from I with their counts."""

import argparse
import re
import sys

OPCODE = re.compile(r"^(?:@!?U?P\w+\s+)?([A-Z0-9_]+)")
ADDRESS = re.compile(r"0x[0-9a-f]+")


class ProfileError(Exception):
    """A file that is not an ncu source-page export of SASS."""


def read(path):
    """The SASS lines of an export: a DataFrame with `sass` (the instruction), `op` (its opcode)
    and `n` (warp instructions executed)."""
    import pandas as pd

    try:
        df = pd.read_csv(path, skiprows=1)
    except (OSError, ValueError, UnicodeDecodeError, EOFError) as e:
        raise ProfileError(f"{path}: cannot be read as an ncu source-page CSV ({type(e).__name__})") from None
    missing = {"Source", "Instructions Executed"} - set(df.columns)
    if missing:
        raise ProfileError(f"{path}: no column {sorted(missing)[0]!r}: export it with --page source --print-source sass")
    out = pd.DataFrame({"sass": df["Source"].astype(str).str.strip()})
    out["n"] = pd.to_numeric(df["Instructions Executed"], errors="coerce").fillna(0.0)
    out["op"] = out["sass"].map(opcode)
    return out


def opcode(sass):
    """An instruction's opcode without its predicate and modifiers ("@!P2 LDS.128 …" → "LDS")."""
    m = OPCODE.match(sass)
    return m.group(1).split(".")[0] if m else "?"


def by_opcode(df):
    """Executed warp instructions by opcode, the largest first."""
    return df.groupby("op")["n"].sum().sort_values(ascending=False)


def same_code(a, b):
    """Whether two exports list the same SASS, addresses aside."""
    if len(a) != len(b):
        return False
    return all(ADDRESS.sub("", x) == ADDRESS.sub("", y) for x, y in zip(a["sass"], b["sass"], strict=True))


def regions(a, b, window):
    """(first line, B − A, A, B) over windows of `window` lines, the largest B − A first."""
    d = b["n"].to_numpy() - a["n"].to_numpy()
    rows = []
    for i in range(0, len(d), window):
        rows.append((i, float(d[i : i + window].sum()), float(a["n"][i : i + window].sum()), float(b["n"][i : i + window].sum())))
    return sorted(rows, key=lambda r: -r[1])


def report(paths, top, window, show):
    profiles = [read(p) for p in paths]
    if len(profiles) == 2 and not same_code(*profiles):
        raise ProfileError(f"{paths[0]} and {paths[1]} are not the same kernel's code: compare runs of one binary's kernel")
    for p, df in zip(paths, profiles, strict=True):
        tot = df["n"].sum()
        ops = by_opcode(df).head(top)
        print(f"{p}: {tot:.4g} warp instructions executed, {len(df)} SASS lines")
        print("  " + ", ".join(f"{op} {n / 1e6:.1f}M" for op, n in ops.items()))
    if len(profiles) == 2:
        a, b = profiles
        print(f"B − A: {b['n'].sum() - a['n'].sum():.4g}; by opcode:")
        d = (by_opcode(b).sub(by_opcode(a), fill_value=0.0)).sort_values(ascending=False).head(top)
        print("  " + ", ".join(f"{op} {n / 1e6:+.1f}M" for op, n in d.items()))
        print(f"windows of {window} lines, the largest B − A first (line: B − A, A, B):")
        for i, dn, an, bn in regions(a, b, window)[:top]:
            print(f"  {i:6d}: {dn / 1e6:+9.1f}M  {an / 1e6:9.1f}M  {bn / 1e6:9.1f}M")
    if show is not None:
        df = profiles[-1]
        for i in range(max(show, 0), min(show + window, len(df))):
            print(f"  {i:6d} {df['n'][i] / 1e6:9.2f}M  {df['sass'][i]}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("profiles", nargs="+", help="one or two ncu source-page SASS exports (.csv or .csv.gz)")
    ap.add_argument("--top", type=int, default=20, help="opcodes and regions printed (default 20)")
    ap.add_argument("--window", type=int, default=64, help="SASS lines a region (default 64)")
    ap.add_argument("--show", type=int, default=None, help="print --window lines of the last file from this index")
    args = ap.parse_args(argv)
    if len(args.profiles) > 2:
        print("error: give one or two profiles", file=sys.stderr)
        return 2
    if args.top < 1 or args.window < 1:
        print("error: --top and --window must be at least 1", file=sys.stderr)
        return 2
    try:
        report(args.profiles, args.top, args.window, args.show)
    except ProfileError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
