#include "kinematics/robot.h"

#include "core/error.h"
#include "core/format.h"
#include "kinematics/arm_kinematics.h"
#include "kinematics/point_kinematics.h"

namespace flowplan::kinematics {

Robot::Robot(RobotDescription description) : description_(std::move(description)) {
  const int64_t S = description_.num_spheres();
  radii_ = torch::empty({S}, torch::kFloat64);
  if (description_.kind == RobotKind::kPoint) {
    radii_[0] = description_.point_radius;
  } else {
    for (int64_t s = 0; s < S; ++s) radii_[s] = description_.spheres[s].radius;
  }
}

void Robot::CheckJoints(const torch::Tensor& q) const {
  const int64_t J = num_joints();
  if (!q.defined() || q.dim() != 2 || q.size(1) != J) {
    throw Error("kinematics: q: expected (N, " + std::to_string(J) + "), got " +
                (q.defined() ? ShapeText(q.sizes().vec()) : std::string("an undefined tensor")));
  }
  if (q.scalar_type() != torch::kFloat32 && q.scalar_type() != torch::kFloat64) {
    throw Error(std::string("kinematics: q: expected float32 or float64, got ") + c10::toString(q.scalar_type()));
  }
}

void Robot::WritePublicScript(jit::ScriptModule& module) const {
  const std::string J = std::to_string(num_joints()), W = std::to_string(workspace_dim());
  const std::string S = std::to_string(num_spheres());
  module.Buffer("robot_sphere_radii", radii_);
  module.Attribute("robot", c10::StringType::get(), RobotToYaml(description_));
  module.Attribute("num_joints", c10::IntType::get(), num_joints());
  module.Attribute("workspace_dim", c10::IntType::get(), workspace_dim());
  module.Define(R"PY(
def tcp(self, q: Tensor) -> Tensor:
    assert q.dim() >= 1 and q.size(-1) == )PY" + J + R"PY(, "tcp: q: expected (..., )PY" + J + R"PY()"
    shape = q.shape[:-1]
    return self.robot_tcp(q.reshape(-1, )PY" + J + R"PY()).reshape(shape + [)PY" + W + R"PY(])

def collision_spheres(self, q: Tensor) -> Tensor:
    assert q.dim() >= 1 and q.size(-1) == )PY" + J + R"PY(, "collision_spheres: q: expected (..., )PY" + J + R"PY()"
    shape = q.shape[:-1]
    centres, axes, origins = self.robot_spheres(q.reshape(-1, )PY" + J + R"PY())
    radii = self.robot_sphere_radii.to(centres.dtype).view(1, )PY" + S + R"PY(, 1).expand(centres.size(0), )PY" + S + R"PY(, 1)
    return torch.cat([centres, radii], -1).reshape(shape + [)PY" + S + ", " + std::to_string(workspace_dim() + 1) + R"PY(])
)PY");
}

std::shared_ptr<const Robot> MakeRobot(const RobotDescription& description, const std::string& where) {
  description.Validate(where);
  if (description.kind == RobotKind::kPoint) return std::make_shared<PointKinematics>(description);
  return std::make_shared<ArmKinematics>(description);
}

}  // namespace flowplan::kinematics
