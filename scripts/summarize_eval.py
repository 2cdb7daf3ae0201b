#!/usr/bin/env python3
"""The stitching errors of one config's runs (one per training seed), from each
RUN/eval_stitching.json and RUN/eval_stitching_split.json.

usage: summarize_eval.py CONFIG RUN [RUN ...]

One run: its mean ± std over the plans. Several: the mean of the runs' means ±
their sample standard deviation (the spread between seeds), then each run's."""
import json
import os
import sys

config, runs = sys.argv[1], sys.argv[2:]
if not runs:
    sys.exit("usage: summarize_eval.py CONFIG RUN [RUN ...]")
parts = []
step = None
for name, label in (("eval_stitching.json", "FP"), ("eval_stitching_split.json", "FP + split")):
    reports = []
    for run in runs:
        path = os.path.join(run, name)
        if os.path.exists(path):
            with open(path) as f:
                reports.append(json.load(f))
    if not reports:
        continue
    if len(reports) < len(runs):
        print(f"warning: {name} in {len(reports)} of {len(runs)} runs", file=sys.stderr)
    if len({r["step"] for r in reports}) > 1:
        print(f"warning: {name}: the runs stopped at different steps {[r['step'] for r in reports]}", file=sys.stderr)
    step = reports[0]["step"]
    if len(reports) == 1:
        test, train = reports[0]["test"], reports[0]["train"]
        parts.append(f"{label}: test {test['mean']:.3f} ± {test['stddev']:.3f} (train pairs {train['mean']:.3f})")
        continue
    means = [r["test"]["mean"] for r in reports]
    mean = sum(means) / len(means)
    spread = (sum((m - mean) ** 2 for m in means) / (len(means) - 1)) ** 0.5
    parts.append(f"{label}: test {mean:.3f} ± {spread:.3f} over {len(means)} seeds "
                 f"({', '.join(f'{m:.3f}' for m in means)})")
if step is None:
    sys.exit(f"{config}: no eval_stitching.json in {', '.join(runs)}")
print(f"  {config:40s} step {step}: " + "; ".join(parts))
