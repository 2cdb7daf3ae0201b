#!/usr/bin/env python3
"""Markdown tables of the stitching errors of scripts/particle_ablation.sh's runs:
one row per variant, then noise vs no noise over the training seeds."""
import json
import os
import statistics
import sys

out = sys.argv[1]


def load(name, file):
    with open(os.path.join(out, name, file)) as f:
        return json.load(f)


def cell(r):
    return f"{r['mean']:.3f} ± {r['stddev']:.3f}"


print("| variant | data | overrides | steps | test pairs | test pairs, split | training pairs |")
print("|---|---|---|---|---|---|---|")
seeds = {"noise": [], "no noise": []}
with open(os.path.join(out, "variants.txt")) as f:
    for line in f:
        name, config, overrides = line.rstrip("\n").split("|")
        plain, split = load(name, "eval_stitching.json"), load(name, "eval_stitching_split.json")
        data = "no noise" if "no_noise" in config else "noise"
        if name.startswith("unet2_seed") or name in ("unet2_noise", "unet2_no_noise"):
            seeds[data].append((plain["test"]["mean"], split["test"]["mean"]))
        print(f"| {name} | {data} | {overrides or '—'} | {plain['step']} | {cell(plain['test'])} | "
              f"{cell(split['test'])} | {cell(plain['train'])} |")

print()
print("Default network (2 levels), test pairs: mean over training seeds of each run's mean error "
      "(min–max over the seeds).")
print()
print("| data | seeds | test pairs | test pairs, split |")
print("|---|---|---|---|")
for data, runs in seeds.items():
    if not runs:
        continue
    plain, split = [r[0] for r in runs], [r[1] for r in runs]
    print(f"| {data} | {len(runs)} | {statistics.mean(plain):.3f} ({min(plain):.3f}–{max(plain):.3f}) | "
          f"{statistics.mean(split):.3f} ({min(split):.3f}–{max(split):.3f}) |")
