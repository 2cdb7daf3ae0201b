// The one validity check's speed on a problem file's scenes: configurations
// and motions of the built-in Franka (or a robot description given as YAML)
// drawn uniformly within the joint limits, per scene.
//
//   collision_bench PROBLEMS.yaml [--robot ROBOT.yaml] [--length 0.5] [--count 20000]
//
// Prints the time per configuration check, per motion check (segments of
// `length` × the joint-space diagonal's 20 %), and the configurations a motion
// check places on average.

#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>
#include <cstdio>
#include <iostream>
#include <memory>

#include "collision/checker.h"
#include "core/error.h"
#include "core/random.h"
#include "problems/problem.h"
#include "sim/franka_model.h"

namespace {

using namespace flowplan;

int Main(int argc, char** argv) {
  const char* usage =
      "usage: collision_bench PROBLEMS.yaml [--robot ROBOT.yaml] [--length 0.5] [--count 20000]\n"
      "The one validity check's speed on each problem's scene, for the built-in Franka or ROBOT.yaml:\n"
      "configurations drawn uniformly within the joint limits (COUNT in all, shared by the scenes) and motions\n"
      "from the valid ones, of LENGTH x 20 % of the joint-space diagonal, to a valid end within the limits.\n"
      "Prints the time per configuration check, per motion check, and the configurations a motion check places.\n";
  if (argc >= 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::cout << usage;
    return 0;
  }
  if (argc < 2) {
    std::cerr << usage;
    return 1;
  }
  std::string robot_path;
  double length = 0.5;
  int count = 20000;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--robot") robot_path = argv[i + 1];
    else if (flag == "--length") length = std::stod(argv[i + 1]);
    else if (flag == "--count") count = std::stoi(argv[i + 1]);
    else throw Error("unknown option " + flag);
  }
  const problems::ProblemSet set = problems::LoadProblemSet(argv[1]);
  kinematics::RobotDescription robot = sim::LoadFrankaModel().description();
  if (!robot_path.empty()) {
    std::ifstream in(robot_path);
    std::stringstream text;
    text << in.rdbuf();
    robot = kinematics::RobotFromYaml(text.str(), robot_path);
  }
  const int J = robot.num_joints;
  double diagonal = 0.0;
  for (int j = 0; j < J; ++j) diagonal += std::pow(robot.joint_upper[j] - robot.joint_lower[j], 2);
  const double step = length * 0.2 * std::sqrt(diagonal);
  using Clock = std::chrono::steady_clock;
  double config_seconds = 0.0, motion_seconds = 0.0;
  int64_t configs = 0, motions = 0, placed = 0, valid_configs = 0, valid_motions = 0;
  Rng rng(1);
  for (const problems::Problem& problem : set.problems) {
    const auto body = std::make_shared<const collision::BodyModel>(collision::WithHeld(robot, problem.World().held));
    collision::Floor floor;
    floor.present = std::isfinite(problem.floor_height);
    floor.height = floor.present ? problem.floor_height : 0.0;
    const collision::Checker checker(body, std::make_shared<const collision::World>(problem.scene, 3, floor), {});
    const int per_problem = count / static_cast<int>(set.problems.size()) + 1;
    std::vector<std::vector<double>> qs;
    for (int n = 0; n < per_problem; ++n) {
      std::vector<double> q(static_cast<size_t>(J));
      for (int j = 0; j < J; ++j) q[j] = rng.Uniform(robot.joint_lower[j], robot.joint_upper[j]);
      qs.push_back(q);
    }
    auto began = Clock::now();
    std::vector<int> ok(qs.size());
    for (size_t n = 0; n < qs.size(); ++n) ok[n] = checker.Valid(qs[n].data());
    config_seconds += std::chrono::duration<double>(Clock::now() - began).count();
    configs += static_cast<int64_t>(qs.size());
    for (int v : ok) valid_configs += v;
    // Motions from valid configurations, `step` long in a random direction.
    std::vector<std::pair<std::vector<double>, std::vector<double>>> segments;
    for (size_t n = 0; n < qs.size(); ++n) {
      if (!ok[n]) continue;
      std::vector<double> d(static_cast<size_t>(J)), b(static_cast<size_t>(J));
      double norm = 0.0;
      for (int j = 0; j < J; ++j) norm += (d[j] = rng.Normal()) * d[j];
      bool inside = true;
      for (int j = 0; j < J; ++j) {
        b[j] = qs[n][j] + step * d[j] / std::sqrt(norm);
        inside = inside && b[j] >= robot.joint_lower[j] && b[j] <= robot.joint_upper[j];
      }
      if (inside && checker.Valid(b.data())) segments.emplace_back(qs[n], b);
    }
    began = Clock::now();
    for (const auto& [a, b] : segments) {
      const collision::MotionVerdict verdict = checker.CheckMotion(a.data(), b.data());
      placed += verdict.checks;
      valid_motions += verdict.valid;
    }
    motion_seconds += std::chrono::duration<double>(Clock::now() - began).count();
    motions += static_cast<int64_t>(segments.size());
  }
  std::printf("spheres %d, links %zu, self pairs %zu\n", collision::BodyModel(robot).num_spheres(), robot.links.size(),
              collision::BodyModel(robot).self_pairs().size());
  std::printf("configurations: %lld, %.2f us each, %.1f %% valid\n", static_cast<long long>(configs),
              1e6 * config_seconds / configs, 100.0 * valid_configs / configs);
  std::printf("motions of %.3f rad: %lld, %.2f us each, %.1f configurations placed, %.1f %% valid\n", step,
              static_cast<long long>(motions), 1e6 * motion_seconds / std::max<int64_t>(motions, 1),
              static_cast<double>(placed) / std::max<int64_t>(motions, 1), 100.0 * valid_motions / std::max<int64_t>(motions, 1));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "collision_bench: " << e.what() << "\n";
    return 1;
  }
}
