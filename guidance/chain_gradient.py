# TorchScript (compiled by flowplan at run time, jit/library.h): the Guide's
# native_gradient (guidance/guide.py) where it has none (portable kernels, a
# robot other than an arm, or a user cost): the chain computes every gradient.

from typing import Dict, Optional

import torch
from torch import Tensor


class ChainGradient:
    def native_gradient(self, x: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Optional[Tensor]:
        return None
