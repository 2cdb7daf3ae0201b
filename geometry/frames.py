# TorchScript (compiled by flowplan at run time, jit/library.h): frames of
# obstacle shapes. W is the workspace dimension (3, or 2 for the particle).

import torch
from torch import Tensor


def rotation_matrices(rotation: Tensor) -> Tensor:
    """Rotations of K shapes, local to world: (K, 4) quaternions (w, x, y, z) of
    any non-zero norm -> (K, 3, 3); (K, 1) angles (rad, 2-D) -> (K, 2, 2).
    Each entry of the rotation of a unit quaternion q is a quadratic form of q,
    e.g. R_00 = w^2 + x^2 - y^2 - z^2, R_01 = 2(xy - wz): R = (q q^T) . C / |q|^2
    with the constant C (16, 9) below, a handful of operations however many
    shapes (this runs in every guidance step)."""
    if rotation.size(1) == 1:
        c = torch.cos(rotation[:, 0])
        s = torch.sin(rotation[:, 0])
        return torch.stack([c, -s, s, c], 1).view(-1, 2, 2)
    # Rows: q_a q_b for (a, b) = (w, w), (w, x), ..., (z, z); columns: R_00, R_01, ..., R_22.
    C = torch.tensor([[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],       # ww
                      [0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0],      # wx
                      [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0],      # wy
                      [0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],      # wz
                      [0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0],      # xw
                      [1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0],     # xx
                      [0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],       # xy
                      [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],       # xz
                      [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0],      # yw
                      [0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],       # yx
                      [-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0],     # yy
                      [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0],       # yz
                      [0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],      # zw
                      [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],       # zx
                      [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0],       # zy
                      [-1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0]],    # zz
                     dtype=rotation.dtype, device=rotation.device)
    K = rotation.size(0)
    products = (rotation.unsqueeze(2) * rotation.unsqueeze(1)).view(K, 16)   # q_a q_b
    squared_norm = products[:, 0] + products[:, 5] + products[:, 10] + products[:, 15]
    return (torch.mm(products, C) / squared_norm.unsqueeze(1)).view(K, 3, 3)


def with_rotation_matrices(params: Tensor, orientation: int, W: int) -> Tensor:
    """Rows (K, C) of rotated shapes whose orientation (a quaternion, or an
    angle in 2-D) starts at column `orientation`, with their rotation matrices
    appended row by row (K, C + W W): what shape_rotations then reads back
    instead of computing. Computed in float64, returned in the rows' dtype."""
    rotations = rotation_matrices(params[:, orientation:orientation + (4 if W == 3 else 1)].double())
    return torch.cat([params, rotations.reshape(params.size(0), W * W).to(params.dtype)], 1)


def shape_rotations(params: Tensor, orientation: int, W: int) -> Tensor:
    """The rotations (K, W, W) of rotated shapes' rows (K, C) whose orientation
    starts at column `orientation`: read back when the rows carry them
    (with_rotation_matrices), else computed (rotation_matrices)."""
    turn = 4 if W == 3 else 1
    if params.size(1) == orientation + turn + W * W:
        return params[:, orientation + turn:].reshape(params.size(0), W, W)
    return rotation_matrices(params[:, orientation:orientation + turn])


def to_local(points: Tensor, centres: Tensor, rotations: Tensor) -> Tensor:
    """points (M, W), centres (K, W), rotations (K, W, W) -> (M, K, W): each point
    in each shape's frame, R_k^T (p - c_k) = (p^T R_k - c_k^T R_k)^T: one matrix
    product with the rotations side by side (W, K W), and a contiguous result."""
    M = points.size(0)
    K = centres.size(0)
    W = points.size(1)
    side_by_side = rotations.transpose(0, 1).reshape(W, K * W)                 # [i, k W + j] = R_k[i, j]
    shifts = torch.bmm(centres.unsqueeze(1), rotations).view(1, K, W)          # c_k^T R_k
    return torch.mm(points, side_by_side).view(M, K, W) - shifts


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


def largest(vectors: Tensor) -> Tensor:
    """The largest coordinate (...) of vectors (..., W), taken coordinate by
    coordinate (as lengths: ATen's max over a last dimension of 2 or 3 is slow)."""
    total = vectors.select(-1, 0)
    for i in range(1, vectors.size(-1)):
        total = torch.maximum(total, vectors.select(-1, i))
    return total


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
