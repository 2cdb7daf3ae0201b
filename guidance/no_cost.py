# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# NoCost, the end of a CostChain.

from typing import Dict

import torch
from torch import Tensor


class NoCost:
    def active(self, scene: Dict[str, Tensor], opts: Dict[str, float]) -> bool:
        return False

    def autograd_source(self, opts: Dict[str, float]) -> str:
        return ""

    def value(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        return torch.zeros([q.size(0)], dtype=q.dtype, device=q.device)

    def gradient(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        return torch.zeros([q.size(0), q.size(1), q.size(2) + qd.size(2)], dtype=q.dtype, device=q.device)
