#include "guidance/collision_cost.h"

#include "core/error.h"
#include "core/format.h"
#include "guidance/scene.h"

namespace flowplan::guidance {
namespace {

// Distances below this are treated as this when dividing, so that a sphere
// centre exactly on an obstacle centre gets a finite (zero) push.
constexpr double kMinDistance = 1e-9;

}  // namespace

CollisionCost::CollisionCost(std::shared_ptr<const kinematics::Robot> robot, double margin)
    : robot_(std::move(robot)), margin_(margin) {
  FLOWPLAN_DEMAND(robot_ != nullptr);
}

void CollisionCost::Check(const torch::Tensor& x, const torch::Tensor& obstacles) const {
  if (!x.defined() || x.dim() != 3 || x.size(2) < robot_->num_joints()) {
    throw Error("collision cost: x: expected (B, T, D) with D >= " + std::to_string(robot_->num_joints()) + ", got " +
                (x.defined() ? ShapeText(x.sizes().vec()) : std::string("(undefined)")));
  }
  const int64_t W = robot_->workspace_dim();
  if (!obstacles.defined() || obstacles.dim() != 2 || obstacles.size(1) != W + 1) {
    throw Error("collision cost: obstacles: expected (K, " + std::to_string(W + 1) + "), got " +
                (obstacles.defined() ? ShapeText(obstacles.sizes().vec()) : std::string("(undefined)")));
  }
}

torch::Tensor CollisionCost::Value(const torch::Tensor& x, const torch::Tensor& obstacles) const {
  Check(x, obstacles);
  const int64_t B = x.size(0), T = x.size(1), J = robot_->num_joints(), W = robot_->workspace_dim();
  if (obstacles.size(0) == 0) return torch::zeros({B}, x.options());
  const torch::Tensor q = x.slice(2, 0, J).reshape({B * T, J});
  const torch::Tensor centres = robot_->Spheres(q).centres;                          // (N, S, W)
  const torch::Tensor o = obstacles.to(x.options());
  const torch::Tensor diff = centres.unsqueeze(2) - o.slice(1, 0, W).view({1, 1, -1, W});  // (N, S, K, W)
  const torch::Tensor reach = margin_ + robot_->SphereRadii(x.scalar_type()).view({1, -1, 1}) +
                              o.select(1, W).view({1, 1, -1});                       // (1, S, K)
  const torch::Tensor penetration = torch::relu(reach - diff.norm(2, -1));           // (N, S, K)
  return penetration.sum({1, 2}).view({B, T}).sum(1);
}

CostAndGradient CollisionCost::ValueAndGradient(const torch::Tensor& x, const torch::Tensor& obstacles) const {
  Check(x, obstacles);
  const int64_t B = x.size(0), T = x.size(1), D = x.size(2), J = robot_->num_joints(), W = robot_->workspace_dim();
  if (obstacles.size(0) == 0) return {torch::zeros({B}, x.options()), torch::zeros_like(x)};
  const torch::Tensor q = x.slice(2, 0, J).reshape({B * T, J});
  const kinematics::SpherePoses poses = robot_->Spheres(q);
  const torch::Tensor o = obstacles.to(x.options());
  const torch::Tensor diff = poses.centres.unsqueeze(2) - o.slice(1, 0, W).view({1, 1, -1, W});  // (N, S, K, W)
  const torch::Tensor distance = diff.norm(2, -1);                                               // (N, S, K)
  const torch::Tensor reach = margin_ + robot_->SphereRadii(x.scalar_type()).view({1, -1, 1}) +
                              o.select(1, W).view({1, 1, -1});
  const torch::Tensor penetration = torch::relu(reach - distance);
  // ∂/∂c_s of Σ_k relu(reach − ‖c_s − o_k‖) = −Σ_k [active] (c_s − o_k) / ‖c_s − o_k‖.
  const torch::Tensor push = (penetration > 0).to(x.scalar_type()) / distance.clamp_min(kMinDistance);  // (N, S, K)
  const torch::Tensor grad_centres = -(push.unsqueeze(-1) * diff).sum(2);                              // (N, S, W)
  const torch::Tensor grad_q = robot_->SpheresVjp(poses, grad_centres).view({B, T, J});
  torch::Tensor gradient = D > J ? torch::cat({grad_q, torch::zeros({B, T, D - J}, x.options())}, 2) : grad_q;
  return {penetration.sum({1, 2}).view({B, T}).sum(1), gradient};
}

void CollisionCost::WriteScript(jit::ScriptModule& module, const std::string& name) const {
  const std::string J = std::to_string(robot_->num_joints()), W = std::to_string(robot_->workspace_dim());
  module.Define("def " + name + R"PY((self, x: Tensor, obstacles: Tensor) -> Tuple[Tensor, Tensor]:
    B = x.size(0)
    T = x.size(1)
    if obstacles.size(0) == 0:
        return torch.zeros([B], dtype=x.dtype, device=x.device), torch.zeros_like(x)
    q = x[:, :, 0:)PY" + J + "].reshape(B * T, " + J + R"PY()
    centres, axes, origins = self.robot_spheres(q)
    o = obstacles.to(x.dtype)
    diff = centres.unsqueeze(2) - o[:, 0:)PY" + W + "].view(1, 1, -1, " + W + R"PY()
    distance = torch.norm(diff, 2, -1)
    reach = )PY" + jit::ScriptFloat(margin_) + R"PY( + self.robot_sphere_radii.to(x.dtype).view(1, -1, 1) + o[:, )PY" + W +
                 R"PY(].view(1, 1, -1)
    penetration = torch.relu(reach - distance)
    push = (penetration > 0).to(x.dtype) / distance.clamp_min(1e-9)
    grad_centres = -(push.unsqueeze(-1) * diff).sum(2)
    grad_q = self.robot_spheres_vjp(centres, axes, origins, grad_centres).view(B, T, )PY" + J + R"PY()
    if x.size(2) > )PY" + J + R"PY(:
        grad_q = torch.cat([grad_q, torch.zeros([B, T, x.size(2) - )PY" + J + R"PY(], dtype=x.dtype, device=x.device)], 2)
    return penetration.sum([1, 2]).view(B, T).sum(1), grad_q
)PY");
}

torch::Tensor SphereClearance(const kinematics::Robot& robot, const torch::Tensor& x, const torch::Tensor& obstacles) {
  const int64_t B = x.size(0), T = x.size(1), J = robot.num_joints(), W = robot.workspace_dim();
  const torch::Tensor q = x.slice(2, 0, J).reshape({B * T, J});
  const torch::Tensor centres = robot.Spheres(q).centres;
  const torch::Tensor o = obstacles.to(x.options());
  const torch::Tensor distance = (centres.unsqueeze(2) - o.slice(1, 0, W).view({1, 1, -1, W})).norm(2, -1);
  const torch::Tensor clearance =
      distance - robot.SphereRadii(x.scalar_type()).view({1, -1, 1}) - o.select(1, W).view({1, 1, -1});  // (N, S, K)
  return std::get<0>(clearance.min(1)).view({B, T, -1});
}

}  // namespace flowplan::guidance
