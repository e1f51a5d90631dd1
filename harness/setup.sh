#!/usr/bin/env bash
# harness/setup.sh OUT — what `make test` and `make bench` need, installed when missing.
#
# 1. System (Debian/Ubuntu): a C compiler, make, pkg-config, the HDF5 C library, Python 3
#    with venv. Missing ones are installed with apt-get as root or through passwordless
#    sudo; otherwise one line says what to run.
# 2. Python >= 3.11 with the packages of requirements.lock. If $PYTHON already imports them,
#    nothing is installed (machines without a network work from what is there). Else pip
#    installs the lock into the project environment ./.venv, or into $PYTHON's own virtual
#    environment when $PYTHON runs inside one (the user's choice); never into a system
#    interpreter's packages (a shared interpreter's versions are not ours to change).
#    The renderer (moderngl) is tried on its own when it is the one thing missing, and not
#    required: without it `harness render` and the report's renders say why and skip.
# The interpreter to use is written to OUT (make reads it). Environment: PYTHON (default
# python3), CC (default cc), HAIRBENCH_READERS=1 also installs requirements-readers.lock.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-build/python}
PY=${PYTHON:-python3}
CC_BIN=${CC:-cc}
VENV=.venv
LOG=build/setup.log
MODULES="h5py numpy pandas matplotlib pytest hypothesis"
APT_PKGS="build-essential pkg-config libhdf5-dev hdf5-tools python3 python3-venv python3-pip"
mkdir -p "$(dirname "$OUT")" build

die() { echo "error: $*" >&2; exit 1; }
say() { echo "setup: $*" >&2; }

as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"
  elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then sudo "$@"
  else return 1; fi
}

have_hdf5() {
  local flags
  flags=$(pkg-config --cflags hdf5 2>/dev/null || true)
  [ -n "$flags" ] || flags=$(h5cc -show 2>/dev/null | tr ' ' '\n' | grep '^-I' | tr '\n' ' ' || true)
  # shellcheck disable=SC2086
  echo '#include <hdf5.h>' | "$CC_BIN" $flags -E -x c - >/dev/null 2>&1
}

# ---- 1. system packages ----
need=()
command -v "$CC_BIN" >/dev/null 2>&1 && command -v make >/dev/null 2>&1 || need+=("a C compiler and make")
command -v pkg-config >/dev/null 2>&1 || need+=(pkg-config)
{ ! command -v "$CC_BIN" >/dev/null 2>&1 || ! have_hdf5; } && need+=("the HDF5 C library")
command -v "$PY" >/dev/null 2>&1 || need+=("$PY")
if [ ${#need[@]} -gt 0 ]; then
  what=$(IFS=,; echo "${need[*]}" | sed 's/,/, /g')
  command -v apt-get >/dev/null 2>&1 || die "missing $what: install them with your package manager (on Debian/Ubuntu: apt-get install $APT_PKGS)"
  say "installing $what with apt-get ($APT_PKGS)"
  if ! as_root true; then
    die "missing $what: run 'sudo apt-get install -y $APT_PKGS'"
  fi
  { as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq &&
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $APT_PKGS; } >>"$LOG" 2>&1 ||
    die "apt-get could not install $APT_PKGS (see $LOG; no network?)"
  PY=${PYTHON:-python3}
fi

# ---- 2. Python ----
"$PY" -c 'import sys; sys.exit(sys.version_info < (3, 11))' ||
  die "$PY is Python $("$PY" -c 'import platform; print(platform.python_version())'); hairbench needs Python >= 3.11 (set PYTHON=/path/to/python3.11 or newer)"

imports() { "$1" -c "import $(echo "$MODULES" | tr ' ' ',')" >/dev/null 2>&1; }
# The renderer (moderngl on EGL) is installed with the lock but not required: where pip cannot
# bring it (no network), one line says so and the renders are skipped with that reason.
renderer() {
  "$1" -c "import moderngl" >/dev/null 2>&1 && return 0
  say "installing the renderer (moderngl, glcontext from requirements.lock) into $1"
  grep -E '^(moderngl|glcontext)==' requirements.lock |
    xargs "$1" -m pip install -q --disable-pip-version-check --retries 1 --timeout 30 >>"$LOG" 2>&1 ||
    say "moderngl could not be installed into $1 (see $LOG): harness render and the report's renders are skipped"
}
done_with() {
  renderer "$1"
  if [ "${HAIRBENCH_READERS:-}" = 1 ] && ! "$1" -c "import MDAnalysis, vtkmodules.vtkIOXdmf2, pxr" >/dev/null 2>&1; then
    say "installing the optional readers (requirements-readers.lock) into $1"
    "$1" -m pip install -q --disable-pip-version-check --retries 1 --timeout 30 -r requirements-readers.lock >>"$LOG" 2>&1 ||
      die "pip could not install requirements-readers.lock into $1 (see $LOG)"
  fi
  echo "$1" > "$OUT"
  exit 0
}

imports "$PY" && done_with "$(command -v "$PY")"
[ -x "$VENV/bin/python" ] && imports "$VENV/bin/python" && done_with "$PWD/$VENV/bin/python"

inside_venv=$("$PY" -c 'import sys; print(int(sys.prefix != sys.base_prefix))')
pip_install() {
  "$1" -m pip install -q --disable-pip-version-check --retries 1 --timeout 30 -r requirements.lock >>"$LOG" 2>&1
}
if [ "$inside_venv" = 1 ] && "$PY" -m pip --version >/dev/null 2>&1; then
  say "installing requirements.lock into $PY (its virtual environment) with pip"
  pip_install "$PY" || die "pip could not install requirements.lock into $PY (see $LOG; no network?): run '$PY -m pip install -r requirements.lock' where PyPI is reachable"
  imports "$PY" || die "requirements.lock installed but '$MODULES' still do not import in $PY (see $LOG)"
  done_with "$(command -v "$PY")"
fi

say "installing requirements.lock into the project environment $VENV ($PY's own packages are left as they are)"
if [ ! -x "$VENV/bin/python" ]; then
  if ! "$PY" -m venv "$VENV" >>"$LOG" 2>&1; then
    rm -rf "$VENV"
    as_root true || die "$PY cannot create a virtual environment: run 'sudo apt-get install -y python3-venv'"
    { as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq &&
      as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends python3-venv; } >>"$LOG" 2>&1 ||
      die "apt-get could not install python3-venv (see $LOG; no network?)"
    "$PY" -m venv "$VENV" >>"$LOG" 2>&1 || die "$PY -m venv $VENV failed (see $LOG)"
  fi
fi
pip_install "$VENV/bin/python" ||
  die "pip could not install requirements.lock into $VENV (see $LOG; no network?): run '$VENV/bin/python -m pip install -r requirements.lock' where PyPI is reachable"
imports "$VENV/bin/python" || die "requirements.lock installed but '$MODULES' still do not import in $VENV (see $LOG)"
done_with "$PWD/$VENV/bin/python"
