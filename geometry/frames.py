# TorchScript (compiled by flowplan at run time, jit/library.h): frames of
# obstacle shapes. W is the workspace dimension (3, or 2 for the particle).


def rotation_matrices(rotation: Tensor) -> Tensor:
    """Rotations of K shapes, local to world: (K, 4) quaternions (w, x, y, z) of
    any non-zero norm (normalised here) -> (K, 3, 3); (K, 1) angles (rad, 2-D)
    -> (K, 2, 2)."""
    if rotation.size(1) == 1:
        c = torch.cos(rotation[:, 0])
        s = torch.sin(rotation[:, 0])
        return torch.stack([c, -s, s, c], 1).view(-1, 2, 2)
    q = rotation / torch.norm(rotation, 2, 1, True)
    w = q[:, 0]
    x = q[:, 1]
    y = q[:, 2]
    z = q[:, 3]
    return torch.stack([1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y),
                        2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x),
                        2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)], 1).view(-1, 3, 3)


def to_local(points: Tensor, centres: Tensor, rotations: Tensor) -> Tensor:
    """points (M, W), centres (K, W), rotations (K, W, W) -> (M, K, W): each point
    in each shape's frame, R_k^T (p - c_k)."""
    offset = points.unsqueeze(0) - centres.unsqueeze(1)                     # (K, M, W)
    return torch.bmm(offset, rotations).transpose(0, 1)                      # rows times R_k


def to_world(vectors: Tensor, rotations: Tensor) -> Tensor:
    """vectors (M, K, W) in the shapes' frames, rotations (K, W, W) -> (M, K, W): R_k v."""
    return torch.bmm(vectors.transpose(0, 1), rotations.transpose(1, 2)).transpose(0, 1)


def lengths(vectors: Tensor) -> Tensor:
    """Euclidean lengths (...) of vectors (..., W), summed coordinate by
    coordinate (a reduction over a last dimension of 2 or 3 is slow in ATen)."""
    squares = vectors * vectors
    total = squares.select(-1, 0)
    for i in range(1, vectors.size(-1)):
        total = total + squares.select(-1, i)
    return torch.sqrt(total)


def sign_of(x: Tensor) -> Tensor:
    """+1 where x >= 0, -1 elsewhere (a side for points on a plane of symmetry)."""
    return torch.where(x < 0.0, -torch.ones_like(x), torch.ones_like(x))


def unit_or(vectors: Tensor, norms: Tensor, fallback: Tensor) -> Tensor:
    """vectors (..., W) divided by their norms (...), or `fallback` (W,) where the norm is 0."""
    zero = (norms <= 0.0).unsqueeze(-1)
    return torch.where(zero, fallback.expand_as(vectors), vectors / torch.where(norms <= 0.0, torch.ones_like(norms), norms).unsqueeze(-1))


def first_bad_row(bad: Tensor) -> int:
    """Index of the first True of bad (K,), or -1."""
    rows = torch.nonzero(bad)
    if rows.size(0) == 0:
        return -1
    return int(rows[0, 0])


def check_rows(params: Tensor, columns: int, what: str) -> str:
    """'' if params is (K, columns) of finite values, else what is wrong."""
    if params.dim() != 2 or params.size(1) != columns:
        return "expected (K, " + str(columns) + ") rows of " + what + ", got " + str(params.shape)
    row = first_bad_row(torch.logical_not(torch.isfinite(params).all(1)))
    if row >= 0:
        return "row " + str(row) + ": expected finite values"
    return ""


def check_non_negative(values: Tensor, what: str) -> str:
    """'' if every value of (K,) is >= 0, else which row is not."""
    row = first_bad_row(values < 0.0)
    if row >= 0:
        return "row " + str(row) + ": expected a non-negative " + what + ", got " + str(float(values[row]))
    return ""


def check_quaternions(quaternions: Tensor) -> str:
    """'' if no quaternion of (K, 4) is zero, else which is."""
    row = first_bad_row((quaternions == 0.0).all(1))
    if row >= 0:
        return "row " + str(row) + ": expected a non-zero quaternion (w, x, y, z)"
    return ""
