// Training and planning throughput of the flow planner on the CPU:
// optimizer-free gradient steps (the cost of a training step) and plans per
// second, for 1 and 2 worker threads and UNets of 2, 3 and 4 levels, on
// particle-sized trajectories (T = 64, D = 4) and Franka-sized ones (D = 14).
//
//   train_bench
//   train_bench --benchmark_filter=Gradient

#include <benchmark/benchmark.h>

#include "eval/stitching.h"
#include "models/model_config.h"
#include "planning/assemble.h"
#include "sim/franka_model.h"
#include "objectives/flow_matching.h"
#include "trainer/sharded_gradient.h"

namespace flowplan {
namespace {

models::ModelConfig Unet(int levels) {
  models::ModelConfig config;
  config.unet.down_dims.assign({32, 64, 128, 256});
  config.unet.down_dims.resize(static_cast<size_t>(levels));
  return config;
}

// One gradient of a batch of 128 trajectories, sharded 4 ways over `threads` workers.
void BM_Gradient(benchmark::State& state) {
  const int levels = static_cast<int>(state.range(0)), threads = static_cast<int>(state.range(1));
  const int64_t D = state.range(2);
  at::set_num_threads(1);
  const models::ModelConfig config = Unet(levels);
  auto net = models::MakeTrajectoryNet(config, D, 0);
  trainer::ShardedGradient gradient(*net, [&] { return models::MakeTrajectoryNet(config, D, 0); }, 4, threads);
  auto generator = at::make_generator<at::CPUGeneratorImpl>(0);
  const objectives::FlowMatchingObjective objective;
  const auto batch = objective.Draw(torch::randn({128, 64, D}), generator);
  const trainer::BatchLoss loss = [&](models::Network& n, const objectives::ObjectiveBatch& b) {
    return objective.Loss(n, b, models::Conditioning::kInpaint);
  };
  for (auto _ : state) benchmark::DoNotOptimize(gradient.Compute(batch, loss));
  state.counters["steps/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Gradient)
    ->ArgNames({"levels", "threads", "D"})
    ->ArgsProduct({{2, 3, 4}, {1, 2}, {4, 14}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// 64 plans of 10 Euler steps, in chunks of 16 over `threads` workers.
void BM_Plan(benchmark::State& state) {
  const int levels = static_cast<int>(state.range(0)), threads = static_cast<int>(state.range(1));
  const int64_t D = state.range(2);
  at::set_num_threads(1);
  auto net = models::MakeTrajectoryNet(Unet(levels), D, 0);
  planning::PlannerParts parts;
  parts.net = net;
  parts.normalizer = models::MinMaxNormalizer(-torch::ones({D}), torch::ones({D}));
  parts.trajectory.env = "bench";
  parts.trajectory.dt = 0.05;
  parts.trajectory.horizon = 64;
  for (int64_t i = 0; i < D; ++i) parts.trajectory.state_labels.push_back((i < D / 2 ? "q" : "dq") + std::to_string(i % (D / 2)));
  parts.trajectory.robot = D == 14 ? sim::LoadFrankaModel().description()
                                   : kinematics::PointRobot("disc", 2, 0.05, -1.0, 1.0);
  const auto planner = planning::AssemblePlanner(parts);
  planning::PlanRequest request;
  request.start = torch::zeros({64, D});
  request.goal = torch::full({64, D}, 0.5);
  for (auto _ : state) benchmark::DoNotOptimize(planning::PlanInChunks(*planner, request, threads));
  state.counters["plans/s"] = benchmark::Counter(64.0 * static_cast<double>(state.iterations()),
                                                 benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Plan)
    ->ArgNames({"levels", "threads", "D"})
    ->ArgsProduct({{2, 4}, {1, 2}, {4, 14}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace flowplan

BENCHMARK_MAIN();
