# TorchScript (compiled by flowplan at run time, jit/library.h): helpers of
# the trajectory samplers. Shapes: B plans, T states, D state dims.


def conditioned(x: Tensor, start: Tensor, goal: Tensor, inpainting: bool) -> Tensor:
    """x (B, T, D) with its ends overwritten under inpainting, unchanged otherwise."""
    if inpainting:
        return inpaint(x, start, goal)
    return x


def setting_int(opts: Dict[str, float], key: str) -> int:
    value = opts[key]
    assert value == float(int(value)), key + ": expected a whole number, got " + str(value)
    return int(value)


def ceil_int(value: float) -> int:
    """The smallest whole number >= value."""
    whole = int(value)
    return whole + 1 if float(whole) < value else whole


def split_steps(steps: int, split_time: float) -> int:
    """Euler steps of splitting's second stage (split_time -> 1): the first
    stage's steps over the same stretch of flow time, at least one."""
    return max(1, int(steps * (1.0 - split_time) + 1e-9))


def guide_targets() -> List[str]:
    """Where the flow planner may guide (sampler.guide_at)."""
    return ["state", "velocity", "prediction"]
