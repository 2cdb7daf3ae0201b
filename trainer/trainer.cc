#include "trainer/trainer.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>

#include "checkpoints/checkpoint.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/progress.h"
#include "core/random.h"
#include "models/normalizer.h"
#include "trainer/flow_matching.h"
#include "trainer/run_dir.h"
#include "trainer/sharded_gradient.h"

namespace flowplan::trainer {
namespace {

// Stream indices of the run's generators (see StreamSeed).
constexpr uint64_t kTrainStream = 1;
constexpr uint64_t kInitStream = 2;
constexpr uint64_t kValidationStream = 3;

/// Seeds LibTorch's global generator for the duration of a scope (module
/// constructors draw their initial weights from it) and restores it after.
class ScopedGlobalSeed {
 public:
  explicit ScopedGlobalSeed(uint64_t seed) {
    auto generator = at::detail::getDefaultCPUGenerator();
    std::lock_guard<std::mutex> lock(generator.mutex());
    saved_ = generator.get_state();
    generator.set_current_seed(seed);
  }
  ~ScopedGlobalSeed() {
    auto generator = at::detail::getDefaultCPUGenerator();
    std::lock_guard<std::mutex> lock(generator.mutex());
    generator.set_state(saved_);
  }

 private:
  torch::Tensor saved_;
};

models::VelocityNetPtr BuildNet(const TrainingSetup& setup, int64_t state_dim) {
  ScopedGlobalSeed seed(StreamSeed(setup.seed, kInitStream));
  return models::MakeVelocityNet(setup.model, state_dim, planning::ConditionDim(setup.flow.conditioning, state_dim));
}

double CosineLearningRate(const TrainerConfig& config, int64_t step) {
  const double progress = static_cast<double>(step) / static_cast<double>(config.steps);
  return config.lr * 0.5 * (1.0 + std::cos(M_PI * std::min(progress, 1.0)));
}

void SetLearningRate(torch::optim::AdamW& optimizer, double lr) {
  for (auto& group : optimizer.param_groups()) {
    static_cast<torch::optim::AdamWOptions&>(group.options()).lr(lr);
  }
}

void UpdateEma(models::VelocityNet& ema, const models::VelocityNet& net, double decay) {
  torch::NoGradGuard no_grad;
  const auto source = net.parameters(true);
  auto target = ema.parameters(true);
  for (size_t i = 0; i < source.size(); ++i) target[i].mul_(decay).add_(source[i], 1.0 - decay);
}

/// Keeps the rows of a metrics file up to `step` (a resumed run rewrites what follows).
void TruncateMetrics(const std::string& path, int64_t step) {
  std::ifstream in(path);
  if (!in) return;
  std::string kept, line;
  while (std::getline(in, line)) {
    const auto pos = line.find("\"step\": ");
    if (pos == std::string::npos) continue;
    if (std::stoll(line.substr(pos + 8)) <= step) kept += line + "\n";
  }
  WriteFileAtomically(path, kept);
}

std::string Number(double value) {
  if (!std::isfinite(value)) return "null";
  std::ostringstream out;
  out.precision(7);
  out << value;
  return out.str();
}

class MetricsLog {
 public:
  explicit MetricsLog(const std::string& path) : out_(path, std::ios::app) {
    if (!out_) throw Error(path + ": cannot open metrics file for writing");
  }
  void Write(const std::string& json) {
    out_ << json << "\n";
    out_.flush();
  }

