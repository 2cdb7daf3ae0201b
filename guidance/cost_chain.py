# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# CostChain, a list of cost terms as a chain: submodules term (any cost class)
# and rest (another CostChain, or a NoCost at the end). Each term's gradient is
# capped per state at guidance.clip (raw units) and weighted by
# opts[term.weight_key].


def active(self, scene: Dict[str, Tensor], opts: Dict[str, float]) -> bool:
    return self.term.active(scene, opts) or self.rest.active(scene, opts)


def value(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
    """sum_k w_k C_k (B,)."""
    total = self.rest.value(q, qd, scene, opts)
    weight = opts[self.term.weight_key]
    if weight != 0.0:
        value, grad_q, grad_qd = self.term.value_and_gradient(q, qd, scene, opts)
        total = total + weight * value
    return total


def gradient(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tuple[Tensor, Tensor]:
    """sum_k w_k clip(dC_k/dq), sum_k w_k clip(dC_k/dqd), each (B, T, J)."""
    grad_q, grad_qd = self.rest.gradient(q, qd, scene, opts)
    weight = opts[self.term.weight_key]
    if weight != 0.0:
        value, term_q, term_qd = self.term.value_and_gradient(q, qd, scene, opts)
        term_q, term_qd = clip_states(term_q, term_qd, opts["guidance.clip"])
        grad_q = grad_q + weight * term_q
        grad_qd = grad_qd + weight * term_qd
    return grad_q, grad_qd
