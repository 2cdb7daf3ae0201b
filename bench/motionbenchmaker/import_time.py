#!/usr/bin/env python3
"""How `flowplan scenes import` time grows with the number of problems, on the published MotionBenchMaker files.

usage: import_time.py FLOWPLAN TARBALL [--families a,b] [--counts 10,50,100] [--repeats 3]

For each family, imports its first N scene/request pairs for every N of --counts (the median of --repeats runs
each), and prints the times, the time per added problem between the smallest and largest N (the slope), and the
process's fixed cost (the intercept). Linear growth shows as one slope for every pair of counts.
"""
import argparse
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("flowplan")
    parser.add_argument("tarball")
    parser.add_argument("--families", default="bookshelf_thin,table_under_pick")
    parser.add_argument("--counts", default="10,50,100")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    counts = [int(n) for n in args.counts.split(",")]
    with tempfile.TemporaryDirectory() as scratch:
        with tarfile.open(args.tarball) as tar:
            tar.extractall(scratch)
        root = os.path.join(scratch, os.listdir(scratch)[0])
        print("| family | " + " | ".join(f"{n} problems (s)" for n in counts) + " | s per problem | fixed s |")
        print("|---|" + "---|" * (len(counts) + 2))
        for family in args.families.split(","):
            folder = os.path.join(root, f"{family}_panda")
            if not os.path.isdir(folder):
                sys.exit(f"import_time.py: {args.tarball}: no folder {family}_panda")
            times = []
            for n in counts:
                files = []
                for i in range(1, n + 1):
                    files += [os.path.join(folder, f"scene{i:04d}.yaml"), os.path.join(folder, f"request{i:04d}.yaml")]
                runs = []
                for _ in range(args.repeats):
                    began = time.perf_counter()
                    done = subprocess.run([args.flowplan, "scenes", "import", *files, "--out",
                                           os.path.join(scratch, "out.yaml"), "--log-level", "warn"],
                                          capture_output=True, text=True)
                    runs.append(time.perf_counter() - began)
                    if done.returncode != 0:
                        sys.exit(f"import_time.py: {family}, {n} problems: {done.stderr.strip()}")
                times.append(statistics.median(runs))
            slope = (times[-1] - times[0]) / (counts[-1] - counts[0])
            fixed = times[0] - slope * counts[0]
            print(f"| {family} | " + " | ".join(f"{t:.2f}" for t in times) + f" | {slope:.4f} | {fixed:.2f} |")


if __name__ == "__main__":
    main()
