"""Reads a flowplan trajectory file with h5py and checks the layout of docs/dataset_format.md."""
import sys

import h5py
import numpy as np

with h5py.File(sys.argv[1], "r") as f:
    assert f.attrs["format"] == "flowplan.trajectories", f.attrs["format"]
    assert int(f.attrs["format_version"]) == 2
    robot = f.attrs["robot"]
    env = f.attrs["env"]
    labels = f.attrs["state_labels"].split(",")
    states = f["states"]
    n, t, d = states.shape
    assert states.dtype == np.float32 and d == len(labels), (states.dtype, labels)
    assert f["commanded_start"].dtype == np.float64 and f["commanded_start"].shape[0] == n
    assert f["commanded_goal"].shape == f["commanded_start"].shape
    assert f["family"].dtype == np.int32 and f["family"].shape == (n,)
    assert float(f.attrs["dt"]) > 0
    assert "seed:" in f.attrs["config"] and "threads" not in f.attrs["config"] and "out:" not in f.attrs["config"]
    for group in ("eval/train_pairs", "eval/test_pairs"):
        pairs = f[group]
        p = pairs["start"].shape[0]
        assert pairs["start"].shape == (p, d) and pairs["goal"].shape == (p, d)
        assert len(pairs.attrs["names"].split(";")) == p
    for name in f.get("extras", {}):
        assert f["extras"][name].shape[:2] == (n, t), name
    x = states[...]
    assert np.isfinite(x).all()
    if env == "particle":
        assert labels == ["x", "y", "vx", "vy"], labels
        assert x[..., :2].min() >= 0 and x[..., :2].max() <= 1
        assert "kind: point" in robot and "num_joints: 2" in robot and "workspace_dim: 2" in robot, robot
    if env == "franka":
        assert labels == [f"q{j}" for j in range(1, 8)] + [f"dq{j}" for j in range(1, 8)], labels
        assert "name: franka_panda" in robot and "kind: arm" in robot and "num_joints: 7" in robot, robot
        assert f["extras"]["tcp"].shape == (n, t, 3) and f["extras"]["torques"].shape == (n, t, 7)
        limits = np.array([87.0] * 4 + [12.0] * 3)
        assert (np.abs(f["extras"]["torques"][...]) <= limits + 1e-3).all()
print("layout ok")
