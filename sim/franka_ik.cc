#include "sim/franka_ik.h"

#include <cstdio>

#include "core/error.h"

namespace flowplan::sim {

std::string FormatPoint(const Eigen::Vector3d& p) {
  auto format = [](double v) {
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%.3g", v);
    std::string text = buffer;
    if (text == "-0") text = "0";
    if (text.find_first_of(".e") == std::string::npos) text += ".0";
    return text;
  };
  return "(" + format(p.x()) + ", " + format(p.y()) + ", " + format(p.z()) + ")";
}

ArmIkModel FrankaIkModel(const FrankaModel& model) {
  ArmIkModel arm;
  arm.model = &model.mj();
  for (int j = 0; j < kFrankaJoints; ++j) {
    arm.qpos.push_back(j);
    arm.dof.push_back(j);
  }
  arm.tcp_site = model.tcp_site();
  arm.lower = model.limits().q_lower;
  arm.upper = model.limits().q_upper;
  return arm;
}

IkResult SolveTcpIk(const FrankaModel& model, mjData& d, const Eigen::Vector3d& target,
                    const JointVector& seed, const IkOptions& options) {
  const ArmIkResult solved = SolveArmIk(FrankaIkModel(model), d, target, options.tcp_rotation, seed, options.posture,
                                        options);
  IkResult result;
  result.converged = solved.converged;
  result.q = solved.q;
  result.position_error = solved.position_error;
  result.orientation_error = solved.orientation_error;
  result.iterations = solved.iterations;
  return result;
}

JointVector SolveTcpIkOrThrow(const FrankaModel& model, mjData& d, const Eigen::Vector3d& target,
                              const JointVector& seed, const IkOptions& options) {
  const IkResult result = SolveTcpIk(model, d, target, seed, options);
  if (!result.converged) {
    char closest[64];
    if (result.position_error >= options.position_tolerance) {
      std::snprintf(closest, sizeof(closest), "closest %.2g m away", result.position_error);
    } else {
      std::snprintf(closest, sizeof(closest), "gripper cannot point down there, off by %.2g rad",
                    result.orientation_error);
    }
    throw Error("franka IK: target " + FormatPoint(target) + " is unreachable (" + closest + ")");
  }
  return result.q;
}

}  // namespace flowplan::sim
