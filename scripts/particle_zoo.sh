#!/usr/bin/env bash
# The model zoo on the particle cross: every model trained from
# configs/particle_cross.yaml with the overrides of its row, evaluated by
# `flowplan eval stitching` (and with inference-time splitting where the
# sampler has it), exported and loaded in Python; the table goes to
# runs/zoo/summary.md. A row whose evaluation exists is skipped, a stopped
# training resumes, so the script continues where it stopped.
#
# usage: scripts/particle_zoo.sh [extra overrides for every row, e.g. train.steps=50]
set -euo pipefail
cd "$(dirname "$0")/.."
FLOWPLAN=${FLOWPLAN:-build/apps/flowplan/flowplan}
PYTHON=$(./scripts/find_python.sh)
CONFIG=configs/particle_cross.yaml
ROOT=${ZOO_ROOT:-runs/zoo}
extra=("$@")

# name | overrides
rows=(
  "fp_unet|"
  "fp_unet_direct|objective.conditioning=direct"
  "fp_transformer|model.name=transformer"
  "fp_transformer_direct|model.name=transformer objective.conditioning=direct"
  "mpd|objective.name=ddpm"
  "vae|model.name=state_vae objective.name=vae"
)

"$FLOWPLAN" generate --config "$CONFIG" "${extra[@]}"
mkdir -p "$ROOT"
for row in "${rows[@]}"; do
  name=${row%%|*}
  read -r -a overrides <<< "${row#*|}"
  run="$ROOT/$name"
  settings=("${overrides[@]}" "${extra[@]}" "run_dir=$run")
  if [ -f "$run/eval_stitching.json" ]; then
    echo "=== $name: evaluated already ($run/eval_stitching.json)"
    continue
  fi
  echo "=== $name: ${overrides[*]:-(the preset)}"
  started=$(date +%s)
  if compgen -G "$run/checkpoints/step_*.pt" > /dev/null; then
    "$FLOWPLAN" train --resume "$run"
  else
    rm -rf "$run"
    "$FLOWPLAN" train --config "$CONFIG" "${settings[@]}"
  fi
  # Training seconds summed over every invocation that trained this row.
  before=$(cat "$run/train_seconds.txt" 2> /dev/null || echo 0)
  echo $(( before + $(date +%s) - started )) > "$run/train_seconds.txt"
  if [ "$name" != mpd ] && [ "$name" != vae ]; then
    "$FLOWPLAN" eval stitching --ckpt "$run" sampler.splitting=midpoint --out "$run/eval_stitching_split.json"
  fi
  "$FLOWPLAN" export --ckpt "$run"
  "$PYTHON" - "$run/planner.pt" <<'PY'
import sys
import torch
planner = torch.jit.load(sys.argv[1])
with torch.no_grad():
    plans = planner.sample(torch.zeros(4), torch.tensor([1.0, 0.0, 0.0, 0.0]), 4)
assert plans.shape == (4, planner.horizon, 4), plans.shape
print(f"{sys.argv[1]}: {planner.planner} planner, sample -> {tuple(plans.shape)}")
PY
  "$FLOWPLAN" eval stitching --ckpt "$run"  # last: its report marks the row as done
done
"$PYTHON" scripts/summarize_zoo.py "$ROOT" | tee "$ROOT/summary.md"
