#!/usr/bin/env python3
"""Plots flowplan datasets and evaluation plans as PNG files.

  plot.py dataset DATA.h5 --out dataset.png [--episodes 300]
      particle: x-y paths; franka: TCP paths in the y-z plane (/extras/tcp)
  plot.py plans EVAL.plans.h5 --data DATA.h5 --out plans.png
      the dataset in grey, the test-pair plans of `flowplan eval stitching` on top

Needs Debian's python3-h5py and python3-matplotlib (run with /usr/bin/python3).
"""
import argparse
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def paths_2d(f):
    """Returns (N, T, 2) paths to draw, axis labels, and a title."""
    env = f.attrs["env"]
    if "extras" in f and "tcp" in f["extras"]:
        tcp = f["extras"]["tcp"][...]
        return tcp[..., 1:3], ("TCP y (m)", "TCP z (m)"), f"{env}: TCP paths"
    states = f["states"][...]
    return states[..., :2], tuple(f.attrs["state_labels"].split(",")[:2]), f"{env}: paths"


def draw_dataset(ax, f, episodes, faint=False):
    paths, labels, title = paths_2d(f)
    family = f["family"][...]
    rng = np.random.default_rng(0)
    chosen = rng.choice(len(paths), size=min(episodes, len(paths)), replace=False)
    colors = plt.get_cmap("tab10")
    for i in chosen:
        color = "0.75" if faint else colors(max(int(family[i]), 0) % 10)
        ax.plot(paths[i, :, 0], paths[i, :, 1], color=color, lw=0.6, alpha=0.5 if not faint else 0.4)
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    ax.set_aspect("equal", adjustable="datalim")
    return title


def command_dataset(args):
    with h5py.File(args.data, "r") as f:
        fig, ax = plt.subplots(figsize=(6, 6))
        title = draw_dataset(ax, f, args.episodes)
        ax.set_title(f"{title} ({min(args.episodes, f['states'].shape[0])} of {f['states'].shape[0]} episodes)")
    fig.tight_layout()
    fig.savefig(args.out, dpi=args.dpi)
    print(f"wrote {args.out}")


def command_plans(args):
    with h5py.File(args.data, "r") as data, h5py.File(args.plans, "r") as plans:
        if "extras" in data and "tcp" in data["extras"]:
            sys.exit("plot.py plans: Franka plans are joint-space; plot their TCP with flowplan's kinematics")
        names = data["eval/test_pairs"].attrs["names"].split(";")
        fig, ax = plt.subplots(figsize=(6, 6))
        draw_dataset(ax, data, args.episodes, faint=True)
        x = plans["test/plans"][...]
        index = plans["test/pair_index"][...]
        colors = plt.get_cmap("tab10")
        for p, name in enumerate(names):
            chosen = np.flatnonzero(index == p)
            if len(chosen) == 0:  # fewer plans than pairs
                continue
            for k, i in enumerate(chosen):
                ax.plot(x[i, :, 0], x[i, :, 1], color=colors(p + 2), lw=1.0, alpha=0.8,
                        label=f"plan {name}" if k == 0 else None)
            ax.plot(*x[chosen[0], 0, :2], "ko", ms=5)
            ax.plot(*x[chosen[0], -1, :2], "k*", ms=9)
        ax.legend(loc="upper center", fontsize=8)
        ax.set_title(args.title or "stitching: plans between pairs no training episode connects", fontsize=10)
    fig.tight_layout()
    fig.savefig(args.out, dpi=args.dpi)
    print(f"wrote {args.out}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("dataset", help="draw a dataset's paths")
    p.add_argument("data")
    p.add_argument("--out", required=True)
    p.add_argument("--episodes", type=int, default=300)
    p.set_defaults(run=command_dataset)
    p = sub.add_parser("plans", help="draw evaluation plans over the dataset")
    p.add_argument("plans")
    p.add_argument("--data", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--episodes", type=int, default=200)
    p.add_argument("--title", help="figure title (default: says what the plans are)")
    p.set_defaults(run=command_plans)
    for p in sub.choices.values():
        p.add_argument("--dpi", type=int, default=120, help="resolution of the 6 x 6 inch PNG")
    args = parser.parse_args()
    args.run(args)


if __name__ == "__main__":
    main()
