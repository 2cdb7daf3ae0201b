#include "sim/arm_ik.h"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <cmath>

#include "core/error.h"
#include "core/random.h"

namespace flowplan::sim {
namespace {

constexpr int kStallIterations = 30;
using RowJacobian = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>;

/// Rotation vector (axis · angle, world frame) that turns `current` into `target`.
Eigen::Vector3d OrientationError(const Eigen::Matrix3d& target, const Eigen::Matrix3d& current) {
  const Eigen::Matrix3d delta = target * current.transpose();
  const Eigen::AngleAxisd angle_axis(delta);
  return angle_axis.angle() * angle_axis.axis();
}

/// The solve for N joints (Eigen::Dynamic: any number). Fixed sizes are the same
/// algorithm, vectorized by Eigen in their own order of operations; the common
/// arms use them, so that their solutions do not depend on how many joints
/// other arms have.
template <int N>
ArmIkResult Solve(const ArmIkModel& arm, mjData& d, const Eigen::Vector3d& target, const Eigen::Matrix3d& rotation,
                  const Eigen::VectorXd& seed_in, const Eigen::VectorXd& posture_in, const IkSettings& settings) {
  using Vector = Eigen::Matrix<double, N, 1>;
  using Jacobian = Eigen::Matrix<double, 6, N>;
  using Square = Eigen::Matrix<double, N, N>;
  const mjModel& m = *arm.model;
  const int J = static_cast<int>(arm.qpos.size());
  const Vector seed = seed_in, posture = posture_in;
  const Vector lower = arm.lower.array() + settings.limit_margin;
  const Vector upper = arm.upper.array() - settings.limit_margin;
  const int site = arm.tcp_site;

  ArmIkResult best;
  best.q = Eigen::VectorXd::Zero(J);
  best.position_error = INFINITY;
  best.orientation_error = INFINITY;
  Vector q = seed.cwiseMax(lower).cwiseMin(upper);
  RowJacobian jacp(3, m.nv), jacr(3, m.nv);
  Jacobian jacobian(6, J);
  for (int iteration = 0; iteration <= settings.max_iterations; ++iteration) {
    for (int j = 0; j < J; ++j) d.qpos[arm.qpos[j]] = q[j];
    mj_kinematics(&m, &d);
    mj_comPos(&m, &d);
    const Eigen::Vector3d position = Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * site);
    const Eigen::Matrix3d current = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.site_xmat + 9 * site);
    Eigen::Matrix<double, 6, 1> error;
    error.head<3>() = target - position;
    error.tail<3>() = OrientationError(rotation, current);
    const double position_error = error.head<3>().norm();
    const double orientation_error = error.tail<3>().norm();
    if (position_error + orientation_error < best.position_error + best.orientation_error) {
      best.q = q;
      best.position_error = position_error;
      best.orientation_error = orientation_error;
      best.iterations = iteration;
    }
    if (position_error < settings.position_tolerance && orientation_error < settings.orientation_tolerance) {
      best.q = q;
      best.position_error = position_error;
      best.orientation_error = orientation_error;
      best.iterations = iteration;
      best.converged = true;
      return best;
    }
    if (iteration == settings.max_iterations) break;
    // An unreachable target stops improving: give up once the best pose is old.
    if (iteration - best.iterations > kStallIterations) break;

    mj_jacSite(&m, &d, jacp.data(), jacr.data(), site);
    for (int j = 0; j < J; ++j) {
      jacobian.col(j).segment(0, 3) = jacp.col(arm.dof[j]);
      jacobian.col(j).segment(3, 3) = jacr.col(arm.dof[j]);
    }
    const Eigen::JacobiSVD<Jacobian> svd(jacobian, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const auto& s = svd.singularValues();
    const double lambda2 = settings.damping * settings.damping;
    Vector step = Vector::Zero(J);
    Square range_projector = Square::Zero(J, J);
    for (int i = 0; i < s.size(); ++i) {
      const double ui_e = svd.matrixU().col(i).dot(error);
      step += (s[i] / (s[i] * s[i] + lambda2)) * ui_e * svd.matrixV().col(i);
      if (s[i] > 1e-9) range_projector += svd.matrixV().col(i) * svd.matrixV().col(i).transpose();
    }
    // The posture acts only in the exact null space of the task, so it does not
    // disturb convergence.
    step += settings.posture_gain * (Square::Identity(J, J) - range_projector) * (posture - q);
    const double largest = step.cwiseAbs().maxCoeff();
    if (largest > settings.max_step) step *= settings.max_step / largest;
    q = (q + step).cwiseMax(lower).cwiseMin(upper);
  }
  return best;
}

}  // namespace

ArmIkResult SolveArmIk(const ArmIkModel& arm, mjData& d, const Eigen::Vector3d& target,
                       const Eigen::Matrix3d& rotation, const Eigen::VectorXd& seed, const Eigen::VectorXd& posture,
                       const IkSettings& settings) {
  const size_t J = arm.qpos.size();
  if (arm.model == nullptr || arm.dof.size() != J || static_cast<size_t>(arm.lower.size()) != J ||
      static_cast<size_t>(arm.upper.size()) != J || static_cast<size_t>(seed.size()) != J ||
      static_cast<size_t>(posture.size()) != J || arm.tcp_site < 0 || arm.tcp_site >= arm.model->nsite) {
    throw Error("IK: the arm's joints, limits, seed and posture disagree in length, or it has no TCP site");
  }
  auto solve = J == 7   ? &Solve<7>
               : J == 6 ? &Solve<6>
                        : &Solve<Eigen::Dynamic>;
  ArmIkResult result = solve(arm, d, target, rotation, seed, posture, settings);
  auto keep_better = [&](ArmIkResult retry) {
    if (retry.converged || retry.position_error < result.position_error) result = std::move(retry);
  };
  if (!result.converged && seed != posture) keep_better(solve(arm, d, target, rotation, posture, posture, settings));
  Rng rng(settings.restart_seed);
  Eigen::VectorXd start(static_cast<Eigen::Index>(J));
  for (int restart = 0; restart < settings.restarts && !result.converged; ++restart) {
    for (Eigen::Index j = 0; j < start.size(); ++j) start[j] = rng.Uniform(arm.lower[j], arm.upper[j]);
    keep_better(solve(arm, d, target, rotation, start, posture, settings));
  }
  return result;
}

}  // namespace flowplan::sim
