#include "trainer/trainer.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <cstdlib>

#include "checkpoints/checkpoint.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"
#include "core/interrupt.h"
#include "core/progress.h"
#include "core/random.h"
#include "distributed/gradient_all_reduce.h"
#include "models/normalizer.h"
#include "trainer/training_batch.h"
#include "trainer/run_dir.h"
#include "trainer/sharded_gradient.h"

namespace flowplan::trainer {
namespace {

// Stream tags of the run's generators (see StreamSeed), apart from small episode indices.
constexpr uint64_t kTrainStream = 0x7261'696e'0001ULL;
constexpr uint64_t kInitStream = 0x7261'696e'0002ULL;
constexpr uint64_t kValidationStream = 0x7261'696e'0003ULL;

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

/// The seed of data part `part`'s generator; part 0 keeps the stream of runs
/// with a single part.
uint64_t PartSeed(uint64_t seed, int part) {
  const uint64_t stream = StreamSeed(seed, kTrainStream);
  return part == 0 ? stream : StreamSeed(stream, static_cast<uint64_t>(part));
}

models::NetworkPtr BuildNet(const TrainingSetup& setup, int64_t state_dim) {
  ScopedGlobalSeed seed(StreamSeed(setup.seed, kInitStream));
  // Initialised on the CPU (the same weights on every device), then moved.
  auto net = models::MakeNetwork(setup.model, state_dim, models::ConditionDim(setup.objective.conditioning, state_dim));
  net->to(setup.device);
  return net;
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

/// Averages parameters and floating-point buffers (constant ones, like the
/// UNet's sinusoid frequencies, stay what they are; statistics a network might
/// keep in buffers are averaged like weights).
void UpdateEma(models::Network& ema, const models::Network& net, double decay) {
  torch::NoGradGuard no_grad;
  const auto source = net.parameters(true);
  auto target = ema.parameters(true);
  for (size_t i = 0; i < source.size(); ++i) target[i].mul_(decay).add_(source[i], 1.0 - decay);
  const auto source_buffers = net.buffers(true);
  auto target_buffers = ema.buffers(true);
  for (size_t i = 0; i < source_buffers.size(); ++i) {
    // Equal buffers are left alone: d·x + (1 − d)·x is not exactly x in floating point.
    if (target_buffers[i].is_floating_point() && !torch::equal(target_buffers[i], source_buffers[i])) {
      target_buffers[i].mul_(decay).add_(source_buffers[i], 1.0 - decay);
    }
  }
}

/// Keeps the rows of a metrics file up to `step` (a resumed run rewrites what
/// follows); rows it cannot read are dropped.
void TruncateMetrics(const std::string& path, int64_t step) {
  std::ifstream in(path);
  if (!in) return;
  std::string kept, line;
  while (std::getline(in, line)) {
    const auto pos = line.find("\"step\": ");
    if (pos == std::string::npos) continue;
    char* end = nullptr;
    const long long row_step = std::strtoll(line.c_str() + pos + 8, &end, 10);
    if (end != line.c_str() + pos + 8 && row_step <= step) kept += line + "\n";
  }
  WriteFileAtomically(path, kept);
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

double ValidationLoss(const objectives::Objective& objective, models::Network& net, const torch::Tensor& val,
                      models::Conditioning conditioning, int batch_size, uint64_t seed) {
  if (!val.defined() || val.size(0) == 0) return NAN;
  torch::NoGradGuard no_grad;
  auto generator = at::make_generator<at::CPUGeneratorImpl>(seed);
  const torch::Device device = net.parameters().empty() ? torch::Device(torch::kCPU) : net.parameters()[0].device();
  double total = 0.0;
  int64_t count = 0;
  for (int64_t begin = 0; begin < val.size(0); begin += batch_size) {
    const torch::Tensor batch = val.slice(0, begin, std::min<int64_t>(begin + batch_size, val.size(0)));
    const objectives::ObjectiveBatch drawn = objective.Draw(batch, generator).To(device);  // drawn on the CPU
    total += objective.Loss(net, drawn, conditioning).item<double>() * batch.size(0);
    count += batch.size(0);
  }
  return total / static_cast<double>(count);
}


namespace {

/// The part of the training episodes one generator draws from.
struct DataPart {
  int index;               // p in [0, train.data_parts)
  torch::Tensor data;      // (N_p, T, D) normalized: training episodes p, p + Q, ... (Q data parts)
  at::Generator generator;  // seeded by PartSeed(seed, p)
};

/// One training run: the networks, optimizer, generator and run folder, and
/// the steps that advance them.
class TrainingRun {
 public:
  TrainingRun(const TrainingSetup& setup, const datasets::TrajectorySplits& data, TrainStart start)
      : setup_(setup),
        config_(setup.train),
        data_(data),
        run_(setup.run_dir),
        T_(data.horizon()),
        D_(data.state_dim()),
        net_(BuildNet(setup, D_)),
        ema_(BuildNet(setup, D_)),
        optimizer_(net_->parameters(), torch::optim::AdamWOptions(config_.lr).weight_decay(config_.weight_decay)),
        objective_(objectives::MakeObjective(setup.objective, setup.model)),
        communicator_(setup.communicator != nullptr ? *setup.communicator : single_process_),
        lead_(communicator_.rank() == 0),
        normalizer_(SharedNormalizer(data)) {
    const int parts = config_.data_parts, ranks = communicator_.size();
    if (config_.precision == models::Precision::kBf16 && !setup.device.is_cpu()) {
      throw Error("train.precision=bf16 is CPU autocast and device is " + setup.device.str() +
                  ": set train.precision=fp32 or device=cpu");
    }
    if (parts % ranks != 0) {
      throw Error("train.data_parts=" + std::to_string(parts) + " must be a multiple of the number of processes (" +
                  std::to_string(ranks) + "): every process trains the same number of data parts");
    }
    if (data.num_train < parts) {
      throw Error("train.data_parts=" + std::to_string(parts) + ": the data has only " +
                  std::to_string(data.num_train) + " training episodes");
    }
    models::CopyWeights(*net_, *ema_);
    if (const auto* trajectory_net = dynamic_cast<const models::TrajectoryNet*>(net_.get())) {
      trajectory_net->CheckHorizon(T_);
      if (setup.objective.split_prob > 0.0) {
        models::CheckHalfHorizon(*trajectory_net, T_, "objective.split_prob > 0 trains on");
      }
    }
    // This process's parts: p = rank, rank + R, ... (R processes); episode i of the training split is in part i mod Q.
    // The loader may have split them off already (a process that read only its own episodes).
    std::vector<int> mine;
    for (int part = communicator_.rank(); part < parts; part += ranks) mine.push_back(part);
    if (!data.train_parts.empty() && data.parts != mine) {
      throw Error("the data holds parts other than this process's (train.data_parts=" + std::to_string(parts) + ")");
    }
    for (size_t k = 0; k < mine.size(); ++k) {
      const int part = mine[k];
      const torch::Tensor episodes = data.train_parts.empty()
                                         ? data.train.slice(0, part, data.train.size(0), parts)
                                         : data.train_parts[k];
      parts_.push_back(DataPart{part, normalizer_.Normalize(episodes).contiguous(),
                                at::make_generator<at::CPUGeneratorImpl>(PartSeed(setup.seed, part))});
    }
    if (lead_) run_.Create();
    if (start == TrainStart::kResume) {
      Restore();
    } else if (!run_.CheckpointSteps().empty()) {
      throw Error(run_.root() + ": holds checkpoints of an earlier run; continue it with flowplan train --resume " +
                  run_.root() + ", or choose another run_dir");
    } else if (lead_) {
      std::remove(run_.metrics().c_str());
    }
    // Written only once the run is known to start: a failed start leaves the folder as it was.
    if (lead_) WriteFileAtomically(run_.config(), setup.config_yaml);
    val_n_ = data.val.size(0) > 0 ? normalizer_.Normalize(data.val) : data.val;
    gradient_ = std::make_unique<ShardedGradient>(*net_, [&] { return BuildNet(setup_, D_); }, config_.shards,
                                                  setup.threads);
    if (ranks > 1) {
      all_reduce_ = std::make_unique<distributed::GradientAllReduce>(net_->parameters(), setup.bucket_bytes);
    }
    if (lead_) metrics_ = std::make_unique<MetricsLog>(run_.metrics());
    spdlog::info("model: {} parameters, horizon {}, state dim {}, {} training / {} validation episodes", 
                 models::CountParameters(*net_), T_, D_, data.num_train, data.val.size(0));
    if (config_.precision == models::Precision::kBf16) {
      spdlog::info("precision bf16: the loss under CPU autocast (backward follows its dtypes), weights and optimizer in float32; {}",
                   models::DescribeBf16Kernels());
    }
    if (ranks > 1 || parts > 1) {
      spdlog::info("{} data parts over {} process{}{}", parts, ranks, ranks == 1 ? "" : "es",
                   all_reduce_ ? ", gradients summed in " + std::to_string(all_reduce_->buckets()) + " bucket(s)"
                               : std::string());
    }
  }

  TrainResult Run() {
    const auto started = std::chrono::steady_clock::now();
    const int64_t last_step =
        setup_.stop_at_step > 0 ? std::min(setup_.stop_at_step, config_.steps) : config_.steps;
    result_.first_step = step_;
    ProgressMeter progress("train", config_.steps, "steps", 0.0);
    progress.Update(step_);
    net_->train();
    while (step_ < last_step) {
      if (StopRequested()) StopInterrupted(Save());
      const double lr = CosineLearningRate(config_, step_);
      const double loss = Step(lr);
      window_loss_ += loss;
      ++window_steps_;
      if (step_ % config_.log_every == 0 || step_ == last_step) LogProgress(lr, progress.Rate(step_));
      // The checkpoint comes first, so that an evaluation cut short by Ctrl-C loses nothing.
      const bool checkpoint_due = step_ % config_.checkpoint_every == 0 || step_ == last_step;
      if (checkpoint_due) result_.checkpoint = Save();
      // Rank 0 alone evaluates; the others wait for it at the next collective.
      if (lead_ && ((config_.eval_every > 0 && step_ % config_.eval_every == 0) || step_ == last_step)) {
        try {
          Evaluate();
          LogEvaluation();
        } catch (const Error&) {
          if (!InterruptRequested()) throw;
          if (communicator_.size() == 1) StopInterrupted(checkpoint_due ? result_.checkpoint : Save());
          // The other processes are already in the next step: all stop together once its all-reduce
          // carries the interrupt (after the loop, if this was the last step).
          spdlog::warn("evaluation at step {} interrupted; stopping with the other processes", step_);
        }
      }
    }
    if (InterruptRequested()) StopInterrupted(run_.LatestCheckpoint());  // an evaluation of the last step cut short
    if (result_.checkpoint.empty()) {
      // Resumed at the final step: nothing left to train, and its metrics are logged already.
      if (lead_) Evaluate();
      result_.checkpoint = run_.LatestCheckpoint();
    }
    result_.steps = step_;
    result_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return result_;
  }

 private:
  void Restore() {
    const std::string path = run_.LatestCheckpoint();
    const checkpoints::CheckpointHeader header = checkpoints::ReadCheckpointHeader(path);
    if (header.trajectory.horizon != T_ || header.normalizer.dim() != D_) {
      throw Error(path + ": checkpoint was trained on (T, D) = (" + std::to_string(header.trajectory.horizon) + ", " +
                  std::to_string(header.normalizer.dim()) + "), the data has (" + std::to_string(T_) + ", " +
                  std::to_string(D_) + ")");
    }
    // A process that read only its own episodes has no fingerprint; rank 0 checks for the job.
    const bool changed = !data_.fingerprint.empty() && header.data_fingerprint != data_.fingerprint;
    const std::string message = path + ": was trained on data with fingerprint " + header.data_fingerprint +
                                ", but " + setup_.data_path + " now has fingerprint " + data_.fingerprint +
                                "; the data file changed since the run started (restore it, or train into a new "
                                "run_dir)";
    if (communicator_.size() > 1) {
      // Rank 0 alone read the whole file; every process learns its verdict.
      const torch::Tensor verdict = communicator_.AllGather(torch::full({1}, changed ? 1.0f : 0.0f));
      if (verdict[0][0].item<float>() > 0.0f) {
        throw Error(lead_ ? message : path + ": rank 0 found that the data file changed since the run started");
      }
    } else if (changed) {
      throw Error(message);
    }
    checkpoints::LoadCheckpointWeights(path, {net_.get(), ema_.get(), &optimizer_}, setup_.device);
    normalizer_ = header.normalizer;
    if (static_cast<int>(header.rng_states.size()) != config_.data_parts) {
      throw Error(path + ": holds the generators of " + std::to_string(header.rng_states.size()) +
                  " data part(s), the run has train.data_parts=" + std::to_string(config_.data_parts));
    }
    for (DataPart& part : parts_) part.generator.set_state(header.rng_states[static_cast<size_t>(part.index)]);
    step_ = header.step;
    if (lead_) TruncateMetrics(run_.metrics(), step_);
    spdlog::info("resuming {} at step {}", path, step_);
  }

  /// The normalizer of the whole training split: fitted here, or, in a job of
  /// several processes, fitted by rank 0 (which reads the whole split) and shared.
  models::MinMaxNormalizer SharedNormalizer(const datasets::TrajectorySplits& data) {
    if (communicator_.size() == 1) return models::MinMaxNormalizer::Fit(data.train);
    const int64_t D = data.state_dim();
    torch::Tensor bounds = torch::zeros({2 * D});
    if (lead_) {
      const auto fitted = models::MinMaxNormalizer::Fit(data.train);
      bounds = torch::cat({fitted.lo(), fitted.hi()}).to(torch::kFloat32);
    }
    const torch::Tensor shared = communicator_.AllGather(bounds)[0];  // (2D,) rank 0's
    return models::MinMaxNormalizer(shared.slice(0, 0, D).clone(), shared.slice(0, D, 2 * D).clone());
  }

  [[noreturn]] void StopInterrupted(const std::string& checkpoint) const {
    throw Error("interrupted at step " + std::to_string(step_) + "; checkpoint " + checkpoint +
                "; continue with: flowplan train --resume " + setup_.run_dir);
  }

  /// Whether the run stops before the next step: Ctrl-C here, or, in a job of
  /// several processes, in any of them (agreed on in the previous step's all-reduce).
  bool StopRequested() const { return communicator_.size() > 1 ? stop_agreed_ : InterruptRequested(); }

  /// The gradient of one data part's share of the batch, into net_'s .grad; returns its loss.
  double PartGradient(DataPart& part, int64_t batch_size) {
    const torch::Tensor x1 =
        DrawTrainingTrajectories(part.data, batch_size, setup_.objective.split_prob, part.generator);
    const models::Conditioning conditioning = setup_.objective.conditioning;
    return gradient_->Compute(objective_->Draw(x1, part.generator).To(setup_.device),
                              [&](models::Network& net, const objectives::ObjectiveBatch& batch) {
                                const models::AutocastScope autocast(config_.precision);  // on this worker's thread
                                return objective_->Loss(net, batch, conditioning);
                              });
  }

  /// The gradient of the whole batch's mean loss into net_'s .grad (every part
  /// draws B * (p + 1) / Q - B * p / Q trajectories (Q data parts); their losses are weighted by
  /// that share and summed over the parts of every process); returns the loss.
  double BatchGradient() {
    const int64_t B = config_.batch_size, Q = config_.data_parts;
    if (Q == 1) return PartGradient(parts_[0], B);
    double loss = 0.0;
    std::vector<torch::Tensor> sum;
    auto params = net_->parameters();
    for (DataPart& part : parts_) {
      const int64_t share = B * (part.index + 1) / Q - B * part.index / Q;
      const double weight = static_cast<double>(share) / static_cast<double>(B);
      loss += PartGradient(part, share) * weight;
      torch::NoGradGuard no_grad;
      for (size_t i = 0; i < params.size(); ++i) {
        const torch::Tensor g = params[i].grad().defined() ? params[i].grad() * weight : torch::zeros_like(params[i]);
        if (sum.size() <= i) sum.push_back(g); else sum[i].add_(g);
      }
    }
    for (size_t i = 0; i < params.size(); ++i) params[i].mutable_grad() = sum[i];
    return loss;
  }

  /// One optimizer step at learning rate `lr`; returns the batch loss.
  double Step(double lr) {
    SetLearningRate(optimizer_, lr);
    double loss = BatchGradient();
    if (all_reduce_) {
      std::vector<double> scalars{loss, InterruptRequested() ? 1.0 : 0.0};
      all_reduce_->Run(communicator_, scalars);
      loss = scalars[0];
      stop_agreed_ = scalars[1] > 0.0;
    }
    if (config_.grad_clip > 0.0) torch::nn::utils::clip_grad_norm_(net_->parameters(), config_.grad_clip);
    optimizer_.step();
    const double n = static_cast<double>(step_);
    UpdateEma(*ema_, *net_, std::min(config_.ema_decay, (1.0 + n) / (10.0 + n)));
    ++step_;
    if (!std::isfinite(loss)) {
      throw Error("training diverged at step " + std::to_string(step_) + " (loss " + JsonNumber(loss) +
                  "); lower train.lr or set train.grad_clip");
    }
    return loss;
  }

  void LogProgress(double lr, double rate) {
    result_.train_loss = window_loss_ / static_cast<double>(window_steps_);
    spdlog::info("step {}/{} loss {:.5f} lr {:.3g} {:.2f} steps/s ETA {}", step_, config_.steps, result_.train_loss,
                 lr, rate, FormatDuration(rate > 0 ? static_cast<double>(config_.steps - step_) / rate : NAN));
    if (metrics_) metrics_->Write("{\"step\": " + std::to_string(step_) + ", \"loss\": " + JsonNumber(result_.train_loss) +
                    ", \"lr\": " + JsonNumber(lr) + ", \"steps_per_s\": " + JsonNumber(rate) + "}");
    window_loss_ = 0.0;
    window_steps_ = 0;
  }

  /// Validation loss and the evaluator's scores of the EMA weights into result_.
  void Evaluate() {
    spdlog::info("evaluating the EMA weights at step {}", step_);
    ema_->eval();
    result_.val_loss = ValidationLoss(*objective_, *ema_, val_n_, setup_.objective.conditioning, config_.val_batch_size,
                                      StreamSeed(setup_.seed, kValidationStream));
    result_.scores = setup_.evaluate ? setup_.evaluate(ema_, normalizer_) : Scores{};
    std::string scores;
    for (const auto& [name, value] : result_.scores) scores += fmt::format(", {} {:.4f}", name, value);
    spdlog::info("eval step {}: val loss {:.5f}{}", step_, result_.val_loss, scores);
  }

  void LogEvaluation() {
    std::string row = "{\"step\": " + std::to_string(step_) + ", \"val_loss\": " + JsonNumber(result_.val_loss);
    for (const auto& [name, value] : result_.scores) row += ", " + JsonString(name) + ": " + JsonNumber(value);
    metrics_->Write(row + "}");
  }

  /// Writes a checkpoint of the current step and returns its path. Collective
  /// in a job of several processes (rank 0 gathers every part's generator and writes).
  std::string Save() {
    const std::string path = run_.checkpoint(step_);
    std::vector<torch::Tensor> states;
    for (const DataPart& part : parts_) states.push_back(part.generator.get_state());
    if (communicator_.size() > 1) {
      // (R, parts per process * state bytes): rank r's parts are r, r + R, ...; part p is row p mod R, block p / R.
      const torch::Tensor gathered = communicator_.AllGather(torch::cat(states));
      const int64_t bytes = states[0].numel(), R = communicator_.size();
      states.clear();
      for (int64_t p = 0; p < config_.data_parts; ++p) {
        states.push_back(gathered[p % R].slice(0, (p / R) * bytes, (p / R + 1) * bytes).clone());
      }
    }
    if (!lead_) return path;
    checkpoints::CheckpointHeader header;
    header.step = step_;
    header.config_yaml = setup_.config_yaml;
    header.normalizer = normalizer_;
    header.rng_states = states;
    header.trajectory = data_.info;
    header.data_fingerprint = data_.fingerprint;
    checkpoints::SaveCheckpoint(path, header, {net_.get(), ema_.get(), &optimizer_});
    run_.PruneCheckpoints(config_.keep_checkpoints);
    return path;
  }

  const TrainingSetup& setup_;
  const TrainerConfig& config_;
  const datasets::TrajectorySplits& data_;
  RunDir run_;
  const int64_t T_, D_;
  models::NetworkPtr net_, ema_;
  torch::optim::AdamW optimizer_;
  std::unique_ptr<objectives::Objective> objective_;
  distributed::SingleProcess single_process_;
  distributed::Communicator& communicator_;
  const bool lead_;  // rank 0: writes the run folder and evaluates
  models::MinMaxNormalizer normalizer_;
  std::vector<DataPart> parts_;  // this process's parts, ascending
  torch::Tensor val_n_;    // (N_val, T, D) normalized
  std::unique_ptr<ShardedGradient> gradient_;
  std::unique_ptr<distributed::GradientAllReduce> all_reduce_;  // null in a single process
  bool stop_agreed_ = false;
  std::unique_ptr<MetricsLog> metrics_;
  int64_t step_ = 0;
  double window_loss_ = 0.0;
  int64_t window_steps_ = 0;
  TrainResult result_;
};

}  // namespace

TrainResult Train(const TrainingSetup& setup, const datasets::TrajectorySplits& data, TrainStart start) {
  // LibTorch runs single-threaded, parallelism comes from the gradient shards
  // (see ShardedGradient); denormals are flushed (they are orders of magnitude
  // slower on x86) before any worker thread, which inherits the mode, starts.
  at::globalContext().setFlushDenormal(true);
  at::set_num_threads(1);
  return TrainingRun(setup, data, start).Run();
}

}  // namespace flowplan::trainer
