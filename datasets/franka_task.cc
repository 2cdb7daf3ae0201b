#include "datasets/franka_task.h"

#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "core/random.h"
#include "sim/franka_ik.h"

namespace flowplan::datasets {
namespace {

using sim::Augmentation;
using sim::JointVector;

Eigen::Vector3d Point(const std::vector<double>& p) { return {p[0], p[1], p[2]}; }

class FrankaWorker : public EpisodeWorker {
 public:
  FrankaWorker(std::shared_ptr<const sim::FrankaModel> model,
               std::shared_ptr<const sim::FrankaCollisionModel> collision_model, const FrankaTaskConfig& config,
               FrankaGoals goals, std::vector<Family> families, std::vector<JointVector> family_start_q,
               std::vector<JointVector> family_goal_q)
      : model_(std::move(model)),
        collision_model_(std::move(collision_model)),
        config_(config),
        goals_(goals),
        families_(std::move(families)),
        family_start_q_(std::move(family_start_q)),
        family_goal_q_(std::move(family_goal_q)),
        simulator_(*model_, config.rollout),
        scratch_(sim::MakeData(model_->mj())) {
    ik_.posture = Eigen::Map<const JointVector>(config.rollout.controller.posture.data());
    if (collision_model_) collision_ = std::make_unique<sim::FrankaCollisionChecker>(*collision_model_);
  }

  EpisodeRecord Run(int64_t index, uint64_t seed) override {
    Rng rng(seed);
    if (goals_ == FrankaGoals::kJoint) return RunJoint(rng);
    const Augmentation scheme = config_.rollout.augmentation.scheme;
    EpisodeRecord record;
    Eigen::Vector3d start, goal;
    JointVector q0;
    bool reachable = true;
    if (goals_ == FrankaGoals::kCross) {
      const int family = static_cast<int>(index % static_cast<int64_t>(families_.size()));
      record.family = family;
      start = Point(families_[family].start);
      goal = Point(families_[family].goal);
      q0 = family_start_q_[family];
      if (scheme == Augmentation::kRandomPosition) {
        const double jitter = config_.rollout.augmentation.position_jitter;
        const Eigen::Vector3d nominal_start = start, nominal_goal = goal;
        reachable = DrawReachablePair(
            rng,
            [&](Eigen::Vector3d* s, Eigen::Vector3d* g) {
              for (int i = 0; i < 3; ++i) (*s)[i] = nominal_start[i] + jitter * rng.Normal();
              for (int i = 0; i < 3; ++i) (*g)[i] = nominal_goal[i] + jitter * rng.Normal();
            },
            family_start_q_[family], family_goal_q_[family], &start, &goal, &q0);
      }
    } else {
      reachable = DrawReachablePair(
          rng,
          [&](Eigen::Vector3d* s, Eigen::Vector3d* g) {
            for (int i = 0; i < 3; ++i) (*s)[i] = rng.Uniform(config_.reach_lower[i], config_.reach_upper[i]);
            for (int i = 0; i < 3; ++i) (*g)[i] = rng.Uniform(config_.reach_lower[i], config_.reach_upper[i]);
          },
          ik_.posture, ik_.posture, &start, &goal, &q0);
    }
    record.commanded_start.assign(start.data(), start.data() + 3);
    record.commanded_goal.assign(goal.data(), goal.data() + 3);
    if (!reachable) {
      // Keep the record's shape; the generator drops rejected episodes.
      simulator_.Clear(&episode_);
      Fill(&record);
      record.rejected = true;
      record.reject_reason = "no start/goal pair reachable with the gripper down in " +
                             std::to_string(config_.max_draws) + " draws";
      return record;
    }
    simulator_.Rollout(q0, goal, scheme, rng, &episode_);
    Fill(&record);
    return record;
  }

