"""Time per guided plan (B = 1) of an exported planner from Python around the paper's sphere: the load, the
first two calls and the median of the next twenty.

    PYTHONPATH=build/python T=THREADS /usr/bin/python3 bench/python_plan_latency.py [--torch] [PLANNER.pt]

With the package (default): flowplan.load_planner, flowplan's native kernels. With --torch: torch.jit.load of
the file as written (its portable code) with the graph executor's optimisations off, as a user without the
package would. T: intra-op threads, default 2; default planner: the shipped split planner
(pretrained/franka_joint_split_planner.pt). Run two at once to see a shared machine (docs/export.md).
"""
import os
import sys
import time

import torch

args = [a for a in sys.argv[1:] if a != "--torch"]
plain_torch = "--torch" in sys.argv[1:]
path = args[0] if args else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "pretrained",
                                         "franka_joint_split_planner.pt")
torch.set_num_threads(int(os.environ.get("T", "2")))
started = time.perf_counter()
if plain_torch:
    torch._C._set_graph_executor_optimize(False)
    planner = torch.jit.load(path)
else:
    import flowplan
    planner = flowplan.load_planner(path, native=True)
loaded = time.perf_counter() - started
start = torch.cat([planner.ik(torch.tensor([0.5, -0.3, 0.2])), torch.zeros(7)])
goal = torch.cat([planner.ik(torch.tensor([0.5, 0.3, 0.2])), torch.zeros(7)])
sphere = torch.tensor([[0.5, 0.0, 0.2, 0.1]])
times = []
with torch.no_grad():
    for _ in range(22):
        started = time.perf_counter()
        planner.sample(start, goal, 1, spheres=sphere)
        times.append(time.perf_counter() - started)
print(f"{os.path.basename(path)} {'torch.jit.load' if plain_torch else 'flowplan.load_planner'}: "
      f"threads {torch.get_num_threads()}, OMP_WAIT_POLICY {os.environ.get('OMP_WAIT_POLICY', 'unset')}: "
      f"load {loaded:.2f} s, first {times[0] * 1e3:.1f} ms, second {times[1] * 1e3:.1f} ms, "
      f"median of the next twenty {sorted(times[2:])[10] * 1e3:.1f} ms")
