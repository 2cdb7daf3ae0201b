#include "sim/franka_rollout.h"

#include <cmath>
#include <cstdio>

#include "core/error.h"

namespace flowplan::sim {
namespace {

constexpr int kStateDim = 2 * kFrankaJoints;

std::string Number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.4g", value);
  return buffer;
}

void CheckRange(const std::string& key, const std::array<double, 2>& range) {
  if (range[0] > range[1]) {
    throw Error(key + ": expected [min, max] with min <= max, got [" + Number(range[0]) + ", " +
                Number(range[1]) + "]");
  }
}

}  // namespace

void FrankaRolloutConfig::Validate(const std::string& where, const FrankaLimits& limits) const {
  CheckRange(where + ".augmentation.force_range", augmentation.force_range);
  CheckRange(where + ".augmentation.force_interval", augmentation.force_interval);
  for (int j = 0; j < kFrankaJoints; ++j) {
    const double q = controller.posture[j];
    if (q < limits.q_lower[j] || q > limits.q_upper[j]) {
      throw Error(where + ".controller.posture[" + std::to_string(j) + "]: expected a value in [" +
                  Number(limits.q_lower[j]) + ", " + Number(limits.q_upper[j]) + "] (joint limits), got " +
                  Number(q));
    }
  }
}

FrankaSimulator::FrankaSimulator(const FrankaModel& model, const FrankaRolloutConfig& config)
    : model_(model),
      config_(config),
      data_(MakeData(model.mj())),
      controller_(model, config.controller, config.control_hz),
      sigma_(config.augmentation.noise_scale *
             Eigen::Map<const JointVector>(config.augmentation.torque_noise_sigma.data())) {
  FLOWPLAN_DEMAND(model.mj().opt.timestep == config.physics_timestep());
}

void FrankaSimulator::Reject(FrankaEpisode* episode, const std::string& reason) {
  episode->rejected = true;
  episode->reject_reason = reason + " at t = " + Number(data_->time) + " s";
}

void FrankaSimulator::Clear(FrankaEpisode* episode) const {
  const size_t T = static_cast<size_t>(config_.horizon);
  episode->states.assign(T * kStateDim, 0.0);
  episode->tcp.assign(T * 3, 0.0);
  episode->torques.assign(T * kFrankaJoints, 0.0);
  episode->external_force.assign(T * 3, 0.0);
  episode->warnings = 0;
  episode->physics_steps = 0;
  episode->rejected = false;
  episode->reject_reason.clear();
}

void FrankaSimulator::CheckState(FrankaEpisode* episode) {
  const mjData& d = *data_;
  if (HasInstabilityWarning(d)) {
    const char* kind = d.warning[mjWARN_BADQACC].number > 0   ? "acceleration"
                       : d.warning[mjWARN_BADQVEL].number > 0 ? "velocity"
                                                              : "position";
    Reject(episode, std::string("MuJoCo reported a bad ") + kind + " (simulation unstable)");
    return;
  }
  const JointVector& limit = model_.limits().velocity;
  for (int j = 0; j < kFrankaJoints; ++j) {
    if (!std::isfinite(d.qpos[j]) || !std::isfinite(d.qvel[j])) {
      Reject(episode, "joint " + std::to_string(j + 1) + " state is not finite");
      return;
    }
    if (std::abs(d.qvel[j]) > config_.reject_velocity_factor * limit[j]) {
      Reject(episode, "joint " + std::to_string(j + 1) + " speed " + Number(std::abs(d.qvel[j])) +
                          " rad/s exceeds " + Number(config_.reject_velocity_factor) + " x its limit " +
                          Number(limit[j]) + " rad/s");
      return;
    }
  }
}

void FrankaSimulator::Rollout(const JointVector& q0, const Eigen::Vector3d& goal, Augmentation scheme,
                              Rng& rng, FrankaEpisode* episode) {
  const Eigen::Matrix3d rotation = DownwardTcpRotation();
  Simulate(
      q0, [&](const mjData& d) { return controller_.Compute(d, goal, rotation); }, StateCheck(), scheme, rng,
      episode);
}