  /// franka_joint: draws (start, goal) and rolls out until the episode keeps
  /// clear of the arm itself and the floor, up to max_draws draws.
  EpisodeRecord RunJoint(Rng& rng) {
    const sim::FrankaLimits& limits = model_->limits();
    const double horizon_time = (config_.rollout.horizon - 1) * config_.rollout.record_dt();
    const double longest = horizon_time - config_.joint_motion.min_hold;
    auto draw = [&](JointVector* q) {
      for (int j = 0; j < sim::kFrankaJoints; ++j) {
        (*q)[j] = rng.Uniform(limits.q_lower[j] + config_.joint_margin, limits.q_upper[j] - config_.joint_margin);
      }
      return collision_->FirstCollision(*q).empty();
    };
    const sim::FrankaSimulator::StateCheck check = [&](const JointVector& q) {
      const std::string collision = collision_->FirstCollision(q);
      return collision.empty() ? collision : "collision " + collision;
    };
    std::string reason = "no draw";
    JointVector start = JointVector::Zero(), goal = JointVector::Zero();
    for (int attempt = 0; attempt < config_.max_draws; ++attempt) {
      if (!draw(&start) || !draw(&goal)) {
        reason = "start or goal in collision";
        continue;
      }
      const double duration = sim::MinimumJerkMotion::Duration(start, goal, limits.velocity, config_.joint_motion);
      if (duration > longest) {
        reason = "motion longer than the episode allows";
        continue;
      }
      const sim::MinimumJerkMotion motion(start, goal, duration);
      if (!ReferenceIsClear(motion)) {
        reason = "reference motion in collision";
        continue;
      }
      simulator_.RolloutJoints(motion, config_.joint_motion, check, config_.rollout.augmentation.scheme, rng,
                               &episode_);
      if (!episode_.rejected) return JointRecord(start, goal);
      if (episode_.reject_reason.rfind("collision", 0) != 0) return JointRecord(start, goal);  // unstable, too fast
      reason = episode_.reject_reason;
    }
    // Keep the record's shape; the generator drops rejected episodes.
    simulator_.Clear(&episode_);
    EpisodeRecord record = JointRecord(start, goal);
    record.rejected = true;
    record.reject_reason = "no collision-free episode in " + std::to_string(config_.max_draws) + " draws (last: " +
                           reason + ")";
    return record;
  }

  EpisodeRecord RunNominal(int family) override {
    Rng unused(0);
    EpisodeRecord record;
    record.family = family;
    record.commanded_start = families_[family].start;
    record.commanded_goal = families_[family].goal;
    simulator_.Rollout(family_start_q_[family], Point(families_[family].goal), Augmentation::kNone, unused,
                       &episode_);
    Fill(&record);
    return record;
  }

 private:
  // Draws (start, goal) with `draw` until the IK reaches both with the gripper
  // pointing down (seeded with start_seed and goal_seed); `q0` receives the
  // start configuration. False after max_draws failed draws.
  template <class Draw>
  bool DrawReachablePair(Rng& rng, Draw draw, const JointVector& start_seed, const JointVector& goal_seed,
                         Eigen::Vector3d* start, Eigen::Vector3d* goal, JointVector* q0) {
    for (int attempt = 0; attempt < config_.max_draws; ++attempt) {
      draw(start, goal);
      const sim::IkResult at_start = sim::SolveTcpIk(*model_, *scratch_, *start, start_seed, ik_);
      if (!at_start.converged) continue;
      if (!sim::SolveTcpIk(*model_, *scratch_, *goal, goal_seed, ik_).converged) continue;
      *q0 = at_start.q;
      return true;
    }
    *q0 = start_seed;
    return false;
  }

  // Whether the noise-free reference keeps clear at every control step.
  bool ReferenceIsClear(const sim::MinimumJerkMotion& motion) {
    const int steps = (config_.rollout.horizon - 1) * config_.rollout.record_every;
    JointVector q, velocity, acceleration;
    for (int k = 0; k <= steps; ++k) {
      const double t = static_cast<double>(k) / config_.rollout.control_hz;
      if (t > motion.duration()) break;
      motion.Sample(t, &q, &velocity, &acceleration);
      if (!collision_->FirstCollision(q).empty()) return false;
    }
    return true;
  }

  EpisodeRecord JointRecord(const JointVector& start, const JointVector& goal) {
    EpisodeRecord record;
    record.commanded_start.assign(start.data(), start.data() + sim::kFrankaJoints);
    record.commanded_goal.assign(goal.data(), goal.data() + sim::kFrankaJoints);
    Fill(&record);
    return record;
  }

  void Fill(EpisodeRecord* record) const {
    record->states = episode_.states;
    record->extras["tcp"] = episode_.tcp;
    record->extras["torques"] = episode_.torques;
    if (config_.rollout.augmentation.scheme == Augmentation::kRandomForce) {
      record->extras["external_force"] = episode_.external_force;
    }
    record->simulator_warnings = episode_.warnings;
    record->rejected = episode_.rejected;
    record->reject_reason = episode_.reject_reason;
  }

  std::shared_ptr<const sim::FrankaModel> model_;
  std::shared_ptr<const sim::FrankaCollisionModel> collision_model_;
  std::unique_ptr<sim::FrankaCollisionChecker> collision_;  // franka_joint only
  const FrankaTaskConfig config_;
  const FrankaGoals goals_;
  const std::vector<Family> families_;
  const std::vector<JointVector> family_start_q_;
  const std::vector<JointVector> family_goal_q_;
  sim::FrankaSimulator simulator_;
  sim::MjDataPtr scratch_;  // for IK
  sim::IkOptions ik_;
  sim::FrankaEpisode episode_;
};

std::string Number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.4g", v);
  return buffer;
}

}  // namespace

