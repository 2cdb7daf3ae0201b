# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# CostChain, a list of cost terms as a chain: submodules term (any cost class)
# and rest (another CostChain, or a NoCost at the end). Each term's gradient
# [dC/dq, dC/dqd] is capped per state at guidance.clip (raw units) and weighted
# by opts[term.weight_key].
# kernels/arm_guidance_kernel.cc computes the chain of the built-in terms, their caps and weights too, for an arm with native
# kernels (guidance/arm_guide.py): a change here is a change there.

from typing import Dict

import torch
from torch import Tensor

from flowplan.script.guidance.guidance import clip_states


class CostChain:
    def active(self, scene: Dict[str, Tensor], opts: Dict[str, float]) -> bool:
        return self.term.active(scene, opts) or self.rest.active(scene, opts)

    def autograd_source(self, opts: Dict[str, float]) -> str:
        """The file of a term whose gradient needs autograd, or ''."""
        source = self.term.autograd_source(opts)
        return source if source != "" else self.rest.autograd_source(opts)

    def value(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        """sum_k w_k C_k (B,)."""
        total = self.rest.value(q, qd, scene, opts)
        weight = opts[self.term.weight_key]
        if weight != 0.0:
            value, grad_q, grad_qd = self.term.value_and_gradient(q, qd, scene, opts)
            total = total + weight * value
        return total

    def gradient(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        """sum_k w_k clip([dC_k/dq, dC_k/dqd]) (B, T, 2J)."""
        gradient = self.rest.gradient(q, qd, scene, opts)
        weight = opts[self.term.weight_key]
        if weight != 0.0:
            value, term_q, term_qd = self.term.value_and_gradient(q, qd, scene, opts)
            gradient = gradient + weight * clip_states(torch.cat([term_q, term_qd], 2), opts["guidance.clip"])
        return gradient
