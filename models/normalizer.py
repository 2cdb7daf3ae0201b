# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# Normalizer, per-dimension min-max normalization to [-1, 1] (SPEC section 2).
# Buffers lo, hi (D,) in raw units, float32. x: (..., D).

import torch
from torch import Tensor


class Normalizer:
    def normalize(self, x: Tensor) -> Tensor:
        """raw -> [-1, 1] (float64 x stays float64: the float32 statistics promote)."""
        return (x - self.lo) / (self.hi - self.lo) * 2.0 - 1.0

    def denormalize_unclamped(self, x: Tensor) -> Tensor:
        """[-1, 1] -> raw, without clamping (for gradients through it)."""
        return (x + 1.0) * 0.5 * (self.hi - self.lo) + self.lo

    def denormalize(self, x: Tensor) -> Tensor:
        """[-1, 1] -> raw, clamping to [-1, 1] first."""
        return self.denormalize_unclamped(torch.clamp(x, -1.0, 1.0))

    def raw_per_normalized(self) -> Tensor:
        """d(raw)/d(normalized) per dimension (D,): (hi - lo) / 2."""
        return 0.5 * (self.hi - self.lo)
