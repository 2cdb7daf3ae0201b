#include "sim/joint_rollout.h"

#include <cmath>

#include "core/error.h"
#include "core/format.h"

namespace flowplan::sim {

JointSimulator::JointSimulator(const mjModel& model, JointDrives drives, const JointRolloutConfig& config,
                               const JointMotionConfig& motion)
    : model_(model),
      drives_(std::move(drives)),
      config_(config),
      kp_(motion.stiffness),
      kd_(2.0 * motion.damping_ratio * std::sqrt(motion.stiffness)),
      J_(static_cast<int>(drives_.qpos.size())),
      data_(MakeData(model)) {
  FLOWPLAN_DEMAND(model.nv == J_ && model.nu == J_ && static_cast<int>(drives_.dof.size()) == J_);
  FLOWPLAN_DEMAND(drives_.velocity_limit.size() == J_ && drives_.effort_limit.size() == J_);
  FLOWPLAN_DEMAND(model.opt.timestep == config.physics_timestep());
  full_mass_.resize(J_, J_);
  mass_.resize(J_, J_);
  q_.resize(J_);
  qdot_.resize(J_);
  bias_.resize(J_);
  passive_.resize(J_);
  control_ = Eigen::VectorXd::Zero(J_);
  sigma_ = config.torque_noise_share * drives_.effort_limit;
}

void JointSimulator::Reject(JointEpisode* episode, const std::string& reason) const {
  episode->rejected = true;
  episode->reject_reason = reason + " at t = " + ShortNumber(data_->time) + " s";
}

void JointSimulator::Clear(JointEpisode* episode) const {
  const size_t T = static_cast<size_t>(config_.horizon), J = static_cast<size_t>(J_);
  episode->states.assign(T * 2 * J, 0.0);
  episode->tcp.assign(T * 3, 0.0);
  episode->torques.assign(T * J, 0.0);
  episode->warnings = 0;
  episode->physics_steps = 0;
  episode->rejected = false;
  episode->reject_reason.clear();
}

void JointSimulator::Rollout(const JointMotion& motion, const StateCheck& check, bool noise, Rng& rng,
                             JointEpisode* episode) {
  const mjModel& m = model_;
  mjData& d = *data_;
  const int J = J_, T = config_.horizon;
  Clear(episode);
  mj_resetData(&m, &d);
  Eigen::VectorXd q0, unused_velocity, unused_acceleration;
  motion.Sample(0.0, &q0, &unused_velocity, &unused_acceleration);
  for (int j = 0; j < J; ++j) d.qpos[drives_.qpos[j]] = q0[j];

  const int site = drives_.tcp_site;
  const int last_control_step = (T - 1) * config_.record_every;
  Eigen::VectorXd torque(J);
  for (int k = 0; k <= last_control_step; ++k) {
    for (int s = 0; s < config_.physics_substeps; ++s) {
      mj_step1(&m, &d);
      if (s == 0) {
        for (int j = 0; j < J; ++j) {
          q_[j] = d.qpos[drives_.qpos[j]];
          qdot_[j] = d.qvel[drives_.dof[j]];
          bias_[j] = d.qfrc_bias[drives_.dof[j]];
          passive_[j] = d.qfrc_passive[drives_.dof[j]];
        }
        if (check) {
          const std::string objection = check(q_);
          if (!objection.empty()) {
            Reject(episode, objection);
            episode->warnings = WarningCount(d);
            return;
          }
        }
        mj_fullM(&m, full_mass_.data(), d.qM);  // symmetric: storage order is moot
        for (int a = 0; a < J; ++a) {
          for (int b = 0; b < J; ++b) mass_(a, b) = full_mass_(drives_.dof[a], drives_.dof[b]);
        }
        control_ = TrackingTorque<Eigen::VectorXd>(motion, d.time, q_, qdot_, mass_, bias_, passive_, kp_, kd_);
      }
      torque = control_;
      if (noise) {
        for (int j = 0; j < J; ++j) torque[j] += sigma_[j] * rng.Normal();
      }
      torque = torque.cwiseMax(-drives_.effort_limit).cwiseMin(drives_.effort_limit);
      for (int j = 0; j < J; ++j) d.ctrl[j] = torque[j];  // motor j drives joint j

      if (s == 0 && k % config_.record_every == 0) {
        const size_t t = static_cast<size_t>(k / config_.record_every);
        double* state = &episode->states[t * 2 * J];
        for (int j = 0; j < J; ++j) {
          state[j] = d.qpos[drives_.qpos[j]];
          state[J + j] = d.qvel[drives_.dof[j]];
          episode->torques[t * J + j] = torque[j];
        }
        for (int i = 0; i < 3; ++i) episode->tcp[t * 3 + i] = d.site_xpos[3 * site + i];
      }
      if (k == last_control_step) break;  // the last recorded state ends the episode

      mj_step2(&m, &d);
      ++episode->physics_steps;
      if (HasInstabilityWarning(d)) {
        Reject(episode, "MuJoCo reported a bad state (simulation unstable)");
      } else {
        for (int j = 0; j < J && !episode->rejected; ++j) {
          const double qj = d.qpos[drives_.qpos[j]], vj = d.qvel[drives_.dof[j]];
          if (!std::isfinite(qj) || !std::isfinite(vj)) {
            Reject(episode, "joint " + std::to_string(j + 1) + " state is not finite");
          } else if (std::abs(vj) > config_.reject_velocity_factor * drives_.velocity_limit[j]) {
            Reject(episode, "joint " + std::to_string(j + 1) + " speed " + ShortNumber(std::abs(vj)) + " exceeds " +
                                ShortNumber(config_.reject_velocity_factor) + " x its limit " +
                                ShortNumber(drives_.velocity_limit[j]));
          }
        }
      }
      if (episode->rejected) {
        episode->warnings = WarningCount(d);
        return;
      }
    }
  }
  episode->warnings = WarningCount(d);
}

}  // namespace flowplan::sim
