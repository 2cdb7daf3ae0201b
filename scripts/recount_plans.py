#!/usr/bin/env python3
"""Recounts the TCP-only and whole-arm successes of saved arm plans.

usage: recount_plans.py [--out RESULT.json] PLAN_OR_FOLDER ...

For every `flowplan plan` output pair PREFIX.h5 / PREFIX.json (a folder is
searched for them), recomputes from the plans in the HDF5 file, with forward
kinematics written here (no flowplan code: modified Denavit-Hartenberg
parameters of the Panda for the built-in Franka; for any other arm, the
kinematic tree of the file's `robot` attribute, revolute and prismatic joints
composed here; that tree is the data flowplan planned with, so for such an
arm this checks the planning and checking, not the import), each plan's TCP path, the clearance of the TCP and of every
collision sphere of the arm to every obstacle, the goal distance and the joint
speeds, and from them the two success counts of `flowplan plan`: the TCP never
inside an obstacle, and no collision sphere of the arm inside one (obstacles of
every shape: spheres, boxes, cylinders, capsules, by signed distances written
here from the shapes' definitions); both also
need the last TCP within the goal tolerance and joint speeds within
max_speed_ratio times the limits. The collision spheres (link, centre in the
link frame, radius) are geometry, read from the file's `robot` attribute.

It also compares, plan by plan, the values behind the counts (smallest TCP
and arm clearance, goal distance, speed ratio) with those in PREFIX.json, and
checks that every plan the report calls a success (the plan checker's
verdict) keeps every collision sphere at every state at least the check's
margin from every obstacle, within the check's speed limit. A report of
`flowplan plan --problems` is recounted problem by problem.
Prints one line per file (its counts and flowplan's), writes them to
RESULT.json if asked, and exits 1 if any count or value differs (by more than
1e-4).
"""
import argparse
import glob
import json
import os
import sys

import h5py
import numpy as np
import yaml

# Panda, modified DH (Craig): (a_{i-1}, d_i, alpha_{i-1}) of joints 1..7.
DH = [(0, 0.333, 0), (0, 0, -np.pi / 2), (0, 0.316, np.pi / 2), (0.0825, 0, np.pi / 2),
      (-0.0825, 0.384, -np.pi / 2), (0, 0, np.pi / 2), (0.088, 0, np.pi / 2)]
VELOCITY_LIMITS = np.array([2.175] * 4 + [2.61] * 3)  # rad/s, Franka's datasheet
TOLERANCE = 1e-4  # largest difference of a per-plan value (relative above 1: m, or a speed ratio)


def transform(rotation_z=0.0, translation=(0.0, 0.0, 0.0)):
    c, s = np.cos(rotation_z), np.sin(rotation_z)
    frame = np.eye(4)
    frame[:2, :2] = [[c, -s], [s, c]]
    frame[:3, 3] = translation
    return frame


def link_frames(q):
    """q (N, 7) -> {link name: (N, 4, 4) pose in the base frame}."""
    n = len(q)
    frame = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    frames = {"link0": frame.copy()}
    for joint, (a, d, alpha) in enumerate(DH):
        ca, sa = np.cos(alpha), np.sin(alpha)
        ct, st = np.cos(q[:, joint]), np.sin(q[:, joint])
        step = np.zeros((n, 4, 4))
        step[:, 0] = np.stack([ct, -st, np.zeros(n), np.full(n, a)], -1)
        step[:, 1] = np.stack([st * ca, ct * ca, np.full(n, -sa), np.full(n, -d * sa)], -1)
        step[:, 2] = np.stack([st * sa, ct * sa, np.full(n, ca), np.full(n, d * ca)], -1)
        step[:, 3, 3] = 1
        frame = frame @ step
        frames[f"link{joint + 1}"] = frame
    # Flange 0.107 m along link 7's z; the hand turned -45 degrees about it;
    # the fingers' frames 0.0584 m further (the right one turned half a turn).
    frames["hand"] = frame @ transform(-np.pi / 4, (0, 0, 0.107))
    frames["left_finger"] = frames["hand"] @ transform(0.0, (0, 0, 0.0584))
    frames["right_finger"] = frames["hand"] @ transform(np.pi, (0, 0, 0.0584))
    frames["tcp"] = frame @ transform(0.0, (0, 0, 0.214))
    return frames


def axis_motion(axis, values, prismatic):
    """(N, 4, 4): turning about the unit axis by `values` (Rodrigues), or sliding along it."""
    a = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    n = len(values)
    out = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    if prismatic:
        out[:, :3, 3] = values[:, None] * a
        return out
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    out[:, :3, :3] = np.eye(3) + np.sin(values)[:, None, None] * k + (1 - np.cos(values))[:, None, None] * (k @ k)
    return out


