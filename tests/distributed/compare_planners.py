"""Largest difference between what two exported flowplan planners compute.

Loads both files with torch.jit.load and evaluates their networks
(`sampler.network.forward(x, t, cond)`) and their plans (`plan(start, goal, noise)`) on the
same fixed random inputs. Weights can differ where the function does not:
a convolution bias just before a GroupNorm has no effect on the output, its
gradient is zero up to rounding, and AdamW turns that rounding into steps of
either sign; comparing outputs is what says two trainings agree.

usage: compare_planners.py A.pt B.pt   -> prints {"velocity": x, "plan": y}
"""
import json
import sys

import torch


def main():
    a = torch.jit.load(sys.argv[1])
    b = torch.jit.load(sys.argv[2])
    T, D = a.noise_shape
    generator = torch.Generator().manual_seed(0)
    x = torch.randn(8, T, D, generator=generator)
    t = torch.rand(8, generator=generator)
    lo, hi = a.normalizer.lo, a.normalizer.hi
    start = lo + (hi - lo) * torch.rand(8, D, generator=generator)
    goal = lo + (hi - lo) * torch.rand(8, D, generator=generator)
    noise = torch.randn(8, T, D, generator=generator)
    with torch.no_grad():
        velocity = (a.sampler.network.forward(x, t, None) - b.sampler.network.forward(x, t, None)).abs().max().item()
        plan = (a.plan(start, goal, noise) - b.plan(start, goal, noise)).abs().max().item()
    print(json.dumps({"velocity": velocity, "plan": plan}))


if __name__ == "__main__":
    main()
