#include "sim/franka_controller.h"

#include <Eigen/Dense>
#include <cmath>

namespace flowplan::sim {
namespace {

// Floor on the eigenvalues of J M⁻¹ Jᵀ (1/kg, 1/(kg m²)); the arm's are about
// 0.1 to 100 away from singularities.
constexpr double kMinInverseInertia = 0.02;

}  // namespace

OperationalSpaceController::OperationalSpaceController(const FrankaModel& model, const OscConfig& config,
                                                       double control_hz)
    : model_(model),
      kp_(config.stiffness),
      kd_(2.0 * config.damping_ratio * std::sqrt(config.stiffness)),
      max_speed_(config.max_speed),
      kp_rot_(config.orientation_stiffness),
      kd_rot_(2.0 * config.damping_ratio * std::sqrt(config.orientation_stiffness)),
      kp_null_(config.nullspace_stiffness),
      kd_null_(2.0 * config.nullspace_damping_ratio * std::sqrt(config.nullspace_stiffness)),
      speed_guard_(config.speed_guard),
      brake_rate_(control_hz),
      posture_(Eigen::Map<const JointVector>(config.posture.data())),
      probe_(MakeData(model.mj())) {}

JointVector OperationalSpaceController::Compute(const mjData& d, const Eigen::Vector3d& target,
                                                const Eigen::Matrix3d& target_rotation) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Matrix67 = Eigen::Matrix<double, 6, kFrankaJoints>;
  using Matrix7 = Eigen::Matrix<double, kFrankaJoints, kFrankaJoints>;
  const mjModel& m = model_.mj();
  const int site = model_.tcp_site();

  mj_jacSite(&m, &d, jacp_.data(), jacr_.data(), site);
  mj_fullM(&m, mass_.data(), d.qM);
  Matrix67 jacobian;
  jacobian.topRows<3>() = jacp_;
  jacobian.bottomRows<3>() = jacr_;

  const Eigen::Map<const JointVector> q(d.qpos), qdot(d.qvel), bias(d.qfrc_bias);
  const Eigen::Map<const Eigen::Vector3d> position(d.site_xpos + 3 * site);
  const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> rotation(d.site_xmat + 9 * site);

  // Orientation error as a small rotation vector: ½ Σ r_i × r_i,target.
  Eigen::Vector3d rotation_error = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) rotation_error += 0.5 * rotation.col(i).cross(target_rotation.col(i));

  const Eigen::Matrix<double, 6, 1> twist = jacobian * qdot;
  Eigen::Matrix<double, 6, 1> acceleration;
  if (kd_ > 0.0) {
    Eigen::Vector3d velocity = (kp_ / kd_) * (target - position);
    const double speed = velocity.norm();
    if (speed > max_speed_) velocity *= max_speed_ / speed;
    acceleration.head<3>() = kd_ * (velocity - twist.head<3>());
  } else {
    acceleration.head<3>() = kp_ * (target - position);
  }
  acceleration.tail<3>() = kp_rot_ * rotation_error - kd_rot_ * twist.tail<3>();

  // J̇ q̇ ≈ (J(q + ε q̇) − J(q)) q̇ / ε, the TCP acceleration that q̇ alone causes.
  constexpr double kEpsilon = 1e-6;  // s
  for (int j = 0; j < kFrankaJoints; ++j) probe_->qpos[j] = d.qpos[j] + kEpsilon * d.qvel[j];
  mj_kinematics(&m, probe_.get());
  mj_comPos(&m, probe_.get());
  mj_jacSite(&m, probe_.get(), jacp_.data(), jacr_.data(), site);
  Matrix67 jacobian_ahead;
  jacobian_ahead.topRows<3>() = jacp_;
  jacobian_ahead.bottomRows<3>() = jacr_;
  acceleration -= (jacobian_ahead * qdot - twist) / kEpsilon;

  const Eigen::LLT<Matrix7> mass_llt(mass_);
  const Eigen::Matrix<double, kFrankaJoints, 6> minv_jt = mass_llt.solve(jacobian.transpose());
  const Matrix6 lambda_inverse = jacobian * minv_jt;
  // Near a singularity J M⁻¹ Jᵀ loses rank and Λ grows without bound; flooring
  // the eigenvalues of J M⁻¹ Jᵀ keeps the task forces finite there. The
  // eigensolver is needed only when trace(Λ) >= 1 / floor: otherwise every
  // eigenvalue of Λ is below 1 / floor, i.e. none of J M⁻¹ Jᵀ is below the floor.
  Matrix6 lambda;
  const Eigen::LLT<Matrix6> llt(lambda_inverse);
  if (llt.info() == Eigen::Success) lambda = llt.solve(Matrix6::Identity());
  if (llt.info() != Eigen::Success || !(lambda.trace() < 1.0 / kMinInverseInertia)) {
    const Eigen::SelfAdjointEigenSolver<Matrix6> eigen(lambda_inverse);
    const Eigen::Matrix<double, 6, 1> inverse_eigenvalues =
        eigen.eigenvalues().cwiseMax(kMinInverseInertia).cwiseInverse();
    lambda = eigen.eigenvectors() * inverse_eigenvalues.asDiagonal() * eigen.eigenvectors().transpose();
  }
  const Eigen::Matrix<double, kFrankaJoints, 6> jbar = minv_jt * lambda;

  JointVector torque = jacobian.transpose() * (lambda * acceleration);
  const JointVector posture_acceleration = kp_null_ * (posture_ - q) - kd_null_ * qdot;
  const JointVector posture_torque = mass_ * posture_acceleration;
  torque += posture_torque - jacobian.transpose() * (jbar.transpose() * posture_torque);
  torque += bias - Eigen::Map<const JointVector>(d.qfrc_passive);

  JointVector brake = JointVector::Zero();
  bool braking = false;
  const JointVector& speed_limit = model_.limits().velocity;
  for (int j = 0; j < kFrankaJoints; ++j) {
    const double excess = std::abs(qdot[j]) - speed_guard_ * speed_limit[j];
    if (excess > 0.0) {
      brake[j] = -brake_rate_ * excess * (qdot[j] > 0.0 ? 1.0 : -1.0);
      braking = true;
    }
  }
  if (braking) torque += mass_ * brake;
  const JointVector& limit = model_.limits().torque;
  return torque.cwiseMax(-limit).cwiseMin(limit);
}

}  // namespace flowplan::sim
