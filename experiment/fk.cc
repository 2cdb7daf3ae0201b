// `flowplan fk`: the Franka's TCP and flange of joint angles, through MuJoCo
// and through the kinematics planners use, side by side.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <memory>

#include "core/error.h"
#include "experiment/commands.h"
#include "collision/body_model.h"
#include "kinematics/robot.h"
#include "robotfiles/robot_folder.h"
#include "sim/franka_model.h"

namespace flowplan::experiment {
namespace {

void RunFrankaFk(const std::string& text) {
  const std::vector<double> q = ParseNumbers(text, "--q");
  if (q.size() != sim::kFrankaJoints) {
    throw Error("--q: expected 7 joint angles, got " + std::to_string(q.size()) + " in \"" + text + "\"");
  }
  const sim::FrankaModel model = sim::LoadFrankaModel();
  const sim::FrankaLimits& limits = model.limits();
  for (size_t j = 0; j < q.size(); ++j) {
    if (q[j] < limits.q_lower[j] || q[j] > limits.q_upper[j]) {
      spdlog::warn("q{} = {} is outside the joint's limits [{}, {}]", j + 1, q[j], limits.q_lower[j], limits.q_upper[j]);
    }
  }
  const sim::FrankaPose pose = sim::FrankaForwardKinematics(model, q);
  const kinematics::Robot robot(model.description(), "the Franka");
  const torch::Tensor tcp = robot.Tcp(torch::tensor(q, torch::kFloat64).view({1, -1}))[0];
  const Eigen::Vector3d torch_tcp(tcp[0].item<double>(), tcp[1].item<double>(), tcp[2].item<double>());
  auto point = [](const Eigen::Vector3d& p) { return fmt::format("({:.9f}, {:.9f}, {:.9f})", p.x(), p.y(), p.z()); };
  fmt::print("TCP (MuJoCo):     {} m\n", point(pose.tcp_position));
  fmt::print("TCP (LibTorch):   {} m\n", point(torch_tcp));
  fmt::print("flange (MuJoCo):  {} m\n", point(pose.flange_position));
  fmt::print("|TCP difference|: {:.3g} m\n", (pose.tcp_position - torch_tcp).norm());
}

/// A robot folder's TCP through its two kinematics: the planners' (LibTorch) and the collision check's (plain C++).
void RunRobotFk(const std::string& text, const std::string& folder) {
  const kinematics::RobotDescription d = robotfiles::LoadRobot(folder);
  const std::vector<double> q = ParseNumbers(text, "--q");
  if (q.size() != static_cast<size_t>(d.num_joints)) {
    throw Error("--q: expected " + std::to_string(d.num_joints) + " joint values of robot \"" + d.name + "\", got " +
                std::to_string(q.size()) + " in \"" + text + "\"");
  }
  for (int j = 0; j < d.num_joints; ++j) {
    if (q[j] < d.joint_lower[j] || q[j] > d.joint_upper[j]) {
      spdlog::warn("{} = {} is outside the joint's limits [{}, {}]", d.JointName(j), q[j], d.joint_lower[j], d.joint_upper[j]);
    }
  }
  const kinematics::Robot robot(d, folder);
  const torch::Tensor tcp = robot.Tcp(torch::tensor(q, torch::kFloat64).view({1, -1}))[0];
  const Eigen::Vector3d torch_tcp(tcp[0].item<double>(), tcp[1].item<double>(), tcp[2].item<double>());
  const collision::BodyModel body(d, folder);
  Eigen::Vector3d native_tcp;
  body.Tcp(q.data(), native_tcp.data());
  auto point = [](const Eigen::Vector3d& p) { return fmt::format("({:.9f}, {:.9f}, {:.9f})", p.x(), p.y(), p.z()); };
  fmt::print("TCP (LibTorch):           {} m\n", point(torch_tcp));
  fmt::print("TCP (collision check):    {} m\n", point(native_tcp));
  fmt::print("|TCP difference|: {:.3g} m\n", (native_tcp - torch_tcp).norm());
}

}  // namespace

Command AddFkCommand(CLI::App& app) {
  auto q = std::make_shared<std::string>();
  auto robot = std::make_shared<std::string>();
  CLI::App* command = app.add_subcommand(
      "fk", "print the TCP position of joint values: the Franka's through MuJoCo and LibTorch, a robot folder's "
            "through LibTorch and the collision check's kinematics");
  command->add_option("--q", *q, "joint values, comma-separated (the Franka: 7 angles in rad, e.g. "
                                 "--q=0,-0.785,0,-2.356,0,1.571,0.785)")
      ->required();
  command->add_option("--robot", *robot, "a robot folder (`flowplan robot import`) instead of the Franka")
      ->check(CLI::ExistingPath);
  return {command, [q, robot] { robot->empty() ? RunFrankaFk(*q) : RunRobotFk(*q, *robot); }};
}

}  // namespace flowplan::experiment
