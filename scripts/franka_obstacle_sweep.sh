#!/usr/bin/env bash
# Obstacle avoidance on the Franka, the paper's scene: TCP from (0.5, -0.3, 0.2)
# to (0.5, 0.3, 0.2) around one sphere at (0.5, 0, 0.2) whose radius is swept,
# 64 plans per radius, each plan executed in MuJoCo. Planners: the reach flow
# planner (FP), the same with inference-time splitting (FP + split) and
# RRT-Connect. Every cell is one `flowplan plan` report
# (OUT/<planner>_r<radius>.json); a cell whose report exists is skipped, so an
# interrupted sweep continues where it stopped. Radii whose start or goal lies
# inside the sphere are refused by `flowplan plan` and recorded as such.
# The table and the plot: scripts/summarize_sweep.py OUT.
#
# usage: scripts/franka_obstacle_sweep.sh [RUN_DIR (runs/franka_reach)] [OUT (RUN_DIR/sweep)]
# RRT-Connect plans for the robot, horizon and dt of CONFIG's dataset
# (default configs/franka_reach.yaml); RADII overrides the radii.
set -euo pipefail
cd "$(dirname "$0")/.."
FLOWPLAN=${FLOWPLAN:-build/apps/flowplan/flowplan}
PYTHON=$(./scripts/find_python.sh)
RUN=${1:-runs/franka_reach}
OUT=${2:-$RUN/sweep}
CONFIG=${CONFIG:-configs/franka_reach.yaml}
RADII=${RADII:-"0.025 0.05 0.075 0.1 0.125 0.15 0.175 0.2 0.225 0.25 0.275 0.3 0.325"}
mkdir -p "$OUT"
common=(--start-tcp 0.5,-0.3,0.2 --goal-tcp 0.5,0.3,0.2 --scene configs/scenes/franka_sphere.yaml
        -n 64 --seed 1 --execute --no-plot --log-level warn)

for radius in $RADII; do
  for planner in fp fp_split rrt_connect; do
    prefix="$OUT/${planner}_r${radius}"
    [ -f "$prefix.json" ] || [ -f "$prefix.refused" ] && continue
    case $planner in
      fp) source=(--ckpt "$RUN") ;;
      fp_split) source=(--ckpt "$RUN" sampler.splitting=midpoint) ;;
      rrt_connect) source=(--rrt-connect --config "$CONFIG") ;;
    esac
    if ! message=$("$FLOWPLAN" plan "${source[@]}" "${common[@]}" --radius "$radius" --out "$prefix" 2>&1); then
      if grep -q "inside obstacle" <<< "$message"; then
        echo "$message" > "$prefix.refused.tmp" && mv "$prefix.refused.tmp" "$prefix.refused"
      else
        echo "$message" >&2
        exit 1
      fi
    fi
    echo "$planner r=$radius done"
  done
done
"$PYTHON" scripts/summarize_sweep.py "$OUT"
