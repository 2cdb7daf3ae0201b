#include "datasets/franka_task.h"

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
  FrankaWorker(std::shared_ptr<const sim::FrankaModel> model, const FrankaTaskConfig& config,
               FrankaGoals goals, std::vector<Family> families, std::vector<JointVector> family_start_q,
               std::vector<JointVector> family_goal_q)
      : model_(std::move(model)),
        config_(config),
        goals_(goals),
        families_(std::move(families)),
        family_start_q_(std::move(family_start_q)),
        family_goal_q_(std::move(family_goal_q)),
        simulator_(*model_, config.rollout),
        scratch_(sim::MakeData(model_->mj())) {
    ik_.posture = Eigen::Map<const JointVector>(config.rollout.controller.posture.data());
  }

  EpisodeRecord Run(int64_t index, uint64_t seed) override {
    Rng rng(seed);
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
  layout.point_dim = 3;
  layout.info.robot = model_->description();
  layout.extras["tcp"] = 3;
  layout.extras["torques"] = sim::kFrankaJoints;
  if (config_.rollout.augmentation.scheme == Augmentation::kRandomForce) layout.extras["external_force"] = 3;
  return layout;
}

std::vector<Family> FrankaTask::Families() const { return families_; }

std::unique_ptr<EpisodeWorker> FrankaTask::MakeWorker() const {
  return std::make_unique<FrankaWorker>(model_, config_, goals_, families_, family_start_q_, family_goal_q_);
}

}  // namespace flowplan::datasets
