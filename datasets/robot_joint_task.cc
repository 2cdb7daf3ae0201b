#include "datasets/robot_joint_task.h"


#include "collision/checker.h"
#include "core/error.h"
#include "core/format.h"
#include "core/random.h"

namespace flowplan::datasets {
namespace {


class RobotJointWorker : public EpisodeWorker {
 public:
  RobotJointWorker(std::shared_ptr<const robotfiles::SimulationModel> model,
                   std::shared_ptr<const collision::Checker> checker, const kinematics::RobotDescription& robot,
                   const std::vector<double>& effort_limit, const RobotJointTaskConfig& config)
      : model_(std::move(model)),
        checker_(std::move(checker)),
        config_(config),
        J_(robot.num_joints),
        lower_(Eigen::Map<const Eigen::VectorXd>(robot.joint_lower.data(), J_)),
        upper_(Eigen::Map<const Eigen::VectorXd>(robot.joint_upper.data(), J_)),
        velocity_(Eigen::Map<const Eigen::VectorXd>(robot.velocity_limit.data(), J_)),
        margin_(Margins(robot, config)),
        simulator_(*model_->model, Drives(*model_, robot, effort_limit), config.rollout, config.joint_motion) {}

  EpisodeRecord Run(int64_t, uint64_t seed) override {
    Rng rng(seed);
    const double horizon_time = (config_.rollout.horizon - 1) * config_.rollout.record_dt();
    const double longest = horizon_time - config_.joint_motion.min_hold;
    // Single configurations drawn at most (a robot whose free configurations are rare, like an arm on a floor it can
    // reach through, finds its pairs one at a time).
    int64_t budget = 100 * static_cast<int64_t>(config_.max_draws);
    auto draw = [&](Eigen::VectorXd* q) {
      --budget;
      for (int j = 0; j < J_; ++j) {
        (*q)[j] = rng.Uniform(lower_[j] + margin_[j], upper_[j] - margin_[j]);
      }
      return checker_->Valid(q->data());
    };
    const sim::JointSimulator::StateCheck check = [&](const Eigen::VectorXd& q) {
      const collision::Contact contact = checker_->FirstContact(q.data());
      return contact.found() ? "collision: " + checker_->Describe(contact) : std::string();
    };
    std::string reason = "no draw";
    Eigen::VectorXd start = Eigen::VectorXd::Zero(J_), goal = Eigen::VectorXd::Zero(J_);
    for (int attempt = 0; attempt < config_.max_draws && budget > 0; ++attempt) {
      // A start free of collision, then a goal free of collision that the episode has time to reach.
      bool found = false;
      while (budget > 0 && !(found = draw(&start))) {
      }
      if (!found) {
        reason = "no configuration free of collision";
        break;
      }
      found = false;
      double duration = 0.0;
      while (budget > 0 && !found) {
        if (!draw(&goal)) continue;
        duration = sim::JointMotion::Duration(start, goal, velocity_, config_.joint_motion);
        found = duration <= longest;
      }
      if (!found) {
        reason = "no goal free of collision that the episode has time to reach";
        break;
      }
      const sim::JointMotion motion(start, goal, duration);
      if (!ReferenceIsClear(motion)) {
        reason = "reference motion in collision";
        continue;
      }
      simulator_.Rollout(motion, check, config_.rollout.torque_noise_share > 0.0, rng, &episode_);
      if (!episode_.rejected) return Record(start, goal);
      if (episode_.reject_reason.rfind("collision", 0) != 0) return Record(start, goal);  // unstable, too fast
      reason = episode_.reject_reason;
    }
    // Keep the record's shape; the generator drops rejected episodes.
    simulator_.Clear(&episode_);
    EpisodeRecord record = Record(start, goal);
    record.rejected = true;
    record.reject_reason = "no collision-free episode in " + std::to_string(config_.max_draws) + " attempts and " +
                           std::to_string(100 * static_cast<int64_t>(config_.max_draws) - budget) +
                           " configurations drawn (last: " + reason + ")";
    return record;
  }

  EpisodeRecord RunNominal(int) override {
    FLOWPLAN_DEMAND(false);  // the task has no families
    return {};
  }

 private:
  static sim::JointDrives Drives(const robotfiles::SimulationModel& model, const kinematics::RobotDescription& robot,
                                 const std::vector<double>& effort_limit) {
    sim::JointDrives drives;
    drives.qpos = model.qpos;
    drives.dof = model.dof;
    drives.velocity_limit = Eigen::Map<const Eigen::VectorXd>(robot.velocity_limit.data(), robot.num_joints);
    drives.effort_limit = Eigen::Map<const Eigen::VectorXd>(effort_limit.data(), robot.num_joints);
    drives.tcp_site = model.tcp_site;
    return drives;
  }

  // How far inside its limits each joint's starts and goals keep.
  static Eigen::VectorXd Margins(const kinematics::RobotDescription& robot, const RobotJointTaskConfig& config) {
    Eigen::VectorXd margin(robot.num_joints);
    for (const kinematics::RobotLink& link : robot.links) {
      if (link.joint < 0) continue;
      margin[link.joint] = link.type == kinematics::JointType::kPrismatic ? config.slide_margin : config.joint_margin;
    }
    return margin;
  }

