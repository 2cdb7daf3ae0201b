"""Largest absolute difference between the weights of two flowplan checkpoints.

Reads both files with PyTorch's own loader (torch.jit.load), independently of
the C++ code that wrote them, and compares every floating-point parameter and
buffer of the online and the EMA network (and the normalizer), plus the step.

usage: compare_checkpoints.py A.pt B.pt   -> prints {"max_abs_diff": x, "tensors": n}
"""
import json
import sys

import torch


def tensors(path):
    module = torch.jit.load(path, map_location="cpu")
    out = {name: t for name, t in module.named_parameters()}
    out.update({name: t for name, t in module.named_buffers()})
    return module, out


def main():
    a_module, a = tensors(sys.argv[1])
    b_module, b = tensors(sys.argv[2])
    if set(a) != set(b):
        sys.exit("different entries: %s" % sorted(set(a) ^ set(b)))
    if a_module.step != b_module.step:
        sys.exit("different steps: %d and %d" % (a_module.step, b_module.step))
    weights = [k for k in a if a[k].is_floating_point()]
    if not any(k.startswith("model.") for k in weights) or not any(k.startswith("ema.") for k in weights):
        sys.exit("no model./ema. weights in %s: %s" % (sys.argv[1], sorted(a)[:10]))
    diff = max((a[k].double() - b[k].double()).abs().max().item() for k in weights)
    print(json.dumps({"max_abs_diff": diff, "tensors": len(weights)}))


if __name__ == "__main__":
    main()
