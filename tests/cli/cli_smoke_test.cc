// The real `flowplan` binary on tiny budgets: the whole pipeline, resume, and
// every kind of bad input ending in one clear line and a non-zero exit.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "checkpoints/checkpoint.h"
#include "models/model_config.h"
#include "tests/support/command.h"
#include "tests/support/scratch_dir.h"

namespace flowplan {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

using flowplan::testing::ExpectCleanFailure;
using flowplan::testing::ExpectOk;
using flowplan::testing::Flowplan;
using flowplan::testing::FlowplanInterruptedWhen;
using flowplan::testing::Outcome;

std::string Tiny() { return std::string(FLOWPLAN_SOURCE_DIR) + "/tests/cli/tiny.yaml"; }

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = flowplan::testing::ScratchDir();
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string Paths(const std::string& run = "run") const {
    return " generate.out=" + Path("data.h5") + " data.path=" + Path("data.h5") + " run_dir=" + Path(run);
  }
  Outcome Generate() { return Flowplan("generate --config " + Tiny() + Paths()); }

  fs::path dir_;
};

TEST_F(CliTest, ConfigsWithTheOlderModelArchitectureKeyStillLoad) {
  // Run folders and checkpoints written before model.architecture became model.name.
  std::ofstream(Path("old.yaml")) << "model:\n  architecture: transformer\n";
  const Outcome shown = Flowplan("config show --config " + Path("old.yaml") + " --log-level warn");
  ExpectOk(shown);
  EXPECT_THAT(shown.output, HasSubstr("  name: transformer"));
  EXPECT_THAT(shown.output, ::testing::Not(HasSubstr("architecture")));
  ExpectCleanFailure(Flowplan("config show model.architecture=unet1d"), "model.architecture");
}

TEST_F(CliTest, GenerateTrainEvalExportThenPlanFromPython) {
  ExpectOk(Generate());
  ExpectOk(Outcome{std::system((std::string(FLOWPLAN_PYTHON) + " " + FLOWPLAN_SOURCE_DIR +
                                "/tests/cli/check_dataset_layout.py " + Path("data.h5"))
                                   .c_str()),
                   "h5py layout check"});
  ExpectOk(Flowplan("train --config " + Tiny() + Paths()));
  EXPECT_TRUE(fs::exists(Path("run/config.yaml")));
  EXPECT_TRUE(fs::exists(Path("run/metrics.jsonl")));
  EXPECT_TRUE(fs::exists(Path("run/checkpoints/step_00000006.pt")));

  const Outcome eval = Flowplan("eval stitching --ckpt " + Path("run"));
  ExpectOk(eval);
  EXPECT_THAT(eval.output, HasSubstr("stitching error"));
  std::ifstream report(Path("run/eval_stitching.json"));
  std::stringstream json;
  json << report.rdbuf();
  EXPECT_THAT(json.str(), HasSubstr("\"test\": {\"pairs\": \"test\""));
  EXPECT_THAT(json.str(), HasSubstr("(0,0)->(1,0)"));

  ExpectOk(Flowplan("export --ckpt " + Path("run")));
  ASSERT_TRUE(fs::exists(Path("run/planner.pt")));
  const std::string python = std::string(FLOWPLAN_PYTHON) + " -c \"import torch; p = torch.jit.load('" +
                             Path("run/planner.pt") +
                             "'); s = torch.tensor([0., 0., 0., 0.]); g = torch.tensor([1., 0., 0., 0.]); "
                             "x = p.sample(s, g, 3); assert x.shape == (3, p.horizon, 4); "
                             "assert torch.equal(x[:, 0], s.expand(3, 4)) and torch.equal(x[:, -1], g.expand(3, 4))\"";
  EXPECT_EQ(std::system(python.c_str()), 0) << python;
}

