#!/usr/bin/env python3
"""Plots flowplan datasets and evaluation plans as PNG files.

  plot.py dataset DATA.h5 --out dataset.png [--episodes 300]
      particle: x-y paths; franka: TCP paths in the y-z plane (/extras/tcp)
  plot.py plans EVAL.plans.h5 --data DATA.h5 --out plans.png
      the dataset in grey, the test-pair plans of `flowplan eval stitching` on top
  plot.py scene PLAN.h5 --out plan.png [--data DATA.h5] [--compare OTHER.h5]
      the TCP paths of `flowplan plan` with the obstacles (spheres, boxes,
      cylinders, capsules: their outlines projected; particle: the unit
      square; Franka: seen from above and from the front), valid plans solid
      and plans that failed the plan check dotted, executed paths dashed;
      --compare draws another plan file's paths in grey (e.g. unguided)
  plot.py problems P1.yaml [P2.yaml ...] --out scenes.png [--index 0] [--planner FILE.pt]
      one 3-D panel per problem file (problem --index of each): its boxes,
      cylinders and spheres, the start and goal TCP, and with --planner (an
      exported Franka planner, whose kinematics draws it) the arm's collision
      spheres at the start (blue) and the goal (orange)

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


def rotation(turn):
    """Rotation matrix of a quaternion (w, x, y, z) (3-D) or an angle (2-D)."""
    if len(turn) == 1:
        c, s = np.cos(turn[0]), np.sin(turn[0])
        return np.array([[c, -s], [s, c]])
    w, x, y, z = np.asarray(turn) / np.linalg.norm(turn)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def surface_points(kind, row, W, inflate=0.0):
    """Points (M, W) on the surface of an obstacle (grown by `inflate`), for drawing its outline."""
    angles = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    if W == 2:
        circle = np.stack([np.cos(angles), np.sin(angles)], 1)
    else:
        u, v = np.meshgrid(angles, np.linspace(0, np.pi, 24))
        circle = np.stack([np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)], -1).reshape(-1, 3)
    if kind == "spheres":
        return row[:W] + (row[W] + inflate) * circle
    if kind == "capsules":
        a, b, r = row[:W], row[W:2 * W], row[2 * W] + inflate
        return np.concatenate([a + r * circle, b + r * circle])
    centre = row[:W]
    if kind == "boxes":
        half, turn = 0.5 * row[W:2 * W], row[2 * W:]
        corners = np.array(np.meshgrid(*[[-1, 1]] * W)).reshape(W, -1).T * half
    else:  # cylinders: axis along local z (2-D: local y)
        radius, half, turn = row[W], 0.5 * row[W + 1], row[W + 2:]
        if W == 2:
            corners = np.array([[-radius, -half], [radius, -half], [radius, half], [-radius, half]])
        else:
            rim = np.stack([radius * np.cos(angles), radius * np.sin(angles)], 1)
            corners = np.concatenate([np.c_[rim, np.full(len(rim), -half)], np.c_[rim, np.full(len(rim), half)]])
    points = centre + corners @ rotation(turn).T
    if inflate > 0:
        points = (points[:, None, :] + inflate * circle[None]).reshape(-1, W)
    return points


def convex_hull(points):
    """The convex hull (H, 2) of 2-D points, counter-clockwise (Andrew's monotone chain)."""
    pts = sorted(set(map(tuple, np.round(points, 12))))
    if len(pts) < 3:
        return np.array(pts)

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def read_scene(f):
    """[(kind, row)] of a plan file's obstacles, in their numbering order."""
    if "scene" not in f:
        return []
    out = []
    for kind in ("spheres", "boxes", "cylinders", "capsules"):
        if kind in f["scene"]:
            out += [(kind, row) for row in f["scene"][kind][...]]
    return out


def command_scene(args):
    with h5py.File(args.plans, "r") as f:
        tcp, goal_tcp = f["tcp"][...], f["goal_tcp"][...]
        # Files written before /valid: every plan drawn as one kind.
        valid = f["valid"][...].astype(bool) if "valid" in f else None
        obstacles = read_scene(f)
        executed = f["executed/tcp"][...] if "executed" in f else None
        env, scale = f.attrs["env"], float(f.attrs["guidance_scale"])
        planner = str(f.attrs["planner"]) if "planner" in f.attrs else ""
        radius = robot_radius(f)
        other = None
        if args.compare:
            with h5py.File(args.compare, "r") as g:
                other = g["tcp"][...]
        W = tcp.shape[-1]
        if W == 2:
            planes, names, views = [(0, 1)], ("x", "y"), [""]
        else:
            # The same two views for every plan: from above, and from the front (looking along the base's x).
            planes, names, views = [(0, 1), (1, 2)], ("x (m)", "y (m)", "z (m)"), ["from above", "from the front"]
        fig, axes = plt.subplots(1, len(planes), figsize=(6 * len(planes), 6), squeeze=False)
        for ax, (a, b), view in zip(axes[0], planes, views):
            if W == 2 and args.data:
                with h5py.File(args.data, "r") as data:
                    draw_dataset(ax, data, args.episodes, faint=True)
            if other is not None:
                for i in range(len(other)):
                    ax.plot(other[i, :, a], other[i, :, b], color="0.6", lw=0.8, alpha=0.6,
                            label=args.compare_label if i == 0 else None)
            # A classical planner has no guidance scale to name.
            name = args.label or ("plans" if planner in ("rrt_connect",) else f"plans (scale {scale:g})")
            if valid is None:
                for i in range(len(tcp)):
                    ax.plot(tcp[i, :, a], tcp[i, :, b], color="tab:blue", lw=0.9, alpha=0.7,
                            label=name if i == 0 else None)
            else:
                # Valid plans (passed the plan checker) solid blue; failed ones dotted purple, drawn on top.
                for kind, chosen, style in (("valid", np.nonzero(valid)[0], dict(color="tab:blue", lw=0.9, alpha=0.7)),
                                            ("failed the plan check", np.nonzero(~valid)[0],
                                             dict(color="tab:purple", lw=1.1, ls=":", alpha=0.9))):
                    for n, i in enumerate(chosen):
                        ax.plot(tcp[i, :, a], tcp[i, :, b], **style,
                                label=f"{name}: {len(chosen)} {kind}" if n == 0 else None)
            if executed is not None:
                for i in range(len(executed)):
                    ax.plot(executed[i, :, a], executed[i, :, b], color="tab:orange", lw=0.8, ls="--", alpha=0.8,
                            label="executed in MuJoCo" if i == 0 else None)
            for k, (kind, row) in enumerate(obstacles):
                # The shape's outline in this plane: the hull of its surface points' projections.
                hull = convex_hull(surface_points(kind, row, W)[:, [a, b]])
                ax.add_patch(plt.Polygon(hull, color="tab:red", alpha=0.35, label="obstacle" if k == 0 else None))
                if radius > 0:
                    grown = convex_hull(surface_points(kind, row, W, radius)[:, [a, b]])
                    ax.add_patch(plt.Polygon(grown, fill=False, ls=":", color="tab:red"))
            ax.plot(tcp[0, 0, a], tcp[0, 0, b], "ko", ms=6, label="start")
            ax.plot(goal_tcp[a], goal_tcp[b], "k*", ms=11, label="goal")
            ax.set_xlabel(names[a] if W == 3 else names[0])
            ax.set_ylabel(names[b] if W == 3 else names[1])
            ax.set_aspect("equal", adjustable="datalim")
            if view:
                ax.set_title(view, fontsize=10)
            if W == 2:
                ax.set_xlim(-0.05, 1.05)
                ax.set_ylim(-0.05, 1.05)
        # Below the panels, where it hides no path.
        handles, labels = axes[0][0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 3), fontsize=8, frameon=False)
        what = "TCP paths" if env == "franka" else "paths"
        fig.suptitle(args.title or f"{env}: {len(tcp)} {what} around {len(obstacles)} obstacle(s)", fontsize=11)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    save(fig, args.out, args.dpi)
    print(f"wrote {args.out}")


