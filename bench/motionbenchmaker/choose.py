#!/usr/bin/env python3
"""The variant of one planner that validation chooses: most valid plans over every validation problem (a refused
problem counts as a failure), then the lowest median time per plan.

usage: choose.py --planner NAME --variants JSON --out chosen.json VAL_JSON...
(VAL_JSON: ROOT/val/<planner>/<variant>/<family>.json, reports of `flowplan plan --problems`)
"""
import argparse
import json
import os
import statistics
import sys


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--planner", required=True)
    parser.add_argument("--variants", required=True, help="JSON: variant -> arguments of flowplan plan")
    parser.add_argument("--out", required=True)
    parser.add_argument("reports", nargs="+")
    args = parser.parse_args()
    variants = json.loads(args.variants)
    rows = {}
    for path in args.reports:
        variant = os.path.basename(os.path.dirname(path))
        if variant not in variants:
            sys.exit(f"choose.py: {path}: variant {variant!r} is not one of {sorted(variants)}")
        with open(path) as f:
            report = json.load(f)
        row = rows.setdefault(variant, {"valid": 0, "plans": 0, "times": []})
        for problem in report["problems"]:
            row["plans"] += max(1, len(problem["samples"]))
            for sample in problem["samples"]:
                row["valid"] += bool(sample["success"])
                row["times"].append(sample["planning_time_s"])
    table = {}
    for variant, row in rows.items():
        table[variant] = {"valid": row["valid"], "plans": row["plans"],
                          "median_time_s": statistics.median(row["times"]) if row["times"] else float("inf")}
    chosen = min(table, key=lambda v: (-table[v]["valid"], table[v]["median_time_s"], v))
    result = {"planner": args.planner, "variant": chosen, "arguments": variants[chosen], "validation": table,
              "rule": "most valid plans over the validation problems, then the lowest median time per plan"}
    tmp = args.out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
    os.replace(tmp, args.out)


if __name__ == "__main__":
    main()
