#include "kinematics/point_kinematics.h"

namespace flowplan::kinematics {

torch::Tensor PointKinematics::Tcp(const torch::Tensor& q) const {
  CheckJoints(q);
  return q;
}

torch::Tensor PointKinematics::TcpVjp(const torch::Tensor& q, const torch::Tensor& g) const {
  CheckJoints(q);
  return g;
}

SpherePoses PointKinematics::Spheres(const torch::Tensor& q) const {
  CheckJoints(q);
  return {q.unsqueeze(1), torch::Tensor(), torch::Tensor()};
}

torch::Tensor PointKinematics::SpheresVjp(const SpherePoses&, const torch::Tensor& grad_centres) const {
  return grad_centres.squeeze(1);
}

void PointKinematics::WriteScript(jit::ScriptModule& module) const {
  module.Define(R"PY(
def robot_tcp(self, q: Tensor) -> Tensor:
    return q

def robot_tcp_vjp(self, q: Tensor, g: Tensor) -> Tensor:
    return g

def robot_spheres(self, q: Tensor) -> Tuple[Tensor, Tensor, Tensor]:
    none = torch.zeros([0], dtype=q.dtype, device=q.device)
    return q.unsqueeze(1), none, none

def robot_spheres_vjp(self, centres: Tensor, axes: Tensor, origins: Tensor, g: Tensor) -> Tensor:
    return g.squeeze(1)
)PY");
  WritePublicScript(module);
}

}  // namespace flowplan::kinematics
