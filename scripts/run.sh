#!/usr/bin/env bash
# The main job on a fresh machine: the paper's last figure with ground truth (validation error
# versus training size for the four constraint sets over 20 simulated experiments), written to
# results/sample_size/. Installs what it needs first (scripts/setup.sh), then builds physid in
# release mode (cold: about 12 min on 2 cores; the build directory is shared with
# scripts/test.sh). Arguments replace the default `--out results/sample_size`, e.g.
#   bash scripts/run.sh --out /tmp/sample_size --threads 1
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup.sh
setup_rust
setup_system
[ $# -gt 0 ] || set -- --out results/sample_size
cargo build --release --bin physid
exec "$CARGO_TARGET_DIR/release/physid" experiment scenarios/sample_size.toml "$@"