FrankaTask::FrankaTask(FrankaGoals goals, const FrankaTaskConfig& config, const std::string& where)
    : goals_(goals), config_(config) {
  auto model = std::make_shared<sim::FrankaModel>(sim::LoadFrankaModel());
  model->SetPhysics(config.rollout.physics_timestep(), config.rollout.integrator);
  config.rollout.Validate(where, model->limits());
  for (int i = 0; i < 3; ++i) {
    if (config.reach_lower[i] > config.reach_upper[i]) {
      throw Error(where + ".reach_lower[" + std::to_string(i) + "]: expected at most reach_upper[" +
                  std::to_string(i) + "] = " + Number(config.reach_upper[i]) + ", got " +
                  Number(config.reach_lower[i]));
    }
  }
  model_ = std::move(model);
  if (goals_ == FrankaGoals::kJoint) {
    for (int j = 0; j < sim::kFrankaJoints; ++j) {
      const sim::FrankaLimits& limits = model_->limits();
      if (2.0 * config.joint_margin >= limits.q_upper[j] - limits.q_lower[j]) {
        throw Error(where + ".joint_margin: expected less than half of joint " + std::to_string(j + 1) +
                    "'s range " + Number(limits.q_upper[j] - limits.q_lower[j]) + " rad, got " +
                    Number(config.joint_margin));
      }
    }
    const double horizon_time = (config.rollout.horizon - 1) * config.rollout.record_dt();
    if (config.joint_motion.min_duration + config.joint_motion.min_hold > horizon_time) {
      throw Error(where + ".joint_motion.min_duration: expected at most the episode's " + Number(horizon_time) +
                  " s less joint_motion.min_hold, got " + Number(config.joint_motion.min_duration));
    }
    collision_model_ = std::make_shared<const sim::FrankaCollisionModel>(config.floor_height);
  }

  if (goals_ == FrankaGoals::kCross) {
    if (config.cross_starts.empty() || config.cross_starts.size() != config.cross_goals.size()) {
      throw Error(where + ".cross_goals: expected one goal per start (" + std::to_string(config.cross_starts.size()) +
                  " starts), got " + std::to_string(config.cross_goals.size()));
    }
    auto text = [](const std::array<double, 3>& p) {
      return "(" + Number(p[0]) + "," + Number(p[1]) + "," + Number(p[2]) + ")";
    };
    for (size_t i = 0; i < config.cross_starts.size(); ++i) {
      const auto& a = config.cross_starts[i];
      const auto& b = config.cross_goals[i];
      families_.push_back({text(a) + "->" + text(b), {a.begin(), a.end()}, {b.begin(), b.end()}});
    }
  }
  sim::IkOptions ik;
  ik.posture = Eigen::Map<const JointVector>(config.rollout.controller.posture.data());
  sim::MjDataPtr scratch = sim::MakeData(model_->mj());
  auto solve = [&](const std::vector<double>& target, const std::string& key) {
    try {
      return sim::SolveTcpIkOrThrow(*model_, *scratch, Point(target), ik.posture, ik);
    } catch (const Error& e) {
      throw Error(where + "." + key + ": " + e.what());
    }
  };
  for (size_t i = 0; i < families_.size(); ++i) {
    family_start_q_.push_back(solve(families_[i].start, "cross_starts[" + std::to_string(i) + "]"));
    family_goal_q_.push_back(solve(families_[i].goal, "cross_goals[" + std::to_string(i) + "]"));
  }
}

EpisodeLayout FrankaTask::Layout() const {
  EpisodeLayout layout;
  layout.info.env = "franka";
  layout.info.dt = config_.rollout.record_dt();
  layout.info.horizon = config_.rollout.horizon;
  for (int j = 1; j <= sim::kFrankaJoints; ++j) layout.info.state_labels.push_back("q" + std::to_string(j));
  for (int j = 1; j <= sim::kFrankaJoints; ++j) layout.info.state_labels.push_back("dq" + std::to_string(j));
  layout.point_dim = goals_ == FrankaGoals::kJoint ? sim::kFrankaJoints : 3;
  layout.info.robot = model_->description();
  layout.extras["tcp"] = 3;
  layout.extras["torques"] = sim::kFrankaJoints;
  if (config_.rollout.augmentation.scheme == Augmentation::kRandomForce) layout.extras["external_force"] = 3;
  return layout;
}

std::vector<Family> FrankaTask::Families() const { return families_; }

std::unique_ptr<EpisodeWorker> FrankaTask::MakeWorker() const {
  return std::make_unique<FrankaWorker>(model_, collision_model_, config_, goals_, families_, family_start_q_,
                                        family_goal_q_);
}

}  // namespace flowplan::datasets