TEST_F(CliTest, ResumeAfterAStopEqualsOneRun) {
  ExpectOk(Generate());
  ExpectOk(Flowplan("train --config " + Tiny() + Paths("straight")));
  ExpectOk(Flowplan("train --config " + Tiny() + Paths("stopped") + " --until 3"));
  EXPECT_FALSE(fs::exists(Path("stopped/checkpoints/step_00000006.pt")));
  const Outcome resumed = Flowplan("train --resume " + Path("stopped"));
  ExpectOk(resumed);
  EXPECT_THAT(resumed.output, HasSubstr("resuming"));
  EXPECT_THAT(resumed.output, HasSubstr("trained 3 steps, to step 6"));
  const Outcome finished = Flowplan("train --resume " + Path("stopped"));
  ExpectOk(finished);
  EXPECT_THAT(finished.output, HasSubstr("nothing left to train: the run ended at step 6"));
  EXPECT_FALSE(fs::exists(Path("stopped/checkpoints/step_00000007.pt")));

  models::ModelConfig model;
  model.unet.down_dims = {8, 16};
  auto load = [&](const std::string& path) {
    auto net = models::MakeTrajectoryNet(model, 4, 0), ema = models::MakeTrajectoryNet(model, 4, 0);
    checkpoints::LoadCheckpointWeights(path, {net.get(), ema.get(), nullptr});
    std::vector<torch::Tensor> weights = net->parameters();
    for (const auto& p : ema->parameters()) weights.push_back(p);
    return weights;
  };
  const auto a = load(Path("straight/checkpoints/step_00000006.pt"));
  const auto b = load(Path("stopped/checkpoints/step_00000006.pt"));
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(torch::equal(a[i], b[i])) << "tensor " << i;
}

TEST_F(CliTest, TrainedNetworkCannotBeChangedByOverridesOrRetrainedInPlace) {
  ExpectOk(Generate());
  ExpectOk(Flowplan("train --config " + Tiny() + Paths()));
  ExpectCleanFailure(Flowplan("eval stitching --ckpt " + Path("run") + " model.unet.groups=4"),
                     "model.unet.groups: the network was trained with 8");
  ExpectCleanFailure(Flowplan("export --ckpt " + Path("run") + " objective.conditioning=direct"), "objective.conditioning");
  ExpectCleanFailure(Flowplan("train --resume " + Path("run") + " model.unet.kernel_size=3"), "model.unet.kernel_size");
  // Nor can a resumed run change its data, seed or optimizer: it would be another run.
  ExpectCleanFailure(Flowplan("train --resume " + Path("run") + " train.lr=0.01"), "train.lr: the run was trained with");
  ExpectCleanFailure(Flowplan("train --resume " + Path("run") + " seed=7"), "seed: the run was trained with 1");
  ExpectCleanFailure(Flowplan("train --resume " + Path("run") + " data.val_fraction=0.5"), "data.val_fraction");
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + Paths()), "holds checkpoints of an earlier run");
  // What may change: the sampler, the evaluation, and the length of training.
  ExpectOk(Flowplan("eval stitching --ckpt " + Path("run") + " sampler.steps=4 sampler.splitting=midpoint"));
  const Outcome longer = Flowplan("train --resume " + Path("run") + " train.steps=8 threads=1 eval.num_plans=2");
  ExpectOk(longer);
  EXPECT_THAT(longer.output, HasSubstr("warm restart"));
  EXPECT_TRUE(fs::exists(Path("run/checkpoints/step_00000008.pt")));
}

TEST_F(CliTest, CtrlCDuringTrainingWritesACheckpointToResumeFrom) {
  ExpectOk(Generate());
  // SIGINT once it has logged step 2 of 100,000.
  const Outcome stopped = FlowplanInterruptedWhen(
      "train --config " + Tiny() + Paths() + " train.steps=100000 train.eval_every=0 --log-level info", "step 2/100000",
      Path("train.log"));
  EXPECT_NE(stopped.exit_code, 0) << stopped.output;
  EXPECT_THAT(stopped.output, HasSubstr("interrupted at step"));
  EXPECT_THAT(stopped.output, HasSubstr("flowplan train --resume"));
  const auto checkpoints = fs::directory_iterator(Path("run/checkpoints"));
  EXPECT_NE(checkpoints, fs::directory_iterator()) << "no checkpoint written on interrupt";
}

TEST_F(CliTest, CtrlCDuringAnEvaluationStillLeavesTheStepsCheckpoint) {
  ExpectOk(Generate());
  // The evaluation after step 1 plans 400,000 times (many seconds); SIGINT once it has started.
  const Outcome stopped = FlowplanInterruptedWhen(
      "train --config " + Tiny() + Paths() + " train.steps=100000 train.eval_every=1 train.checkpoint_every=100000 "
      "eval.num_plans=400000",
      "evaluating the EMA weights at step 1", Path("train.log"));
  EXPECT_NE(stopped.exit_code, 0) << stopped.output;
  EXPECT_THAT(stopped.output, HasSubstr("interrupted at step 1; checkpoint "));
  EXPECT_TRUE(fs::exists(Path("run/checkpoints/step_00000001.pt"))) << stopped.output;
  ExpectOk(Flowplan("train --resume " + Path("run") + " --until 2 eval.num_plans=4"));
}

