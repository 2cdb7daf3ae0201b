"""Checks the files of `flowplan plan` with h5py and a forward kinematics of its own.

usage: check_plan.py PLAN.h5 PLAN.json
Recomputes every plan's TCP path (Franka: modified Denavit-Hartenberg parameters
written here, sharing no code with flowplan; particle: the position), the TCP
clearance to every obstacle (spheres, boxes, cylinders, capsules: signed
distances written here from the shapes' definitions, by nearest points), the
goal distance, the TCP clear flags and the quality metrics (path lengths,
largest speed ratio, mean squared jerk, duration), checks what a plan called a
success must satisfy (speeds within check.max_speed_ratio, every state's
whole-arm clearance, the ends), and compares them with what flowplan wrote.
"""
import json
import sys

import h5py
import numpy as np

# Franka Panda, modified DH (Craig): (a_{i-1}, d_i, alpha_{i-1}); then the flange
# (d = 0.107) and the TCP 0.107 m further along the flange's z axis.
DH = [(0, 0.333, 0), (0, 0, -np.pi / 2), (0, 0.316, np.pi / 2), (0.0825, 0, np.pi / 2),
      (-0.0825, 0.384, -np.pi / 2), (0, 0, np.pi / 2), (0.088, 0, np.pi / 2)]


def franka_tcp(q):
    """q (..., 7) -> TCP (..., 3)."""
    shape = q.shape[:-1]
    q = q.reshape(-1, 7)
    out = np.zeros((len(q), 3))
    for n, angles in enumerate(q):
        frame = np.eye(4)
        for (a, d, alpha), theta in zip(DH, angles):
            ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(theta), np.sin(theta)
            frame = frame @ np.array([[ct, -st, 0, a], [st * ca, ct * ca, -sa, -d * sa],
                                      [st * sa, ct * sa, ca, d * ca], [0, 0, 0, 1]])
        out[n] = (frame @ np.array([0, 0, 0.214, 1]))[:3]
    return out.reshape(*shape, 3)


def rotation(turn):
    """Local-to-world rotation of a quaternion (w, x, y, z) of any norm, or of an angle (2-D)."""
    if len(turn) == 1:
        c, s = np.cos(turn[0]), np.sin(turn[0])
        return np.array([[c, -s], [s, c]])
    w, x, y, z = np.asarray(turn) / np.linalg.norm(turn)
    return np.array([[w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z]])


def box_distance(p, half):
    """Signed distance of points p (N, n) to the box |x_i| <= half_i: to its nearest point outside,
    minus the distance to the nearest face inside."""
    nearest = np.clip(p, -half, half)
    outside = np.linalg.norm(p - nearest, axis=-1)
    inside = np.min(half - np.abs(p), axis=-1)
    return np.where(outside > 0, outside, -inside)


def distance(kind, row, p):
    """Signed distance of points p (N, W) to one obstacle."""
    W = p.shape[1]
    if kind == "spheres":
        return np.linalg.norm(p - row[:W], axis=-1) - row[W]
    if kind == "capsules":
        a, b, r = row[:W], row[W:2 * W], row[2 * W]
        t = np.clip((p - a) @ (b - a) / max((b - a) @ (b - a), 1e-300), 0, 1)
        return np.linalg.norm(p - (a + t[:, None] * (b - a)), axis=-1) - r
    if kind == "boxes":
        local = (p - row[:W]) @ rotation(row[2 * W:])
        return box_distance(local, 0.5 * row[W:2 * W])
    local = (p - row[:W]) @ rotation(row[W + 2:])  # cylinders, axis along the last local axis
    radial = np.linalg.norm(local[:, :W - 1], axis=-1)
    return box_distance(np.stack([radial, local[:, W - 1]], 1), np.array([row[W], 0.5 * row[W + 1]]))