  // Whether the noise-free reference keeps clear at every control step.
  bool ReferenceIsClear(const sim::JointMotion& motion) const {
    const int steps = (config_.rollout.horizon - 1) * config_.rollout.record_every;
    Eigen::VectorXd q, velocity, acceleration;
    for (int k = 0; k <= steps; ++k) {
      const double t = static_cast<double>(k) / config_.rollout.control_hz;
      if (t > motion.duration()) break;
      motion.Sample(t, &q, &velocity, &acceleration);
      if (!checker_->Valid(q.data())) return false;
    }
    return true;
  }

  EpisodeRecord Record(const Eigen::VectorXd& start, const Eigen::VectorXd& goal) const {
    EpisodeRecord record;
    record.commanded_start.assign(start.data(), start.data() + J_);
    record.commanded_goal.assign(goal.data(), goal.data() + J_);
    record.states = episode_.states;
    record.extras["tcp"] = episode_.tcp;
    record.extras["torques"] = episode_.torques;
    record.simulator_warnings = episode_.warnings;
    record.rejected = episode_.rejected;
    record.reject_reason = episode_.reject_reason;
    return record;
  }

  std::shared_ptr<const robotfiles::SimulationModel> model_;
  std::shared_ptr<const collision::Checker> checker_;
  const RobotJointTaskConfig config_;
  const int J_;
  const Eigen::VectorXd lower_, upper_, velocity_, margin_;
  sim::JointSimulator simulator_;
  sim::JointEpisode episode_;
};

}  // namespace

RobotJointTask::RobotJointTask(const std::string& folder, const RobotJointTaskConfig& config, const std::string& where)
    : config_(config), file_(robotfiles::LoadRobotFile(folder)) {
  const std::string source = folder + "/robot.yaml";
  robot_ = file_.Description(source);
  if (robot_.velocity_limit.size() != static_cast<size_t>(robot_.num_joints)) {
    throw Error(source + ": robot.velocity_limit: data is timed by each joint's speed limit; expected " +
                std::to_string(robot_.num_joints) + " values");
  }
  for (const kinematics::RobotLink& link : robot_.links) {
    if (link.joint < 0) continue;
    const int j = link.joint;
    const double range = robot_.joint_upper[j] - robot_.joint_lower[j];
    if (!std::isfinite(range)) {
      throw Error(source + ": joint \"" + robot_.JointName(j) + "\" has no finite limits; random configurations need them");
    }
    const bool slide = link.type == kinematics::JointType::kPrismatic;
    const double margin = slide ? config.slide_margin : config.joint_margin;
    if (2.0 * margin >= range) {
      throw Error(where + (slide ? ".slide_margin" : ".joint_margin") + ": expected less than half of joint \"" +
                  robot_.JointName(j) + "\"'s range " + ShortNumber(range) + ", got " + ShortNumber(margin));
    }
  }
  const double horizon_time = (config.rollout.horizon - 1) * config.rollout.record_dt();
  if (config.joint_motion.min_duration + config.joint_motion.min_hold > horizon_time) {
    throw Error(where + ".joint_motion.min_duration: expected at most the episode's " + ShortNumber(horizon_time) +
                " s less joint_motion.min_hold, got " + ShortNumber(config.joint_motion.min_duration));
  }
  auto model = std::make_shared<robotfiles::SimulationModel>(robotfiles::LoadSimulationModel(file_, config.drives, source));
  model->model->opt.timestep = config.rollout.physics_timestep();
  model->model->opt.integrator = config.rollout.integrator == sim::Integrator::kEuler ? mjINT_EULER : mjINT_IMPLICIT;
  model->model->opt.disableflags |= mjDSBL_CONTACT;
  model_ = std::move(model);
  collision::Floor floor;
  floor.present = std::isfinite(config.floor_height);
  floor.height = floor.present ? config.floor_height : 0.0;
  checker_ = std::make_shared<const collision::Checker>(
      std::make_shared<const collision::BodyModel>(robot_, source),
      std::make_shared<const collision::World>(geometry::Scene{}, 3, floor), collision::CheckSettings{});
}

RobotJointTask::~RobotJointTask() = default;

EpisodeLayout RobotJointLayout(const kinematics::RobotDescription& robot, const RobotJointTaskConfig& config) {
  EpisodeLayout layout;
  layout.info.env = "robot_joint";
  layout.info.dt = config.rollout.record_dt();
  layout.info.horizon = config.rollout.horizon;
  const int J = robot.num_joints;
  for (int j = 1; j <= J; ++j) layout.info.state_labels.push_back("q" + std::to_string(j));
  for (int j = 1; j <= J; ++j) layout.info.state_labels.push_back("dq" + std::to_string(j));
  layout.point_dim = J;
  layout.info.robot = robot;
  layout.extras["tcp"] = 3;
  layout.extras["torques"] = J;
  return layout;
}

EpisodeLayout RobotJointTask::Layout() const { return RobotJointLayout(robot_, config_); }

std::unique_ptr<EpisodeWorker> RobotJointTask::MakeWorker() const {
  return std::make_unique<RobotJointWorker>(model_, checker_, robot_, file_.effort_limit, config_);
}

}  // namespace flowplan::datasets
