# TorchScript (compiled by flowplan at run time, jit/library.h): boxes (rotated
# rectangles in 2-D). Row layout, 3-D (K, 10): centre (3), full side lengths
# (3), orientation quaternion (w, x, y, z); 2-D (K, 5): centre (2), side
# lengths (2), angle (rad).


def box_columns(W: int) -> int:
    return 10 if W == 3 else 5


def box_problem(params: Tensor, W: int) -> str:
    for i in range(W):
        problem = check_non_negative(params[:, W + i], "size")
        if problem != "":
            return problem
    if W == 3:
        return check_quaternions(params[:, 6:10])
    return ""


def box_distance(points: Tensor, params: Tensor) -> Tuple[Tensor, Tensor]:
    """Signed distance from points (M, W) to boxes (K, box_columns(W)) (negative
    inside): (M, K), and its gradient with respect to the points (M, K, W):
    outside, the direction from the nearest surface point; inside, the normal of
    the nearest face."""
    W = points.size(1)
    rotations = rotation_matrices(params[:, 2 * W:])
    local = to_local(points, params[:, 0:W], rotations)               # (M, K, W)
    gap = local.abs() - 0.5 * params[:, W:2 * W].unsqueeze(0)       # per axis, > 0 outside that slab
    outside = torch.relu(gap)
    outside_length = lengths(outside)                                 # (M, K)
    deepest, face = torch.max(gap, -1)                                 # (M, K)
    distance = outside_length + torch.clamp(deepest, max=0.0)
    towards_outside = outside / torch.where(outside_length > 0.0, outside_length, torch.ones_like(outside_length)).unsqueeze(-1)
    face_normal = torch.zeros_like(gap).scatter_(-1, face.unsqueeze(-1), 1.0)
    direction = torch.where((outside_length > 0.0).unsqueeze(-1), towards_outside, face_normal) * sign_of(local)
    return distance, to_world(direction, rotations)
