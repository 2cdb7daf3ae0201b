// Franka rollout throughput: physics steps/s and episodes/s of franka_cross
// for 1 and 2 threads, and whole 10,000-episode generations with their
// quality figures for every augmentation scheme.
//
//   sim_bench                                          # everything (a few minutes)
//   sim_bench --benchmark_filter=Rollouts              # the rollout loop only
//   sim_bench --benchmark_filter='Franka/goals:0/scheme:0/controller:0'  # franka_cross, 1 and 2 threads

#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <atomic>
#include <cmath>
#include <limits>

#include "core/parallel.h"
#include "core/random.h"
#include "datasets/franka_task.h"
#include "datasets/generator.h"
#include "sim/franka_ik.h"
#include "sim/mujoco_util.h"

namespace flowplan {
namespace {

using datasets::FrankaGoals;
using datasets::FrankaTask;
using datasets::FrankaTaskConfig;

// Rolls out `episodes` franka_cross episodes per iteration on `threads` workers.
void BM_FrankaCrossRollouts(benchmark::State& state) {
  const int episodes = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  const FrankaTask task(FrankaGoals::kCross, FrankaTaskConfig{});
  std::vector<std::unique_ptr<datasets::EpisodeWorker>> workers;
  for (int w = 0; w < threads; ++w) workers.push_back(task.MakeWorker());
  const FrankaTaskConfig config;
  const int64_t steps_per_episode =
      int64_t{config.rollout.horizon - 1} * config.rollout.record_every * config.rollout.physics_substeps;
  int64_t total = 0;
  for (auto _ : state) {
    std::atomic<int> rejected{0};
    ParallelFor(episodes, threads, [&](int worker, int i) {
      const datasets::EpisodeRecord record = workers[worker]->Run(total + i, StreamSeed(1, total + i));
      rejected += record.rejected;
    });
    total += episodes;
    benchmark::DoNotOptimize(rejected.load());
  }
  state.counters["episodes/s"] = benchmark::Counter(static_cast<double>(total), benchmark::Counter::kIsRate);
  state.counters["physics_steps/s"] =
      benchmark::Counter(static_cast<double>(total * steps_per_episode), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_FrankaCrossRollouts)
    ->ArgNames({"episodes", "threads"})
    ->Args({500, 1})
    ->Args({500, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The whole generation as `flowplan generate` runs it, with quality figures:
// the share of kept episodes whose last TCP position is within 2 cm of the
// commanded goal, the mean time of the first state within 2 cm, rejections, MuJoCo warnings, the largest |torque| and |q̇|
// relative to their limits, and the spread of the TCP half-way (RMS distance
// of state T/2 from its family's mean, franka_cross only).
// Args: goals (0 cross, 1 reach), augmentation scheme (enum order of
// sim::Augmentation), controller (0 default, 1 reference gains: Kp 2.5, no
// speed cap), threads.
void BM_GenerateFranka(benchmark::State& state) {
  const FrankaGoals goals = state.range(0) == 0 ? FrankaGoals::kCross : FrankaGoals::kReach;
  FrankaTaskConfig config;
  config.rollout.augmentation.scheme = static_cast<sim::Augmentation>(state.range(1));
  if (state.range(2) == 1) {
    config.rollout.controller.stiffness = 2.5;
    config.rollout.controller.max_speed = std::numeric_limits<double>::infinity();
  }
  const FrankaTask task(goals, config);
  datasets::GenerateOptions options;
  options.episodes = 10000;
  options.threads = static_cast<int>(state.range(3));
  options.seed = 0;
  options.show_progress = false;
  datasets::TrajectoryDataset dataset;
  for (auto _ : state) dataset = datasets::GenerateDataset(task, options);

  const sim::FrankaLimits& limits = task.model().limits();
  const auto& tcp = dataset.extras.at("tcp").values;
  const auto& torques = dataset.extras.at("torques").values;
  const int64_t T = dataset.info.horizon, D = dataset.info.state_dim();
  int64_t within = 0, arrived = 0;
  double arrival_time = 0.0;
  double torque_ratio = 0.0, speed_ratio = 0.0;
  Eigen::Vector3d mid_sum[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  int64_t mid_count[2] = {0, 0};
  for (int64_t i = 0; i < dataset.num_episodes; ++i) {
    const size_t last = static_cast<size_t>((i * T + T - 1) * 3);
    const Eigen::Vector3d end(tcp[last], tcp[last + 1], tcp[last + 2]);
    const Eigen::Vector3d goal(dataset.commanded_goal[3 * i], dataset.commanded_goal[3 * i + 1],
                               dataset.commanded_goal[3 * i + 2]);
    within += (end - goal).norm() < 0.02;
    for (int64_t t = 0; t < T; ++t) {
      const size_t at = static_cast<size_t>((i * T + t) * 3);
      if ((Eigen::Vector3d(tcp[at], tcp[at + 1], tcp[at + 2]) - goal).norm() < 0.02) {
        arrival_time += static_cast<double>(t) * dataset.info.dt;
        ++arrived;
        break;
      }
    }
    for (int64_t t = 0; t < T; ++t) {
      for (int j = 0; j < 7; ++j) {
        torque_ratio = std::max(torque_ratio, std::abs(torques[(i * T + t) * 7 + j]) / limits.torque[j]);
        speed_ratio = std::max(speed_ratio, std::abs(dataset.states[(i * T + t) * D + 7 + j]) / limits.velocity[j]);
      }
    }
    const int family = dataset.family[i];
    if (family >= 0) {
      const size_t mid = static_cast<size_t>((i * T + T / 2) * 3);
      mid_sum[family] += Eigen::Vector3d(tcp[mid], tcp[mid + 1], tcp[mid + 2]);
      ++mid_count[family];
    }
  }
  double spread = 0.0;
  int64_t spread_count = 0;
  for (int64_t i = 0; i < dataset.num_episodes; ++i) {
    const int family = dataset.family[i];
    if (family < 0) continue;
    const size_t mid = static_cast<size_t>((i * T + T / 2) * 3);
    spread += (Eigen::Vector3d(tcp[mid], tcp[mid + 1], tcp[mid + 2]) - mid_sum[family] / mid_count[family]).squaredNorm();
    ++spread_count;
  }
  state.counters["episodes/s"] = benchmark::Counter(static_cast<double>(options.episodes * state.iterations()),
                                                    benchmark::Counter::kIsRate);
  state.counters["within_2cm_%"] = 100.0 * static_cast<double>(within) / static_cast<double>(dataset.num_episodes);
  state.counters["rejected"] = static_cast<double>(dataset.rejected_episodes);
  state.counters["warnings"] = static_cast<double>(dataset.simulator_warnings);
  state.counters["max_torque/limit"] = torque_ratio;
  state.counters["max_speed/limit"] = speed_ratio;
  if (arrived > 0) state.counters["first_within_2cm_s"] = arrival_time / static_cast<double>(arrived);
  if (spread_count > 0) state.counters["mid_spread_mm"] = 1000.0 * std::sqrt(spread / spread_count);
}
BENCHMARK(BM_GenerateFranka)
    ->ArgNames({"goals", "scheme", "controller", "threads"})
    ->Args({0, 0, 0, 1})  // franka_cross, per-joint noise: 1 thread
    ->Args({0, 0, 0, 2})  // ... and 2 threads
    ->Args({0, 1, 0, 2})  // same noise
    ->Args({0, 2, 0, 2})  // no noise
    ->Args({0, 3, 0, 2})  // random start/goal
    ->Args({0, 4, 0, 2})  // random forces
    ->Args({0, 0, 1, 2})  // per-joint noise under the reference gains
    ->Args({1, 0, 0, 2})  // franka_reach
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

// IK with the gripper pointing down for points drawn uniformly in the SPEC box
// x in [0.35, 0.75], y in [-0.5, 0.5], z in [0.15, 0.75]: solves/s and the
// share of the box that is reachable.
void BM_TcpIkSpecBox(benchmark::State& state) {
  const sim::FrankaModel model = sim::LoadFrankaModel();
  sim::MjDataPtr d = sim::MakeData(model.mj());
  int64_t solves = 0, reached = 0;
  for (auto _ : state) {
    Rng rng(5);
    for (int i = 0; i < 2000; ++i) {
      const Eigen::Vector3d target(rng.Uniform(0.35, 0.75), rng.Uniform(-0.5, 0.5), rng.Uniform(0.15, 0.75));
      reached += sim::SolveTcpIk(model, *d, target, sim::FrankaReadyPose()).converged;
      ++solves;
    }
  }
  state.counters["solves/s"] = benchmark::Counter(static_cast<double>(solves), benchmark::Counter::kIsRate);
  state.counters["reachable_%"] = 100.0 * static_cast<double>(reached) / static_cast<double>(solves);
}
BENCHMARK(BM_TcpIkSpecBox)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace flowplan

int main(int argc, char** argv) {
  flowplan::sim::InstallMujocoHandlers();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