def box_faces(centre, size, turn):
    """The 6 faces (6, 4, 3) of a box."""
    signs = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                      [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
    corners = np.asarray(centre) + (0.5 * signs * np.asarray(size)) @ rotation(turn).T
    faces = [[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [1, 2, 6, 5], [0, 3, 7, 4]]
    return [corners[f] for f in faces]


def draw_problem_obstacles(ax, scene):
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    faces = []
    for box in scene.get("boxes") or []:
        faces += box_faces(box["centre"], box["size"], box.get("quaternion") or [1, 0, 0, 0])
    angles = np.linspace(0, 2 * np.pi, 17)
    for cylinder in scene.get("cylinders") or []:
        r, h = cylinder["radius"], cylinder["height"]
        turn = rotation(cylinder.get("quaternion") or [1, 0, 0, 0])
        rim = np.stack([r * np.cos(angles), r * np.sin(angles)], 1)
        low = np.asarray(cylinder["centre"]) + np.c_[rim, np.full(len(rim), -h / 2)] @ turn.T
        high = np.asarray(cylinder["centre"]) + np.c_[rim, np.full(len(rim), h / 2)] @ turn.T
        faces += [np.array([low[i], low[i + 1], high[i + 1], high[i]]) for i in range(len(angles) - 1)]
        faces += [low, high]
    if faces:
        ax.add_collection3d(Poly3DCollection(faces, facecolor=(0.84, 0.15, 0.16, 0.25),
                                             edgecolor=(0.5, 0.1, 0.1, 0.5), linewidths=0.3))
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 16), np.linspace(0, np.pi, 8))
    for sphere in scene.get("spheres") or []:
        c, r = sphere["centre"], sphere["radius"]
        ax.plot_surface(c[0] + r * np.cos(u) * np.sin(v), c[1] + r * np.sin(u) * np.sin(v), c[2] + r * np.cos(v),
                        color="tab:red", alpha=0.3, linewidth=0)


