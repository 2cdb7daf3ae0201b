#include "sim/franka_ik.h"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.h"

namespace flowplan::sim {
namespace {

using Jacobian = Eigen::Matrix<double, 6, kFrankaJoints>;
constexpr int kStallIterations = 30;
using RowJacobian = Eigen::Matrix<double, 3, kFrankaJoints, Eigen::RowMajor>;

/// Rotation vector (axis · angle, world frame) that turns `current` into `target`.
Eigen::Vector3d OrientationError(const Eigen::Matrix3d& target, const Eigen::Matrix3d& current) {
  const Eigen::Matrix3d delta = target * current.transpose();
  const Eigen::AngleAxisd angle_axis(delta);
  return angle_axis.angle() * angle_axis.axis();
}

IkResult Solve(const FrankaModel& model, mjData& d, const Eigen::Vector3d& target, const JointVector& seed,
               const IkOptions& options) {
  const mjModel& m = model.mj();
  const FrankaLimits& limits = model.limits();
  const JointVector lower = limits.q_lower.array() + options.limit_margin;
  const JointVector upper = limits.q_upper.array() - options.limit_margin;
  const int site = model.tcp_site();

  IkResult best;
  best.position_error = INFINITY;
  best.orientation_error = INFINITY;
  JointVector q = seed.cwiseMax(lower).cwiseMin(upper);
  RowJacobian jacp, jacr;
  for (int iteration = 0; iteration <= options.max_iterations; ++iteration) {
    for (int j = 0; j < kFrankaJoints; ++j) d.qpos[j] = q[j];
    mj_kinematics(&m, &d);
    mj_comPos(&m, &d);
    const Eigen::Vector3d position = Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * site);
    const Eigen::Matrix3d rotation =
        Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.site_xmat + 9 * site);
    Eigen::Matrix<double, 6, 1> error;
    error.head<3>() = target - position;
    error.tail<3>() = OrientationError(options.tcp_rotation, rotation);
    const double position_error = error.head<3>().norm();
    const double orientation_error = error.tail<3>().norm();
    if (position_error + orientation_error < best.position_error + best.orientation_error) {
      best.q = q;
      best.position_error = position_error;
      best.orientation_error = orientation_error;
      best.iterations = iteration;
    }
    if (position_error < options.position_tolerance && orientation_error < options.orientation_tolerance) {
      best.q = q;
      best.position_error = position_error;
      best.orientation_error = orientation_error;
      best.iterations = iteration;
      best.converged = true;
      return best;
    }
    if (iteration == options.max_iterations) break;
    // An unreachable target stops improving: give up once the best pose is old.
    if (iteration - best.iterations > kStallIterations) break;

    mj_jacSite(&m, &d, jacp.data(), jacr.data(), site);
    Jacobian jacobian;
    jacobian.topRows<3>() = jacp;
    jacobian.bottomRows<3>() = jacr;
    const Eigen::JacobiSVD<Jacobian> svd(jacobian, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const auto& s = svd.singularValues();
    const double lambda2 = options.damping * options.damping;
    JointVector step = JointVector::Zero();
    Eigen::Matrix<double, kFrankaJoints, kFrankaJoints> range_projector =
        Eigen::Matrix<double, kFrankaJoints, kFrankaJoints>::Zero();
    for (int i = 0; i < s.size(); ++i) {
      const double ui_e = svd.matrixU().col(i).dot(error);
      step += (s[i] / (s[i] * s[i] + lambda2)) * ui_e * svd.matrixV().col(i);
      if (s[i] > 1e-9) range_projector += svd.matrixV().col(i) * svd.matrixV().col(i).transpose();
    }
    // The posture acts only in the exact null space of the task, so it does not
    // disturb convergence.
    step += options.posture_gain *
            (Eigen::Matrix<double, kFrankaJoints, kFrankaJoints>::Identity() - range_projector) *
            (options.posture - q);
    const double largest = step.cwiseAbs().maxCoeff();
    if (largest > options.max_step) step *= options.max_step / largest;
    q = (q + step).cwiseMax(lower).cwiseMin(upper);
  }
  return best;
}

}  // namespace

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

IkResult SolveTcpIk(const FrankaModel& model, mjData& d, const Eigen::Vector3d& target,
                    const JointVector& seed, const IkOptions& options) {
  IkResult result = Solve(model, d, target, seed, options);
  if (result.converged || seed == options.posture) return result;
  IkResult retry = Solve(model, d, target, options.posture, options);
  return retry.converged || retry.position_error < result.position_error ? retry : result;
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
