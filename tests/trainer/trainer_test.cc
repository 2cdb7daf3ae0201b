#include "trainer/trainer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "checkpoints/checkpoint.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "datasets/generator.h"
#include "datasets/particle_task.h"
#include "tests/support/scratch_dir.h"
#include "trainer/run_dir.h"
#include "objectives/flow_matching.h"
#include "trainer/sharded_gradient.h"

namespace flowplan::trainer {
namespace {

namespace fs = std::filesystem;

datasets::TrajectorySplits TinyData() {
  sim::ParticleConfig particle;
  particle.horizon = 16;
  datasets::ParticleCrossTask task(particle);
  datasets::GenerateOptions options;
  options.episodes = 64;
  options.seed = 1;
  options.show_progress = false;
  return datasets::SplitTrajectories(datasets::GenerateDataset(task, options), 0.125, 1, "tiny");
}

TrainingSetup TinySetup(const std::string& name) {
  TrainingSetup setup;
  setup.run_dir = (flowplan::testing::ScratchDir() / name).string();
  fs::remove_all(setup.run_dir);
  setup.config_yaml = "tiny: true\n";
  setup.seed = 3;
  setup.model.unet.down_dims = {8, 16};
  setup.train.steps = 12;
  setup.train.batch_size = 8;
  setup.train.log_every = 4;
  setup.train.eval_every = 6;
  setup.train.checkpoint_every = 6;
  return setup;
}

std::vector<torch::Tensor> Weights(const std::string& checkpoint, const TrainingSetup& setup) {
  const int64_t cond = models::ConditionDim(setup.objective.conditioning, 4);
  auto net = models::MakeNetwork(setup.model, 4, cond);
  auto ema = models::MakeNetwork(setup.model, 4, cond);
  checkpoints::LoadCheckpointWeights(checkpoint, {net.get(), ema.get(), nullptr});
  std::vector<torch::Tensor> out;
  for (const auto& p : net->parameters()) out.push_back(p.clone());
  for (const auto& p : ema->parameters()) out.push_back(p.clone());
  return out;
}

struct ZooCase {
  const char* name;
  models::Architecture architecture;
  objectives::ObjectiveKind objective;
  models::Conditioning conditioning;
  models::Precision precision = models::Precision::kFp32;
};

void PrintTo(const ZooCase& c, std::ostream* os) { *os << c.name; }

class ResumeTest : public ::testing::TestWithParam<ZooCase> {
 protected:
  TrainingSetup Setup(const std::string& name) const {
    TrainingSetup setup = TinySetup(name + "_" + GetParam().name);
    setup.model.architecture = GetParam().architecture;
    setup.model.transformer.d_model = 16;
    setup.model.transformer.heads = 2;
    setup.model.vae.hidden = {16, 16};
    setup.model.vae.latent = 4;
    setup.objective.name = GetParam().objective;
    setup.objective.conditioning = GetParam().conditioning;
    setup.objective.ddpm.steps = 5;
    setup.train.precision = GetParam().precision;
    return setup;
  }
};

TEST_P(ResumeTest, ResumingGivesTheSameWeightsAsOneRun) {
  const auto data = TinyData();
  const TrainingSetup straight = Setup("straight");
  const TrainResult a = Train(straight, data, TrainStart::kFresh);

  TrainingSetup interrupted = Setup("interrupted");
  interrupted.stop_at_step = 5;  // not a logging, evaluation or checkpoint step
  const TrainResult first_part = Train(interrupted, data, TrainStart::kFresh);
  EXPECT_EQ(first_part.steps, 5);
  interrupted.stop_at_step = 0;
  const TrainResult b = Train(interrupted, data, TrainStart::kResume);
  EXPECT_EQ(b.steps, 12);

  const auto wa = Weights(a.checkpoint, straight), wb = Weights(b.checkpoint, interrupted);
  ASSERT_EQ(wa.size(), wb.size());
  for (size_t i = 0; i < wa.size(); ++i) EXPECT_TRUE(torch::equal(wa[i], wb[i])) << "tensor " << i;
  EXPECT_TRUE(torch::equal(checkpoints::ReadCheckpointHeader(a.checkpoint).rng_states[0],
                           checkpoints::ReadCheckpointHeader(b.checkpoint).rng_states[0]));
}

INSTANTIATE_TEST_SUITE_P(
    Zoo, ResumeTest,
    ::testing::Values(
        ZooCase{"FlowUNet", models::Architecture::kUNet1D, objectives::ObjectiveKind::kFlowMatching,
                models::Conditioning::kInpaint},
        ZooCase{"FlowUNetDirect", models::Architecture::kUNet1D, objectives::ObjectiveKind::kFlowMatching,
                models::Conditioning::kDirect},
        ZooCase{"FlowTransformer", models::Architecture::kTransformer, objectives::ObjectiveKind::kFlowMatching,
                models::Conditioning::kInpaint},
        ZooCase{"FlowTransformerDirect", models::Architecture::kTransformer, objectives::ObjectiveKind::kFlowMatching,
                models::Conditioning::kDirect},
        ZooCase{"Ddpm", models::Architecture::kUNet1D, objectives::ObjectiveKind::kDdpm, models::Conditioning::kInpaint},
        ZooCase{"Vae", models::Architecture::kStateVae, objectives::ObjectiveKind::kVae, models::Conditioning::kInpaint},
        ZooCase{"FlowUNetBf16", models::Architecture::kUNet1D, objectives::ObjectiveKind::kFlowMatching,
                models::Conditioning::kInpaint, models::Precision::kBf16},
        ZooCase{"FlowTransformerDirectBf16", models::Architecture::kTransformer,
                objectives::ObjectiveKind::kFlowMatching, models::Conditioning::kDirect, models::Precision::kBf16},
        ZooCase{"DdpmBf16", models::Architecture::kUNet1D, objectives::ObjectiveKind::kDdpm,
                models::Conditioning::kInpaint, models::Precision::kBf16},
        ZooCase{"VaeBf16", models::Architecture::kStateVae, objectives::ObjectiveKind::kVae,
                models::Conditioning::kInpaint, models::Precision::kBf16}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(TrainerTest, NormalizerIsFittedOnTheTrainingSplitOnly) {
  datasets::TrajectorySplits data = TinyData();
  data.val = data.val * 10.0 + 5.0;  // far outside the training range
  const TrainingSetup setup = TinySetup("normalizer");
  const auto header = checkpoints::ReadCheckpointHeader(Train(setup, data, TrainStart::kFresh).checkpoint);
  const auto expected = models::MinMaxNormalizer::Fit(data.train);
  EXPECT_TRUE(torch::equal(header.normalizer.lo(), expected.lo()));
  EXPECT_TRUE(torch::equal(header.normalizer.hi(), expected.hi()));
}

TEST(TrainerTest, EmaFollowsTheWeightsWithWarmUp) {
  // After step n (n = 1, 2, ...) the EMA is d ema + (1 - d) w with d = min(ema_decay, n / (9 + n)).
  const auto data = TinyData();
  TrainingSetup setup = TinySetup("ema");
  setup.train.checkpoint_every = 1;
  setup.train.keep_checkpoints = 100;
  setup.train.ema_decay = 0.2;  // reached at step 3: 3 / 12 = 0.25 > 0.2
  setup.stop_at_step = 4;
  Train(setup, data, TrainStart::kFresh);
  RunDir run(setup.run_dir);
  const size_t P = models::MakeTrajectoryNet(setup.model, 4, 0)->parameters().size();
  for (int64_t n = 2; n <= 4; ++n) {
    const auto before = Weights(run.checkpoint(n - 1), setup), after = Weights(run.checkpoint(n), setup);
    const double d = std::min(0.2, static_cast<double>(n) / (9.0 + static_cast<double>(n)));
    for (size_t i = 0; i < P; ++i) {
      const torch::Tensor expected = d * before[P + i] + (1.0 - d) * after[i];
      EXPECT_TRUE(torch::allclose(after[P + i], expected, 1e-5, 1e-6)) << "step " << n << ", parameter " << i;
    }
  }
}

TEST(TrainerTest, EmaLeavesConstantBuffersExactlyAsTheyAre) {
  // The UNet's sinusoid frequencies are a buffer that training never changes;
  // averaging it with itself would drift it by rounding.
  const TrainingSetup setup = TinySetup("ema_buffers");
  const std::string path = Train(setup, TinyData(), TrainStart::kFresh).checkpoint;
  auto net = models::MakeNetwork(setup.model, 4, 0);
  auto ema = models::MakeNetwork(setup.model, 4, 0);
  checkpoints::LoadCheckpointWeights(path, {net.get(), ema.get(), nullptr});
  const auto fresh = models::MakeNetwork(setup.model, 4, 0)->named_buffers();
  ASSERT_GT(fresh.size(), 0u);
  for (const auto& item : fresh) {
    EXPECT_TRUE(torch::equal(ema->named_buffers()[item.key()], item.value())) << item.key();
    EXPECT_TRUE(torch::equal(net->named_buffers()[item.key()], item.value())) << item.key();
  }
}

TEST(TrainerTest, ForeignGeneratorStateIsNamed) {
  const TrainingSetup setup = TinySetup("foreign_rng");
  const std::string path = Train(setup, TinyData(), TrainStart::kFresh).checkpoint;
  checkpoints::CheckpointHeader header = checkpoints::ReadCheckpointHeader(path);
  header.rng_states = {torch::zeros({3}, torch::kUInt8)};
  auto net = models::MakeTrajectoryNet(setup.model, 4, 0);
  const std::string foreign = (fs::path(setup.run_dir) / "foreign.pt").string();
  checkpoints::SaveCheckpoint(foreign, header, {net.get(), net.get(), nullptr});
  EXPECT_THAT([&] { checkpoints::ReadCheckpointHeader(foreign); },
              ::testing::ThrowsMessage<Error>(::testing::AllOf(::testing::HasSubstr("foreign.pt"),
                                                               ::testing::HasSubstr("rng_state"))));
}

class PrecisionTest : public ::testing::TestWithParam<models::Precision> {
 protected:
  TrainingSetup Setup(const std::string& name) const {
    TrainingSetup setup = TinySetup(name + (GetParam() == models::Precision::kBf16 ? "_bf16" : "_fp32"));
    setup.train.precision = GetParam();
    return setup;
  }
};

TEST_P(PrecisionTest, ThreadCountDoesNotChangeTheWeights) {
  const auto data = TinyData();
  TrainingSetup one = Setup("one_thread");
  one.threads = 1;
  TrainingSetup two = Setup("two_threads");
  two.threads = 2;
  TrainingSetup three = Setup("three_threads");
  three.threads = 3;
  const auto w1 = Weights(Train(one, data, TrainStart::kFresh).checkpoint, one);
  const auto w2 = Weights(Train(two, data, TrainStart::kFresh).checkpoint, two);
  const auto w3 = Weights(Train(three, data, TrainStart::kFresh).checkpoint, three);
  for (size_t i = 0; i < w1.size(); ++i) {
    EXPECT_TRUE(torch::equal(w1[i], w2[i])) << "tensor " << i;
    EXPECT_TRUE(torch::equal(w1[i], w3[i])) << "tensor " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(Fp32AndBf16, PrecisionTest,
                         ::testing::Values(models::Precision::kFp32, models::Precision::kBf16),
                         [](const auto& info) { return info.param == models::Precision::kBf16 ? "bf16" : "fp32"; });

TEST(TrainerTest, Bf16TrainingTakesOtherStepsToANearValidationLoss) {
  // Weights are no measure here: AdamW's first steps are about lr * sign(gradient), so
  // parameters whose gradient is near zero step either way under bfloat16 rounding.
  const auto data = TinyData();
  TrainingSetup fp32 = TinySetup("near_fp32");
  TrainingSetup bf16 = TinySetup("near_bf16");
  bf16.train.precision = models::Precision::kBf16;
  const TrainResult a = Train(fp32, data, TrainStart::kFresh), b = Train(bf16, data, TrainStart::kFresh);
  const auto wa = Weights(a.checkpoint, fp32), wb = Weights(b.checkpoint, bf16);
  double changed = 0.0;
  for (size_t i = 0; i < wa.size(); ++i) changed = std::max(changed, (wa[i] - wb[i]).abs().max().item<double>());
  EXPECT_GT(changed, 0.0) << "bf16 training should not be float32 training";
  EXPECT_NEAR(b.val_loss, a.val_loss, 0.02 * a.val_loss);
  EXPECT_NEAR(b.train_loss, a.train_loss, 0.05 * a.train_loss);
}

TEST(TrainerTest, ShardsSumToTheWholeBatchGradient) {
  // The sharded gradient equals the gradient of the unsharded batch up to rounding.
  torch::manual_seed(0);
  models::ModelConfig config;
  config.unet.down_dims = {8, 16};
  auto master = models::MakeTrajectoryNet(config, 4, 0);
  auto reference = models::MakeTrajectoryNet(config, 4, 0);
  models::CopyWeights(*master, *reference);
  auto generator = at::make_generator<at::CPUGeneratorImpl>(1);
  const objectives::FlowMatchingObjective objective;
  const objectives::ObjectiveBatch batch = objective.Draw(torch::randn({10, 16, 4}), generator);
  ShardedGradient sharded(*master, [&] { return models::MakeTrajectoryNet(config, 4, 0); }, 3, 2);
  const double loss = sharded.Compute(batch, [&](models::Network& net, const objectives::ObjectiveBatch& part) {
    return objective.Loss(net, part, models::Conditioning::kInpaint);
  });
  const torch::Tensor whole = objective.Loss(*reference, batch, models::Conditioning::kInpaint);
  whole.backward();
  EXPECT_NEAR(loss, whole.item<double>(), 1e-6);
  const auto a = master->parameters(), b = reference->parameters();
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(torch::allclose(a[i].grad(), b[i].grad(), 1e-4, 1e-6)) << "parameter " << i;
  }
}

TEST(TrainerTest, RunFolderHoldsConfigMetricsAndPrunedCheckpoints) {
  TrainingSetup setup = TinySetup("layout");
  setup.train.checkpoint_every = 2;
  setup.train.keep_checkpoints = 2;
  // The evaluator sees the EMA weights and the normalizer; its scores are logged.
  std::vector<double> norms;
  setup.evaluate = [&](const models::NetworkPtr& net, const models::MinMaxNormalizer& normalizer) {
    double sum = 0.0;
    for (const auto& p : net->parameters()) sum += p.pow(2).sum().item<double>();
    norms.push_back(std::sqrt(sum));
    return Scores{{"ema_norm", norms.back()}, {"lo0", normalizer.lo()[0].item<double>()}};
  };
  const TrainResult result = Train(setup, TinyData(), TrainStart::kFresh);
  RunDir run(setup.run_dir);
  EXPECT_TRUE(fs::exists(run.config()));
  EXPECT_TRUE(fs::exists(run.metrics()));
  EXPECT_EQ(run.CheckpointSteps(), (std::vector<int64_t>{10, 12}));
  EXPECT_EQ(run.LatestCheckpoint(), result.checkpoint);
  const auto header = checkpoints::ReadCheckpointHeader(result.checkpoint);
  EXPECT_EQ(header.step, 12);
  EXPECT_EQ(header.config_yaml, "tiny: true\n");
  EXPECT_EQ(header.trajectory.horizon, 16);
  EXPECT_EQ(header.trajectory.state_labels.size(), 4u);
  ASSERT_EQ(norms.size(), 2u);  // steps 6 and 12
  ASSERT_EQ(result.scores.size(), 2u);
  EXPECT_EQ(result.scores[0].first, "ema_norm");
  EXPECT_EQ(result.scores[0].second, norms.back());
  EXPECT_EQ(result.scores[1].second, header.normalizer.lo()[0].item<double>());
  const std::string metrics = ReadFile(run.metrics());
  EXPECT_NE(metrics.find("\"step\": 6, \"val_loss\": "), std::string::npos);
  EXPECT_NE(metrics.find("\"ema_norm\": "), std::string::npos);
}

TEST(TrainerTest, FreshRunRefusesAFolderWithCheckpoints) {
  const auto data = TinyData();
  const TrainingSetup setup = TinySetup("used_folder");
  Train(setup, data, TrainStart::kFresh);
  const std::string config_before = ReadFile(RunDir(setup.run_dir).config());
  TrainingSetup again = setup;
  again.config_yaml = "another: run\n";
  EXPECT_THAT([&] { Train(again, data, TrainStart::kFresh); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("holds checkpoints of an earlier run")));
  EXPECT_EQ(ReadFile(RunDir(setup.run_dir).config()), config_before);
}

TEST(TrainerTest, ResumeWithoutCheckpointIsAClearError) {
  const TrainingSetup setup = TinySetup("empty_run");
  EXPECT_THAT([&] { Train(setup, TinyData(), TrainStart::kResume); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("holds no checkpoint")));
}

TEST(TrainerTest, SplitTrainingNeedsAHalfHorizonTheNetCanTake) {
  TrainingSetup setup = TinySetup("bad_split");
  setup.model.unet.down_dims = {8, 8, 8, 8, 8};  // T must be a multiple of 16; halves have 8
  EXPECT_THAT([&] { Train(setup, TinyData(), TrainStart::kFresh); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("objective.split_prob")));
}

}  // namespace
}  // namespace flowplan::trainer
