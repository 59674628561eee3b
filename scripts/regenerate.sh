#!/usr/bin/env bash
# Regenerates the committed results (results/NAME/) with the release binary, each by the command
# its docs give. Usage: bash scripts/regenerate.sh [NAME ...]   (default: all but the blind
# benchmarks, which take a few minutes each: give `blind`, `blind_seed2`,
# `blind_real_{seed1,seed2,baseline_seed1,baseline_seed2}` and `generalize` (15 min) by name). PHYSID_BIN=path runs that
# binary instead of building one (a copy keeps a long regeneration apart from ongoing builds).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/physid-target}"
B="${PHYSID_BIN:-$CARGO_TARGET_DIR/release/physid}"
K=data/kuka_lwr4
run() {
  case "$1" in
    sample_size) "$B" experiment scenarios/sample_size.toml --out results/sample_size ;;
    ci_baseline) "$B" experiment scenarios/ci.toml --out results/ci_baseline ;;
    noise) "$B" sweep scenarios/sweeps/noise.toml --out results/noise ;;
    excitation) "$B" experiment scenarios/excitation/compare.toml --out results/excitation ;;
    excitation_on_shell) "$B" experiment scenarios/excitation/compare_on_shell.toml --out results/excitation_on_shell ;;
    excitation_kuka) "$B" experiment scenarios/excitation/compare_kuka.toml --out results/excitation_kuka ;;
    kuka_diagnosis)
      "$B" diagnose --robot $K/kuka_lwr4.urdf --data $K/measurements_1.csv $K/measurements_2.csv \
        --validate $K/measurements_3.csv --report results/kuka_diagnosis > results/.kuka_diagnosis.txt 2>&1
      # The report folder is replaced whole by the command; its text joins it afterwards.
      mv results/.kuka_diagnosis.txt results/kuka_diagnosis/diagnose.txt ;;
    blind) "$B" blind --cases 102 --seed 1 --out results/blind ;;
    blind_seed2) "$B" blind --cases 102 --seed 2 --out results/blind_seed2 ;;
    blind_real_seed1|blind_real_seed2|blind_real_baseline_seed1|blind_real_baseline_seed2)
      runs=$K/measurements_1.csv,$K/measurements_2.csv,$K/measurements_3.csv
      seed=${1##*seed}; mode=(); name=seed$seed
      case "$1" in *baseline*) mode=(--real-baseline); name=baseline_seed$seed ;; esac
      mkdir -p results/blind_real
      "$B" blind --real "$runs" --real-robot $K/kuka_lwr4.urdf "${mode[@]}" --cases 55 --seed "$seed" \
        --out results/blind_real/$name ;;
    generalize) "$B" generalize --cases 22 --seeds 1,2 --out results/generalize ;;
    whole_robot) "$B" experiment scenarios/quadruped.toml --out results/whole_robot ;;
    whole_robot_force_noise) "$B" whole-robot --force-noise 0.5,1,2,5,10,20 --sizes 1000,3000 --out results/whole_robot_force_noise ;;
    whole_robot_trot) "$B" whole-robot --trot 0.15,2.5 --out results/whole_robot_trot ;;
    whole_robot_logged) "$B" whole-robot --logged --out results/whole_robot_logged ;;
    whole_robot_trot_logged) "$B" whole-robot --trot 0.15,2.5 --logged --out results/whole_robot_trot_logged ;;
    *) echo "unknown result '$1'" >&2; exit 2 ;;
  esac
}
[ $# -gt 0 ] || set -- sample_size ci_baseline noise excitation excitation_on_shell excitation_kuka kuka_diagnosis whole_robot whole_robot_force_noise whole_robot_trot whole_robot_logged whole_robot_trot_logged
[ -n "${PHYSID_BIN:-}" ] || cargo build --release --quiet --bin physid
for r in "$@"; do
  start=$(date +%s)
  run "$r" > /dev/null
  echo "$r: $(( $(date +%s) - start )) s"
done