 private:
  std::ofstream out_;
};

}  // namespace

double ValidationLoss(models::VelocityNet& net, const torch::Tensor& val, planning::Conditioning conditioning,
                      int batch_size, uint64_t seed) {
  if (!val.defined() || val.size(0) == 0) return NAN;
  torch::NoGradGuard no_grad;
  auto generator = at::make_generator<at::CPUGeneratorImpl>(seed);
  double total = 0.0;
  int64_t count = 0;
  for (int64_t begin = 0; begin < val.size(0); begin += batch_size) {
    const torch::Tensor batch = val.slice(0, begin, std::min<int64_t>(begin + batch_size, val.size(0)));
    total += FlowMatchingLoss(net, batch, conditioning, generator).item<double>() * batch.size(0);
    count += batch.size(0);
  }
  return total / static_cast<double>(count);
}

TrainResult Train(const TrainingSetup& setup, const datasets::TrajectorySplits& data, bool resume) {
  const auto started = std::chrono::steady_clock::now();
  const TrainerConfig& config = setup.train;
  const int64_t T = data.horizon(), D = data.state_dim();
  // One intra-op thread: parallelism comes from the gradient shards (see ShardedGradient).
  at::set_num_threads(1);
  RunDir run(setup.run_dir);
  run.Create();
  WriteFileAtomically(run.config(), setup.config_yaml);

  models::VelocityNetPtr net = BuildNet(setup, D);
  models::VelocityNetPtr ema = BuildNet(setup, D);
  models::CopyWeights(*net, *ema);
  net->CheckHorizon(T);
  if (setup.flow.split_prob > 0.0) {
    try {
      net->CheckHorizon(T / 2);
      if (T % 2 != 0) throw Error("odd horizon " + std::to_string(T));
    } catch (const Error& e) {
      throw Error("flow.split_prob > 0 trains on half trajectories of " + std::to_string(T / 2) +
                  " states, which the network cannot take: " + e.what());
    }
  }
  torch::optim::AdamW optimizer(net->parameters(),
                                torch::optim::AdamWOptions(config.lr).weight_decay(config.weight_decay));
  auto generator = at::make_generator<at::CPUGeneratorImpl>(StreamSeed(setup.seed, kTrainStream));

  models::MinMaxNormalizer normalizer = models::MinMaxNormalizer::Fit(data.train);
  int64_t step = 0;
  if (resume) {
    const std::string path = run.LatestCheckpoint();
    const checkpoints::CheckpointHeader header = checkpoints::ReadCheckpointHeader(path);
    if (header.horizon != T || header.normalizer.dim() != D) {
      throw Error(path + ": checkpoint was trained on (T, D) = (" + std::to_string(header.horizon) + ", " +
                  std::to_string(header.normalizer.dim()) + "), the data has (" + std::to_string(T) + ", " +
                  std::to_string(D) + ")");
    }
    checkpoints::LoadCheckpointWeights(path, {net.get(), ema.get(), &optimizer});
    normalizer = header.normalizer;
    generator.set_state(header.rng_state);
    step = header.step;
    TruncateMetrics(run.metrics(), step);
    spdlog::info("resuming {} at step {}", path, step);
  } else {
    std::remove(run.metrics().c_str());
  }
  spdlog::info("model: {} parameters, horizon {}, state dim {}, {} training / {} validation episodes",
               models::CountParameters(*net), T, D, data.train.size(0), data.val.size(0));

  const torch::Tensor train_n = normalizer.Normalize(data.train);
  const torch::Tensor val_n = data.val.size(0) > 0 ? normalizer.Normalize(data.val) : data.val;
  const int64_t num_train = train_n.size(0);
  const planning::FlowPlanner ema_planner(ema, normalizer, setup.flow.conditioning, T, setup.sampler);
  MetricsLog metrics(run.metrics());
  ShardedGradient gradient(*net, [&] { return BuildNet(setup, D); }, config.shards, setup.threads);

  auto save = [&](int64_t at_step) {
    checkpoints::CheckpointHeader header;
    header.step = at_step;
    header.config_yaml = setup.config_yaml;
    header.normalizer = normalizer;
    header.rng_state = generator.get_state();
    header.env = data.env;
    header.dt = data.dt;
    header.state_labels = data.state_labels;
    header.horizon = T;
    const std::string path = run.checkpoint(at_step);
    checkpoints::SaveCheckpoint(path, header, {net.get(), ema.get(), &optimizer});
    run.PruneCheckpoints(config.keep_checkpoints);
    return path;
  };

  TrainResult result;
  auto evaluate = [&](int64_t at_step) {
    ema->eval();
    result.val_loss = ValidationLoss(*ema, val_n, setup.flow.conditioning, config.val_batch_size,
                                     StreamSeed(setup.seed, kValidationStream));
    auto stitching = [&](const datasets::EvalPairTensors& pairs, const std::string& label) {
      if (!pairs.names.empty()) return eval::EvaluateStitching(ema_planner, pairs, label, setup.eval, setup.threads);
      eval::StitchingResult none;  // datasets without start/goal families (e.g. random reaches)
      none.pairs = label;
      none.mean = none.std = NAN;
      return none;
    };
    result.test = stitching(data.test_pairs, "test");
    result.train = stitching(data.train_pairs, "train");
    spdlog::info("eval step {}: val loss {:.5f}, stitching error test {:.4f} ± {:.4f}, train {:.4f} ± {:.4f}",
                 at_step, result.val_loss, result.test.mean, result.test.std, result.train.mean, result.train.std);
    metrics.Write("{\"step\": " + std::to_string(at_step) + ", \"val_loss\": " + Number(result.val_loss) +
                  ", \"stitch_test_mean\": " + Number(result.test.mean) + ", \"stitch_test_std\": " +
                  Number(result.test.std) + ", \"stitch_train_mean\": " + Number(result.train.mean) +
                  ", \"stitch_train_std\": " + Number(result.train.std) + "}");
  };

  ProgressMeter progress("train", config.steps, "steps", 0.0);
  progress.Update(step);
  double window_loss = 0.0;
  int64_t window_steps = 0;
  net->train();
  const int64_t last_step = setup.stop_at_step > 0 ? std::min(setup.stop_at_step, config.steps) : config.steps;
  while (step < last_step) {
    if (InterruptRequested()) {
      const std::string path = save(step);
      throw Error("interrupted at step " + std::to_string(step) + "; checkpoint " + path +
                  "; continue with: flowplan train --resume " + setup.run_dir);
    }
    const double lr = CosineLearningRate(config, step);
    SetLearningRate(optimizer, lr);
    const torch::Tensor index = torch::randint(num_train, {config.batch_size}, generator, torch::kInt64);
    torch::Tensor x1 = train_n.index_select(0, index);
    const bool split = torch::rand({1}, generator).item<double>() < setup.flow.split_prob;
    if (split) x1 = SplitHalves(x1);
    const double loss_value = gradient.Compute(DrawFlowMatchingBatch(x1, generator), setup.flow.conditioning);
    if (config.grad_clip > 0.0) torch::nn::utils::clip_grad_norm_(net->parameters(), config.grad_clip);
    optimizer.step();
    const double n = static_cast<double>(step);
    UpdateEma(*ema, *net, std::min(config.ema_decay, (1.0 + n) / (10.0 + n)));
    ++step;

    if (!std::isfinite(loss_value)) {
      throw Error("training diverged at step " + std::to_string(step) + " (loss " + Number(loss_value) +
                  "); lower train.lr or set train.grad_clip");
    }
    window_loss += loss_value;
    ++window_steps;
    if (step % config.log_every == 0 || step == config.steps) {
      result.train_loss = window_loss / static_cast<double>(window_steps);
      const double rate = progress.Rate(step);
      spdlog::info("step {}/{} loss {:.5f} lr {:.3g} {:.2f} steps/s ETA {}", step, config.steps, result.train_loss,
                   lr, rate, FormatDuration(rate > 0 ? static_cast<double>(config.steps - step) / rate : NAN));
      metrics.Write("{\"step\": " + std::to_string(step) + ", \"loss\": " + Number(result.train_loss) +
                    ", \"lr\": " + Number(lr) + ", \"steps_per_s\": " + Number(rate) + "}");
      window_loss = 0.0;
      window_steps = 0;
    }
    if ((config.eval_every > 0 && step % config.eval_every == 0) || step == last_step) evaluate(step);
    if (step % config.checkpoint_every == 0 || step == last_step) result.checkpoint = save(step);
  }
  if (result.checkpoint.empty()) {
    // Resumed at the final step: nothing left to train.
    evaluate(step);
    result.checkpoint = run.LatestCheckpoint();
  }
  result.steps = step;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return result;
}

}  // namespace flowplan::trainer
