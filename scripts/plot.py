#!/usr/bin/env python3
"""Plots flowplan datasets and evaluation plans as PNG files.

  plot.py dataset DATA.h5 --out dataset.png [--episodes 300]
      particle: x-y paths; franka: TCP paths in the y-z plane (/extras/tcp)
  plot.py plans EVAL.plans.h5 --data DATA.h5 --out plans.png
      the dataset in grey, the test-pair plans of `flowplan eval stitching` on top
  plot.py scene PLAN.h5 --out plan.png [--data DATA.h5] [--compare OTHER.h5]
      the TCP paths of `flowplan plan` with the obstacles (particle: the unit
      square; Franka: the two planes in which the paths spread most), executed
      paths dashed; --compare draws another plan file's paths in grey (e.g. unguided)

Needs Debian's python3-h5py and python3-matplotlib (run with /usr/bin/python3).
"""
import argparse
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def save(fig, out, dpi):
    """Writes the figure to a temporary name and renames it into place: never a half-written OUT."""
    root, extension = os.path.splitext(out)
    temporary = f"{root}.tmp-{os.getpid()}{extension}"  # the extension tells matplotlib the format
    fig.savefig(temporary, dpi=dpi)
    os.replace(temporary, out)


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
    save(fig, args.out, args.dpi)
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
    save(fig, args.out, args.dpi)
    print(f"wrote {args.out}")


def robot_radius(f):
    """The point robot's radius from the robot description (0 for an arm)."""
    for line in f.attrs["robot"].splitlines():
        if line.startswith("point_radius:"):
            return float(line.split(":")[1])
    return 0.0


def command_scene(args):
    with h5py.File(args.plans, "r") as f:
        tcp, obstacles, goal_tcp = f["tcp"][...], f["obstacles"][...], f["goal_tcp"][...]
        executed = f["executed/tcp"][...] if "executed" in f else None
        env, scale = f.attrs["env"], float(f.attrs["guidance_scale"])
        radius = robot_radius(f)
        other = None
        if args.compare:
            with h5py.File(args.compare, "r") as g:
                other = g["tcp"][...]
        W = tcp.shape[-1]
        if W == 2:
            planes, names = [(0, 1)], ("x", "y")
        else:
            spread = np.concatenate([tcp.reshape(-1, 3), obstacles[:, :3]]).std(0)
            order = np.argsort(-spread)
            planes, names = [(order[0], order[1]), (order[0], order[2])], ("x (m)", "y (m)", "z (m)")
        fig, axes = plt.subplots(1, len(planes), figsize=(6 * len(planes), 6), squeeze=False)
        for ax, (a, b) in zip(axes[0], planes):
            if W == 2 and args.data:
                with h5py.File(args.data, "r") as data:
                    draw_dataset(ax, data, args.episodes, faint=True)
            if other is not None:
                for i in range(len(other)):
                    ax.plot(other[i, :, a], other[i, :, b], color="0.6", lw=0.8, alpha=0.6,
                            label="unguided" if i == 0 else None)
            for i in range(len(tcp)):
                ax.plot(tcp[i, :, a], tcp[i, :, b], color="tab:blue", lw=0.9, alpha=0.7,
                        label=f"plans (scale {scale:g})" if i == 0 else None)
            if executed is not None:
                for i in range(len(executed)):
                    ax.plot(executed[i, :, a], executed[i, :, b], color="tab:orange", lw=0.8, ls="--", alpha=0.8,
                            label="executed in MuJoCo" if i == 0 else None)
            for k, o in enumerate(obstacles):
                ax.add_patch(plt.Circle((o[a], o[b]), o[-1], color="tab:red", alpha=0.35,
                                        label="obstacle" if k == 0 else None))
                if radius > 0:
                    ax.add_patch(plt.Circle((o[a], o[b]), o[-1] + radius, fill=False, ls=":", color="tab:red"))
            ax.plot(tcp[0, 0, a], tcp[0, 0, b], "ko", ms=6, label="start")
            ax.plot(goal_tcp[a], goal_tcp[b], "k*", ms=11, label="goal")
            ax.set_xlabel(names[a] if W == 3 else names[0])
            ax.set_ylabel(names[b] if W == 3 else names[1])
            ax.set_aspect("equal", adjustable="datalim")
            if W == 2:
                ax.set_xlim(-0.05, 1.05)
                ax.set_ylim(-0.05, 1.05)
        axes[0][0].legend(loc="best", fontsize=8)
        what = "TCP paths" if env == "franka" else "paths"
        fig.suptitle(args.title or f"{env}: {len(tcp)} {what} around {len(obstacles)} obstacle(s)", fontsize=11)
    fig.tight_layout()
    save(fig, args.out, args.dpi)
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
    p = sub.add_parser("scene", help="draw the plans of flowplan plan with their obstacles")
    p.add_argument("plans")
    p.add_argument("--out", required=True)
    p.add_argument("--data", help="particle: draw this dataset faintly underneath")
    p.add_argument("--episodes", type=int, default=200)
    p.add_argument("--compare", help="another plan file (e.g. unguided) drawn in grey")
    p.add_argument("--title")
    p.set_defaults(run=command_scene)
    for p in sub.choices.values():
        p.add_argument("--dpi", type=int, default=120, help="resolution of the 6 x 6 inch PNG")
    args = parser.parse_args()
    args.run(args)


if __name__ == "__main__":
    main()
