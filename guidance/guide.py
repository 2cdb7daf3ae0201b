# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# Guide, guidance of a sampler towards low cost (SPEC section 2). Costs see
# raw (de-normalized) states x = [q, qd] (D = 2J); a guidance step moves the
# normalized trajectories against
#   sum_k w_k clip(dC_k/dx) * (hi - lo) / 2,
# the chain rule through the normalizer. Submodules normalizer and costs (a
# CostChain); attribute num_joints; the method native_gradient, from
# guidance/arm_guide.py (an arm with the built-in terms and native kernels:
# the same gradient in one native call) or guidance/chain_gradient.py (none).

from typing import Dict, Tuple

import torch
from torch import Tensor

from flowplan.script.guidance.guidance import schedule_factor


class Guide:
    def active(self, scene: Dict[str, Tensor], opts: Dict[str, float]) -> bool:
        """Whether guidance runs: a non-zero scale and a term with something to do."""
        return opts["guidance.scale"] != 0.0 and self.costs.active(scene, opts)

    def check_grad_mode(self, x: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]):
        """Fails with one clear line if guidance would need autograd (a user's cost)
        and the caller runs under torch.inference_mode(), where a new tensor (from
        x, any tensor of the call) is an inference tensor."""
        if self.active(scene, opts):
            source = self.costs.autograd_source(opts)
            assert source == "" or not (x * 0.0).is_inference(), source + ": a user cost takes its gradient by autograd, which cannot run under torch.inference_mode(); plan under torch.no_grad() instead"

    def split(self, x: Tensor) -> Tuple[Tensor, Tensor]:
        J = self.num_joints
        return x[:, :, 0:J], x[:, :, J:2 * J]

    def value(self, x: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        """sum_k w_k C_k (B,) of raw trajectories x (B, T, D)."""
        q, qd = self.split(x)
        return self.costs.value(q, qd, scene, opts)

    def raw_gradient(self, x: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        """sum_k w_k clip(dC_k/dx) (B, T, D) at raw trajectories x (B, T, D)."""
        q, qd = self.split(x)
        return self.costs.gradient(q, qd, scene, opts)

    def gradient(self, x: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        """The guidance gradient (B, T, D) with respect to normalized trajectories
        x (B, T, D): one native call where the guide has one that takes these
        tensors (native_gradient), else the chain's terms through the normalizer."""
        native = self.native_gradient(x, scene, opts)
        if native is not None:
            return native
        raw = self.normalizer.denormalize_unclamped(x)
        return self.raw_gradient(raw, scene, opts) * self.normalizer.raw_per_normalized()

    def step(self, x: Tensor, t: float, scene: Dict[str, Tensor], opts: Dict[str, float], schedule: str) -> Tensor:
        """One guidance step after the sampler step that reached flow time t:
        x - scale * b_t * gradient(x), x (B, T, D) normalized."""
        return x - (opts["guidance.scale"] * schedule_factor(schedule, t)) * self.gradient(x, scene, opts)
