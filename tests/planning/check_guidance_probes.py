"""Runs scripts/guidance_probes.py on the shipped Franka reach planner (a few
plans) and checks it: its unguided plans equal the planner's own
plan(..., scale=0) and its clean-sample predictions the sampler's one Euler
step to t = 1 (to 1e-5); what holds by construction holds (a push after the
last step is the plan's change: survival 1; at t = 1 both gradients are the
plan's, and one step before it the clean-sample prediction is the plan:
cosine 1); every figure is finite and the cosines lie in [-1, 1].

usage: check_guidance_probes.py PYTHON SCRIPT PLANNER.pt OUT_DIR
"""
import json
import math
import os
import subprocess
import sys


def main():
    python, script, planner, out = sys.argv[1:5]
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "probes.json")
    subprocess.run([python, script, f"shipped={planner}", "--plans", "6", "--json", path], check=True)
    with open(path) as f:
        result = json.load(f)[0]
    failures = []
    for key in ("check_unguided_plan_max_abs", "check_x1hat_max_abs"):
        if not result.get(key, 1.0) <= 1e-5:
            failures.append(f"{key} = {result.get(key)}, expected at most 1e-5")
    if result["plans_used"] < 1:
        failures.append("no plan came within the collision margin of the sphere")
    else:
        if abs(result["survival_median"][-1] - 1.0) > 1e-4:
            failures.append(f"survival after the last step {result['survival_median'][-1]}, expected 1")
        for key, index in (("cos_x1hat_median", -1), ("cos_x1hat_median", -2), ("cos_xt_median", -1)):
            if abs(result[key][index] - 1.0) > 1e-5:
                failures.append(f"{key}[{index}] = {result[key][index]}, expected 1")
        for key in ("survival_median", "cos_xt_median", "cos_x1hat_median"):
            if not all(math.isfinite(v) for v in result[key]):
                failures.append(f"{key} has a non-finite value: {result[key]}")
        for key in ("cos_xt_median", "cos_x1hat_median"):
            if not all(-1.0 - 1e-6 <= v <= 1.0 + 1e-6 for v in result[key]):
                failures.append(f"{key} outside [-1, 1]: {result[key]}")
        if len(result["survival_median"]) != result["steps"]:
            failures.append(f"{len(result['survival_median'])} survival figures for {result['steps']} steps")
    for failure in failures:
        print("FAILED:", failure, file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