def tree_frames(robot, q):
    """q (N, J) -> {link name: (N, 4, 4)} and "tcp", from a robot description (its `links`: parent, pos, quat,
    joint, axis, type, offset; its TCP)."""
    n = len(q)
    frames, by_index = {}, []
    for link in robot["links"]:
        fixed = np.eye(4)
        fixed[:3, :3] = rotation(link.get("quat", [1, 0, 0, 0]))
        fixed[:3, 3] = link.get("pos", [0, 0, 0])
        joint = link.get("joint", -1)
        values = q[:, joint] if joint >= 0 else np.full(n, float(link.get("offset", 0.0)))
        local = fixed @ axis_motion(link.get("axis", [0, 0, 1]), values, link.get("type", "revolute") == "prismatic")
        parent = link.get("parent", -1)
        frame = local if parent < 0 else by_index[parent] @ local
        by_index.append(frame)
        frames[link["name"]] = frame
    tcp = np.eye(4)
    tcp[:3, :3] = rotation(robot.get("tcp_quat", [1, 0, 0, 0]))
    tcp[:3, 3] = robot.get("tcp_pos", [0, 0, 0])
    frames["tcp"] = by_index[robot["tcp_link"]] @ tcp
    return frames


def rotation(quaternion):
    """Local-to-world rotation (3, 3) of a quaternion (w, x, y, z) of any norm."""
    w, x, y, z = np.asarray(quaternion) / np.linalg.norm(quaternion)
    return np.array([[w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z]])


def inside_box(p, half):
    """Signed distance of points p (..., n) to the box |x_i| <= half_i (nearest point outside, nearest face inside)."""
    outside = np.linalg.norm(p - np.clip(p, -half, half), axis=-1)
    return np.where(outside > 0, outside, -np.min(half - np.abs(p), axis=-1))


def signed_distance(kind, row, p):
    """Signed distance of points p (..., 3) to one obstacle (negative inside)."""
    if kind == "spheres":
        return np.linalg.norm(p - row[:3], axis=-1) - row[3]
    if kind == "capsules":
        a, ab = row[:3], row[3:6] - row[:3]
        t = np.clip((p - a) @ ab / max(ab @ ab, 1e-300), 0, 1)
        return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1) - row[6]
    if kind == "boxes":
        return inside_box((p - row[:3]) @ rotation(row[6:10]), 0.5 * row[3:6])
    local = (p - row[:3]) @ rotation(row[5:9])  # cylinders: axis along local z
    return inside_box(np.stack([np.linalg.norm(local[..., :2], axis=-1), local[..., 2]], -1),
                      np.array([row[3], 0.5 * row[4]]))


def read_obstacles(g):
    """[(kind, row)] of a plan group's obstacles."""
    scene = g["scene"]
    return [(kind, row.astype(np.float64)) for kind in ("spheres", "boxes", "cylinders", "capsules") if kind in scene
            for row in scene[kind][...]]


def check_limits(report):
    """The plan checker's speed ratio and margin of a report (`check`: an object; YAML text in older reports);
    None before reports had it."""
    if "check" not in report:
        return None
    check = report["check"]
    if isinstance(check, str):
        check = yaml.safe_load(check)
    return float(check["max_speed_ratio"]), float(check["margin"])


