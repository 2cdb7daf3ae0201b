// Guided planning latency of the Franka flow planner (the reach preset's
// network: UNet [32, 64, 128], T = 64, D = 14; weights do not change the time):
// one planning call of B plans with 10 Euler steps, with and without
// trajectory splitting, around 0 (unguided), 1 or 8 spheres, in-process and
// through the exported TorchScript file, with LibTorch's intra-op threads at
// 1 or 2.
//
//   plan_bench
//   plan_bench --benchmark_filter='B:1/'

#include <benchmark/benchmark.h>

#include <filesystem>

#include <unistd.h>

#include "models/model_config.h"
#include "planning/assemble.h"
#include "sim/franka_model.h"

namespace flowplan {
namespace {

std::unique_ptr<planning::LearnedPlanner> MakePlanner(bool split) {
  torch::manual_seed(0);
  models::ModelConfig model;
  model.unet.down_dims = {32, 64, 128};
  planning::PlannerParts parts;
  parts.net = models::MakeTrajectoryNet(model, 14, 0);
  parts.net->eval();
  parts.trajectory.env = "franka";
  parts.trajectory.dt = 1.0 / 15.0;
  parts.trajectory.horizon = 64;
  for (int j = 1; j <= 7; ++j) parts.trajectory.state_labels.push_back("q" + std::to_string(j));
  for (int j = 1; j <= 7; ++j) parts.trajectory.state_labels.push_back("dq" + std::to_string(j));
  parts.trajectory.robot = sim::LoadFrankaModel().description();
  const auto& d = parts.trajectory.robot;
  torch::Tensor lo = torch::full({14}, -2.0f), hi = torch::full({14}, 2.0f);
  for (int j = 0; j < 7; ++j) {
    lo[j] = static_cast<float>(d.joint_lower[j]);
    hi[j] = static_cast<float>(d.joint_upper[j]);
  }
  parts.normalizer = models::MinMaxNormalizer(lo, hi);
  parts.sampler.steps = 10;
  parts.sampler.splitting = split ? planning::Splitting::kMidpoint : planning::Splitting::kNone;
  return planning::AssemblePlanner(parts);
}

torch::Tensor Obstacles(int count) {
  torch::Tensor o = torch::empty({count, 4});
  for (int k = 0; k < count; ++k) {
    o[k][0] = 0.5f;
    o[k][1] = -0.3f + 0.6f * static_cast<float>(k) / static_cast<float>(std::max(1, count - 1));
    o[k][2] = 0.2f;
    o[k][3] = 0.1f;
  }
  return o;
}

struct Case {
  int64_t B;
  bool split;
  int spheres;
  bool exported;
  int threads;
};

Case Read(const benchmark::State& state) {
  return {state.range(0), state.range(1) != 0, static_cast<int>(state.range(2)), state.range(3) != 0,
          static_cast<int>(state.range(4))};
}

void BM_Plan(benchmark::State& state) {
  const Case c = Read(state);
  at::set_num_threads(c.threads);
  at::globalContext().setFlushDenormal(true);
  const auto planner = MakePlanner(c.split);
  torch::manual_seed(1);
  const torch::Tensor lo = planner->module().attr("normalizer").toModule().attr("lo").toTensor();
  const torch::Tensor hi = planner->module().attr("normalizer").toModule().attr("hi").toTensor();
  const torch::Tensor start = (lo + (hi - lo) * 0.4).expand({c.B, 14}).contiguous();
  const torch::Tensor goal = (lo + (hi - lo) * 0.6).expand({c.B, 14}).contiguous();
  const torch::Tensor noise = torch::randn({c.B, 64, 14}), renoise = torch::randn({c.B, 64, 14});
  const torch::Tensor obstacles = c.spheres > 0 ? Obstacles(c.spheres) : torch::Tensor();
  // Two calls before timing: a script's first call compiles its graphs, and under LibTorch's default executor
  // (what a caller of the exported file gets) the first two calls also profile them (docs/export.md).
  if (!c.exported) {
    for (int warm = 0; warm < 2; ++warm) {
      planner->PlanWithNoise(start, goal, noise, c.split ? renoise : torch::Tensor(), geometry::SphereRows(obstacles));
    }
    for (auto _ : state) {
      benchmark::DoNotOptimize(planner->PlanWithNoise(start, goal, noise, c.split ? renoise : torch::Tensor(),
                                                      geometry::SphereRows(obstacles)));
    }
  } else {
    const std::string path =
        (std::filesystem::temp_directory_path() / ("flowplan_plan_bench_" + std::to_string(::getpid()) + ".pt")).string();
    planner->Save(path);
    torch::jit::Module module = torch::jit::load(path);
    std::filesystem::remove(path);
    const torch::jit::IValue re = c.split ? torch::jit::IValue(renoise) : torch::jit::IValue();
    const torch::jit::IValue ob = c.spheres > 0 ? torch::jit::IValue(obstacles) : torch::jit::IValue();
    torch::NoGradGuard no_grad;
    for (int warm = 0; warm < 2; ++warm) module.run_method("plan", start, goal, noise, re, ob);
    for (auto _ : state) benchmark::DoNotOptimize(module.run_method("plan", start, goal, noise, re, ob));
  }
  state.counters["plans/s"] =
      benchmark::Counter(static_cast<double>(c.B * state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Plan)
    ->ArgNames({"B", "split", "spheres", "exported", "threads"})
    ->ArgsProduct({{1, 64}, {0, 1}, {0, 1, 8}, {0, 1}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);

}  // namespace
}  // namespace flowplan

BENCHMARK_MAIN();
