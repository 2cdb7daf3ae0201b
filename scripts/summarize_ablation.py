#!/usr/bin/env python3
"""Markdown table of the stitching errors of scripts/particle_ablation.sh's runs."""
import json
import os
import sys

out = sys.argv[1]
print("| variant | data | overrides | steps | test pairs | test pairs, split | training pairs |")
print("|---|---|---|---|---|---|---|")
with open(os.path.join(out, "variants.txt")) as f:
    for line in f:
        name, config, overrides = line.rstrip("\n").split("|")
        with open(os.path.join(out, name, "eval_stitching.json")) as g:
            plain = json.load(g)
        with open(os.path.join(out, name, "eval_stitching_split.json")) as g:
            split = json.load(g)
        data = "no noise" if "no_noise" in config else "noise"
        cell = lambda r: f"{r['mean']:.3f} ± {r['stddev']:.3f}"
        print(f"| {name} | {data} | {overrides or '—'} | {plain['step']} | {cell(plain['test'])} | "
              f"{cell(split['test'])} | {cell(plain['train'])} |")
