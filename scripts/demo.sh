#!/usr/bin/env bash
# The main job on a small default: generate the particle cross dataset and a
# noise-free copy, train a planner on each, evaluate stitching on pairs no
# training episode connects, export the planner, plot, and say where it all went.
set -euo pipefail
cd "$(dirname "$0")/.."
FLOWPLAN=${FLOWPLAN:-build/apps/flowplan/flowplan}
PYTHON=$(./scripts/find_python.sh)
start_time=$(date +%s)

setting() {  # setting CONFIG KEY: a value of the resolved config
  "$FLOWPLAN" config show --config "$1" --log-level warn | sed -n "s/^$2: //p"
}

# Training seeds (SEEDS="0 1 2" for the spread between seeds): seed=N changes the
# initial weights, batches and validation split; every seed trains on the same
# data. The config's own seed trains in its run_dir, seed N in RUN_DIR_seedN.
SEEDS=${SEEDS:-0}
summaries=()
for config in configs/particle_cross.yaml configs/particle_cross_no_noise.yaml; do
  base=$(setting "$config" run_dir)
  own_seed=$(setting "$config" seed)
  case " $SEEDS " in
    *" $own_seed "*) ;;
    *) echo "SEEDS=\"$SEEDS\": it must include $config's own seed ($own_seed), whose run the demo plans with" >&2
       exit 1 ;;
  esac
  data=$("$FLOWPLAN" config show --config "$config" --log-level warn | sed -n 's/^  out: //p' | head -1)
  echo "=== $config: dataset $data, run $base"
  "$FLOWPLAN" generate --config "$config"
  runs=()
  for seed in $SEEDS; do
    run=$base
    overrides=()
    if [ "$seed" != "$own_seed" ]; then
      run="${base}_seed$seed"
      overrides=("seed=$seed" "run_dir=$run")
      echo "=== $config, seed $seed: run $run"
    fi
    runs+=("$run")
    # A run left by an earlier demo with this very config is continued (a finished
    # one is left as it is); one made with another config is replaced.
    if [ -d "$run/checkpoints" ] && cmp -s <("$FLOWPLAN" config show --config "$config" "${overrides[@]}" --log-level warn) "$run/config.yaml"; then
      "$FLOWPLAN" train --resume "$run"
    else
      [ -d "$run" ] && echo "replacing $run (made with another config)"
      rm -rf "$run"
      "$FLOWPLAN" train --config "$config" "${overrides[@]}"
    fi
    "$FLOWPLAN" eval stitching --ckpt "$run"
    "$FLOWPLAN" eval stitching --ckpt "$run" sampler.splitting=midpoint --out "$run/eval_stitching_split.json"
    "$FLOWPLAN" export --ckpt "$run"
    "$PYTHON" scripts/plot.py plans "$run/eval_stitching.plans.h5" --data "$data" --out "$run/plans.png"
    "$PYTHON" scripts/plot.py plans "$run/eval_stitching_split.plans.h5" --data "$data" --out "$run/plans_split.png"
  done
  "$PYTHON" scripts/plot.py dataset "$data" --out "$base/dataset.png"
  summaries+=("$("$PYTHON" scripts/summarize_eval.py "$config" "${runs[@]}")")
done

run=$(setting configs/particle_cross.yaml run_dir)
data=$("$FLOWPLAN" config show --config configs/particle_cross.yaml --log-level warn | sed -n 's/^  out: //p' | head -1)
echo "=== guidance: plans from (0,0) to (1,0) around the disc of configs/scenes/particle_disc.yaml"
for mode in unguided guided; do
  scale=$([ "$mode" = unguided ] && echo "guidance.scale=0" || echo "")
  "$FLOWPLAN" plan --ckpt "$run" --config configs/particle_cross.yaml --start 0,0 --goal 1,0 \
    --scene configs/scenes/particle_disc.yaml -n 64 \
    --no-plot --out "$run/plan_$mode" --force sampler.splitting=midpoint $scale  # the demo's own outputs
