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


def span(values):
    """Mean of per-run errors, with (min–max) when there are several runs."""
    return f"{statistics.mean(values):.3f}" + (f" ({min(values):.3f}–{max(values):.3f})" if len(values) > 1 else "")


def cell(r):
    return f"{r['mean']:.3f} ± {r['stddev']:.3f}"


_crossing = {}


def crossing(path):
    """What the data offers for stitching: (vy std among the states within 0.05
    of the centre (0.5, 0.5), pooled over the two families; how many of those
    standard deviations apart the families' mean vy are; how close the nearest
    training episode comes to connecting a test pair (mean over the test pairs
    of the smallest ½(|first position − start| + |last position − goal|));
    accel_noise of the file's config)."""
    if path not in _crossing:
        with h5py.File(path, "r") as f:
            states, family = f["states"][...], f["family"][...]
            config = f.attrs["config"]
            test_start, test_goal = f["eval/test_pairs/start"][...], f["eval/test_pairs/goal"][...]
        vy = []
        for k in (0, 1):
            x = states[family == k]
            near = (np.abs(x[..., 0] - 0.5) < 0.05) & (np.abs(x[..., 1] - 0.5) < 0.05)
            vy.append(x[..., 3][near])
        pooled = float(np.sqrt((vy[0].var() + vy[1].var()) / 2))
        separation = abs(float(vy[0].mean() - vy[1].mean())) / pooled
        first, last = states[:, 0, :2], states[:, -1, :2]
        nearest = float(np.mean([
            (0.5 * (np.linalg.norm(first - a[:2], axis=1) + np.linalg.norm(last - b[:2], axis=1))).min()
            for a, b in zip(test_start, test_goal)]))
        accel = next(line.split(":")[1].strip() for line in config.splitlines()
                     if line.strip().startswith("accel_noise:"))
        _crossing[path] = (pooled, separation, nearest, accel)
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
        if name in ("unet2_noise", "unet2_no_noise") or name.startswith("unet2_accel") \
                or name.startswith("unet2_seed"):
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
    print(f"| {data} | {len(runs)} | {span(plain)} | {span(split)} |")

if scales:
    print()
    print("Noise scale (default network): the acceleration noise of the data; the spread of vy among the "
          "states within 0.05 of the crossing (0.5, 0.5); how many of those standard deviations apart the "
          "two families' mean vy are (the families overlap in the full state only when this is small); how "
          "close the nearest training episode comes to connecting a test pair (mean endpoint distance; "
          "0 would be a training episode that joins them); the test-pair stitching error, mean over the "
          "training seeds of each run's mean (min–max).")
    print()
    print("| accel_noise | vy std at the crossing | family separation (std) | nearest training episode | seeds "
          "| test pairs | test pairs, split |")
    print("|---|---|---|---|---|---|---|")
    levels = {}
    for stats, plain, split in scales:
        levels.setdefault(stats, []).append((plain["test"]["mean"], split["test"]["mean"]))
    for (pooled, separation, nearest, accel), runs in sorted(levels.items(), key=lambda r: float(r[0][3])):
        plain, split = [r[0] for r in runs], [r[1] for r in runs]
        print(f"| {accel} | {pooled:.3f} | {separation:.1f} | {nearest:.3f} | {len(runs)} | {span(plain)} | "
              f"{span(split)} |")
