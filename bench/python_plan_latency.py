"""Time per guided plan (B = 1) of an exported planner from Python: the load,
the first two calls and the median of the next ten, planning around the
paper's sphere with the graph executor's optimisations off.

    T=THREADS /usr/bin/python3 bench/python_plan_latency.py [PLANNER.pt]

(T: intra-op threads, default 2; default planner: the shipped reach planner).
Run two at once to see a shared machine (docs/export.md, "Threads on a shared machine").
"""
import os
import sys
import time

import torch

path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                                          "pretrained", "franka_reach_planner.pt")
torch.set_num_threads(int(os.environ.get("T", "2")))
torch._C._set_graph_executor_optimize(False)
t0 = time.perf_counter()
planner = torch.jit.load(path)
t1 = time.perf_counter()
start = torch.cat([planner.ik(torch.tensor([0.5, -0.3, 0.2])), torch.zeros(7)])
goal = torch.cat([planner.ik(torch.tensor([0.5, 0.3, 0.2])), torch.zeros(7)])
sphere = torch.tensor([[0.5, 0.0, 0.2, 0.1]])
times = []
with torch.no_grad():
    for _ in range(12):
        started = time.perf_counter()
        planner.sample(start, goal, 1, spheres=sphere)
        times.append(time.perf_counter() - started)
print(f"threads {torch.get_num_threads()}, OMP_WAIT_POLICY {os.environ.get('OMP_WAIT_POLICY', 'unset')}: "
      f"load {t1 - t0:.2f} s, first {times[0] * 1e3:.0f} ms, second {times[1] * 1e3:.0f} ms, "
      f"median of the next ten {sorted(times[2:])[5] * 1e3:.1f} ms")