def check(f, group, report, samples):
    """Checks the plans of one request: the HDF5 group `group` and its `samples` of the report."""
    g = f[group]
    plans, tcp = g["plans"][...].astype(np.float64), g["tcp"][...]
    obstacles = [(kind, row) for kind in ("spheres", "boxes", "cylinders", "capsules") if kind in g["scene"]
                 for row in g["scene"][kind][...]]
    names = g.attrs["obstacle_names"].split(",") if obstacles else []
    assert names == [f"{k}[{i}]" for k in ("spheres", "boxes", "cylinders", "capsules")
                     for i in range(len(g["scene"][k]) if k in g["scene"] else 0)], names
    goal_tcp, env = g["goal_tcp"][...], f.attrs["env"]
    mine = franka_tcp(plans[..., :7]) if env == "franka" else plans[..., :2]
    assert np.abs(mine - tcp).max() < 1e-4, np.abs(mine - tcp).max()
    assert len(samples) == len(plans) == report["num_samples"]
    tolerance, max_ratio, dt = report["goal_tolerance"], report["max_speed_ratio"], f.attrs["dt"]
    limits = np.array([2.175] * 4 + [2.61] * 3) if env == "franka" else None
    J = 7 if env == "franka" else 2
    assert isinstance(report["check"], dict), report["check"]  # settings are JSON objects, not YAML text
    check = {k: float("-inf") if v is None else float(v) for k, v in report["check"].items()}
    start, goal_state = g["start"][...], g["goal"][...]
    valid = g["valid"][...]
    assert valid.shape == (len(samples),) and valid.dtype == np.int32, (valid.shape, valid.dtype)
    for i, sample in enumerate(samples):
        assert valid[i] == int(sample["success"]), (i, valid[i], sample["success"])
        goal = np.linalg.norm(mine[i, -1] - goal_tcp)
        assert abs(goal - sample["goal_distance"]) < 1e-4, (goal, sample["goal_distance"])
        clearance = [np.min(distance(kind, row, mine[i])) for kind, row in obstacles]
        assert np.allclose(clearance, sample["tcp_clearance"], atol=1e-4), (clearance, sample["tcp_clearance"])
        collides = bool(len(clearance)) and min(clearance) < 0
        assert sample["tcp_collision"] == collides
        ratio = 0.0
        if limits is not None:
            ratio = np.max(np.abs(np.diff(plans[i, :, :7], axis=0)) / dt / limits)
        assert abs(ratio - sample["speed_ratio"]) < 1e-4 * max(1, ratio), (ratio, sample["speed_ratio"])
        assert sample["feasible"] == (ratio <= max_ratio)
        assert sample["tcp_clear"] == (not collides and goal <= tolerance and ratio <= max_ratio)
        # The whole robot reaches at least as far as its TCP.
        assert all(a <= t + 1e-6 for a, t in zip(sample["arm_clearance"], sample["tcp_clearance"]))
        if "executed" in sample:
            executed = g["executed/tcp"][i]
            assert abs(np.linalg.norm(executed[-1] - goal_tcp) - sample["executed"]["goal_distance"]) < 1e-3
            assert not sample["executed"]["success"] or sample["success"], sample  # executed successes passed the check
        q = plans[i, :, :J]
        quality = sample["quality"]
        assert abs(np.linalg.norm(np.diff(q, axis=0), axis=1).sum() - quality["joint_path_length"]) < 1e-4
        assert abs(np.linalg.norm(np.diff(mine[i], axis=0), axis=1).sum() - quality["tcp_path_length"]) < 1e-4
        assert abs(ratio - quality["max_speed_ratio"]) < 1e-4 * max(1, ratio)
        jerk = np.mean((np.diff(q, n=3, axis=0) / dt ** 3) ** 2)
        assert abs(jerk - quality["mean_squared_jerk"]) < 1e-4 * max(1.0, jerk), (jerk, quality)
        away = np.nonzero(np.abs(q - q[-1]).max(1) > check["joint_tolerance"])[0]
        assert abs((away[-1] + 1 if len(away) else 0) * dt - quality["duration_s"]) < 1e-6, quality  # 7 digits
        if sample["success"]:
            assert sample["found"] and sample["failure"] == "none" and sample["reason"] == ""
            assert ratio <= check["max_speed_ratio"] + 1e-6, (ratio, check)
            assert all(a >= check["margin"] - 1e-6 for a in sample["arm_clearance"]), sample["arm_clearance"]
            assert np.abs(q[0] - start[:J]).max() <= check["joint_tolerance"] + 1e-6
            assert np.abs(q[-1] - goal_state[:J]).max() <= check["joint_tolerance"] + 1e-6
        else:
            assert sample["failure"] != "none" and sample["reason"], sample


with h5py.File(sys.argv[1], "r") as f, open(sys.argv[2]) as report_file:
    report = json.load(report_file)
    if "problems" in report:  # flowplan plan --problems
        planned = [p for p in report["problems"] if p["status"] == "planned"]
        assert report["planned"] == len(planned) and report["refused"] == report["num_problems"] - len(planned)
        for p in report["problems"]:
            assert p["status"] in ("planned", "refused"), p
            assert (p["status"] == "refused") == bool(p["reason"]), p
        for p in planned:
            check(f, p["group"], report, p["samples"])
            assert abs(np.mean([s["success"] for s in p["samples"]]) - p["success_rate"]) < 1e-6
        successes = sum(s["success"] for p in planned for s in p["samples"])
        assert abs(successes / (report["num_problems"] * report["num_samples"]) - report["success_rate"]) < 1e-6
    else:
        assert f.attrs["obstacle_names"] == ",".join(report["obstacles"])
        check(f, "/", report, report["samples"])
        rate = np.mean([s["tcp_clear"] for s in report["samples"]])
        assert abs(rate - report["tcp_clear_rate"]) < 1e-6
        assert abs(np.mean([s["success"] for s in report["samples"]]) - report["success_rate"]) < 1e-6
print("plan files ok")