void FrankaSimulator::RolloutJoints(const MinimumJerkMotion& motion, const JointMotionConfig& joint_motion,
                                    const StateCheck& check, Augmentation scheme, Rng& rng, FrankaEpisode* episode) {
  JointTrackingController tracking(model_, joint_motion);
  JointVector q0, unused_velocity, unused_acceleration;
  motion.Sample(0.0, &q0, &unused_velocity, &unused_acceleration);
  Simulate(
      q0, [&](const mjData& d) { return tracking.Compute(d, motion, d.time); }, check, scheme, rng, episode);
}

template <class Control>
void FrankaSimulator::Simulate(const JointVector& q0, Control control_law, const StateCheck& check, Augmentation scheme,
                               Rng& rng, FrankaEpisode* episode) {
  const mjModel& m = model_.mj();
  mjData& d = *data_;
  const int T = config_.horizon;
  Clear(episode);

  mj_resetData(&m, &d);
  for (int j = 0; j < kFrankaJoints; ++j) d.qpos[j] = q0[j];
  const JointVector& torque_limit = model_.limits().torque;
  const int site = model_.tcp_site();
  mjtNum* hand_force = d.xfrc_applied + 6 * model_.hand_body();
  const AugmentationConfig& augmentation = config_.augmentation;
  const double timestep = m.opt.timestep;

  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  int64_t next_force_step = 0;
  const int last_control_step = (T - 1) * config_.record_every;
  JointVector control = JointVector::Zero();
  for (int k = 0; k <= last_control_step; ++k) {
    for (int s = 0; s < config_.physics_substeps; ++s) {
      mj_step1(&m, &d);
      if (s == 0) {
        if (check) {
          const std::string objection = check(Eigen::Map<const JointVector>(d.qpos));
          if (!objection.empty()) {
            Reject(episode, objection);
            episode->warnings = WarningCount(d);
            return;
          }
        }
        control = control_law(d);
      }
      JointVector torque = control;
      switch (scheme) {
        case Augmentation::kPerJointNoise:
          for (int j = 0; j < kFrankaJoints; ++j) torque[j] += sigma_[j] * rng.Normal();
          break;
        case Augmentation::kSameNoise:
          torque += sigma_ * rng.Normal();
          break;
        case Augmentation::kRandomForce:
          if (episode->physics_steps == next_force_step) {
            Eigen::Vector3d direction;
            do {
              direction = Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal());
            } while (direction.norm() < 1e-6);
            force = direction.normalized() *
                    rng.Uniform(augmentation.force_range[0], augmentation.force_range[1]);
            const double interval =
                rng.Uniform(augmentation.force_interval[0], augmentation.force_interval[1]);
            next_force_step += std::max<int64_t>(1, std::llround(interval / timestep));
          }
          break;
        case Augmentation::kNone:
        case Augmentation::kRandomPosition:
          break;
      }
      torque = torque.cwiseMax(-torque_limit).cwiseMin(torque_limit);
      for (int j = 0; j < kFrankaJoints; ++j) d.ctrl[j] = torque[j];
      for (int i = 0; i < 3; ++i) hand_force[i] = force[i];

      if (s == 0 && k % config_.record_every == 0) {
        const size_t t = static_cast<size_t>(k / config_.record_every);
        double* state = &episode->states[t * kStateDim];
        for (int j = 0; j < kFrankaJoints; ++j) {
          state[j] = d.qpos[j];
          state[kFrankaJoints + j] = d.qvel[j];
          episode->torques[t * kFrankaJoints + j] = torque[j];
        }
        for (int i = 0; i < 3; ++i) {
          episode->tcp[t * 3 + i] = d.site_xpos[3 * site + i];
          episode->external_force[t * 3 + i] = force[i];
        }
      }
      if (k == last_control_step) break;  // the last recorded state ends the episode

      mj_step2(&m, &d);
      ++episode->physics_steps;
      CheckState(episode);
      if (episode->rejected) {
        episode->warnings = WarningCount(d);
        return;
      }
    }
  }
  episode->warnings = WarningCount(d);
}

}  // namespace flowplan::sim