TEST_F(CliTest, BadConfigKeyValueAndFile) {
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + " train.bach_size=8"), "train.bach_size");
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + " train.batch_size=abc"), "train.batch_size");
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + " train.lr=-1"), "train.lr");
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + " objective.conditioning=global"), "one of inpaint, direct");
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + " model.unet.time_scale=.inf"),
                     "model.unet.time_scale: expected a finite number");
  ExpectCleanFailure(Flowplan("generate --config " + Tiny() + " --shard 99999999999/1"), "--shard");
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + " --until -5"), "--until");
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + " device=gpu"), "device=gpu: expected cpu, cuda or cuda:N");
  ExpectCleanFailure(Flowplan("problems problems.min_spheres=9 --out " + Path("p.yaml")),
                     "problems.min_spheres: larger than max_spheres");
  EXPECT_FALSE(fs::exists(Path("p.yaml")));
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + " device=cuda:1"), "device=cuda:1: this LibTorch has no CUDA");
  ExpectCleanFailure(Flowplan("generate --config " + Path("missing.yaml")), "missing.yaml");
  std::ofstream(Path("broken.yaml")) << "train:\n  steps: [1\n";
  ExpectCleanFailure(Flowplan("train --config " + Path("broken.yaml")), "broken.yaml");
  std::ofstream(Path("unknown.yaml")) << "trian:\n  steps: 1\n";
  ExpectCleanFailure(Flowplan("train --config " + Path("unknown.yaml")), "unknown.yaml:1: trian: unknown key");
}

TEST_F(CliTest, BadFilesAreNamed) {
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + Paths() + " data.path=" + Path("absent.h5")), "absent.h5");
  // A folder that cannot exist (its parent is a file), even for root.
  std::ofstream(Path("a_file")) << "x";
  ExpectCleanFailure(Flowplan("generate --config " + Tiny() + " generate.out=" + Path("a_file/sub/data.h5")),
                     "a_file/sub");
  // A folder that takes no new files even from root: refused before any rollout.
  const Outcome unwritable = Flowplan("generate --config " + Tiny() + " generate.out=/proc/flowplan_cli_test.h5");
  ExpectCleanFailure(unwritable, "/proc/flowplan_cli_test.h5: cannot write");
  EXPECT_THAT(unwritable.output, Not(HasSubstr("episodes/s")));
  std::ofstream(Path("garbage.pt")) << "not a checkpoint";
  ExpectCleanFailure(Flowplan("eval stitching --ckpt " + Path("garbage.pt")), "garbage.pt");
  ExpectCleanFailure(Flowplan("export --ckpt " + Path("nothing_here.pt")), "nothing_here.pt");
  ExpectCleanFailure(Flowplan("train --resume " + Path("no_run")), "no_run");
  std::filesystem::create_directories(Path("empty_folder"));
  ExpectCleanFailure(Flowplan("train --resume " + Path("empty_folder")), "empty_folder: not a run folder");
  // A folder given as the config would otherwise read as an empty file: all defaults.
  ExpectCleanFailure(Flowplan("train --config " + Path("empty_folder")), "empty_folder");
  ExpectCleanFailure(Flowplan("config show --config " + Path("empty_folder")), "empty_folder");
  ExpectCleanFailure(Flowplan("genrate --config " + Tiny()), "unknown command \"genrate\"");
  std::ofstream(Path("text.h5")) << "hello";
  ExpectCleanFailure(Flowplan("train --config " + Tiny() + Paths() + " data.path=" + Path("text.h5")), "not an HDF5 file");
}

