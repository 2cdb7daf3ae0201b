#!/usr/bin/env python3
"""One line per run from RUN/eval_stitching.json and RUN/eval_stitching_split.json."""
import json
import os
import sys

config, run = sys.argv[1], sys.argv[2]
parts = []
for name, label in (("eval_stitching.json", "FP"), ("eval_stitching_split.json", "FP + split")):
    path = os.path.join(run, name)
    if not os.path.exists(path):
        continue
    with open(path) as f:
        report = json.load(f)
    test, train = report["test"], report["train"]
    parts.append(f"{label}: test {test['mean']:.3f} ± {test['stddev']:.3f} (train pairs {train['mean']:.3f})")
print(f"  {config:40s} step {report['step']}: " + "; ".join(parts))
