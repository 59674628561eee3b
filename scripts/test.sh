#!/usr/bin/env bash
# Runs every physid test on a fresh machine: formatting, lints, the Rust test suite, and the
# Python cross-checks against pinocchio, MuJoCo and CVXPY, the scripts' command lines, the
# rendering of diagnose's report.html in a headless browser, the Slurm job-array recipe of docs/sweeps.md on a
# single-node Slurm cluster, and the README's main command
# (scripts/run.sh into a temporary directory, its outputs parsed). Installs what it needs
# (scripts/setup.sh: Debian packages, the Python venv) when missing. Build outputs go to $CARGO_TARGET_DIR (default
# ~/.cache/physid-target) so that repeated runs build incrementally.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup.sh
step() { printf '\n== %s (at %d s)\n' "$*" "$SECONDS"; }

step "setup (system packages, Python venv $PHYSID_VENV)"
setup_rust
setup_system
setup_test_tools
setup_python
"$PHYSID_VENV/bin/python" -c "import numpy, mujoco, pinocchio; print('numpy', numpy.__version__, 'mujoco', mujoco.__version__, 'pinocchio', pinocchio.__version__)"

step "cargo fmt --all --check"
cargo fmt --all --check

step "cargo clippy --workspace --all-targets -- -D warnings"
cargo clippy --quiet --release --workspace --all-targets -- -D warnings

step "cargo test --release"
cargo test --release 2>&1 | tee "$CARGO_TARGET_DIR/physid-test.log" | grep -E '^(test result|running|test .*FAILED|failures)' || true
if grep -qE 'test result: FAILED|error(\[E[0-9]+\])?:' "$CARGO_TARGET_DIR/physid-test.log"; then
  cat "$CARGO_TARGET_DIR/physid-test.log"; exit 1
fi
rust_passed=$(grep -oE 'test result: ok\. [0-9]+ passed' "$CARGO_TARGET_DIR/physid-test.log" | awk '{s+=$4} END {print s+0}')

step "python cross-checks (pinocchio, MuJoCo, CVXPY) and the main command"
cargo build --quiet --release --bin physid
export PHYSID_BIN="$CARGO_TARGET_DIR/release/physid"
py_passed=0; py_failed=0
main_out=$(mktemp -d)
trap 'rm -rf "$main_out"' EXIT
# The Python package (python/) built as its wheel (maturin, in the shared target dir; the
# shared libraries it links bundled) and installed from it into a temporary folder: the
# Python checks and tests run on what `pip install physid-*.whl` installs.
step "the Python wheel (maturin build --release), installed"
PATH="$PHYSID_VENV/bin:$PATH" maturin build --quiet --release -m python/Cargo.toml \
  --auditwheel repair --out "$main_out/wheels"
export PHYSID_PYTHON="$main_out/python"
"$PHYSID_VENV/bin/python" -m pip install -q --disable-pip-version-check --no-deps --no-index \
  --target "$PHYSID_PYTHON" "$main_out"/wheels/physid-*.whl
ls -l "$main_out"/wheels/physid-*.whl
for s in check_scripts_cli check_pinocchio check_mujoco check_cvxpy check_rosbag check_panda check_schemas check_report_html check_slurm check_python_package python_keywords pytest check_main_outputs; do
  if [ "$s" = pytest ]; then
    step "the Python package's tests (pytest python/tests)"
    out=$("$PHYSID_VENV/bin/python" -m pytest -q -p no:cacheprovider python/tests 2>&1) && rc=0 || rc=$?
    [ "$rc" != 0 ] || echo "$out" | grep -qE '[0-9]+ failed' || out="$out (0 failed)"
  elif [ "$s" = check_main_outputs ]; then
    step "the README's main command (bash scripts/run.sh), outputs parsed"
    out=$( { bash scripts/run.sh --out "$main_out/sample_size" >"$main_out/run.log" 2>&1 ||
               { tail -n 20 "$main_out/run.log"; exit 1; }; } &&
           "$PHYSID_VENV/bin/python" scripts/check_main_outputs.py "$main_out/sample_size" 2>&1 ) && rc=0 || rc=$?
  else
    out=$("$PHYSID_VENV/bin/python" "scripts/$s.py" 2>&1) && rc=0 || rc=$?
  fi
  echo "$out"
  # A check that crashed before printing its counts counts as failed (and does not end the run).
  p=$(echo "$out" | { grep -oE '[0-9]+ passed' || true; } | tail -1 | awk '{print $1}')
  f=$(echo "$out" | { grep -oE '[0-9]+ failed' || true; } | tail -1 | awk '{print $1}')
  py_passed=$((py_passed + ${p:-0})); py_failed=$((py_failed + ${f:-1}))
  [ "$rc" = 0 ] || py_failed=$((py_failed + 1))
done

echo
echo "rust: $rust_passed passed; python checks: $py_passed passed, $py_failed failed"
echo "total: $((rust_passed + py_passed)) passed, $py_failed failed"
echo "wall time: $SECONDS s"
[ "$py_failed" = 0 ]
