#!/usr/bin/env bash
# Runs every physid test on a fresh machine: formatting, lints, the Rust test suite, and the
# Python cross-checks against pinocchio and MuJoCo. Installs what it needs (Debian packages,
# the Python venv) when missing. Build outputs go to $CARGO_TARGET_DIR (default
# ~/.cache/physid-target) so that repeated runs build incrementally.
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/physid-target}"
VENV="${PHYSID_VENV:-$HOME/.cache/physid-venv}"
step() { printf '\n== %s\n' "$*"; }

step "system packages"
missing=()
for p in libopenblas-dev libgfortran-12-dev; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ]; then
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
  else
    echo "missing Debian packages: ${missing[*]} (run as root or install them)" >&2; exit 1
  fi
fi
echo "ok"

step "python venv ($VENV)"
if ! "$VENV/bin/python" -c "import numpy, mujoco, pinocchio, cvxpy, clarabel, scs" 2>/dev/null; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q --upgrade pip
  "$VENV/bin/pip" install -q -r scripts/requirements.txt
fi
"$VENV/bin/python" -c "import numpy, mujoco, pinocchio; print('numpy', numpy.__version__, 'mujoco', mujoco.__version__, 'pinocchio', pinocchio.__version__)"

step "cargo fmt --check"
cargo fmt --check

step "cargo clippy --all-targets -- -D warnings"
cargo clippy --quiet --release --all-targets -- -D warnings

step "cargo test --release"
cargo test --release 2>&1 | tee "$CARGO_TARGET_DIR/physid-test.log" | grep -E '^(test result|running|test .*FAILED|failures)' || true
if grep -qE 'test result: FAILED|error(\[E[0-9]+\])?:' "$CARGO_TARGET_DIR/physid-test.log"; then
  cat "$CARGO_TARGET_DIR/physid-test.log"; exit 1
fi
rust_passed=$(grep -oE 'test result: ok\. [0-9]+ passed' "$CARGO_TARGET_DIR/physid-test.log" | awk '{s+=$4} END {print s+0}')

step "python cross-checks (pinocchio, MuJoCo, CVXPY)"
cargo build --quiet --release --bin physid
export PHYSID_BIN="$CARGO_TARGET_DIR/release/physid"
py_passed=0; py_failed=0
for s in check_pinocchio check_mujoco check_cvxpy; do
  out=$("$VENV/bin/python" "scripts/$s.py" 2>&1) && rc=0 || rc=$?
  echo "$out"
  p=$(echo "$out" | grep -oE '[0-9]+ passed' | tail -1 | awk '{print $1}')
  f=$(echo "$out" | grep -oE '[0-9]+ failed' | tail -1 | awk '{print $1}')
  py_passed=$((py_passed + ${p:-0})); py_failed=$((py_failed + ${f:-1}))
  [ "$rc" = 0 ] || py_failed=$((py_failed + 1))
done

echo
echo "rust: $rust_passed passed; python checks: $py_passed passed, $py_failed failed"
echo "total: $((rust_passed + py_passed)) passed, $py_failed failed"
[ "$py_failed" = 0 ]
