#!/usr/bin/env python3
"""The particle zoo's table (markdown) from ROOT/<row>/eval_stitching*.json.

usage: summarize_zoo.py ROOT
"""
import json
import os
import sys

ROWS = [
    ("fp_unet", "FP: UNet, inpainting"),
    ("fp_unet_direct", "FP: UNet, direct conditioning"),
    ("fp_transformer", "FP: transformer, inpainting"),
    ("fp_transformer_direct", "FP: transformer, direct conditioning"),
    ("mpd", "MPD: DDPM, UNet, inpainting, 25 steps"),
    ("vae", "VAE: latent activation maximization"),
]


def cell(report, pairs):
    if report is None:
        return "–"
    part = report[pairs]
    return f"{part['mean']:.3f} ± {part['stddev']:.3f}"


root = sys.argv[1]
print("| model | test pairs | test pairs, split | training pairs | train time (s) |")
print("|---|---|---|---|---|")
for name, label in ROWS:
    run = os.path.join(root, name)
    reports = {}
    for key, file in (("plain", "eval_stitching.json"), ("split", "eval_stitching_split.json")):
        path = os.path.join(run, file)
        reports[key] = json.load(open(path)) if os.path.exists(path) else None
    if reports["plain"] is None:
        print(f"| {label} | not run | | | |")
        continue
    seconds_path = os.path.join(run, "train_seconds.txt")
    seconds = open(seconds_path).read().strip() if os.path.exists(seconds_path) else "–"
    print(f"| {label} | {cell(reports['plain'], 'test')} | {cell(reports['split'], 'test')} | "
          f"{cell(reports['plain'], 'train')} | {seconds} |")
