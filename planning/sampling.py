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