def command_problems(args):
    import yaml
    robot = None
    if args.planner:
        import torch
        robot = torch.jit.load(args.planner).robot
    columns = min(3, len(args.files))
    rows = (len(args.files) + columns - 1) // columns
    fig = plt.figure(figsize=(5.0 * columns, 5.0 * rows))
    for n, path in enumerate(args.files):
        with open(path) as f:
            problems = yaml.safe_load(f)
        problem = problems["problems"][args.index]
        ax = fig.add_subplot(rows, columns, n + 1, projection="3d")
        draw_problem_obstacles(ax, problem["scene"])
        if robot is not None:
            import torch
            q = torch.tensor([problem["start_q"], problem["goal_q"]], dtype=torch.float64)
            spheres = robot.collision_spheres(q).numpy()  # (2, S, 4): centre, radius
            for pose, colour in zip(spheres, ("tab:blue", "tab:orange")):
                ax.scatter(pose[:, 0], pose[:, 1], pose[:, 2], s=(pose[:, 3] * 300) ** 2 / 4, color=colour,
                           alpha=0.35, depthshade=False)
        for key, marker, label in (("start_tcp", "o", "start"), ("goal_tcp", "*", "goal")):
            p = problem[key]
            ax.scatter([p[0]], [p[1]], [p[2]], marker=marker, s=60, color="k", label=label, depthshade=False)
        ax.set_xlim(-0.2, 1.0)
        ax.set_ylim(-0.6, 0.6)
        ax.set_zlim(-0.1, 1.1)
        ax.set_box_aspect((1.2, 1.2, 1.2))
        ax.view_init(elev=22, azim=-135)
        ax.set_xlabel("x (m)", fontsize=7)
        ax.set_ylabel("y (m)", fontsize=7)
        ax.set_zlabel("z (m)", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.set_title(f"{problems.get('source', path)}: {problem.get('name', args.index)}", fontsize=9)
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
    p.add_argument("--compare-label", default="unguided", help="the legend's name of the --compare plans")
    p.add_argument("--label", help="the legend's name of the plans (default: plans (scale S), or plans for RRT-Connect)")
    p.add_argument("--title")
    p.set_defaults(run=command_scene)
    p = sub.add_parser("problems", help="draw one problem of each problem file in 3-D")
    p.add_argument("files", nargs="+")
    p.add_argument("--out", required=True)
    p.add_argument("--index", type=int, default=0, help="which problem of each file")
    p.add_argument("--planner", help="an exported Franka planner: draw the arm at the start and the goal")
    p.set_defaults(run=command_problems)
    for p in sub.choices.values():
        p.add_argument("--dpi", type=int, default=120, help="resolution of the 6 x 6 inch PNG")
    args = parser.parse_args()
    args.run(args)


if __name__ == "__main__":
    main()
