#!/usr/bin/env python3
"""Whether TorchScript's freezing helps the exported planner's network: the
network of an exported planner (`flowplan export`, portable: LibTorch's
operators) as scripted, after torch.jit.freeze, and after
torch.jit.optimize_for_inference; the convolution operators each graph calls
(whether freezing rewrote the 1-D convolutions), and the forward pass at B = 1
timed round-robin (medians of 200 calls, five rounds) on one thread.

usage: /usr/bin/python3 bench/frozen_network.py PLANNER.pt

docs/performance.md ("Latency at B = 1", "Tried and not kept") has the figures.
"""
import collections
import re
import statistics
import sys
import time

import torch


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    torch.set_num_threads(1)
    planner = torch.jit.load(sys.argv[1])
    network = planner.sampler.network.eval()
    frozen = torch.jit.freeze(network)
    optimized = torch.jit.optimize_for_inference(torch.jit.freeze(network))
    modules = {"scripted": network, "frozen": frozen, "optimize_for_inference": optimized}
    for name, module in modules.items():
        graph = str(module.graph if name != "scripted" else module.inlined_graph)
        print(f"{name}: {dict(collections.Counter(re.findall(r'aten::[a-z_0-9]*conv[a-z_0-9]*', graph)))}")
    x = torch.randn(1, int(planner.horizon), int(planner.state_dim))  # (1, T, D) normalized
    t = torch.full([1], 0.5)
    cond = None if planner.conditioning == "inpaint" else torch.zeros(1, 2 * int(planner.state_dim))
    times = {name: [] for name in modules}
    with torch.inference_mode():
        for module in modules.values():
            for _ in range(50):
                module(x, t, cond)
        for _ in range(5):
            for name, module in modules.items():
                calls = []
                for _ in range(200):
                    begin = time.perf_counter()
                    module(x, t, cond)
                    calls.append(time.perf_counter() - begin)
                times[name].append(1e3 * statistics.median(calls))
        difference = (network(x, t, cond) - optimized(x, t, cond)).abs().max().item()
    for name, values in times.items():
        print(f"{name:<24} {statistics.median(values):.3f} ms ({min(values):.3f}-{max(values):.3f}) at B = 1")
    print(f"largest difference of optimize_for_inference's output: {difference:.2e}")


if __name__ == "__main__":
    main()
