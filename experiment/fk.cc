// `flowplan fk`: the Franka's TCP and flange of joint angles, through MuJoCo
// and through the kinematics planners use, side by side.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <memory>

#include "core/error.h"
#include "experiment/commands.h"
#include "kinematics/robot.h"
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

}  // namespace

Command AddFkCommand(CLI::App& app) {
  auto q = std::make_shared<std::string>();
  CLI::App* command = app.add_subcommand("fk", "print the Franka TCP position of joint angles (MuJoCo and LibTorch)");
  command->add_option("--q", *q, "7 joint angles in rad, comma-separated: --q=0,-0.785,0,-2.356,0,1.571,0.785")
      ->required();
  return {command, [q] { RunFrankaFk(*q); }};
}

}  // namespace flowplan::experiment