TEST_F(CliTest, TruncatedCheckpointIsAClearErrorAndLeavesNoPartialOutput) {
  ExpectOk(Generate());
  ExpectOk(Flowplan("train --config " + Tiny() + Paths()));
  const std::string good = Path("run/checkpoints/step_00000006.pt");
  std::ifstream in(good, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(Path("cut.pt"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  ExpectCleanFailure(Flowplan("export --ckpt " + Path("cut.pt") + " --out " + Path("out.pt")), "cut.pt");
  EXPECT_FALSE(fs::exists(Path("out.pt")));
  // A foreign but valid archive: a TorchScript planner is not a checkpoint.
  ExpectOk(Flowplan("export --ckpt " + good + " --out " + Path("planner.pt")));
  ExpectCleanFailure(Flowplan("eval stitching --ckpt " + Path("planner.pt")), "not a flowplan checkpoint");
}

std::string Bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST_F(CliTest, FrankaGenerationIsThreadAndShardInvariantAndH5pyReadsIt) {
  const std::string config = std::string(FLOWPLAN_SOURCE_DIR) + "/configs/franka_cross.yaml generate.episodes=12";
  ExpectOk(Flowplan("generate --config " + config + " threads=1 generate.out=" + Path("one.h5")));
  ExpectOk(Flowplan("generate --config " + config + " threads=2 generate.out=" + Path("two.h5")));
  ExpectOk(Flowplan("generate --config " + config + " --shard 0/2 --out " + Path("s0.h5")));
  ExpectOk(Flowplan("generate --config " + config + " --shard 1/2 --out " + Path("s1.h5")));
  ExpectOk(Flowplan("merge " + Path("s0.h5") + " " + Path("s1.h5") + " --out " + Path("merged.h5")));
  const std::string one = Bytes(Path("one.h5"));
  EXPECT_FALSE(one.empty());
  EXPECT_TRUE(one == Bytes(Path("two.h5"))) << "1 and 2 threads wrote different files";
  EXPECT_TRUE(one == Bytes(Path("merged.h5"))) << "merged shards differ from the whole file";
  ExpectOk(Outcome{std::system((std::string(FLOWPLAN_PYTHON) + " " + FLOWPLAN_SOURCE_DIR +
                                "/tests/cli/check_dataset_layout.py " + Path("one.h5"))
                                   .c_str()),
                   "h5py layout check"});
  ExpectCleanFailure(Flowplan("generate --config " + config + " generate.franka.cross_goals=[[0.5,0.3,0.6],[2,0,0.5]]"),
                     "generate.franka.cross_goals[1]: franka IK: target (2.0, 0.0, 0.5) is unreachable");
  ExpectCleanFailure(Flowplan("merge " + Path("s0.h5") + " " + Path("one.h5") + " --out " + Path("bad.h5")),
                     "in order, each once");
}

TEST_F(CliTest, FkPrintsTheReadyPoseThroughMujocoAndLibTorch) {
  const Outcome ready = Flowplan("fk --q=0,-0.7853981633974483,0,-2.356194490192345,0,1.5707963267948966,0.7853981633974483");
  ExpectOk(ready);
  // Flange of the ready pose (libfranka / MoveIt), TCP 0.107 m below it.
  EXPECT_THAT(ready.output, HasSubstr("flange (MuJoCo):  (0.306890567, 0.000000000, 0.590282052)"));
  EXPECT_THAT(ready.output, HasSubstr("TCP (LibTorch):   (0.306890567, 0.000000000, 0.483282052)"));
  ExpectCleanFailure(Flowplan("fk --q=1,2"), "--q: expected 7 joint angles, got 2");
  ExpectCleanFailure(Flowplan("fk --q=nan,0,0,-1,0,1,0"), "--q value 1 \"nan\": not a finite number");
  ExpectCleanFailure(Flowplan("fk --q=0,,0,-1,0,1,0,0"), "--q value 2 \"\": not a number");
  ExpectCleanFailure(Flowplan("fk --q=0,0,0,-1,0,1,zero"), "--q value 7 \"zero\": not a number");
  const Outcome outside = Flowplan("fk --q=10,0,0,-1,0,1,0");
  ExpectOk(outside);
  EXPECT_THAT(outside.output, HasSubstr("q1 = 10 is outside the joint's limits"));
}

TEST_F(CliTest, HelpListsSubcommandsAndKeys) {
  const Outcome help = Flowplan("--help");
  ExpectOk(help);
  for (const char* command : {"generate", "train", "eval", "export", "merge", "config", "fk"}) {
    EXPECT_THAT(help.output, HasSubstr(command));
  }
  const Outcome keys = Flowplan("config keys");
  ExpectOk(keys);
  EXPECT_THAT(keys.output, HasSubstr("train.batch_size = 256"));
  EXPECT_THAT(keys.output, HasSubstr("model.unet.down_dims = [32, 64, 128, 256]"));
  const Outcome shown = Flowplan("config show --config " + Tiny() + " train.steps=9");
  ExpectOk(shown);
  EXPECT_THAT(shown.output, HasSubstr("steps: 9"));
}

}  // namespace
}  // namespace flowplan
