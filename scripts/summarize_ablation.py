#!/usr/bin/env python3
"""Markdown tables of the stitching errors of scripts/particle_ablation.sh's runs:
one row per variant, then noise vs no noise over the training seeds, then the
noise scale against how far apart the two families stay at the crossing."""
import json
import os
import statistics
import sys

import h5py
import numpy as np

out = sys.argv[1]


def load(name, file):
    with open(os.path.join(out, name, file)) as f:
        return json.load(f)


def cell(r):
    return f"{r['mean']:.3f} ± {r['stddev']:.3f}"


_crossing = {}


def crossing(path):
    """Velocities of the states within 0.05 of the centre (0.5, 0.5), per family:
    (vy std pooled over the families, separation of the families' vy means in
    pooled standard deviations, accel_noise of the file's config)."""
    if path not in _crossing:
        with h5py.File(path, "r") as f:
            states, family = f["states"][...], f["family"][...]
            config = f.attrs["config"]
        vy = []
        for k in (0, 1):
            x = states[family == k]
            near = (np.abs(x[..., 0] - 0.5) < 0.05) & (np.abs(x[..., 1] - 0.5) < 0.05)
            vy.append(x[..., 3][near])
        pooled = float(np.sqrt((vy[0].var() + vy[1].var()) / 2))
        separation = abs(float(vy[0].mean() - vy[1].mean())) / pooled
        accel = next(line.split(":")[1].strip() for line in config.splitlines()
                     if line.strip().startswith("accel_noise:"))
        _crossing[path] = (pooled, separation, accel)
    return _crossing[path]


print("| variant | data | overrides | steps | test pairs | test pairs, split | training pairs |")
print("|---|---|---|---|---|---|---|")
seeds = {"noise": [], "no noise": []}
scales = []
with open(os.path.join(out, "variants.txt")) as f:
    for line in f:
        name, config, overrides = line.rstrip("\n").split("|")
        plain, split = load(name, "eval_stitching.json"), load(name, "eval_stitching_split.json")
        data = "no noise" if "no_noise" in config else "noise"
        if name.startswith("unet2_seed") or name in ("unet2_noise", "unet2_no_noise"):
            seeds[data].append((plain["test"]["mean"], split["test"]["mean"]))
        if name in ("unet2_noise", "unet2_no_noise") or name.startswith("unet2_accel"):
            scales.append((crossing(plain["data"]), plain, split))
        print(f"| {name} | {os.path.basename(plain['data'])} | {overrides or '—'} | {plain['step']} | "
              f"{cell(plain['test'])} | {cell(split['test'])} | {cell(plain['train'])} |")

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

if scales:
    print()
    print("Noise scale (default network, seed 0): the acceleration noise of the data, the spread of vy "
          "among the states within 0.05 of the crossing (0.5, 0.5), and how many of those standard "
          "deviations apart the two families' mean vy are (the families overlap in the full state only "
          "when this is small).")
    print()
    print("| accel_noise | vy std at the crossing | family separation (std) | test pairs | test pairs, split |")
    print("|---|---|---|---|---|")
    for (pooled, separation, accel), plain, split in sorted(scales, key=lambda r: float(r[0][2])):
        print(f"| {accel} | {pooled:.3f} | {separation:.1f} | {cell(plain['test'])} | {cell(split['test'])} |")