done
"$PYTHON" scripts/plot.py scene "$run/plan_guided.h5" --compare "$run/plan_unguided.h5" --data "$data" \
  --out "$run/plan_guided.png" --title "particle: guided (blue) and unguided (grey) plans around a disc"
guided_summary=$("$PYTHON" - "$run" <<'PY'
import json, sys
rates = {m: json.load(open(f"{sys.argv[1]}/plan_{m}.json"))["arm_clear_rate"] for m in ("unguided", "guided")}
print(f"  plans whose disc stays clear of the obstacle: unguided {rates['unguided']:.0%}, guided {rates['guided']:.0%} (64 each)")
if rates["guided"] <= rates["unguided"]:
    sys.exit("guidance did not help: " + str(rates))
PY
)
echo "$guided_summary"

echo "=== the exported planner, loaded by Python with nothing but torch"
"$PYTHON" - "$run/planner.pt" <<'PY'
import sys
import torch
planner = torch.jit.load(sys.argv[1])
torch.manual_seed(0)
start, goal = torch.tensor([0.0, 0.0, 0.0, 0.0]), torch.tensor([1.0, 0.0, 0.0, 0.0])
plans = planner.sample(start, goal, 8)
print(f"{sys.argv[1]}: sample(start, goal, 8) -> {tuple(plans.shape)}; "
      f"first state {plans[0, 0].tolist()}, last state {plans[0, -1].tolist()}")
ends = max((plans[:, 0] - start).abs().max().item(), (plans[:, -1] - goal).abs().max().item())
if ends > 1e-6:
    sys.exit(f"{sys.argv[1]}: the plans' ends are {ends} away from the requested start and goal")
print(f"all 8 plans start and end at the requested states (largest difference {ends})")
PY

echo "=== the shipped Franka planner around a sphere, one plan executed and rendered in MuJoCo"
franka=runs/franka_demo
mkdir -p "$franka"
"$FLOWPLAN" plan --planner pretrained/franka_reach_planner.pt --start-tcp 0.5,-0.3,0.2 --goal-tcp 0.5,0.3,0.2 \
  --sphere 0.5,0,0.2,0.1 -n 16 --seed 1 --out "$franka/plan" --force --log-level warn
franka_summary=$("$PYTHON" - "$franka/plan.json" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
valid = sum(s["success"] for s in report["samples"])
print(f"  {valid} of {len(report['samples'])} plans valid by the plan checker "
      f"(every state and motion clear of the sphere, within the joint and speed limits)")
if valid == 0:
    sys.exit("the shipped planner made no valid plan around the sphere")
PY
)
echo "$franka_summary"
"$FLOWPLAN" render "$franka/plan.h5" --index 0 --out "$franka/plan_0" --log-level warn

echo
echo "=== stitching error on the novel pairs (lower is better; one seed: mean ± std over the plans,"
echo "    several: the mean of the seeds' means ± their sample std, then each seed's mean)"
printf '%s\n' "${summaries[@]}"
echo
echo "=== guidance around the disc (runs/particle_cross/plan_guided.png)"
echo "$guided_summary"
echo
echo "=== the Franka (runs/franka_demo/plan.png; plan_0.gif, the arm in MuJoCo)"
echo "$franka_summary"
echo
echo "=== where everything went"
for config in configs/particle_cross.yaml configs/particle_cross_no_noise.yaml; do
  run=$(setting "$config" run_dir)
  echo "  $config -> $run/{config.yaml,metrics.jsonl,checkpoints/,eval_stitching.json,planner.pt,*.png}"
  for seed in $SEEDS; do
    if [ -d "${run}_seed$seed" ]; then echo "    seed $seed -> ${run}_seed$seed/"; fi
  done
  if [ -f "$run/plan_guided.json" ]; then echo "    and $run/plan_{unguided,guided}.{h5,json}, plan_guided.png"; fi
done
echo "  the Franka -> runs/franka_demo/{plan.h5,plan.json,plan.png,plan_0.gif,plan_0.png}"
echo "  datasets in data/; total time $(( $(date +%s) - start_time )) s"