def recount_group(f, g, report, samples):
    """Counts and largest differences of the plans of one request: HDF5 group G and its report SAMPLES."""
    plans = g["plans"][...].astype(np.float64)      # (N, T, D)
    obstacles = read_obstacles(g)
    goal_tcp = g["goal_tcp"][...].astype(np.float64)
    dt = float(f.attrs["dt"])
    robot = yaml.safe_load(f.attrs["robot"])
    n, t = plans.shape[:2]
    J = int(robot["num_joints"])
    q = plans[..., :J].reshape(-1, J)
    franka = f.attrs["env"] == "franka"
    frames = link_frames(q) if franka else tree_frames(robot, q)
    velocity_limits = VELOCITY_LIMITS if franka else np.array(robot["velocity_limit"], dtype=np.float64)
    tcp = frames["tcp"][:, :3, 3].reshape(n, t, 3)
    names = [link["name"] for link in robot["links"]]
    centres = np.stack([(frames[names[s["link"]]] @ np.append(s["centre"], 1.0))[:, :3] for s in robot["spheres"]],
                       1).reshape(n, t, -1, 3)                    # (N, T, S, 3)
    radii = np.array([s["radius"] for s in robot["spheres"]])    # (S,)
    if obstacles:
        tcp_gap = np.min([signed_distance(kind, row, tcp).min(1) for kind, row in obstacles], 0)
        arm_gap = np.min([(signed_distance(kind, row, centres) - radii).min((1, 2)) for kind, row in obstacles], 0)
    else:
        tcp_gap = arm_gap = np.full(n, np.inf)
    goal = np.linalg.norm(tcp[:, -1] - goal_tcp, axis=-1)
    ratio = (np.abs(np.diff(plans[..., :J], axis=1)) / dt / velocity_limits).max((1, 2))
    # Per plan, the values behind the counts, against flowplan's (largest difference).
    gaps = {"tcp_clearance": (tcp_gap, [min(s["tcp_clearance"], default=np.inf) for s in samples]),
            "arm_clearance": (arm_gap, [min(s["arm_clearance"], default=np.inf) for s in samples]),
            "goal_distance": (goal, [s["goal_distance"] for s in samples]),
            "speed_ratio": (ratio, [s["speed_ratio"] for s in samples])}
    worst = {}
    for key, (values, theirs) in gaps.items():
        theirs = np.array(theirs, dtype=np.float64)
        finite = np.isfinite(values) & np.isfinite(theirs)
        same_inf = np.all(np.isfinite(values) == np.isfinite(theirs))
        worst[key] = float(np.max(np.abs(values[finite] - theirs[finite]) / np.maximum(1, np.abs(theirs[finite])),
                                  initial=0.0)) if same_inf else float("inf")
    reached = (goal <= report["goal_tolerance"]) & (ratio <= report["max_speed_ratio"])
    mine = {"tcp": int(np.sum(reached & (tcp_gap >= 0))), "arm": int(np.sum(reached & (arm_gap >= 0)))}
    theirs = {"tcp": int(sum(s["tcp_clear"] for s in samples)), "arm": int(sum(s["arm_clear"] for s in samples))}
    # A plan the checker calls a success keeps every sphere at every state clear here too, within its speed limit.
    limits = check_limits(report)
    unsound = 0
    if limits is not None:
        speed, margin = limits
        unsound = sum(1 for i, s in enumerate(samples)
                      if s["success"] and (arm_gap[i] < margin - TOLERANCE or ratio[i] > speed + TOLERANCE))
    return n, mine, theirs, worst, unsound


def recount(prefix):
    report = json.load(open(prefix + ".json"))
    with h5py.File(prefix + ".h5", "r") as f:
        if yaml.safe_load(f.attrs["robot"]).get("kind", "arm") != "arm":
            raise SystemExit(f"{prefix}.h5: env {f.attrs['env']!r}: only arms' plans are recounted")
        # A `flowplan plan --problems` report holds one group and list of samples per planned problem.
        parts = ([(f[p["group"]], p["samples"]) for p in report["problems"] if p["status"] == "planned"]
                 if "problems" in report else [(f, report["samples"])])
        total, mine, theirs, worst, unsound = 0, {"tcp": 0, "arm": 0}, {"tcp": 0, "arm": 0}, {}, 0
        for g, samples in parts:
            n, m, t, w, u = recount_group(f, g, report, samples)
            total += n
            unsound += u
            for key in mine:
                mine[key] += m[key]
                theirs[key] += t[key]
            for key, value in w.items():
                worst[key] = max(worst.get(key, 0.0), value)
    return {"file": prefix, "plans": total, "recounted": mine, "flowplan": theirs, "largest_difference": worst,
            "successes_not_clear": unsound,
            "agrees": mine == theirs and all(v <= TOLERANCE for v in worst.values()) and unsound == 0}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("paths", nargs="+")
    parser.add_argument("--out")
    args = parser.parse_args()
    prefixes = []
    for path in args.paths:
        if os.path.isdir(path):
            found = sorted(glob.glob(os.path.join(path, "**", "*.h5"), recursive=True))
            prefixes += [p[:-3] for p in found if os.path.exists(p[:-3] + ".json")]
        else:
            prefixes.append(path[:-3] if path.endswith(".h5") else path)
    if not prefixes:
        raise SystemExit(f"no plan files (PREFIX.h5 with PREFIX.json) in {' '.join(args.paths)}")
    results = [recount(prefix) for prefix in prefixes]
    differ = [r for r in results if not r["agrees"]]
    for r in results:
        mark = "" if r["agrees"] else (f"   <-- differs {r['largest_difference']}, "
                                        f"{r['successes_not_clear']} successes not clear")
        print(f"{r['file']}: TCP {r['recounted']['tcp']}/{r['plans']} (flowplan {r['flowplan']['tcp']}), "
              f"arm {r['recounted']['arm']}/{r['plans']} (flowplan {r['flowplan']['arm']}){mark}")
    summary = {"files": len(results), "differ": len(differ),
               "plans": sum(r["plans"] for r in results), "results": results}
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out + ".tmp", "w") as f:
            json.dump(summary, f, indent=1)
        os.replace(args.out + ".tmp", args.out)
    print(f"{len(results)} files, {summary['plans']} plans: {len(differ)} with a different count")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
