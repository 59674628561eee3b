#!/usr/bin/env bash
# Installs what physid needs on a fresh Debian machine, and nothing that is already there:
#   bash scripts/setup.sh            the system library (OpenBLAS) and a Rust toolchain check
#   bash scripts/setup.sh --python   also the Python venv of the cross-check scripts
# Idempotent, and safe to re-run after an interrupted attempt: an interrupted dpkg is finished
# first, and the venv counts as ready only once a marker naming its requirements is written last.
# Each missing piece that it cannot install itself stops it with one line that names the piece
# and the command that installs it. Sourced by scripts/run.sh and scripts/test.sh.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

PHYSID_VENV="${PHYSID_VENV:-$HOME/.cache/physid-venv}"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/physid-target}"

die() { printf 'physid setup: %s\n' "$*" >&2; exit 1; }

# apt-get, quietly; its own output is shown only when it fails.
apt_quiet() {
  local log
  log=$(mktemp)
  if ! DEBIAN_FRONTEND=noninteractive "$@" >"$log" 2>&1; then
    tail -n 5 "$log" >&2
    rm -f "$log"
    return 1
  fi
  rm -f "$log"
}

setup_rust() {
  command -v cargo >/dev/null 2>&1 ||
    die "no cargo on PATH: install Rust 1.86 or newer (https://rustup.rs, or Debian's cargo package)"
}

# The Debian packages physid links against: OpenBLAS (BLAS and LAPACK, linked by crates/core/build.rs).
setup_system() {
  install_debian libopenblas-dev
}

# What only the tests use (one apt-get run): the headless browser of the check that renders
# diagnose's report.html, and Slurm with munge for the check that runs the job-array recipe of
# docs/sweeps.md on a single-node cluster.
setup_test_tools() {
  install_debian chromium-headless-shell slurm-wlm munge
}

# Installs the Debian packages given that are missing.
install_debian() {
  local wanted=("$@") missing=() p
  command -v dpkg >/dev/null 2>&1 || {
    # Not Debian: the build script finds OpenBLAS by pkg-config or the usual directories.
    echo "physid setup: not a Debian system; install the equivalent of ${wanted[*]} (e.g. openblas-devel or brew install openblas; a Chromium for the report check, Slurm and munge for the sweep check) if asked for"
    return 0
  }
  for p in "${wanted[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  [ "$(id -u)" = 0 ] ||
    die "missing Debian package ${missing[*]}: run 'sudo apt-get install ${missing[*]}' (or this script as root)"
  echo "physid setup: installing ${missing[*]} (apt-get)"
  apt_quiet dpkg --configure -a || true
  apt_quiet apt-get update -qq ||
    die "apt-get update failed (no network to the Debian mirror?): install ${missing[*]} by hand"
  apt_quiet apt-get install -y -qq --no-install-recommends "${missing[@]}" ||
    die "apt-get install ${missing[*]} failed: run 'apt-get install ${missing[*]}' to see why"
}

# The cross-check scripts' venv, rebuilt whenever scripts/requirements.txt changes or an earlier
# attempt did not finish (no marker).
setup_python() {
  local python marker want
  python=$(command -v python3 || true)
  [ -n "$python" ] || die "no python3: install it (apt-get install python3 python3-venv)"
  marker="$PHYSID_VENV/.physid-ready"
  want=$(cat scripts/requirements.txt; "$python" --version 2>&1)
  if [ -f "$marker" ] && [ "$(cat "$marker")" = "$want" ]; then
    return 0
  fi
  echo "physid setup: creating the Python venv $PHYSID_VENV (pip, about 250 MB)"
  "$python" -m venv --clear "$PHYSID_VENV" 2>/dev/null ||
    die "python3 cannot create a venv: install the venv module (apt-get install python3-venv)"
  "$PHYSID_VENV/bin/python" -m pip install -q --disable-pip-version-check \
    -r scripts/requirements.txt 2>"$PHYSID_VENV/pip-error.log" ||
    die "pip could not install scripts/requirements.txt (no network to PyPI?); see $PHYSID_VENV/pip-error.log, then re-run: bash scripts/setup.sh --python"
  printf '%s' "$want" >"$marker"
}

main() {
  setup_rust
  setup_system
  if [ "${1:-}" = "--python" ]; then
    setup_python
  fi
}

# Run when executed; only define the functions when sourced.
if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  main "$@"
fi
