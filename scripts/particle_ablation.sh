#!/usr/bin/env bash
# What makes the particle planner stitch: UNet depth (receptive field), the
# data's noise augmentation, inpainting vs direct conditioning, and inference
# splitting. Every variant is configs/particle_cross.yaml (or its no-noise twin)
# with one change, trained for the same steps; the table goes to
# runs/ablation/summary.md. About an hour on two cores.
set -euo pipefail
cd "$(dirname "$0")/.."
FLOWPLAN=${FLOWPLAN:-build/apps/flowplan/flowplan}
PYTHON=$(./scripts/find_python.sh)
OUT=${OUT:-runs/ablation}
STEPS=${STEPS:-3000}
mkdir -p "$OUT"

for config in configs/particle_cross.yaml configs/particle_cross_no_noise.yaml; do
  data=$("$FLOWPLAN" config show --config "$config" --log-level warn | sed -n 's/^  out: //p' | head -1)
  [ -f "$data" ] || "$FLOWPLAN" generate --config "$config"
done

variant() {  # variant NAME CONFIG OVERRIDES...
  local name=$1 config=$2
  shift 2
  local run="$OUT/$name"
  if [ ! -f "$run/eval_stitching_split.json" ]; then
    "$FLOWPLAN" train --config "$config" run_dir="$run" train.steps="$STEPS" "$@"
    "$FLOWPLAN" eval stitching --ckpt "$run"
    "$FLOWPLAN" eval stitching --ckpt "$run" sampler.splitting=midpoint --out "$run/eval_stitching_split.json"
  fi
  echo "$name|$config|$*" >> "$OUT/variants.txt"
}

rm -f "$OUT/variants.txt"
for noise in noise no_noise; do
  config=configs/particle_cross.yaml
  [ "$noise" = no_noise ] && config=configs/particle_cross_no_noise.yaml
  variant "unet2_$noise" "$config"
  variant "unet3_$noise" "$config" "model.unet.down_dims=[32,64,128]"
  variant "unet4_$noise" "$config" "model.unet.down_dims=[32,64,128,256]"
  variant "unet2_direct_$noise" "$config" flow.conditioning=direct
  variant "unet2_nosplit_$noise" "$config" flow.split_prob=0
done
"$PYTHON" scripts/summarize_ablation.py "$OUT" > "$OUT/summary.md"
cat "$OUT/summary.md"
